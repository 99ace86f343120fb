"""Alpha5Component without ROS, against the Alpha 5 twin on 127.0.0.1: the component's contract."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest
from uvms_hardware.alpha5_component import (
    PARAMETERS,
    Alpha5BridgeError,
    Alpha5Component,
    Alpha5State,
)
from uvms_hardware.component import ERROR, OK
from uvms_hardware.hardware_config import load_alpha5
from uvms_hardware.reach_protocol import Mode
from uvms_twins.alpha5_twin import Alpha5Twin

ROBOT = 'bluerov2_alpha5'
JOINTS = ['joint_1', 'joint_2', 'joint_3', 'joint_4']


def settings(port: int, **changes: object) -> dict[str, object]:
    """The node's defaults on the twin's port, no start-up wait, the jaws driven."""
    values: dict[str, object] = {name: default for name, default, _ in PARAMETERS}
    values.update(connection=f'udp:127.0.0.1:{port}', startup_wait_s=0.0, jaw_joint='jaw')
    values.update(changes)
    return values


def read_until(arm: Alpha5Component, done: Callable[[Alpha5State], bool],
               timeout_s: float = 3.0) -> Alpha5State:
    """Call read() then ask() at the poll period until done(state) (the state that did it)."""
    end = time.monotonic() + timeout_s
    while True:
        arm.read(time.monotonic())
        state = arm.state()
        if done(state):
            return state
        arm.ask(time.monotonic())
        assert time.monotonic() < end, 'timed out reading'
        time.sleep(arm.poll_period_s())


@pytest.fixture
def twin() -> Iterator[Alpha5Twin]:
    """The arm and the jaws of bluerov2_alpha5 on a free port, every device in Standby.

    The twin moves the jaws itself, as on the stand (the plant has no jaw).
    """
    with Alpha5Twin(load_alpha5(ROBOT), port=0) as running:
        yield running


@pytest.fixture
def arm(twin: Alpha5Twin) -> Iterator[Alpha5Component]:
    """A configured and active component on the twin; put back and released after."""
    made = Alpha5Component(settings(twin.port), ROBOT, log=lambda level, text: None)
    made.configure()
    made.activate()
    yield made
    made.put_back()
    made.release()


def test_a_round_of_joint_states_comes_once_every_joint_answered(
        twin: Alpha5Twin, arm: Alpha5Component) -> None:
    """read() polls one device per call; the round has the twin's positions, fresh."""
    twin.set_joint_state([0.1, 0.9, 1.0, 0.2], [0.0] * 4)
    # The first rounds may hold answers asked before the twin moved (activate asks too).
    state = read_until(arm, lambda s: s.joints is not None and s.joints.positions[1] > 0.5)
    assert state.joints is not None
    assert state.joints.names == JOINTS
    assert state.joints.positions == pytest.approx([0.1, 0.9, 1.0, 0.2], abs=1e-5)
    assert arm.report(time.monotonic()).level == OK


def test_torques_become_current_on_the_twin_and_the_watchdog_stops_them(
        twin: Alpha5Twin, arm: Alpha5Component) -> None:
    """write() then ask() drives Current mode; no command for watchdog_timeout_s: VELOCITY 0."""
    arm.write(time.monotonic(), (JOINTS, [0.0, 0.2, -0.1, 0.0]))
    arm.ask(time.monotonic())  # the held command goes at the bus's turn (alpha5_bus)
    deadline = time.monotonic() + 2.0
    while twin.joint_commands()['joint_2'][0] != Mode.CURRENT:
        assert time.monotonic() < deadline, twin.joint_commands()
        time.sleep(0.005)
    read_until(arm, lambda s: all(twin.joint_commands()[j] == (Mode.VELOCITY, 0.0)
                                  for j in JOINTS), timeout_s=2.0)


def test_read_never_waits_on_a_silent_arm_and_reports_it(
        twin: Alpha5Twin, arm: Alpha5Component, no_waiting: Any) -> None:
    """Every device silent: read() returns at once, no round comes, the report is ERROR."""
    read_until(arm, lambda s: s.joints is not None)
    for device_id in twin.devices:
        twin.set_silent(device_id)
    end = time.monotonic() + 0.6
    while time.monotonic() < end:
        with no_waiting.check():  # no sleep, select or blocking receive (conftest.py)
            now_s = time.monotonic()
            arm.read(now_s)
            arm.ask(now_s)
        assert arm.state().joints is None
        time.sleep(0.004)
    assert arm.report(time.monotonic()).level == ERROR


def test_the_jaws_open_from_write_jaw_and_report_in_metres(
        twin: Alpha5Twin, arm: Alpha5Component) -> None:
    """write_jaw(+2 mm/s): the twin's jaws in Velocity mode, their opening read back in m."""
    def opening(state: Alpha5State) -> bool:
        arm.write_jaw(time.monotonic(), 0.002)  # as command/jaw comes, every control step
        command = twin.jaw_command()
        return (command is not None and command[0] == Mode.VELOCITY and state.jaw is not None
                and state.jaw.positions[0] > 0.0)

    state = read_until(arm, opening)
    assert state.jaw is not None and state.jaw.names == ['jaw']
    assert 0.0 < state.jaw.positions[0] < 0.015  # within the jaws' 0-15 mm


def test_put_back_leaves_every_device_in_its_mode_from_before(twin: Alpha5Twin) -> None:
    """Standby before activate, Current while driven: Standby again after the put-back."""
    arm = Alpha5Component(settings(twin.port), ROBOT, log=lambda level, text: None)
    arm.configure()
    arm.activate()
    arm.write(time.monotonic(), (JOINTS, [0.0, 0.2, -0.1, 0.0]))
    assert arm.put_back() == []
    arm.release()
    assert {d.mode for d in twin.devices.values()} == {Mode.STANDBY}
    assert not arm.active and not arm.configured


def test_a_device_whose_limits_differ_is_refused_naming_both_values(twin: Alpha5Twin) -> None:
    """A refused configure (Alpha5BridgeError) names the joint; the link is released."""
    twin.set_position_limits(0x03, -1.0, 1.0)
    arm = Alpha5Component(settings(twin.port), ROBOT, log=lambda level, text: None)
    with pytest.raises(Alpha5BridgeError, match='joint_3'):
        arm.configure()
    assert any('POSITION_LIMITS' in e or 'position' in e.lower() for e in arm.configure_errors)
    arm.release()
    assert arm.link is None
