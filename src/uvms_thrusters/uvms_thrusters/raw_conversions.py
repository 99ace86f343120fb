"""The allocator's hot topics as raw CDR: payloads in and out, numpy inside.

The command reader takes a payload of a raw subscription: our controller's layout is read in
place with `struct`; any other layout (a frame id of '', joints in another order, from another
publisher) is deserialized by rclpy and judged by the typed reader of
`uvms_thrusters.conversions`, which stays the reference; a payload that is no message of the
type raises `MalformedPayloadError` (counted in ``decoder.malformed``). Writers fill
preallocated payloads (`uvms_common.cdr_codecs.PayloadWriter`) with the values the typed
builders of `uvms_thrusters.conversions` put in their messages.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from uvms_common.cdr_codecs import PayloadWriter
from uvms_common.cdr_codecs import RawReader as Reader
from uvms_common.hot_messages import (
    THRUSTER_ARRAYS,
    actuator_command_codec,
    generalized_force_codec,
    thruster_state_codec,
)

from uvms_thrusters import conversions
from uvms_thrusters.allocation import AllocatorOutput
from uvms_thrusters.conversions import FloatArray
from uvms_thrusters.errors import ThrusterInputError


def _finite(name: str, values: tuple[float, ...]) -> FloatArray:
    if not math.isfinite(sum(values)) and not all(math.isfinite(v) for v in values):
        raise ThrusterInputError(f'{name} holds a non-finite value: {list(values)}')
    return np.array(values)

def generalized_force_reader(joint_names: Sequence[str]) -> Reader:
    """``command/generalized_force`` to tau_b (6 + n,), joint torques in the model's order."""
    codec = generalized_force_codec(joint_names)
    (w_at, wrench), (j_at, torques) = (codec.struct(['vehicle_wrench']),
                                       codec.struct(['joint_torques']))

    def fast(data: bytes) -> FloatArray:
        return _finite('generalized force',
                       wrench.unpack_from(data, w_at) + torques.unpack_from(data, j_at))

    names = list(joint_names)
    return Reader(codec, fast, lambda msg: conversions.generalized_force_arrays(msg, names)[1])
class ActuatorCommandWriter:
    """uvms_msgs/ActuatorCommand payloads: actual thrusts (N) and motor torques (N m)."""

    def __init__(self, n_thrusters: int, joint_names: Sequence[str]) -> None:
        self._payload = PayloadWriter(actuator_command_codec(n_thrusters, joint_names),
                                      ['thrust'], ['joint_torques'])

    def payload(self, t_ns: int, thrust: FloatArray, joint_torques: FloatArray) -> bytes:
        """The command stamped t_ns."""
        return self._payload.fill(t_ns, np.asarray(thrust, dtype=np.float64).tolist(),
                                  np.asarray(joint_torques, dtype=np.float64).tolist())
class ThrusterStateWriter:
    """uvms_msgs/ThrusterState payloads of allocator steps."""

    def __init__(self, n_thrusters: int) -> None:
        groups = [[name] for name in THRUSTER_ARRAYS]
        self._payload = PayloadWriter(thruster_state_codec(n_thrusters), *groups,
                                      ['achieved_wrench', 'saturation_scale'])

    def payload(self, t_ns: int, output: AllocatorOutput) -> bytes:
        """The thruster state of one step stamped t_ns."""
        allocation = output.allocation
        arrays = [np.asarray(a, dtype=np.float64).tolist() for a in (
            allocation.thrust, output.thrust, output.propeller_speed, output.reference_speed,
            output.motor_current)]
        achieved = np.asarray(allocation.achieved_wrench, dtype=np.float64).tolist()
        return self._payload.fill(t_ns, *arrays,
                                  (*achieved, float(allocation.saturation_scale)))
