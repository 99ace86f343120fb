"""The Alpha 5 bridge drives the jaws from ``command/jaw``, against the twin as the stand runs it.

The twin is built as ``uvms launch --hardware twin`` builds it (``load_alpha5(robot)``: the
plant's four joints; the jaws served and moved by the twin itself, the simulator having no
jaw); the bridge takes its jaw joint from the hardware file (``alpha5.jaw.joint_name``).
"""

from __future__ import annotations

import time
from collections.abc import Iterator

import pytest
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64
from test_alpha5_bridge import JOINTS, ROBOT, SUCCESS, Rig
from uvms_hardware.hardware_config import load_alpha5
from uvms_hardware.reach_protocol import Mode, PacketId
from uvms_twins.alpha5_twin import Alpha5Twin

JAW = 0x01


class JawRig(Rig):
    """The rig with the stand's twin, a ``command/jaw`` publisher and ``jaw_state`` kept."""

    def __init__(self) -> None:
        super().__init__()
        self.twin.stop()
        self.twin = Alpha5Twin(load_alpha5(ROBOT), port=0)
        self.twin.start()
        self.jaw_pub = self.probe.create_publisher(Float64, 'command/jaw', 10)
        self.jaws: list[JointState] = []
        self.probe.create_subscription(JointState, 'jaw_state', self.jaws.append, 1000)

    def open_jaw(self, duration_s: float, speed_m_s: float) -> None:
        """Publish ``speed_m_s`` on command/jaw at 50 Hz for ``duration_s``, spinning."""
        end = time.monotonic() + duration_s
        next_s = 0.0
        while time.monotonic() < end:
            if time.monotonic() >= next_s:
                self.jaw_pub.publish(Float64(data=speed_m_s))
                next_s = time.monotonic() + 0.02
            self.executor.spin_once(timeout_sec=0.005)


@pytest.fixture
def rig() -> Iterator[JawRig]:
    """A fresh stand twin and executor, closed after the test."""
    made = JawRig()
    yield made
    made.close()


def jaw_opening_m(rig: JawRig) -> float:
    """The twin's jaw opening (m)."""
    state = rig.twin.jaw_state()
    assert state is not None
    return state[0]


def test_the_hardware_file_names_the_jaw_and_the_bridge_drives_it(rig: JawRig) -> None:
    """By default (hardware.yaml's joint_name) the bridge drives 'jaw'; joint_states stay 4."""
    bridge = rig.start_bridge()
    rig.spin_until(lambda: len(rig.states) >= 3 and len(rig.jaws) >= 2)
    assert bridge.core is not None and bridge.core.jaw is not None
    assert bridge.core.jaw.joint_name == 'jaw'
    assert list(rig.states[-1].name) == JOINTS
    assert list(rig.jaws[-1].name) == ['jaw']


def test_a_jaw_command_opens_the_twins_jaw(rig: JawRig) -> None:
    """5 mm/s for 1 s: the jaw in Velocity mode at 5 mm/s, 4-6 mm more open, seen on jaw_state."""
    rig.start_bridge()
    rig.spin_until(lambda: len(rig.jaws) >= 1)
    before_m = jaw_opening_m(rig)
    rig.open_jaw(1.0, 0.005)
    mode, setpoint = rig.twin.jaw_command() or (None, None)
    assert mode == Mode.VELOCITY and setpoint == pytest.approx(0.005, rel=1e-5)
    opened_m = jaw_opening_m(rig) - before_m
    assert 0.004 <= opened_m <= 0.006, opened_m
    rig.jaws.clear()
    rig.spin_until(lambda: len(rig.jaws) >= 2)
    assert rig.jaws[-1].position[0] == pytest.approx(jaw_opening_m(rig), abs=0.001)
    assert rig.jaws[-1].position[0] - before_m > 0.004


def test_no_jaw_command_is_velocity_0_within_the_watchdog(rig: JawRig) -> None:
    """Jaw commands stop: VELOCITY 0 reaches device 0x01 within 0.2 s, the jaw stops."""
    bridge = rig.start_bridge()
    rig.open_jaw(0.4, 0.005)
    last_command_s = time.monotonic()
    rig.spin_for(0.5)
    zeros = [t for t, p in rig.twin.received(JAW) if p.packet_id == PacketId.VELOCITY
             and p.floats() == (0.0,) and t > last_command_s - 0.03]
    assert zeros and zeros[0] - last_command_s <= 0.2
    assert rig.twin.jaw_command() == (Mode.VELOCITY, 0.0)
    stopped_m = jaw_opening_m(rig)
    rig.spin_for(0.3)
    assert jaw_opening_m(rig) == pytest.approx(stopped_m, abs=1e-6)
    assert bridge.core is not None and bridge.core.jaw_holding


def test_the_put_back_restores_the_jaws_mode(rig: JawRig) -> None:
    """The jaws rested in Disable: driven in Velocity, then after deactivate Disable again."""
    rig.twin.devices[JAW].mode = Mode.DISABLE
    bridge = rig.start_bridge()
    rig.open_jaw(0.3, 0.005)
    assert (rig.twin.jaw_command() or (None,))[0] == Mode.VELOCITY
    assert bridge.trigger_deactivate() == SUCCESS
    assert (rig.twin.jaw_command() or (None,))[0] == Mode.DISABLE
    velocity_0 = [p for _, p in rig.twin.received(JAW)
                  if p.packet_id == PacketId.VELOCITY and p.floats() == (0.0,)]
    assert velocity_0  # stopped before its mode went back
