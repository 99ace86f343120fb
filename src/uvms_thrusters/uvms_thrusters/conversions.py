"""Messages to numpy and back for the thruster allocator node (the only such place).

Frames: the generalized force command, the actuator command and the thruster state in
``base_link_frd``. Array fields are filled with ``array.array('d')``, which the rosidl classes
take without a per-element check. The command reader validates sizes, frames and finiteness
and raises `ThrusterInputError` naming the field.
"""

from __future__ import annotations

import array
import math
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt
from builtin_interfaces.msg import Time
from geometry_msgs.msg import Point, Vector3
from std_msgs.msg import Header

from uvms_msgs.msg import ActuatorCommand, GeneralizedForce, ThrusterState
from uvms_thrusters.allocation import AllocatorOutput
from uvms_thrusters.errors import ThrusterInputError

FloatArray = npt.NDArray[np.float64]

BASE_LINK_FRD = 'base_link_frd'


def stamp_ns(stamp: Time) -> int:
    """Integer nanoseconds of a builtin_interfaces/Time."""
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def time_from_ns(t_ns: int) -> Time:
    """builtin_interfaces/Time from integer nanoseconds."""
    sec, nanosec = divmod(int(t_ns), 1_000_000_000)
    return Time(sec=sec, nanosec=nanosec)


def _finite(name: str, values: FloatArray) -> FloatArray:
    # A finite sum of a few floats is the cheap test; a huge sum may overflow, so look again.
    if not math.isfinite(sum(values.tolist())) and not np.all(np.isfinite(values)):
        raise ThrusterInputError(f'{name} holds a non-finite value: {values.tolist()}')
    return values


def _check_frame(field: str, frame: str, allowed: Sequence[str]) -> None:
    if frame not in allowed:
        expected = ' or '.join(repr(f) for f in allowed if f) or "''"
        raise ThrusterInputError(f'{field} is {frame!r}, expected {expected}')


def _set_xyz(target: Vector3 | Point, v: npt.ArrayLike) -> None:
    """Set x, y, z of a Vector3 or Point from a 3-vector, as plain floats."""
    target.x, target.y, target.z = np.asarray(v, dtype=np.float64).tolist()


def _floats(values: npt.ArrayLike) -> array.array[float]:
    return array.array('d', np.asarray(values, dtype=np.float64).tolist())


# The message builders take ``out``, a message an earlier call returned, to refill instead of
# building a new one: rclpy serializes at publish, so a node may keep
# one message per publisher. Frames and joint names are set when the message is built.


def generalized_force_arrays(
    msg: GeneralizedForce, joint_names: Sequence[str]
) -> tuple[int, FloatArray]:
    """Stamp (ns) and tau_b (6 + n,) of a command, joint torques in the model's order.

    Raises:
        ThrusterInputError: for another frame, wrong joint names or sizes, non-finite values.
    """
    _check_frame('command header.frame_id', msg.header.frame_id, ('', BASE_LINK_FRD))
    torques = np.asarray(msg.joint_torques, dtype=np.float64)
    names = list(msg.joint_names)
    n = len(joint_names)
    if torques.size != n:
        raise ThrusterInputError(
            f'joint_torques has {torques.size} values, expected {n} ({", ".join(joint_names)})'
        )
    if names and names != list(joint_names):
        if sorted(names) != sorted(joint_names):
            raise ThrusterInputError(
                f'joint_names {names} do not match the arm joints {list(joint_names)}'
            )
        torques = torques[[names.index(name) for name in joint_names]]
    wrench = msg.vehicle_wrench
    tau_b = np.empty(6 + n)
    tau_b[:6] = (
        wrench.force.x,
        wrench.force.y,
        wrench.force.z,
        wrench.torque.x,
        wrench.torque.y,
        wrench.torque.z,
    )
    tau_b[6:] = torques
    return stamp_ns(msg.header.stamp), _finite('generalized force', tau_b)
def actuator_command_message(
    t_ns: int,
    thrust: FloatArray,
    joint_names: Sequence[str],
    joint_torques: FloatArray,
    out: ActuatorCommand | None = None,
) -> ActuatorCommand:
    """uvms_msgs/ActuatorCommand: actual thrusts (N) and motor torques (N m)."""
    msg = out
    if msg is None:
        msg = ActuatorCommand(header=Header(frame_id=BASE_LINK_FRD))
        msg.joint_names = list(joint_names)
    msg.header.stamp = time_from_ns(t_ns)
    msg.thrust = _floats(thrust)
    msg.joint_torques = _floats(joint_torques)
    return msg
def thruster_state_message(
    t_ns: int, output: AllocatorOutput, out: ThrusterState | None = None
) -> ThrusterState:
    """uvms_msgs/ThrusterState of one allocator step."""
    allocation = output.allocation
    msg = out if out is not None else ThrusterState(header=Header(frame_id=BASE_LINK_FRD))
    msg.header.stamp = time_from_ns(t_ns)
    msg.desired_thrust = _floats(allocation.thrust)
    msg.actual_thrust = _floats(output.thrust)
    msg.propeller_speed = _floats(output.propeller_speed)
    msg.reference_speed = _floats(output.reference_speed)
    msg.motor_current = _floats(output.motor_current)
    achieved = np.asarray(allocation.achieved_wrench, dtype=np.float64)
    _set_xyz(msg.achieved_wrench.force, achieved[0:3])
    _set_xyz(msg.achieved_wrench.torque, achieved[3:6])
    msg.saturation_scale = float(allocation.saturation_scale)
    return msg
