"""A thruster fault declared, failed, settled or recovered, a rank loss: one console line each.

Issues 42 and 52 (each line at the time of its own change; the injection said once).
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np
from uvms_common.diagnostics import ERROR, WARN
from uvms_thrusters.health_conversions import health_change


def allocator(status: list[int], rank: int = 6, accommodate: bool = True) -> Any:
    """The allocator fields health_change reads, thruster 0 detected at 11.1 s."""
    detector = SimpleNamespace(detected_at_s=np.array([11.1] + [np.nan] * 7),
                               changed_at_s=np.array([11.1] + [np.nan] * 7),
                               effectiveness=np.array([0.0 if status[0] == 2 else 1.0] * 8),
                               status=np.array(status, np.uint8))
    return SimpleNamespace(detector=detector, rank=rank, fully_actuated=rank == 6,
                           accommodate=accommodate)


def key(alloc: Any) -> tuple[Any, ...]:
    """The allocator node's health key."""
    return (alloc.rank, alloc.accommodate, alloc.detector.status.tobytes())


HEALTHY = allocator([0] * 8)
FAILED = allocator([2] + [0] * 7)


def test_a_thruster_declared_failed_is_one_warn_line() -> None:
    """Thruster 0 failed: WARN naming it, when and that the allocation goes around it."""
    assert health_change(key(HEALTHY), key(FAILED), FAILED) == (
        WARN, 'thruster 0 (T1) fault declared at 11.100 s: failed (eta_hat 0.000) '
        '(allocating around it)')


def test_a_recovered_thruster_is_one_warn_line() -> None:
    """Back to OK: WARN 'recovered'."""
    assert health_change(key(FAILED), key(HEALTHY), HEALTHY) == (
        WARN, 'thruster 0 (T1) recovered at 11.100 s (allocating around it)')


def test_a_rank_loss_is_one_error_line() -> None:
    """Rank 5: ERROR saying the vehicle cannot produce every wrench."""
    lost = allocator([2, 2] + [0] * 6, rank=5)
    level, text = health_change(key(FAILED), key(lost), lost) or ('', '')
    assert level == ERROR
    assert text.startswith('thruster 1 (T2) fault declared')
    assert 'rank 5 < 6: the vehicle cannot produce every wrench' in text


def test_no_change_and_the_first_report_say_nothing() -> None:
    """The same key again, or the first key after configure: no line."""
    assert health_change(key(FAILED), key(FAILED), FAILED) is None
    assert health_change(None, key(FAILED), FAILED) is None


def _console_lines(fault: str, command_n: float = 30.0, seconds: float = 2.5) -> list[str]:
    """The allocator's health lines over a run of a real detector and thruster bank.

    Two thrusters at a constant command; ``fault`` (``fault_injection.thrusters`` text) acts
    on the plant from 1 s; each step's health key goes through ``health_change`` as the
    allocator node does.
    """
    from uvms_thrusters.fault_detection import DetectionParameters, ThrusterFaultDetector
    from uvms_thrusters.thruster_dynamics import ThrusterBank, ThrusterModelParameters
    from uvms_thrusters.thruster_faults import ThrusterFaultInjector, parse_faults

    model = ThrusterModelParameters()
    detector = ThrusterFaultDetector(DetectionParameters(), model, 2)
    plant = ThrusterBank(model, 2)
    injector = ThrusterFaultInjector(parse_faults(fault, 2), 2)
    alloc = SimpleNamespace(detector=detector, rank=6, fully_actuated=True, accommodate=True)
    command = np.full(2, command_n)
    lines, before, dt = [], None, 0.002
    for k in range(round(seconds / dt)):
        t_s = k * dt
        plant.step(injector.motor_demand(command, t_s), dt)
        detector.update(command, plant.omega.copy(), plant.motor_current.copy(), dt, t_s)
        after = (6, True, detector.status.tobytes(), detector.settled.tobytes())
        change = health_change(before, after, alloc)  # type: ignore[arg-type]
        if change is not None:
            lines.append(change[1])
        before = after
    return lines


def test_a_thruster_switched_off_is_declared_then_failed_each_at_its_own_time() -> None:
    """Measured: declared at 1.106 s with eta_hat 0.980 (one filter step), failed 0.19 s later.

    The old lines read 'declared degraded at 1.106 s (eta_hat 0.980)' then 'declared failed
    at 1.106 s': degraded at 0.98, and both at the declaration's time.
    """
    declared, failed = _console_lines('index=0 kind=off at_s=1.0')
    assert declared == ("thruster 0 (T1) fault declared at 1.106 s: its ESC speed left the "
                        "model's; eta_hat being estimated (allocating around it)")
    assert failed.startswith('thruster 0 (T1) failed at 1.2')
    assert failed.endswith('(eta_hat 0.000) (allocating around it)')


def test_a_degraded_thruster_says_its_settled_estimate() -> None:
    """Efficiency 0.3: the declaration, then one line with eta_hat once it has settled."""
    declared, settled = _console_lines('index=0 kind=efficiency value=0.3 at_s=1.0')
    assert 'fault declared at 1.1' in declared and 'degraded' not in declared
    assert settled.startswith('thruster 0 (T1) degraded: eta_hat settled at 0.3')


def test_an_injected_fault_is_reported_once_when_it_starts() -> None:
    """The injector names each fault once, at the first step at or after its at_s."""
    from uvms_thrusters.thruster_faults import ThrusterFaultInjector, parse_faults

    injector = ThrusterFaultInjector(parse_faults(
        'index=0 kind=off at_s=11; index=2 kind=efficiency value=0.3 at_s=12', 8), 8)
    assert injector.newly_started(10.998) == ()
    (off,) = injector.newly_started(11.0)
    assert off.describe() == 'thruster 0 (T1) off'
    assert injector.newly_started(11.5) == ()
    (weak,) = injector.newly_started(13.0)
    assert weak.describe() == 'thruster 2 (T3) at efficiency 0.3'
