"""Tests of uvms_common.realtime: start-up-aware staleness and counted real-time misses."""

from __future__ import annotations

import pytest
from uvms_common.realtime import Event, MissCounter, StalenessMonitor

MS = 1_000_000
S = 1_000 * MS


def test_stale_inputs_during_start_up_are_info_and_never_warn() -> None:
    """Stale, fresh, stale again within the grace: INFO lines only, no alarm."""
    monitor = StalenessMonitor(grace_ns=2 * S)
    events = [monitor.observe(t, stale) for t, stale in
              [(0, True), (1 * MS, True), (5 * MS, False), (300 * MS, True), (302 * MS, False)]]
    assert events == [Event('info', 'waiting'), None, Event('info', 'fresh'),
                      Event('info', 'waiting'), None]
    assert not monitor.alarmed


def test_stale_inputs_after_the_grace_warn_once_and_resume_at_info() -> None:
    """After start-up a stale edge is one WARN; the return of fresh inputs one INFO."""
    monitor = StalenessMonitor(grace_ns=2 * S)
    monitor.observe(0, False)
    assert monitor.observe(3 * S, True) == Event('warn', 'stale')
    assert monitor.alarmed
    assert monitor.observe(3 * S + 2 * MS, True) is None
    assert monitor.observe(3 * S + 4 * MS, False) == Event('info', 'resumed')
    assert not monitor.alarmed


def test_inputs_that_never_become_fresh_warn_when_the_grace_ends() -> None:
    """Waiting is INFO at first; still no fresh input after the grace is a WARN."""
    monitor = StalenessMonitor(grace_ns=2 * S)
    assert monitor.observe(0, True) == Event('info', 'waiting')
    assert monitor.observe(1 * S, True) is None
    assert monitor.observe(2 * S, True) == Event('warn', 'never_fresh')


def test_a_timer_on_time_misses_nothing() -> None:
    """Ticks exactly one period apart: no missed period, no warning."""
    counter = MissCounter(period_ns=2 * MS, grace_ns=0, window_ns=1 * S)
    warnings = [counter.tick(k * 2 * MS) for k in range(2000)]
    assert not any(warnings)
    assert counter.missed == 0 and counter.periods == 1999 and counter.share == 0.0


def test_a_timer_that_skips_a_quarter_of_its_periods_warns_with_the_share() -> None:
    """Every fourth period skipped (the issue's 75 %): the window's share is reported."""
    counter = MissCounter(period_ns=2 * MS, grace_ns=0, window_ns=1 * S)
    ticks = [k * 2 * MS for k in range(4000) if k % 4 != 3]
    shares = [share for t in ticks if (share := counter.tick(t)) is not None]
    assert shares and all(share == pytest.approx(0.25, abs=0.01) for share in shares)
    assert counter.share == pytest.approx(0.25, abs=0.01)


def test_misses_below_the_threshold_or_during_start_up_do_not_warn() -> None:
    """0.5 % missed stays quiet; a long stall inside the start-up grace is not counted."""
    counter = MissCounter(period_ns=2 * MS, grace_ns=2 * S, window_ns=1 * S)
    counter.tick(0)
    counter.tick(500 * MS)  # 249 periods lost while loading, inside the grace
    ticks = [2 * S + k * 2 * MS for k in range(3000) if k % 200 != 199]
    assert not any(counter.tick(t) for t in ticks)
    assert counter.missed == pytest.approx(0.005 * counter.periods, rel=0.2)


def test_ticks_that_could_not_do_their_work_count_as_missed() -> None:
    """A tick on time that found nothing new to do (``ran=False``) misses its period."""
    counter = MissCounter(period_ns=2 * MS, grace_ns=0, window_ns=1 * S)
    shares = [counter.tick(k * 2 * MS, ran=k % 2 == 0) for k in range(1001)]
    assert shares[-1] == pytest.approx(0.5, abs=0.01)


def test_worst_lateness_is_the_longest_delay_beyond_a_period_after_the_grace() -> None:
    """A callback 7 ms after the previous one on a 2 ms timer was 5 ms late."""
    counter = MissCounter(period_ns=2 * MS, grace_ns=10 * MS, window_ns=1 * S)
    for t in (0, 30 * MS, 32 * MS, 34 * MS, 41 * MS, 43 * MS):  # 0 -> 30 ms is in the grace
        counter.tick(t)
    assert counter.worst_late_ns == 5 * MS


def test_process_periods_sum_the_counters_of_the_process() -> None:
    """Periods and misses of every live counter add up; the worst lateness is their max."""
    from uvms_common.realtime import process_periods

    before = process_periods()
    first = MissCounter(period_ns=2 * MS, grace_ns=0, window_ns=1 * S)
    second = MissCounter(period_ns=1 * MS, grace_ns=0, window_ns=1 * S)
    for t in (0, 2 * MS, 4 * MS, 10 * MS):
        first.tick(t)
    for t in (0, 1 * MS, 2 * MS):
        second.tick(t)
    after = process_periods()
    assert after['periods'] - before['periods'] == first.periods + second.periods == 5 + 2
    assert after['missed'] - before['missed'] == 2
    assert after['worst_late_ms'] >= 4.0
