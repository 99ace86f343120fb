"""The simulator's raw payloads carry what its typed messages carry; commands read alike."""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np
import pytest
from rclpy.serialization import deserialize_message, serialize_message
from uvms_common.cdr_codecs import MalformedPayloadError
from uvms_sim.errors import CommandError
from uvms_sim.plant import Plant, initial_coordinates

from uvms_model import UvmsModel, UvmsParameters
from uvms_msgs.msg import ActuatorCommand
from uvms_sim import conversions, raw_conversions

JOINTS = ('joint_1', 'joint_2', 'joint_3')


@functools.cache
def observations() -> list[Any]:
    """Observations of a plant pushed into the wall and about, with contact and without."""
    params = UvmsParameters()
    model = UvmsModel(params)
    q0 = initial_coordinates(model, np.array([0.0, 0.0, 0.0, 0.1, -0.2, 0.3]),
                             np.array([0.0, 0.4, -0.8]), None)
    plant = Plant(params, q0, 1_000_000, True, 0.0)
    seen = []
    thrusts = np.linspace(-20.0, 40.0, plant.n_thrusters)
    for k in range(60):
        plant.step(thrusts, np.array([0.5, -0.3, 0.2]) * (k % 3))
        if k % 20 == 19:
            seen.append(plant.observe(all_frames=False))
    return seen


def typed(msg: Any) -> dict[str, Any]:
    """A message as nested plain values, to compare two messages field by field."""
    out: dict[str, Any] = {}
    for name in type(msg).get_fields_and_field_types():
        value = getattr(msg, name)
        out[name] = typed(value) if hasattr(value, 'get_fields_and_field_types') else (
            list(value) if not isinstance(value, str | bool | int | float) else value)
    return out


@pytest.mark.parametrize('index', range(3))
def test_raw_state_payloads_equal_the_typed_messages(index: int) -> None:
    """Each payload deserializes to exactly the typed message of the same observation."""
    seen = observations()[index]
    reference = conversions.StateMessages(JOINTS)
    reference.update(seen)
    raw = raw_conversions.RawStateMessages(JOINTS)
    raw.update(seen)
    for name in ('clock', 'joint_state', 'odometry', 'wrench', 'ee_pose', 'contact'):
        expected = getattr(reference, name)
        payload = getattr(raw, name)
        assert typed(deserialize_message(payload, type(expected))) == typed(expected), name


def test_ground_truth_not_due_keeps_the_last_payloads() -> None:
    """update(ground_truth=False) refreshes the sensor topics only, as the typed messages."""
    first, second = observations()[:2]
    raw = raw_conversions.RawStateMessages(JOINTS)
    raw.update(first)
    ee_pose, contact, wrench = raw.ee_pose, raw.contact, raw.wrench
    raw.update(second, ground_truth=False)
    assert (raw.ee_pose, raw.contact) == (ee_pose, contact)
    assert raw.wrench != wrench


def command(thrust: list[float], torques: list[float], names: list[str] | None = None,
            frame: str = 'base_link_frd') -> bytes:
    """An actuator command stamped 2 ms, serialized by rclpy."""
    msg = ActuatorCommand(thrust=thrust, joint_names=list(JOINTS) if names is None else names,
                          joint_torques=torques)
    msg.header.stamp.nanosec = 2_000_000
    msg.header.frame_id = frame
    return serialize_message(msg)


def test_command_in_our_layout_reads_in_place() -> None:
    """The allocator's layout gives stamp, thrusts and torques without rclpy."""
    reader = raw_conversions.ActuatorCommandReader(8, JOINTS)
    stamp, thrusts, torques = reader.read(command(list(np.arange(8.0)), [0.1, 0.2, 0.3]))
    assert stamp == 2_000_000
    np.testing.assert_array_equal(thrusts, np.arange(8.0))
    np.testing.assert_array_equal(torques, [0.1, 0.2, 0.3])


def test_command_in_another_joint_order_is_reordered() -> None:
    """Another publisher's joint order goes through the typed path and is put in arm order."""
    reader = raw_conversions.ActuatorCommandReader(8, JOINTS)
    _, _, torques = reader.read(command([0.0] * 8, [3.0, 1.0, 2.0],
                                        ['joint_3', 'joint_1', 'joint_2'], frame=''))
    np.testing.assert_array_equal(torques, [1.0, 2.0, 3.0])


@pytest.mark.parametrize(('thrust', 'torques', 'field'), [
    ([0.0] * 7 + [math.nan], [0.0] * 3, 'thrust holds a non-finite'),
    ([0.0] * 8, [0.0, math.inf, 0.0], 'joint_torques holds a non-finite'),
    ([0.0] * 7, [0.0] * 3, 'thrust has 7 values'),
    ([0.0] * 8, [0.0] * 4, 'joint_torques has 4 values'),
])
def test_bad_command_is_rejected_naming_the_field(thrust: list[float], torques: list[float],
                                                  field: str) -> None:
    """NaN/Inf in our layout and wrong sizes in another are refused alike, field named."""
    reader = raw_conversions.ActuatorCommandReader(8, JOINTS)
    names = None if len(torques) == 3 else [f'j{i}' for i in range(len(torques))]
    with pytest.raises(CommandError, match=field):
        reader.read(command(thrust, torques, names))


@pytest.mark.parametrize('payload', [b'', b'\x00\x01\x00\x00', b'\x01\x00' + bytes(90),
                                     bytes(range(200))])
def test_garbage_is_malformed_and_counted(payload: bytes) -> None:
    """A payload that is no ActuatorCommand raises MalformedPayloadError and is counted."""
    reader = raw_conversions.ActuatorCommandReader(8, JOINTS)
    with pytest.raises(MalformedPayloadError):
        reader.read(payload)
    assert reader.decoder.malformed == 1
