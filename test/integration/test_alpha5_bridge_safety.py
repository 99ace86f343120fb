"""alpha5_bridge on the twin: the arm put back, changes confirmed, no silent joint published.

Issue 46: every way out leaves the arm as found, activation and stops are read back, and a
joint that stops answering is never published as alive.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Iterator
from typing import Any

import pytest
from diagnostic_msgs.msg import DiagnosticStatus
from test_alpha5_bridge import FAILURE, SUCCESS, Rig
from uvms_common.lifecycle import state_label
from uvms_hardware.alpha5_checks import CONFIRM_TRIES, DEFAULT_CONFIRM_TIMEOUT_S, put_back_bound_s
from uvms_hardware.alpha5_probe import Confirmation
from uvms_hardware.reach_protocol import Mode, PacketId, decode_frame, encode_mode

from uvms_hardware import alpha5_component
from uvms_hardware import reach_protocol as rp

#: Devices of the four arm joints, in drive order (joint_1..joint_4).
DEVICES = (0x05, 0x04, 0x03, 0x02)
#: Modes the devices rest in before the bridge starts (Current is no resting mode: Standby).
MODES_BEFORE = {0x05: Mode.DISABLE, 0x04: Mode.PASSIVE, 0x03: Mode.STANDBY, 0x02: Mode.CURRENT}
RESTORED = {0x05: Mode.DISABLE, 0x04: Mode.PASSIVE, 0x03: Mode.STANDBY, 0x02: Mode.STANDBY}


@pytest.fixture
def rig() -> Iterator[Rig]:
    """A fresh twin and executor, closed after the test."""
    made = Rig()
    yield made
    made.close()


def set_modes(rig: Rig, modes: dict[int, Mode]) -> None:
    """Put the twin's devices in ``modes`` as a pendant or an earlier host would have."""
    for device_id, mode in modes.items():
        rig.twin.handle(decode_frame(encode_mode(device_id, mode)))


def modes(rig: Rig) -> dict[int, Mode]:
    """The twin's device modes by device id."""
    return {d: rig.twin.devices[d].mode for d in DEVICES}


def velocity_zero_since(rig: Rig, device_id: int, since_s: float) -> bool:
    """Whether the device received VELOCITY 0 after ``since_s`` (monotonic s)."""
    return any(t >= since_s and p.packet_id == PacketId.VELOCITY
               and rp.packet_values_si(p) == [0.0] for t, p in rig.twin.received(device_id))


def test_activate_raising_half_way_puts_every_device_back(
        rig: Rig, monkeypatch: pytest.MonkeyPatch) -> None:
    """Activate raises after two devices took Standby: all four are back as found, VELOCITY 0.

    The arm rested in Disable, Passive, Standby and Current; the bridge answers ERROR, the
    base puts the arm back (Disable, Passive, Standby, Standby: Current is not left on) and
    the node ends unconfigured.
    """
    set_modes(rig, MODES_BEFORE)
    real = alpha5_component.confirm_setting
    calls = []

    def half_way(*args: Any, **kwargs: Any) -> Confirmation:
        calls.append(args[2].label)
        if len(calls) == 3:
            raise RuntimeError('a bug half-way through activate')
        return real(*args, **kwargs)

    monkeypatch.setattr(alpha5_component, 'confirm_setting', half_way)
    bridge = rig.start_bridge(autostart=False)
    assert bridge.trigger_configure() == SUCCESS
    started_s = time.monotonic()
    bridge.trigger_activate()
    assert 'a bug half-way' in bridge.refusal
    assert modes(rig) == RESTORED
    assert all(velocity_zero_since(rig, d, started_s) for d in DEVICES)
    assert state_label(bridge) == 'unconfigured'
    assert not bridge.device_changed and bridge.link is None


def stamp_s(msg: Any) -> float:
    """A message's header stamp (s)."""
    return msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9


def error_naming(rig: Rig, joint: str) -> bool:
    """Whether the bridge's /diagnostics said ERROR naming ``joint``."""
    return any(s.name == 'alpha5_bridge: alpha5' and s.level == DiagnosticStatus.ERROR
               and joint in s.message for a in rig.diagnostics for s in a.status)


def test_a_silenced_joint_stops_joint_states_and_diagnostics_name_it(rig: Rig) -> None:
    """The elbow stops answering while the arm moves: no joint_states holds its old position.

    joint_1 moves from 0.5 to 0.6 rad after the elbow (joint_3, device 0x03) went silent:
    a joint state with joint_1 at 0.6 could only carry the elbow's stale 1.5 rad, so none
    may come; /diagnostics turns ERROR naming joint_3; when it answers again they resume.
    """
    rig.twin.set_joint_state([0.5, 1.0, 1.5, 2.0], [0.0] * 4)
    rig.start_bridge(silent_timeout_s=0.2)
    rig.spin_until(lambda: len(rig.states) >= 5)
    rig.twin.set_silent(0x03)
    rig.twin.set_joint_state([0.6, 1.1, 1.6, 2.1], [0.0] * 4)
    silenced = len(rig.states)
    rig.spin_for(0.5)
    after = rig.states[silenced:]
    assert not [s for s in after if s.position[0] == pytest.approx(0.6)]
    assert after == []
    rig.spin_until(lambda: error_naming(rig, 'joint_3'), timeout_s=5.0)
    rig.twin.set_silent(0x03, False)
    rig.spin_until(lambda: rig.states[-1].position[2] == pytest.approx(1.6))
    stamps = [stamp_s(s) for s in rig.states]
    assert all(b > a for a, b in itertools.pairwise(stamps))


def test_activation_is_confirmed_through_lost_datagrams(rig: Rig) -> None:
    """The first two datagrams of activate are lost: Standby is sent again until read back.

    The arm rested in Disable: one unconfirmed MODE Standby datagram (the old activate) would
    have left it there while the bridge drove it.
    """
    set_modes(rig, dict.fromkeys(DEVICES, Mode.DISABLE))
    bridge = rig.start_bridge(autostart=False)
    assert bridge.trigger_configure() == SUCCESS
    rig.twin.drop_datagrams(2)
    assert bridge.trigger_activate() == SUCCESS
    assert rig.twin.dropped == 2
    assert modes(rig) == dict.fromkeys(DEVICES, Mode.STANDBY)


def test_stop_is_confirmed_through_lost_datagrams(rig: Rig) -> None:
    """Driven in Current mode, deactivate loses its first three datagrams: the arm still stops.

    The old put-back was one datagram: lost, it left every joint driven at its last current.
    """
    bridge = rig.start_bridge()
    rig.spin_for(0.2, command=[0.5, 0.5, 0.5, 0.5])
    assert modes(rig) == dict.fromkeys(DEVICES, Mode.CURRENT)
    rig.twin.drop_datagrams(3)
    started_s = time.monotonic()
    assert bridge.trigger_deactivate() == SUCCESS
    assert rig.twin.dropped == 3
    assert modes(rig) == dict.fromkeys(DEVICES, Mode.STANDBY)
    assert all(velocity_zero_since(rig, d, started_s) for d in DEVICES)


def test_activation_a_device_does_not_confirm_is_refused_naming_it(rig: Rig) -> None:
    """The elbow goes silent after configure: activate fails naming joint_3; the rest put back.

    The other devices had taken Standby; they are back in Disable, as found.
    """
    set_modes(rig, dict.fromkeys(DEVICES, Mode.DISABLE))
    bridge = rig.start_bridge(autostart=False)
    assert bridge.trigger_configure() == SUCCESS
    rig.twin.set_silent(0x03)
    started_s = time.monotonic()
    assert bridge.trigger_activate() == FAILURE
    took_s = time.monotonic() - started_s
    assert bridge.refusal.startswith('joint_3 (device 0x03, C): MODE Standby not confirmed')
    assert 'joint_1' not in bridge.refusal
    assert modes(rig) == dict.fromkeys(DEVICES, Mode.DISABLE)
    assert state_label(bridge) == 'inactive' and not bridge.device_changed
    assert took_s < 1.5, took_s  # Standby and the put-back, the elbow never answering


def test_put_back_of_a_silent_arm_ends_within_its_bound(rig: Rig) -> None:
    """Every device silent while driven: deactivate still ends, within 4 x 2 x 3 x 30 ms."""
    bridge = rig.start_bridge()
    rig.spin_for(0.2, command=[0.5, 0.5, 0.5, 0.5])
    for device_id in DEVICES:
        rig.twin.set_silent(device_id)
    started_s = time.monotonic()
    assert bridge.trigger_deactivate() == SUCCESS
    took_s = time.monotonic() - started_s
    assert put_back_bound_s(4, CONFIRM_TRIES, DEFAULT_CONFIRM_TIMEOUT_S) == pytest.approx(0.72)
    assert 0.72 <= took_s < 1.0, took_s
