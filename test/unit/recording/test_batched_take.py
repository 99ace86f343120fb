"""Tests of the recorder's batches' log times (the node's batches: test_recorder_node.py)."""

from __future__ import annotations

from uvms_recording.batched_take import log_times_on_clock


def test_a_message_is_logged_at_the_last_clock_received_before_it() -> None:
    """Clocks 10 and 20 received at 100 and 200: arrivals at 50, 150, 200, 250."""
    assert log_times_on_clock([50, 150, 200, 250], [100, 200], [10, 20], 7) == [7, 10, 20, 20]


def test_a_batch_without_clocks_logs_at_the_clock_before_it() -> None:
    """No /clock in the batch: every message at the stamp the clock had."""
    assert log_times_on_clock([1, 2], [], [], 42) == [42, 42]
