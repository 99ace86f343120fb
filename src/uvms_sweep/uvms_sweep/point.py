"""One sweep point: a full lockstep graph run in a process of its own, and its supervisor.

``execute_point`` (run by a Ray task, or directly by the benchmark's baseline) starts
``python -m uvms_sweep.point REQUEST.json`` with its own ``ROS_DOMAIN_ID`` and the
project's loopback DDS defaults, waits for it up to the point's timeout, and returns the
outcome as a plain dict. The child builds the graph of the base scenario with the point's
parameters (``build_graph``: the same path as ``uvms run``), records it to MCAP, and writes
the metrics of ``uvms report`` (``report.COLUMNS``) to a JSON file.

Exit status of the child: 0 done, 1 the run failed (the last stderr line says why).
"""

from __future__ import annotations

import contextlib
import ctypes
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Mapping
from dataclasses import replace
from pathlib import Path
from typing import Any

from uvms_common.ros_environment import ros_environment_defaults

#: Prefix of the child's error line, which the supervisor reports as the failure reason.
ERROR_PREFIX = 'uvms sweep point: error: '
#: Lines of a failed point's log kept for DIR/logs (the rest is start-up noise).
LOG_TAIL_LINES = 40
#: Wall-clock poll period of the supervisor (s): how soon the child's end is seen.
_POLL_S = 0.1
#: Wall-clock period at which the supervisor asks ``should_stop`` (s): how soon a stop is seen.
STOP_POLL_S = 0.5
#: Outcome status of a point stopped by the sweep before it finished (not written to the table).
INTERRUPTED = 'interrupted'
#: Linux prctl option: signal sent to this process when its parent dies.
_PR_SET_PDEATHSIG = 1


def execute_point(
    request: Mapping[str, Any], domain_id: int, timeout_s: float,
    should_stop: Callable[[], bool] | None = None,
) -> dict[str, Any]:
    """Run one point in a child process and return its outcome.

    Args:
        request: ``scenario_path``, ``duration_s``, ``seed``, ``overrides`` (node name to
            dotted parameter name to value), ``point_id`` and ``record`` (return the MCAP).
        domain_id: ROS_DOMAIN_ID of the child: no two concurrent points share one.
        timeout_s: Wall-clock limit of the child, start-up included (s).
        should_stop: Asked every ``STOP_POLL_S`` while the child runs; True kills the child
            and returns the outcome ``interrupted`` (the sweep's Ctrl-C).

    Returns:
        ``point_id``, ``status`` (``done``, ``failed`` or ``interrupted``), ``reason``
        (empty when done),
        ``wall_time_s``, ``sim_time_s``, ``metrics`` (column key to value or None),
        ``mcap`` (bytes, when ``record`` and done), ``log`` (the child's last lines).
    """
    start = time.monotonic()
    outcome: dict[str, Any] = {'point_id': request['point_id'], 'status': 'failed',
                               'reason': '', 'sim_time_s': None, 'metrics': {}, 'mcap': None}
    with tempfile.TemporaryDirectory(prefix='uvms-sweep-point-') as tmp:
        directory = Path(tmp)
        files = {'request': directory / 'request.json', 'result': directory / 'result.json',
                 'mcap': directory / 'point.mcap', 'log': directory / 'point.log'}
        child_request = {**request, 'output': str(files['mcap']), 'result': str(files['result'])}
        files['request'].write_text(json.dumps(child_request), encoding='utf-8')
        env = dict(os.environ)
        ros_environment_defaults(env)
        env['ROS_DOMAIN_ID'] = str(domain_id)
        env['UVMS_SWEEP_PARENT_PID'] = str(os.getpid())
        with files['log'].open('wb') as log:
            # A session of its own: a terminal's Ctrl-C reaches the sweep, which stops its
            # points itself, and killpg reaches anything the child started.
            child = subprocess.Popen(
                [sys.executable, '-m', 'uvms_sweep.point', str(files['request'])],
                stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL, env=env,
                start_new_session=True)
            try:
                status, stopped = _wait(child, start + timeout_s, should_stop)
            finally:
                _kill(child)
        lines = files['log'].read_text(encoding='utf-8', errors='replace').splitlines()
        outcome['log'] = '\n'.join(lines[-LOG_TAIL_LINES:])
        if stopped:
            outcome.update(status=INTERRUPTED, reason=INTERRUPTED)
        elif status is None:
            outcome['reason'] = 'timeout'
        elif status != 0 or not files['result'].is_file():
            outcome['reason'] = _error_line(lines, status)
        else:
            result = json.loads(files['result'].read_text(encoding='utf-8'))
            outcome.update(status='done', sim_time_s=result['sim_time_s'],
                           metrics=result['metrics'])
            if request.get('record'):
                outcome['mcap'] = files['mcap'].read_bytes()
    outcome['wall_time_s'] = time.monotonic() - start
    return outcome


def _wait(
    child: subprocess.Popen[bytes], deadline: float, should_stop: Callable[[], bool] | None
) -> tuple[int | None, bool]:
    """Exit status of the child (None at the deadline, monotonic), and whether it was stopped."""
    next_ask = time.monotonic() + STOP_POLL_S
    while time.monotonic() < deadline:
        status = child.poll()
        if status is not None:
            return status, False
        if should_stop is not None and time.monotonic() >= next_ask:
            if should_stop():
                return None, True
            next_ask = time.monotonic() + STOP_POLL_S
        time.sleep(_POLL_S)
    return child.poll(), False


def _kill(child: subprocess.Popen[bytes]) -> None:
    """Kill the child's process group if it still runs, and reap it."""
    if child.poll() is None:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(child.pid, signal.SIGKILL)
    child.wait()


def _error_line(lines: list[str], status: int) -> str:
    """The child's error line, else its last line, with the exit status when it says none."""
    for line in reversed(lines):
        if line.startswith(ERROR_PREFIX):
            return line[len(ERROR_PREFIX):]
    last = next((line.strip() for line in reversed(lines) if line.strip()), '')
    cause = f'killed by signal {-status}' if status < 0 else f'exit status {status}'
    return f'{cause}: {last}' if last else cause


# --------------------------------------------------------------------------------------------
# The child process
# --------------------------------------------------------------------------------------------


def _die_with_parent() -> None:
    """Ask Linux to kill this process when its supervisor dies (a Ray worker killed hard)."""
    parent = os.environ.get('UVMS_SWEEP_PARENT_PID')
    if not parent or not sys.platform.startswith('linux'):
        return
    with contextlib.suppress(OSError, AttributeError):
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    if str(os.getppid()) != parent:  # the supervisor died before prctl took effect
        os._exit(1)


def run_request(request: Mapping[str, Any]) -> dict[str, Any]:
    """Run the graph of one point in this process; its sim time and metrics.

    Raises:
        ScenarioError, GraphError, AnalysisError: the run could not be made or read.
    """
    from uvms_analysis.metrics import compute_metrics
    from uvms_analysis.report import COLUMNS, LABEL_KEYS
    from uvms_analysis.series import load_run
    from uvms_run.graph import build_graph, run_graph
    from uvms_scenarios.scenario import load_scenario

    scenario = load_scenario(request['scenario_path'])
    overrides = {node: dict(values) for node, values in scenario.overrides.items()}
    for node, values in request['overrides'].items():
        overrides.setdefault(node, {}).update(values)
    scenario = replace(scenario, overrides=overrides).with_changes(
        duration_s=request['duration_s'], seed=request['seed'])
    graph = build_graph(scenario, 'lockstep', output_path=request['output'])
    result = run_graph(graph)
    if result.interrupted:
        raise KeyboardInterrupt
    metrics = compute_metrics(load_run(request['output']))
    values = {}
    for column in COLUMNS:
        if column.key in LABEL_KEYS:
            continue
        value = column.value(metrics)
        values[column.key] = None if value is None else float(value)  # type: ignore[arg-type]
    return {'sim_time_s': result.sim_time_s, 'metrics': values}


def main(argv: list[str] | None = None) -> int:
    """Entry point of the point process: ``python -m uvms_sweep.point REQUEST.json``."""
    from uvms_analysis.series import AnalysisError
    from uvms_run.graph import GraphError
    from uvms_scenarios.scenario import ScenarioError

    _die_with_parent()
    args = sys.argv[1:] if argv is None else argv
    ros_environment_defaults()
    request = json.loads(Path(args[0]).read_text(encoding='utf-8'))
    try:
        outcome = run_request(request)
    except (ScenarioError, GraphError, AnalysisError) as exc:
        print(ERROR_PREFIX + str(exc), file=sys.stderr, flush=True)
        return 1
    except KeyboardInterrupt:
        print(ERROR_PREFIX + 'interrupted', file=sys.stderr, flush=True)
        return 130
    Path(request['result']).write_text(json.dumps(outcome), encoding='utf-8')
    return 0


if __name__ == '__main__':
    sys.exit(main())
