"""Pilot messages: NaN, unknown frames, stale stamps refused and named once; huge values scaled."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
import yaml
from uvms_control.core.pilot.inputs import (
    PilotInputError,
    Refusal,
    RefusalLog,
    check_stamp,
    ee_twist,
    jaw_speed,
    scaled_within,
    vehicle_twist,
)
from uvms_control.core.pilot.limits import PilotLimits, load_pilot_limits

from uvms_description import robots_directory

SPEED = (0.5, 0.5, 0.3)
RATE = (0.0, 0.0, 0.5)


@pytest.mark.parametrize('bad', [math.nan, math.inf, -math.inf])
def test_a_non_finite_twist_is_refused(bad: float) -> None:
    """NaN or inf anywhere refuses the whole message (NOT_FINITE), never reaches the reference."""
    with pytest.raises(PilotInputError) as caught:
        vehicle_twist('pilot/vehicle_twist', (0.1, bad, 0.0), (0.0, 0.0, 0.0), '', SPEED, RATE)
    assert caught.value.kind == Refusal.NOT_FINITE


@pytest.mark.parametrize('frame', ['map_ned', 'base_link', 'world'])
def test_a_vehicle_twist_in_another_frame_is_refused(frame: str) -> None:
    """Only the body frame (or an empty frame_id) carries a vehicle twist."""
    with pytest.raises(PilotInputError) as caught:
        vehicle_twist('pilot/vehicle_twist', (0.1, 0.0, 0.0), (0.0, 0.0, 0.0), frame, SPEED, RATE)
    assert caught.value.kind == Refusal.UNKNOWN_FRAME
    assert repr(frame) in str(caught.value)


def test_an_end_effector_twist_takes_the_body_or_the_map_frame() -> None:
    """base_link_frd and map_ned are known; anything else is refused by name."""
    assert ee_twist('t', (0.01, 0, 0), (0, 0, 0), 'base_link_frd', (0.1,) * 3).in_body
    assert not ee_twist('t', (0.01, 0, 0), (0, 0, 0), 'map_ned', (0.1,) * 3).in_body
    with pytest.raises(PilotInputError, match="'odom'"):
        ee_twist('t', (0.01, 0, 0), (0, 0, 0), 'odom', (0.1,) * 3)


def test_huge_values_are_scaled_down_whole_keeping_the_direction() -> None:
    """1e9 m/s forward and half that sideways: full speed the way it points, not a jump."""
    twist = vehicle_twist('t', (1e9, 5e8, 0.0), (3.0, -2.0, 1e6), '', SPEED, RATE)
    assert twist.linear == pytest.approx((0.5, 0.25, 0.0))
    assert twist.angular == pytest.approx((0.0, 0.0, 0.5))  # roll, pitch limits are 0
    assert twist.clipped


def test_a_twist_within_the_limits_passes_unchanged() -> None:
    """No scaling, not flagged."""
    assert scaled_within((0.1, -0.2, 0.3), SPEED) == ((0.1, -0.2, 0.3), False)


def test_the_jaw_speed_is_clipped_and_nan_refused() -> None:
    """The jaw's limit bounds both ways; NaN is refused."""
    assert jaw_speed('t', -5.0, 0.02) == (-0.02, True)
    with pytest.raises(PilotInputError):
        jaw_speed('t', math.nan, 0.02)


@pytest.mark.parametrize(('stamp', 'kind'), [(9.0, Refusal.STALE), (0.0, Refusal.STALE),
                                             (1.8e9, Refusal.FUTURE)])
def test_stale_and_future_stamps_are_refused(stamp: float, kind: Refusal) -> None:
    """Older than the deadman, unset, or on another clock (wall time against sim time)."""
    with pytest.raises(PilotInputError) as caught:
        check_stamp('t', stamp, 10.0, 0.3)
    assert caught.value.kind == kind


def test_a_fresh_stamp_passes() -> None:
    """Within the deadman either side of the controller's clock."""
    check_stamp('t', 9.8, 10.0, 0.3)
    check_stamp('t', 10.1, 10.0, 0.3)


def test_each_refusal_is_named_once_per_topic_and_counted_always() -> None:
    """The console says it once; /diagnostics counts every one."""
    log = RefusalLog()
    firsts = [log.first('a', Refusal.NOT_FINITE) for _ in range(3)]
    assert firsts == [True, False, False]
    assert log.first('b', Refusal.NOT_FINITE)
    assert log.first('a', Refusal.STALE)
    assert log.counts[Refusal.NOT_FINITE] == 4
    assert 'not finite: 4' in log.summary()


@pytest.mark.parametrize('robot', ['paper_uvms', 'bluerov2_alpha5'])
def test_every_robot_folder_gives_its_pilot_limits(robot: str) -> None:
    """The limits the input tools read are the controller's, from controller.yaml."""
    limits = load_pilot_limits(robot)
    folder = Path(robots_directory()) / robot / 'controller.yaml'
    pilot = yaml.safe_load(folder.read_text())['/**/controller']['ros__parameters']['pilot']
    assert limits.vehicle_speed_m_s == tuple(pilot['max_vehicle_speed_m_s'])
    assert limits.vehicle_acceleration_m_s2 == pilot['max_vehicle_acceleration_m_s2']
    assert limits.deadman_s == pytest.approx(0.3)
    assert limits.vehicle_rate_rad_s[2] > 0.0
    assert PilotLimits.from_parameters({}) == PilotLimits()
