"""Tests of thruster fault injection (plant side) and detection from ESC feedback."""

from __future__ import annotations

import numpy as np
import pytest
from uvms_model.thrusters import ThrusterLayout
from uvms_thrusters.allocation import AllocatorParameters, ThrusterAllocator
from uvms_thrusters.errors import ThrusterParameterError
from uvms_thrusters.fault_detection import (
    STATUS_DEGRADED,
    STATUS_FAILED,
    STATUS_OK,
    DetectionParameters,
    ThrusterFaultDetector,
)
from uvms_thrusters.fault_parameters import (
    FAULT_PARAMETER_SPECS,
    equip,
    fault_settings,
    set_accommodation,
)
from uvms_thrusters.thruster_faults import (
    EscSensor,
    ThrusterFault,
    ThrusterFaultInjector,
    format_faults,
    parse_faults,
)

LAYOUT = ThrusterLayout.from_parameters()
DT = 0.002


def make_allocator(faults: str = '', accommodate: bool = True,
                   speed_noise: float = 1.0) -> ThrusterAllocator:
    """Allocator of the paper robot with ESC telemetry, detection and injected faults."""
    allocator = ThrusterAllocator(AllocatorParameters(
        LAYOUT.thrust_matrix(), LAYOUT.max_thrust_n, np.full(3, 100.0)))
    allocator.injector = ThrusterFaultInjector(parse_faults(faults, LAYOUT.count), LAYOUT.count)
    allocator.esc = EscSensor(LAYOUT.count, speed_noise, 0.05, seed=3)
    allocator.detector = ThrusterFaultDetector(DetectionParameters(),
                                               allocator.params.thruster, LAYOUT.count)
    allocator.accommodate = accommodate
    return allocator


def run(allocator: ThrusterAllocator, tau: np.ndarray, seconds: float,
        start_s: float = 0.0) -> list:
    """Step the allocator on a constant tau; the outputs' desired and actual thrusts."""
    rows = []
    for k in range(round(seconds / DT)):
        out = allocator.step(tau, DT, start_s + k * DT)
        rows.append((start_s + k * DT, out.allocation.thrust.copy(), out.thrust.copy()))
    return rows


PRESS = np.array([60.0, 10.0, 20.0, 2.0, -3.0, 4.0, 0.0, 0.0, 0.0])


def test_fault_text_round_trips() -> None:
    """format_faults writes what parse_faults reads, sorted by onset."""
    text = 'index=5 kind=efficiency value=0.3 at_s=8.0; index=2 kind=off at_s=3'
    faults = parse_faults(text, 8)
    assert faults == (ThrusterFault(2, 'off', 0.0, 3.0),
                      ThrusterFault(5, 'efficiency', 0.3, 8.0))
    assert parse_faults(format_faults(faults), 8) == faults


@pytest.mark.parametrize(('text', 'match'), [
    ('index=9 kind=off at_s=1', r'index in \[0, 7\]'),
    ('index=1 kind=melted at_s=1', 'kind'),
    ('index=1 kind=efficiency value=1.5 at_s=1', r'\[0, 1\]'),
    ('index=1 kind=stuck at_s=1', 'needs a value'),
    ('index=1 kind=saturation value=0 at_s=1', '> 0'),
    ('index=1 kind=off at_s=-1', 'at_s'),
    ('index=1 kind=off when=2', 'entries'),
])
def test_bad_fault_is_refused_naming_the_parameter(text: str, match: str) -> None:
    """A malformed fault names fault_injection.thrusters and what is valid."""
    with pytest.raises(ThrusterParameterError, match=r'fault_injection\.thrusters') as info:
        parse_faults(text, 8)
    assert info.match(match)


@pytest.mark.parametrize(('fault', 'expected'), [
    ('kind=off', 0.0), ('kind=efficiency value=0.3', 30.0), ('kind=stuck value=-7',
                                                             -7.0),
    ('kind=saturation value=40', 40.0)])
def test_injected_fault_sets_what_the_motor_follows(fault: str, expected: float) -> None:
    """From at_s on, the faulty thruster follows its faulted demand; the others are untouched."""
    injector = ThrusterFaultInjector(parse_faults(f'index=1 {fault} at_s=1.0'), 3)
    f_td = np.array([100.0, 100.0, 100.0])
    assert injector.motor_demand(f_td, 0.999).tolist() == [100.0, 100.0, 100.0]
    assert injector.motor_demand(f_td, 1.0).tolist() == [100.0, expected, 100.0]


def test_efficiency_fault_gives_eta_of_the_thrust_at_steady_state() -> None:
    """η = 0.3 on thruster 2: its actual thrust settles at 0.3 of its desired thrust."""
    allocator = make_allocator('index=2 kind=efficiency value=0.3 at_s=0', accommodate=False)
    _, desired, actual = run(allocator, PRESS, 1.0)[-1]
    assert actual[2] == pytest.approx(0.3 * desired[2], rel=1e-3)


def test_off_thruster_is_detected_and_dropped_within_a_second() -> None:
    """Off at 1 s: declared failed with η̂ = 0, its desired thrust zero within 1 s."""
    allocator = make_allocator('index=0 kind=off at_s=1.0')
    rows = run(allocator, PRESS, 2.5)
    detector = allocator.detector
    assert detector is not None
    assert detector.status[0] == STATUS_FAILED
    assert detector.effectiveness[0] == 0.0
    latency = detector.detected_at_s[0] - 1.0
    assert 0.1 <= latency < 0.3  # the persistence time and the spin-down
    zero_from = next(t for t, desired, _ in rows if t > 1.0 and desired[0] == 0.0)
    assert zero_from - 1.0 < 1.0
    assert all(desired[0] == 0.0 for t, desired, _ in rows if t >= zero_from)
    assert np.all(detector.status[1:] == STATUS_OK)
    assert allocator.fully_actuated


def test_efficiency_estimate_converges_to_the_injected_eta() -> None:
    """η = 0.3 on thruster 1: declared degraded, η̂ within 0.05 of 0.3."""
    allocator = make_allocator('index=1 kind=efficiency value=0.3 at_s=0.5')
    run(allocator, PRESS, 3.0)
    detector = allocator.detector
    assert detector is not None
    assert detector.status[1] == STATUS_DEGRADED
    assert detector.effectiveness[1] == pytest.approx(0.3, abs=0.05)
    np.testing.assert_allclose(allocator.effectiveness, detector.effectiveness)


def test_accommodation_restores_the_wrench_the_faulty_thruster_lost() -> None:
    """With η̂ in the allocation, the actual vehicle wrench is the commanded one again."""
    t = LAYOUT.thrust_matrix()
    errors = {}
    for accommodate in (True, False):
        allocator = make_allocator('index=1 kind=efficiency value=0.3 at_s=0.5', accommodate)
        _, _, actual = run(allocator, PRESS, 3.0)[-1]
        errors[accommodate] = np.linalg.norm(t @ actual - PRESS[:6])
    assert errors[False] > 5.0
    assert errors[True] < 0.1 * errors[False]


def test_stuck_thruster_is_taken_out() -> None:
    """Stuck at -20 N while commanded forward: declared failed, η̂ = 0."""
    allocator = make_allocator('index=3 kind=stuck value=-20 at_s=0.5')
    run(allocator, PRESS, 2.0)
    assert allocator.detector is not None
    assert allocator.detector.status[3] == STATUS_FAILED


@pytest.mark.parametrize('seed', range(3))
def test_no_false_alarm_under_sensor_noise_and_changing_commands(seed: int) -> None:
    """20 s of random steps in the command with 1 rad/s of speed noise: nothing declared."""
    allocator = make_allocator(speed_noise=1.0)
    rng = np.random.default_rng(seed)
    for k in range(20):
        tau = rng.normal(0.0, 80.0, 9)
        run(allocator, tau, 1.0, start_s=k)
    assert allocator.detector is not None
    assert np.all(allocator.detector.status == STATUS_OK)
    assert np.all(allocator.effectiveness == 1.0)


def defaults() -> dict[str, object]:
    """The fault parameters at their spec defaults."""
    return {spec.name: spec.default for spec in FAULT_PARAMETER_SPECS}


def test_detection_disabled_leaves_the_allocation_on_t() -> None:
    """fault_detection.enabled false: no detector, η̂ stays 1 even with a thruster off."""
    allocator = ThrusterAllocator(AllocatorParameters(
        LAYOUT.thrust_matrix(), LAYOUT.max_thrust_n, np.full(3, 100.0)))
    values = {**defaults(), 'fault_detection.enabled': False,
              'fault_injection.thrusters': 'index=0 kind=off at_s=0'}
    equip(allocator, fault_settings(values, LAYOUT.count))
    assert allocator.detector is None
    _, desired, actual = run(allocator, PRESS, 0.5)[-1]
    assert actual[0] == pytest.approx(0.0, abs=1e-6) and abs(desired[0]) > 1.0
    assert np.all(allocator.effectiveness == 1.0)


def test_accommodation_switched_at_run_time_moves_the_allocation() -> None:
    """Off: the allocation goes back to T; on again: to T diag(η̂)."""
    allocator = make_allocator('index=0 kind=off at_s=0.2')
    run(allocator, PRESS, 1.0)
    set_accommodation(allocator, False)
    assert np.all(allocator.effectiveness == 1.0)
    set_accommodation(allocator, True)
    assert allocator.effectiveness[0] == 0.0


def test_out_of_range_detection_parameter_is_refused_by_name() -> None:
    """A negative persistence names fault_detection.persistence_s and its range."""
    with pytest.raises(ThrusterParameterError, match=r'fault_detection\.persistence_s'):
        fault_settings({**defaults(), 'fault_detection.persistence_s': -1.0}, LAYOUT.count)
