"""A stop that reaches a launched node while its interpreter is still starting ends it cleanly.

Issue 48: ``[mission-5] Fatal Python error: init_import_site: Failed to import the site
module`` and ``node 'mission' exited: status 1 while stopping`` after a Ctrl-C 1.8-3.7 s
into a launch: the launcher's SIGINT reached a child before its interpreter had imported
``site`` (the ROS wheels' ``.pth`` re-executes Python there).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from uvms_bringup.processes import _child_setup
from uvms_common.scheduling import may_lower_niceness

#: A node module: waits for its stop (as run_node does), then returns.
_NODE = """
import time
from uvms_common.stop_event import active_stop_event

def main():
    stop = active_stop_event()
    while not stop.is_set():
        time.sleep(0.01)
"""

#: A program that never installs stop handlers (sleeps).
_NO_HANDLERS = 'import time\ntime.sleep(60)\n'


def _start(tmp_path: Path, code: str) -> subprocess.Popen[str]:
    env = {**os.environ, 'PYTHONPATH': os.pathsep.join([str(tmp_path), *sys.path])}
    return subprocess.Popen([sys.executable, '-c', code], env=env, stdin=subprocess.DEVNULL,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            process_group=0, preexec_fn=_child_setup(0))


@pytest.mark.parametrize('delay_s', [0.0, 0.02, 0.1])
def test_a_sigint_during_the_interpreters_start_ends_the_node_with_status_0(
        tmp_path: Path, delay_s: float) -> None:
    """Before the fix the child exited 1 with ``init_import_site`` (or a traceback)."""
    (tmp_path / 'stop_test_node.py').write_text(_NODE)
    code = ('from uvms_common.node_entry import run_node_module; '
            "run_node_module('stop_test_node')")
    for _ in range(5):
        child = _start(tmp_path, code)
        time.sleep(delay_s)
        child.send_signal(signal.SIGINT)
        _, err = child.communicate(timeout=30)
        assert child.returncode == 0, err
        assert 'Fatal Python error' not in err and 'Traceback' not in err, err


def test_a_process_that_never_installs_handlers_still_ends_at_sigterm(tmp_path: Path) -> None:
    """SIGINT waits for handlers that never come; the launcher's SIGTERM still ends it."""
    child = _start(tmp_path, _NO_HANDLERS)
    time.sleep(0.5)
    child.send_signal(signal.SIGINT)
    with pytest.raises(subprocess.TimeoutExpired):
        child.wait(timeout=1.0)
    child.send_signal(signal.SIGTERM)
    assert child.wait(timeout=10) == -signal.SIGTERM


def test_a_stop_during_a_slow_import_ends_the_node_at_once(tmp_path: Path) -> None:
    """An import that takes long (rclpy, Pinocchio: over 10 s at load 14) is interrupted.

    Before, the stop waited for the import, and the launcher's SIGTERM and SIGKILL came
    first (``node 'mission' exited: killed by SIGKILL while stopping``).
    """
    (tmp_path / 'slow_import_node.py').write_text('import time\ntime.sleep(30)\n' + _NODE)
    code = ('from uvms_common.node_entry import run_node_module; '
            "run_node_module('slow_import_node')")
    child = _start(tmp_path, code)
    time.sleep(3.0)
    sent = time.monotonic()
    child.send_signal(signal.SIGINT)
    _, err = child.communicate(timeout=60)
    assert child.returncode == 0, err
    assert time.monotonic() - sent < 10.0, err
    assert 'Traceback' not in err and 'KeyboardInterrupt' not in err, err


def test_a_child_starts_at_the_niceness_asked_for_or_at_0_where_refused() -> None:
    """``_child_setup(0, -5)``: the child's niceness -5 where this user may lower it, else 0."""
    allowed = may_lower_niceness(-5)
    child = subprocess.run([sys.executable, '-c', 'import os; print(os.nice(0))'],
                           capture_output=True, text=True, timeout=60, check=True,
                           preexec_fn=_child_setup(0, -5))
    assert int(child.stdout) == (-5 if allowed else os.nice(0))
