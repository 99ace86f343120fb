"""Marker geometry (pure) and its messages: where the wall, arrow, X_d and trail are drawn."""

from __future__ import annotations

import math

import numpy as np
import pytest
from rclpy.serialization import serialize_message
from uvms_recording.typestore import uvms_typestore
from uvms_viz.conversions import NAMESPACES, header_stamp_ns, marker_array
from uvms_viz.marker_geometry import (
    WALL_THICKNESS_M,
    ContactHistory,
    MarkerGeometryError,
    MarkerSettings,
    Trail,
    marker_scene,
    wall_box,
)
from visualization_msgs.msg import Marker

from uvms_msgs.msg import ContactState, ControllerState

SETTINGS = MarkerSettings()


@pytest.mark.parametrize('wall_x_m', [1.7771, 1.9, 2.5])
def test_wall_face_is_on_the_contact_plane_and_follows_it(wall_x_m: float) -> None:
    """The slab's face toward the robot is at x = wall position, wherever the wall moved."""
    box = wall_box(wall_x_m, SETTINGS)
    assert box is not None
    assert box.center[0] - 0.5 * box.size[0] == pytest.approx(wall_x_m, abs=1e-12)
    np.testing.assert_allclose(box.size, [WALL_THICKNESS_M, 2.0, 2.0])


def test_no_wall_draws_no_wall() -> None:
    """Free motion reports a NaN wall position: no wall box."""
    assert wall_box(math.nan, SETTINGS) is None


def test_force_arrow_starts_at_the_end_effector_and_scales_with_the_force() -> None:
    """The arrow runs from X to X + force_scale_m_per_n * F."""
    trail = Trail(4)
    p_ee = np.array([1.78, 0.1, -0.2])
    force = np.array([12.0, -1.0, 0.5])
    scene = marker_scene(p_ee, [1.8, 0.0, -0.2], force, 1.7771, trail, SETTINGS)
    np.testing.assert_allclose(scene.force_tail, p_ee)
    np.testing.assert_allclose(scene.force_tip - scene.force_tail,
                               SETTINGS.force_scale_m_per_n * force)
    np.testing.assert_allclose(scene.reference, [1.8, 0.0, -0.2])


def test_trail_keeps_the_last_positions_oldest_first() -> None:
    """A trail of length 3 fed five points keeps the last three, in order."""
    trail = Trail(3)
    for k in range(5):
        trail.append([float(k), 0.0, 0.0])
    np.testing.assert_allclose(trail.points()[:, 0], [2.0, 3.0, 4.0])
    assert len(trail) == 3


@pytest.mark.parametrize(('field', 'value'), [
    ('force_scale_m_per_n', 0.0), ('force_scale_m_per_n', math.inf), ('trail_length', 1),
    ('wall_size_m', (2.0, -1.0)), ('wall_center_yz_m', (math.nan, 0.0)),
])
def test_bad_setting_is_rejected_naming_it(field: str, value: object) -> None:
    """Each setting out of range names itself and the value."""
    with pytest.raises(MarkerGeometryError, match=field):
        MarkerSettings(**{field: value})  # type: ignore[arg-type]


def test_marker_array_decodes_with_rosbags_to_the_scene() -> None:
    """The CDR of the MarkerArray, read by rosbags, holds the scene in map_ned at its stamp."""
    trail = Trail(10)
    for x in (1.6, 1.7, 1.78):
        trail.append([x, 0.0, -0.1])
    scene = marker_scene([1.78, 0.0, -0.1], [1.8, 0.0, -0.1], [10.0, 0.0, 0.0], 1.7771,
                         trail, SETTINGS)
    data = serialize_message(marker_array(scene, 1_250_000_000))
    msg = uvms_typestore().deserialize_cdr(data, 'visualization_msgs/msg/MarkerArray')
    wall, force, reference, line = msg.markers
    assert tuple(m.ns for m in msg.markers) == NAMESPACES
    assert {(m.header.frame_id, m.header.stamp.sec, m.header.stamp.nanosec)
            for m in msg.markers} == {('map_ned', 1, 250_000_000)}
    assert (wall.type, wall.action) == (Marker.CUBE, Marker.ADD)
    assert wall.pose.position.x == pytest.approx(1.7771 + 0.5 * WALL_THICKNESS_M)
    assert force.type == Marker.ARROW
    assert (force.points[1].x - force.points[0].x) == pytest.approx(0.2)
    assert reference.type == Marker.SPHERE
    assert reference.pose.position.x == 1.8
    assert line.type == Marker.LINE_STRIP
    assert [p.x for p in line.points] == [1.6, 1.7, 1.78]


def test_without_a_wall_the_wall_marker_is_deleted() -> None:
    """A viewer removes the wall marker when the run has no wall."""
    scene = marker_scene([0.0] * 3, [0.0] * 3, [0.0] * 3, math.nan, Trail(2), SETTINGS)
    assert marker_array(scene, 0).markers[0].action == Marker.DELETE


def test_contact_of_the_state_stamp_is_used_whatever_arrived_later() -> None:
    """Exact stamp first; else the newest before it; else the oldest kept; else none."""
    history: ContactHistory[tuple[float, float]] = ContactHistory(capacity=3)
    assert history.at(0) is None
    for k in range(1, 6):
        history.add(k * 10, (float(k), 1.7 + k))
    assert history.at(40) == (4.0, 5.7)
    assert history.at(45) == (4.0, 5.7)
    assert history.at(5) == (3.0, 4.7)  # 10 and 20 were dropped (capacity 3)


@pytest.mark.parametrize('stamp', [(0, 0), (3, 999_999_999), (2_000_000_000, 1)])
def test_stamp_read_from_raw_bytes_equals_the_header_stamp(stamp: tuple[int, int]) -> None:
    """The visualizer's raw read of a stamp matches the stamp rclpy serialized."""
    state = ControllerState()
    state.header.stamp.sec, state.header.stamp.nanosec = stamp
    contact = ContactState()
    contact.header.stamp.sec, contact.header.stamp.nanosec = stamp
    for msg in (state, contact):
        assert header_stamp_ns(serialize_message(msg)) == stamp[0] * 1_000_000_000 + stamp[1]


@pytest.mark.parametrize('data', [b'', b'\x00\x01\x00\x00\x01', b'\x00\x07' + bytes(20)])
def test_stamp_of_bytes_that_are_no_stamped_cdr_is_refused(data: bytes) -> None:
    """Too short or another encapsulation: a ValueError naming the encapsulation."""
    with pytest.raises(ValueError, match='encapsulation'):
        header_stamp_ns(data)
