"""StopEvent keeps SIGINT and SIGTERM once an rclpy executor is built."""

from __future__ import annotations

import os
import signal

import pytest
import rclpy
from rclpy.context import Context
from rclpy.signals import SignalHandlerOptions
from uvms_common.node_main import make_executor
from uvms_common.stop_event import StopEvent, active_stop_event


@pytest.mark.parametrize('kind', ['events', 'single'])
@pytest.mark.parametrize('sig', [signal.SIGINT, signal.SIGTERM])
def test_a_signal_after_the_executor_is_built_sets_the_stop_and_keeps_the_context(
    kind: str, sig: signal.Signals
) -> None:
    """run_node's stop relies on it: the nodes are destroyed before the context shuts down.

    rclpy 7.1.6's EventsExecutor leaves the process's handlers alone; newer rclpy sources
    install C-level SIGINT/SIGTERM handlers in it (asio::signal_set) that shut the context
    down inside spin_once. This test is the guard for a version bump.
    """
    stop = StopEvent()
    context = Context()
    rclpy.init(args=[], context=context, signal_handler_options=SignalHandlerOptions.NO)
    try:
        executor = make_executor(kind, context)
        os.kill(os.getpid(), sig)
        executor.spin_once(timeout_sec=0.05)
        executor.spin_once(timeout_sec=0.05)
        assert stop.is_set()
        assert stop.signal_number == sig
        assert context.ok()
        executor.shutdown()
    finally:
        rclpy.try_shutdown(context=context)
        stop.restore()


def test_restore_puts_the_earlier_handler_back_and_forgets_the_event() -> None:
    """After restore, the process's previous SIGINT handler is in force again."""
    before = signal.getsignal(signal.SIGINT)
    stop = StopEvent()
    assert active_stop_event() is stop
    stop.restore()
    assert signal.getsignal(signal.SIGINT) is before
    assert active_stop_event() is not stop


class EndedError(Exception):
    """Stands in for the process's end (os._exit) in ``ending``'s callback."""


def end() -> None:
    """The end: raises instead of ending the process."""
    raise EndedError


def test_a_signal_inside_ending_calls_the_end_and_outside_only_sets_the_event() -> None:
    """Start-up work (imports, model, kernels) ends at once on a stop; the spin loop polls."""
    stop = StopEvent()
    try:
        with pytest.raises(EndedError), stop.ending(end):
            os.kill(os.getpid(), signal.SIGINT)  # the handler runs as kill returns
        assert stop.is_set()
        os.kill(os.getpid(), signal.SIGTERM)  # outside: no end
        assert stop.signal_number == signal.SIGTERM
        with pytest.raises(EndedError), stop.ending(end):
            pass  # a stop that came before the block ends it on entry
    finally:
        stop.restore()
