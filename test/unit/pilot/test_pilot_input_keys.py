"""Keys to pilot commands: the layout, the held-key windows, the stop key, gears and limits."""

from __future__ import annotations

import math

import pytest
from uvms_pilot.command import (
    GEARS,
    Demand,
    PilotLimits,
    PublishGate,
    command,
    gear_after,
)
from uvms_pilot.keys import KEY_ACTIONS, KEY_AXES, KeyboardDemand

LIMITS = PilotLimits(vehicle_m_s=(0.4, 0.3, 0.2), yaw_rad_s=0.5, ee_m_s=(0.05, 0.05, 0.02),
                     jaw_m_s=0.01)


@pytest.mark.parametrize(('key', 'axis', 'sign'), [
    ('w', 'surge', 1.0), ('s', 'surge', -1.0), ('d', 'sway', 1.0), ('a', 'sway', -1.0),
    ('f', 'heave', 1.0), ('r', 'heave', -1.0), ('e', 'yaw', 1.0), ('q', 'yaw', -1.0),
    ('i', 'arm_x', 1.0), ('k', 'arm_x', -1.0), ('l', 'arm_y', 1.0), ('j', 'arm_y', -1.0),
    ('o', 'arm_z', 1.0), ('u', 'arm_z', -1.0), ('m', 'jaw', 1.0), ('n', 'jaw', -1.0),
])
def test_each_motion_key_drives_its_axis_alone(key: str, axis: str, sign: float) -> None:
    """A motion key asks for the full demand on its axis, in its direction, and nothing else."""
    keys = KeyboardDemand()
    assert keys.press(key, 10.0) is None
    demand = keys.demand(10.05)
    assert getattr(demand, axis) == sign
    assert sum(abs(v) for v in demand.as_tuple()) == 1.0


def test_keys_of_every_axis_and_action_are_distinct() -> None:
    """No key does two things; the issue's actions all have a key."""
    assert not set(KEY_AXES) & set(KEY_ACTIONS)
    assert {'stop', 'hold', 'start_task', 'cancel_task'} <= set(KEY_ACTIONS.values())
    assert KEY_ACTIONS[' '] == 'stop'


def test_single_tap_moves_for_the_first_hold_then_zero() -> None:
    """A tap counts as held over the auto-repeat delay, then the demand is zero."""
    keys = KeyboardDemand(first_hold_s=0.45, repeat_hold_s=0.15)
    keys.press('w', 0.0)
    assert keys.demand(0.44).surge == 1.0
    assert keys.demand(0.46).surge == 0.0


def test_released_key_is_zero_within_the_repeat_window() -> None:
    """Once repeats arrive, the demand falls to zero repeat_hold_s after the last one."""
    keys = KeyboardDemand(first_hold_s=0.45, repeat_hold_s=0.15)
    t = 0.0
    keys.press('e', t)
    for _ in range(20):  # auto-repeat at 30 ms after a 0.4 s delay
        t += 0.4 if t == 0.0 else 0.03
        keys.press('e', t)
        assert keys.demand(t + 0.01).yaw == 1.0
    assert keys.demand(t + 0.14).yaw == 1.0
    assert keys.demand(t + 0.16) == Demand()


def test_opposite_key_takes_over_at_once() -> None:
    """Key s right after w reverses surge; other axes keep their keys."""
    keys = KeyboardDemand()
    keys.press('w', 0.0)
    keys.press('e', 0.01)
    keys.press('s', 0.02)
    demand = keys.demand(0.03)
    assert (demand.surge, demand.yaw) == (-1.0, 1.0)


def test_stop_key_drops_every_held_key() -> None:
    """Space is 'stop' and zeroes the demand at once, not after the hold window."""
    keys = KeyboardDemand()
    keys.press('w', 0.0)
    keys.press('i', 0.0)
    assert keys.press(' ', 0.05) == 'stop'
    assert keys.demand(0.06) == Demand()


def test_unknown_key_changes_nothing() -> None:
    """A key of no use neither moves nor acts."""
    keys = KeyboardDemand()
    keys.press('w', 0.0)
    assert keys.press('z', 0.01) is None
    assert keys.demand(0.02).surge == 1.0


@pytest.mark.parametrize('gear', GEARS)
def test_command_is_demand_times_gear_times_limit(gear: float) -> None:
    """Full demand on every axis gives the gear's fraction of each pilot limit."""
    cmd = command(Demand(1.0, -1.0, 1.0, -1.0, 1.0, -1.0, 1.0, -1.0), LIMITS, gear)
    expected = (0.4 * gear, -0.3 * gear, 0.2 * gear, 0.0, 0.0, -0.5 * gear)
    assert cmd.vehicle_twist == pytest.approx(expected)
    assert cmd.ee_velocity_m_s == pytest.approx((0.05 * gear, -0.05 * gear, 0.02 * gear))
    assert cmd.jaw_m_s == pytest.approx(-0.01 * gear)


@pytest.mark.parametrize('value', [math.nan, math.inf, -math.inf, 1e9, -7.0])
def test_command_never_exceeds_the_limits(value: float) -> None:
    """NaN reads as zero, anything beyond full scale is clipped to the limit."""
    cmd = command(Demand(surge=value, yaw=value), LIMITS, 1.0)
    assert abs(cmd.vehicle_twist[0]) <= 0.4
    assert abs(cmd.vehicle_twist[5]) <= 0.5
    assert all(math.isfinite(v) for v in cmd.vehicle_twist)


def test_bad_gear_and_limits_are_refused_by_name() -> None:
    """A gear outside (0, 1] and a negative or infinite limit name themselves."""
    with pytest.raises(ValueError, match='speed gear'):
        command(Demand(), LIMITS, 1.5)
    with pytest.raises(ValueError, match='yaw_rad_s'):
        PilotLimits(vehicle_m_s=(0.4, 0.3, 0.2), yaw_rad_s=-0.1, ee_m_s=(0.05,) * 3,
                    jaw_m_s=0.01)
    with pytest.raises(ValueError, match='ee_m_s'):
        PilotLimits(vehicle_m_s=(0.4, 0.3, 0.2), yaw_rad_s=0.1, ee_m_s=(0.05, math.inf, 0.0),
                    jaw_m_s=0.01)


def test_limits_are_the_robot_folders_pilot_limits() -> None:
    """The tools scale by the controller's own pilot.* values of the robot folder."""
    from uvms_pilot.limits import pilot_limits

    limits = pilot_limits('bluerov2_alpha5')
    assert limits.vehicle_m_s == (0.5, 0.5, 0.3)
    assert limits.yaw_rad_s == 0.5
    assert limits.ee_m_s == (0.1, 0.1, 0.1)
    full = command(Demand(surge=1.0), limits, 1.0)
    assert full.vehicle_twist[0] == 0.5


def test_gear_actions_select_and_step_within_the_gears() -> None:
    """1, 2, 3 select; up and down step and stop at the ends; others leave the gear."""
    assert gear_after(0, 'gear_3') == 2
    assert gear_after(2, 'gear_up') == 2
    assert gear_after(0, 'gear_down') == 0
    assert gear_after(1, 'gear_down') == 0
    assert gear_after(1, 'hold') == 1


def test_gate_publishes_while_moving_then_one_zero_then_nothing() -> None:
    """A moving part every tick, one zero the tick it stops, then silence for the deadman."""
    gate = PublishGate()
    assert gate.parts_to_publish(Demand()) == ()
    assert gate.parts_to_publish(Demand(surge=1.0)) == ('vehicle',)
    assert gate.parts_to_publish(Demand(surge=1.0, jaw=1.0)) == ('vehicle', 'jaw')
    assert gate.parts_to_publish(Demand()) == ('vehicle', 'jaw')
    assert gate.parts_to_publish(Demand()) == ()


def test_stop_publishes_a_zero_on_every_part() -> None:
    """The stop key zeroes vehicle, arm and jaw now, moving or not."""
    gate = PublishGate()
    gate.parts_to_publish(Demand(arm_x=1.0))
    assert gate.stop_all() == ('vehicle', 'arm', 'jaw')
    assert gate.parts_to_publish(Demand()) == ()
