"""Console-script entry of a node process: stop handlers first, then the node's imports.

``ros2 run`` and ``uvms launch`` start a node by its console script; the launcher may stop
it (SIGINT, then SIGTERM) at any moment, also while the node module is still importing
rclpy, numpy and Pinocchio. The entry installs the ``StopEvent`` before that import, and the
node's ``run_node`` takes it over, so such a stop ends the process with status 0 and no
traceback.

Once the node's ``main`` is done (output closed, node destroyed, DDS participant gone), the
process ends at once: Python's exit handlers run and the streams are flushed, but the
interpreter's finalization (freeing Pinocchio, LLVM and every module, 1-3 s measured on a
loaded 2-core machine) is skipped, so that a stop stays within 2 s of the signal.
"""

from __future__ import annotations

import atexit
import ctypes
import importlib
import os
import sys
import threading

from uvms_common.stop_event import StopEvent

#: Set by ``run_node_module``: the process ends right after the node's ``main`` returns, so
#: ``run_node`` leaves the middleware's teardown to the process's end (``node_main``).
_process_ends_after_main = False


def mark_process_ends_after_main() -> None:
    """Say that this process ends (``end_process``) as soon as its ``main`` returns."""
    global _process_ends_after_main
    _process_ends_after_main = True


def process_ends_after_main() -> bool:
    """Whether this process ends as soon as the node's ``main`` returns (a node process)."""
    return _process_ends_after_main


def _exit_status(code: object) -> int:
    """The process status ``SystemExit(code)`` gives (None: 0; a message: printed, 1)."""
    if code is None:
        return 0
    if isinstance(code, int):
        return code & 0xFF
    print(code, file=sys.stderr)
    return 1


def flush_output() -> None:
    """Flush Python's streams and C's stdio buffers (rcutils logs through the latter)."""
    for stream in (sys.stdout, sys.stderr, sys.__stdout__, sys.__stderr__):
        try:
            if stream is not None:
                stream.flush()
        except (OSError, ValueError):
            pass
    try:
        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError):
        pass


def end_process(status: int) -> None:
    """End the process as Python would, less its finalization: status ``status``.

    As at a normal exit, the threads that are not daemons are waited for and the exit
    handlers run (coverage data, ``weakref.finalize``); the streams are flushed. Skipped is
    freeing every module and object, which nothing written depends on.
    """
    for thread in threading.enumerate():
        if thread is not threading.current_thread() and not thread.daemon:
            thread.join()
    atexit._run_exitfuncs()  # the handlers Python runs before its finalization
    flush_output()
    os._exit(status)


def end_unbuilt() -> None:
    """End a node process stopped before its node was built: status 0, at once.

    Called from the stop signal's handler (``StopEvent.ending``) while the node's module is
    imported or the node is built: nothing was started that a stop must end, and nothing
    outside the process was changed. The streams are flushed where they can be (a signal
    that came in the middle of a write leaves that stream as it is).
    """
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except Exception:  # a stream mid-write: leave it as it is
            pass
    os._exit(0)


def run_node_module(module_name: str) -> None:
    """Import a node module with the stop handlers in place, run its ``main()``, end.

    Exits 0 at once, without building the node, when a stop signal arrives during the
    import (``end_unbuilt``); else with the status of ``main``'s ``sys.exit`` (``end_process``). An
    exception other than SystemExit leaves as usual, with its traceback.
    """
    stop = StopEvent()
    status = 0
    mark_process_ends_after_main()
    try:
        # Ended by a stop: the import (rclpy, numpy, Pinocchio) took more than 10 s on a
        # machine at load 14, so a stop waiting for it outlived the launcher's SIGTERM and
        # SIGKILL (issue 48); nothing is built yet, so nothing is lost. Not interrupted by an
        # exception: one raised into a C extension's initialization (rclpy's pybind11
        # module) comes out as an ImportError with a traceback (a soak cycle of issue 48).
        with stop.ending(end_unbuilt):
            module = importlib.import_module(module_name)
        module.main()
    except SystemExit as exc:
        status = _exit_status(exc.code)
    finally:
        stop.restore()
    end_process(status)
