"""A thruster declared failed, recovered, or a rank loss is one console line (issue 42)."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np
from uvms_common.diagnostics import ERROR, WARN
from uvms_thrusters.health_conversions import health_change


def allocator(status: list[int], rank: int = 6, accommodate: bool = True) -> Any:
    """The allocator fields health_change reads, thruster 0 detected at 11.1 s."""
    detector = SimpleNamespace(detected_at_s=np.array([11.1] + [np.nan] * 7),
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
        WARN, 'thruster 0 (T1) declared failed at 11.100 s (eta_hat 0.000) (allocating around it)')


def test_a_recovered_thruster_is_one_warn_line() -> None:
    """Back to OK: WARN 'recovered'."""
    assert health_change(key(FAILED), key(HEALTHY), HEALTHY) == (
        WARN, 'thruster 0 (T1) recovered (allocating around it)')


def test_a_rank_loss_is_one_error_line() -> None:
    """Rank 5: ERROR saying the vehicle cannot produce every wrench."""
    lost = allocator([2, 2] + [0] * 6, rank=5)
    level, text = health_change(key(FAILED), key(lost), lost) or ('', '')
    assert level == ERROR
    assert text.startswith('thruster 1 (T2) declared failed')
    assert 'rank 5 < 6: the vehicle cannot produce every wrench' in text


def test_no_change_and_the_first_report_say_nothing() -> None:
    """The same key again, or the first key after configure: no line."""
    assert health_change(key(FAILED), key(FAILED), FAILED) is None
    assert health_change(None, key(FAILED), FAILED) is None
