"""Messages of the pilot tools: commands out (TwistStamped, Float64, Joy), live state in.

The one place where the pilot tools meet ROS messages. Frames as the graph names them:
``base_link_frd`` (vehicle body, x forward, y right, z down) and ``map_ned``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import TwistStamped, WrenchStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import Joy
from std_msgs.msg import Float64, Header

#: The vehicle body frame (an empty frame_id means it too, per the pilot contract).
BASE_LINK_FRD = 'base_link_frd'
#: The world frame of the graph.
MAP_NED = 'map_ned'
#: DiagnosticStatus levels (bytes in the message) by name.
LEVEL_NAMES = {0: 'OK', 1: 'WARN', 2: 'ERROR', 3: 'STALE'}


def twist_stamped(stamp: Time, frame_id: str, linear: Sequence[float],
                  angular: Sequence[float]) -> TwistStamped:
    """geometry_msgs/TwistStamped of a velocity (m/s, rad/s) in frame_id at stamp."""
    msg = TwistStamped(header=Header(stamp=stamp, frame_id=frame_id))
    msg.twist.linear.x, msg.twist.linear.y, msg.twist.linear.z = map(float, linear)
    msg.twist.angular.x, msg.twist.angular.y, msg.twist.angular.z = map(float, angular)
    return msg


def jaw_message(jaw_m_s: float) -> Float64:
    """std_msgs/Float64 of the jaw opening velocity (m/s, + opens)."""
    return Float64(data=float(jaw_m_s))


def joy_message(stamp: Time, frame_id: str, axes: Sequence[float],
                buttons: Sequence[int]) -> Joy:
    """sensor_msgs/Joy of a gamepad's normalized axes and 0/1 buttons."""
    return Joy(header=Header(stamp=stamp, frame_id=frame_id), axes=[float(a) for a in axes],
               buttons=[int(b) for b in buttons])


def depth_heading_velocity(msg: Odometry) -> tuple[float, float, tuple[float, float, float]]:
    """Depth (m, map_ned z), heading (deg, 0 north, + east) and body velocity (m/s)."""
    q = msg.pose.pose.orientation
    yaw_rad = math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))
    v = msg.twist.twist.linear
    return (msg.pose.pose.position.z, math.degrees(yaw_rad) % 360.0, (v.x, v.y, v.z))


def force_magnitude_n(msg: WrenchStamped) -> float:
    """|F| of a wrench (N)."""
    f = msg.wrench.force
    return math.sqrt(f.x * f.x + f.y * f.y + f.z * f.z)


def diagnostics_line(msg: DiagnosticArray) -> str | None:
    """The line to show of a DiagnosticArray: its worst status (the first of equals), or None."""
    statuses: list[DiagnosticStatus] = list(msg.status)
    if not statuses:
        return None
    worst = max(statuses, key=lambda s: int.from_bytes(s.level, 'little')
                if isinstance(s.level, bytes) else int(s.level))
    level = int.from_bytes(worst.level, 'little') if isinstance(worst.level, bytes) else int(
        worst.level)
    return f'{LEVEL_NAMES.get(level, level)} {worst.name}: {worst.message}'
