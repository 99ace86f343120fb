"""The graph's stall watch: simulated time that stands still too long is an error."""

import pytest
from uvms_run.stall_watch import MARGIN_S, StallWatch, stall_limit_s


def test_moving_time_is_never_a_stall() -> None:
    """Simulated time advancing every check, however slowly in wall time, is no stall."""
    watch = StallWatch(limit_s=10.0)
    assert all(watch.check(k * 2_000_000, wall_s=9.0 * k) is None for k in range(100))


def test_standing_still_past_the_limit_names_the_time_and_the_wait() -> None:
    """Past the limit the message gives the simulated time and the wall time waited."""
    watch = StallWatch(limit_s=10.0)
    assert watch.check(1_500_000_000, wall_s=100.0) is None
    assert watch.check(1_500_000_000, wall_s=110.0) is None
    stalled = watch.check(1_500_000_000, wall_s=110.5)
    assert stalled is not None
    assert 't = 1.500 s' in stalled and '10 s of wall time' in stalled and 'stalled' in stalled


def test_progress_restarts_the_wait() -> None:
    """After simulated time moves, the wait counts from that check."""
    watch = StallWatch(limit_s=10.0)
    watch.check(0, wall_s=0.0)
    assert watch.check(0, wall_s=9.0) is None
    assert watch.check(2_000_000, wall_s=9.5) is None
    assert watch.check(2_000_000, wall_s=19.0) is None
    assert watch.check(2_000_000, wall_s=19.6) is not None


def test_limit_lies_beyond_the_simulators_own_timeouts() -> None:
    """The limit exceeds the recorder and loop start-up waits and a lockstep timeout."""
    assert stall_limit_s(60.0, 1.0) == 2 * 60.0 + 1.0 + MARGIN_S
    assert stall_limit_s(5.0, 20.0) == 2 * 5.0 + 20.0 + MARGIN_S
    with pytest.raises(ValueError, match='stall limit'):
        StallWatch(0.0)
