"""Tests of uvms_sim.lockstep_wait: the lockstep timeout counts only attentive wall time."""

from __future__ import annotations

import pytest
from uvms_sim.lockstep_wait import AttentiveWait

MS = 1_000_000


def test_a_process_on_time_counts_wall_time_as_it_passes() -> None:
    """Checks every period: the counted wait is the wall time since the publication."""
    wait = AttentiveWait(250 * MS)
    wait.start(1_000 * MS)
    for k in range(1, 5):
        counted = wait.check(1_000 * MS + k * 250 * MS)
    assert counted == 1_000 * MS
    assert wait.wall_ns == 1_000 * MS


def test_a_starved_process_counts_nothing_for_a_late_check() -> None:
    """A check 5 s late (the process did not run) adds nothing; an on-time one its interval."""
    wait = AttentiveWait(250 * MS)
    wait.start(0)
    assert wait.check(5_000 * MS) == 0
    assert wait.wall_ns == 5_000 * MS
    assert wait.check(5_300 * MS) == 300 * MS


def test_checks_run_back_to_back_from_a_queue_count_nothing_more() -> None:
    """Timer events queued behind a backlog and run at once add no time."""
    wait = AttentiveWait(250 * MS)
    wait.start(0)
    wait.check(3_000 * MS)
    assert [wait.check(3_000 * MS + k) for k in range(1, 4)] == [1, 2, 3]


def test_a_new_publication_restarts_the_wait() -> None:
    """start() resets both the counted and the wall time."""
    wait = AttentiveWait(250 * MS)
    wait.start(0)
    wait.check(250 * MS)
    wait.start(300 * MS)
    assert wait.check(400 * MS) == 100 * MS


def test_the_check_period_must_be_positive() -> None:
    """A zero period is refused with its value."""
    with pytest.raises(ValueError, match='got 0'):
        AttentiveWait(0)
