"""Marker scenes to visualization_msgs, and controller and contact messages to numbers.

The only place of uvms_viz's visualizer where messages meet numpy. Markers are in
``map_ned`` (the /tf tree ties it to the ENU twin ``map``, so RViz and Foxglove with a
fixed frame ``map`` draw them upright); each keeps its namespace and id from one
publication to the next, so a viewer replaces it instead of adding one.
"""

from __future__ import annotations

import struct

from builtin_interfaces.msg import Duration, Time
from geometry_msgs.msg import Point
from std_msgs.msg import ColorRGBA, Header
from visualization_msgs.msg import Marker, MarkerArray

from uvms_viz.marker_geometry import FloatArray, MarkerScene

MAP_NED = 'map_ned'

#: Marker namespaces, one marker each (id 0).
WALL_NS = 'wall'
FORCE_NS = 'contact_force'
REFERENCE_NS = 'reference'
TRAIL_NS = 'trail'
NAMESPACES = (WALL_NS, FORCE_NS, REFERENCE_NS, TRAIL_NS)

#: Colours (r, g, b, a).
WALL_RGBA = (0.55, 0.6, 0.65, 0.5)
FORCE_RGBA = (0.9, 0.15, 0.1, 1.0)
REFERENCE_RGBA = (0.1, 0.7, 0.2, 0.9)
TRAIL_RGBA = (0.2, 0.45, 0.9, 0.9)

#: Arrow shaft and head diameters, head length (m); sphere diameter, line width (m).
ARROW_SHAFT_M = 0.015
ARROW_HEAD_M = 0.035
ARROW_HEAD_LENGTH_M = 0.04
REFERENCE_DIAMETER_M = 0.04
TRAIL_WIDTH_M = 0.008


def time_from_ns(t_ns: int) -> Time:
    """builtin_interfaces/Time from integer nanoseconds."""
    sec, nanosec = divmod(int(t_ns), 1_000_000_000)
    return Time(sec=sec, nanosec=nanosec)


#: CDR encapsulation identifiers (XCDR1, OMG DDS-XTypes 7.6.3.1.2): big and little endian.
_CDR_BE, _CDR_LE = 0x00, 0x01


def header_stamp_ns(cdr: bytes) -> int:
    """Stamp (ns) of a serialized message whose first field is a std_msgs/Header.

    A raw subscription's bytes: the 4-byte encapsulation header, then Header.stamp as
    int32 sec and uint32 nanosec at offsets 4 and 8 (both 4-byte aligned). Reading the stamp
    alone spares deserializing a message that is then not used.

    Raises:
        ValueError: Fewer than 12 bytes, or not plain CDR (the encapsulation named).
    """
    if len(cdr) < 12 or cdr[0] != 0 or cdr[1] not in (_CDR_BE, _CDR_LE):
        msg = (f'not a CDR message with a header: {len(cdr)} bytes, encapsulation '
               f'{bytes(cdr[:2]).hex()}')
        raise ValueError(msg)
    sec, nanosec = struct.unpack_from('<iI' if cdr[1] == _CDR_LE else '>iI', cdr, 4)
    return int(sec) * 1_000_000_000 + int(nanosec)


def ns_from_time(stamp: Time) -> int:
    """Integer nanoseconds of a builtin_interfaces/Time."""
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def xyz(vector: object) -> tuple[float, float, float]:
    """(x, y, z) of a geometry_msgs Point or Vector3."""
    return (float(vector.x), float(vector.y), float(vector.z))  # type: ignore[attr-defined]


def _point(p: FloatArray) -> Point:
    return Point(x=float(p[0]), y=float(p[1]), z=float(p[2]))


def _marker(header: Header, ns: str, marker_type: int,
            rgba: tuple[float, float, float, float]) -> Marker:
    marker = Marker(header=header, ns=ns, id=0, type=marker_type, action=Marker.ADD,
                    lifetime=Duration(sec=0, nanosec=0), frame_locked=False)
    marker.pose.orientation.w = 1.0
    marker.color = ColorRGBA(r=rgba[0], g=rgba[1], b=rgba[2], a=rgba[3])
    return marker


def marker_array(scene: MarkerScene, t_ns: int, frame_id: str = MAP_NED) -> MarkerArray:
    """The MarkerArray of a scene stamped t_ns: wall, force arrow, reference, trail.

    Without a wall the ``wall`` marker is sent as DELETE, so a viewer removes it.
    """
    header = Header(stamp=time_from_ns(t_ns), frame_id=frame_id)
    markers = []

    wall = _marker(header, WALL_NS, Marker.CUBE, WALL_RGBA)
    if scene.wall is None:
        wall.action = Marker.DELETE
    else:
        wall.pose.position = _point(scene.wall.center)
        wall.scale.x, wall.scale.y, wall.scale.z = (float(s) for s in scene.wall.size)
    markers.append(wall)

    force = _marker(header, FORCE_NS, Marker.ARROW, FORCE_RGBA)
    force.points = [_point(scene.force_tail), _point(scene.force_tip)]
    force.scale.x, force.scale.y, force.scale.z = ARROW_SHAFT_M, ARROW_HEAD_M, ARROW_HEAD_LENGTH_M
    markers.append(force)

    reference = _marker(header, REFERENCE_NS, Marker.SPHERE, REFERENCE_RGBA)
    reference.pose.position = _point(scene.reference)
    reference.scale.x = reference.scale.y = reference.scale.z = REFERENCE_DIAMETER_M
    markers.append(reference)

    trail = _marker(header, TRAIL_NS, Marker.LINE_STRIP, TRAIL_RGBA)
    trail.points = [_point(p) for p in scene.trail]
    trail.scale.x = TRAIL_WIDTH_M
    markers.append(trail)
    return MarkerArray(markers=markers)
