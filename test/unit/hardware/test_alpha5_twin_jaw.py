"""The Alpha 5 twin's jaws as the stand has them: served from the hardware file, moved by the twin.

The simulator has no jaw joint, so the twin of ``load_alpha5(robot)`` (the plant's four
joints) serves device 0x01 and moves it itself on its clock (here a fake one).
"""

from __future__ import annotations

import pytest
from uvms_hardware.hardware_config import load_alpha5
from uvms_hardware.reach_protocol import Mode, PacketId
from uvms_twins.alpha5_twin import Alpha5Twin

from uvms_hardware import reach_protocol as rp

JAW = 0x01


class FakeClock:
    """A clock the test moves (s)."""

    def __init__(self) -> None:
        self.t_s = 100.0

    def __call__(self) -> float:
        """Now (s)."""
        return self.t_s


def apply(twin: Alpha5Twin, frames: bytes) -> bytes:
    """Every packet of ``frames`` through the twin; the answers."""
    return b''.join(twin.handle(p) for p in rp.FrameSplitter().feed(frames))


@pytest.fixture
def stand() -> tuple[Alpha5Twin, FakeClock]:
    """The twin as the twin stand builds it, on a fake clock."""
    clock = FakeClock()
    return Alpha5Twin(load_alpha5('bluerov2_alpha5'), port=0, clock=clock), clock


def test_the_stand_twin_serves_the_jaws_beside_the_plants_joints(
        stand: tuple[Alpha5Twin, FakeClock]) -> None:
    """Device 0x01 answers MODEL; the plant's joint commands stay the four joints."""
    twin, _ = stand
    answer = list(rp.FrameSplitter().feed(apply(twin, rp.encode_request(JAW,
                                                                        (PacketId.MODEL,)))))
    assert [p.packet_id for p in answer] == [PacketId.MODEL]
    assert sorted(twin.joint_commands()) == ['joint_1', 'joint_2', 'joint_3', 'joint_4']
    assert twin.jaw_command() == (Mode.STANDBY, 0.0)


def test_velocity_mode_opens_the_jaws_and_they_stop_at_the_limit(
        stand: tuple[Alpha5Twin, FakeClock]) -> None:
    """5 mm/s: 5 mm after 1 s (answered as 5 mm on the wire), stopped at 15 mm."""
    twin, clock = stand
    apply(twin, rp.encode_velocity(JAW, 0.005))
    clock.t_s += 1.0
    assert twin.jaw_state() == pytest.approx((0.005, 0.005))
    answer = list(rp.FrameSplitter().feed(apply(twin, rp.encode_request(
        JAW, (PacketId.POSITION,)))))
    assert answer[0].floats()[0] == pytest.approx(5.0, rel=1e-5)  # mm
    clock.t_s += 10.0
    assert twin.jaw_state() == pytest.approx((0.015, 0.0))


def test_velocity_0_and_standby_hold_the_jaws(stand: tuple[Alpha5Twin, FakeClock]) -> None:
    """Opened 2 mm, then VELOCITY 0: they stay; MODE Standby: they stay."""
    twin, clock = stand
    apply(twin, rp.encode_velocity(JAW, 0.002))
    clock.t_s += 1.0
    apply(twin, rp.encode_velocity(JAW, 0.0))
    clock.t_s += 1.0
    assert twin.jaw_state() == pytest.approx((0.002, 0.0))
    apply(twin, rp.encode_mode(JAW, Mode.STANDBY))
    clock.t_s += 1.0
    assert twin.jaw_state() == pytest.approx((0.002, 0.0))


def test_position_mode_moves_the_jaws_at_their_speed_limit(
        stand: tuple[Alpha5Twin, FakeClock]) -> None:
    """POSITION 10 mm: there after the step, at most the 0.5 m/s limit on the way."""
    twin, clock = stand
    twin.jaw_state()  # starts the twin's clock
    apply(twin, rp.encode_position(JAW, 0.010))
    clock.t_s += 0.01
    assert twin.jaw_state() == pytest.approx((0.005, 0.5))
    clock.t_s += 0.1
    assert twin.jaw_state() == pytest.approx((0.010, 0.0))
