"""Run the points of a sweep on Ray: a local Ray on 127.0.0.1 by default, or a given cluster.

Each point is one Ray task (one CPU, no retries) that supervises the point's own process
(``sweep_point.execute_point``); the driver keeps at most ``workers`` tasks in flight, gives
each a ROS_DOMAIN_ID that no other running point has, records every finished point in
DIR/points.csv at once, and skips points whose row says ``done`` (resume).

Ctrl-C sets a flag held by a small actor (``stop_flag.StopFlag``, started and answering
before any point is sent) that every running task polls; each stops its point process and
returns. ``ray.cancel`` is only the last resort for a task that
has not returned after ``CANCEL_GRACE_S``: in Ray 2.60 a cancellation that races with the
task's own reply aborts the driver ("Tried to complete task that was not pending",
ray-project/ray#54798), which a sweep stopped mid-point hit in CI.

Local Ray (no ``--address``), as measured with Ray 2.60 (docs/sweeps.md):
``RAY_USAGE_STATS_ENABLED=0``; ``RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER=0``, which makes Ray take
127.0.0.1 as its address instead of probing 8.8.8.8:53 for it; the node address 127.0.0.1,
so GCS, raylet, object manager and workers listen on 127.0.0.1 only; no dashboard; and an
HTTP proxy on a closed loopback port (127.0.0.1:9, loopback exempt) for Ray's own processes,
because its usage-stats module asks the cloud metadata address 169.254.169.254 and
metadata.google.internal which cloud it runs on even with usage statistics off.

Joining a cluster (``--address``), Ray 2.60: ``ray start --head`` turns token authentication
on whenever a token exists on its machine (~/.ray/auth_token, which a local ``ray.init()``
writes), but a driver sends its token only with RAY_AUTH_MODE=token, which
``ray.init(address=...)`` never sets by itself; so ``join_ray`` sets it where it is unset and
Ray would find a token (``ray_token_source``), and names the missing setting when a join fails.
"""

from __future__ import annotations

import datetime
import logging
import os
import shutil
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from uvms_bringup.declared import CHECK_DOMAIN_ID
from uvms_common.node_main import StopEvent
from uvms_run.bars import PointBar
from uvms_scenarios.scenario import Scenario, load_scenario

from uvms_sweep.maps import draw_figures
from uvms_sweep.stop_flag import point_task, ray_error_line, start_stop_flag
from uvms_sweep.sweep_file import Sweep, SweepPoint, overrides_set_over
from uvms_sweep.table import outcome_row, read_table, write_table

#: ROS_DOMAIN_IDs handed to running points, first to last: 215-231 (Fast DDS's default port
#: mapping allows 0-232, and 232 is the parameter check's, ``declared.CHECK_DOMAIN_ID``; the
#: test suite uses 1-200), then 101 down to 1.
DOMAIN_IDS = (*range(215, CHECK_DOMAIN_ID), *range(101, 0, -1))
#: Environment of a local Ray, set before ``import ray`` (see the module docstring).
LOCAL_RAY_ENVIRONMENT = {
    'RAY_USAGE_STATS_ENABLED': '0',
    'RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER': '0',
    'http_proxy': 'http://127.0.0.1:9',
    'https_proxy': 'http://127.0.0.1:9',
    'HTTP_PROXY': 'http://127.0.0.1:9',
    'HTTPS_PROXY': 'http://127.0.0.1:9',
    'no_proxy': '127.0.0.1,localhost,::1',
    'NO_PROXY': '127.0.0.1,localhost,::1',
}
#: How a driver gives a cluster its token, in one phrase for the join errors (docs/sweeps.md).
_TOKEN_HOW = ("put the cluster's token (`ray get-auth-token` on its head node) in "
              '~/.ray/auth_token, or set RAY_AUTH_TOKEN=<token> or RAY_AUTH_TOKEN_PATH=<file>')
#: Object store of a local Ray (bytes): recordings pass through it, a few MB each.
LOCAL_OBJECT_STORE_BYTES = 256 * 2**20
#: Wall time given to stopped tasks to end their point processes before a forced kill (s).
CANCEL_GRACE_S = 5.0
#: Wall-clock period at which the driver checks for Ctrl-C while points run (s).
_WAIT_S = 0.5


class SweepEngineError(RuntimeError):
    """Ray is missing or cannot be started or joined."""


@dataclass
class SweepSummary:
    """What a sweep invocation did.

    Attributes:
        total: Points of the sweep.
        skipped: Points already done in DIR/points.csv (not run again).
        ran: Points run by this invocation.
        failed: Of those, the failed ones.
        interrupted: Ctrl-C or SIGTERM stopped the sweep.
        table: DIR/points.csv.
        figures: PNG files written.
        ran_ids: Point ids run by this invocation.
    """

    total: int
    skipped: int = 0
    ran: int = 0
    failed: int = 0
    interrupted: bool = False
    table: Path | None = None
    figures: list[Path] = field(default_factory=list)
    ran_ids: list[str] = field(default_factory=list)


def start_local_ray(workers: int) -> Any:
    """Start a local Ray with ``workers`` CPUs, bound to 127.0.0.1 (see the module docstring).

    Call it before anything imports ``ray``: Ray reads RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER when
    it is imported.

    Returns:
        The ``ray`` module.

    Raises:
        SweepEngineError: Ray is not installed (the message says how to install it).
    """
    os.environ.update(LOCAL_RAY_ENVIRONMENT)
    ray = _import_ray()
    # 'local' always starts a new instance: address=None would join a cluster that
    # `ray start` left on this machine (its address file in /tmp/ray), bound as it is.
    ray.init(address='local', num_cpus=workers, num_gpus=0, include_dashboard=False,
             _node_ip_address='127.0.0.1', object_store_memory=LOCAL_OBJECT_STORE_BYTES,
             log_to_driver=False, logging_level=logging.ERROR)
    return ray


def join_ray(address: str) -> Any:
    """Join an existing Ray cluster at ``address``, with the token Ray finds, if any.

    RAY_AUTH_MODE=token is set where RAY_AUTH_MODE is unset and ``ray_token_source`` finds a
    token (see the module docstring); a cluster without authentication ignores the token.

    Raises:
        SweepEngineError: The join failed; one line, naming the setting to give where the
            cluster's token authentication refused the driver.
    """
    os.environ.setdefault('RAY_USAGE_STATS_ENABLED', '0')
    token = ray_token_source(os.environ)
    refresh = False
    if token and 'RAY_AUTH_MODE' not in os.environ:
        os.environ['RAY_AUTH_MODE'] = 'token'
        refresh = 'ray' in sys.modules
    mode = os.environ.get('RAY_AUTH_MODE', '').lower() or None
    if mode == 'token' and token is None:
        raise SweepEngineError(f'cannot join the Ray cluster at {address}: RAY_AUTH_MODE=token '
                               f'but no token here: {_TOKEN_HOW}')
    ray = _import_ray()
    if refresh:
        # Ray reads RAY_AUTH_MODE into its config at import; Ray itself refreshes it so.
        from ray._raylet import Config
        Config.initialize('')
    try:
        ray.init(address=address, log_to_driver=False, logging_level=logging.ERROR)
    except (ConnectionError, RuntimeError, ValueError, ray.exceptions.RayError) as exc:
        raise SweepEngineError(_join_error(address, exc, token, mode)) from exc
    return ray


def ray_token_source(environ: Mapping[str, str]) -> str | None:
    """Where Ray 2.60 takes the token a driver sends, in its order; None: nowhere.

    RAY_AUTH_TOKEN; else the first line of the file RAY_AUTH_TOKEN_PATH names; else
    $HOME/.ray/auth_token (``ray get-auth-token --generate`` and a local ``ray.init()`` write
    it, ``ray start`` reads it).

    Raises:
        SweepEngineError: RAY_AUTH_TOKEN_PATH names a missing or empty file (Ray would abort).
    """
    if environ.get('RAY_AUTH_TOKEN', '').strip():
        return 'RAY_AUTH_TOKEN'
    if path := environ.get('RAY_AUTH_TOKEN_PATH', ''):
        if not _first_line(Path(path)):
            msg = f'RAY_AUTH_TOKEN_PATH={path}: no token there (missing or empty file)'
            raise SweepEngineError(msg)
        return f'RAY_AUTH_TOKEN_PATH={path}'
    default = Path(environ.get('HOME', '.')) / '.ray' / 'auth_token'
    return str(default) if _first_line(default) else None


def _first_line(path: Path) -> str:
    """The file's first line without surrounding whitespace; '' if unreadable."""
    try:
        with path.open(encoding='utf-8') as file:
            return file.readline().strip()
    except (OSError, UnicodeDecodeError):
        return ''


def _join_error(address: str, exc: BaseException, token: str | None, mode: str | None) -> str:
    """One line: why joining ``address`` failed, and the setting to give if it was the token."""
    # Ray 2.60: ConnectionError from a RuntimeError quoting the GCS's refusal.
    if 'InvalidAuthToken' not in f'{exc} {exc.__cause__}':
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        return f'cannot join the Ray cluster at {address}: {first}'
    why = ('and this driver has no token' if token is None and mode is None else
           f'but RAY_AUTH_MODE={mode} here (unset it)' if mode != 'token' else
           f'and refused the token of {token}')
    return (f'cannot join the Ray cluster at {address}: it uses token authentication {why}: '
            f'{_TOKEN_HOW}')


def _import_ray() -> Any:
    """The ray module, or SweepEngineError saying how to install it."""
    try:
        import ray
    except ImportError as exc:
        msg = ("uvms sweep needs Ray: pip install 'uvms-stack[sweep]' (make setup installs "
               'it)')
        raise SweepEngineError(msg) from exc
    return ray


def run_sweep(
    sweep: Sweep,
    scenario: Scenario,
    out_dir: Path,
    *,
    address: str | None = None,
    workers: int | None = None,
    progress: bool = True,
    stop: StopEvent | None = None,
    on_outcome: Callable[[Mapping[str, Any]], None] | None = None,
) -> SweepSummary:
    """Run every point not yet done, record it, and draw the figures.

    Uses the Ray this process is already connected to if there is one (tests, notebooks);
    otherwise starts a local Ray (``address`` None) or joins ``address``, and shuts it down
    at the end.

    Args:
        sweep: The checked sweep (``sweep_validate.check_sweep``).
        scenario: Its base scenario.
        out_dir: Output directory (created).
        address: Ray cluster address; None: a local Ray on this machine.
        workers: Points at once; None: the machine's CPUs (local) or the cluster's.
        progress: Draw the progress bar on stderr.
        stop: Set by SIGINT/SIGTERM: the sweep stops cleanly and keeps what is done.
        on_outcome: Called with each finished point's outcome (benchmarks).

    Raises:
        SweepEngineError: Ray cannot be started or joined.
        TableError: DIR/points.csv belongs to a sweep over other axes.
    """
    out_dir.mkdir(parents=True, exist_ok=True)
    points = sweep_points(sweep, scenario)
    rows = read_table(out_dir, sweep)
    if sweep.path.is_file():
        shutil.copyfile(sweep.path, out_dir / 'sweep.yaml')
    todo = [point for point in points if rows.get(point.point_id, {}).get('status') != 'done']
    summary = SweepSummary(total=len(points), skipped=len(points) - len(todo))
    if todo:
        _run_points(sweep, scenario, out_dir, todo, points, rows, summary, address, workers,
                    progress, stop, on_outcome)
    summary.table = write_table(out_dir, sweep, _ordered(points, rows))
    summary.figures = draw_figures(sweep, points, rows, out_dir)
    return summary


def _run_points(
    sweep: Sweep, scenario: Scenario, out_dir: Path, todo: list[SweepPoint],
    points: Sequence[SweepPoint], rows: dict[str, dict[str, str]], summary: SweepSummary,
    address: str | None, workers: int | None, progress: bool, stop: StopEvent | None,
    on_outcome: Callable[[Mapping[str, Any]], None] | None,
) -> None:
    """Start Ray if needed, run ``todo`` on it, and shut a Ray started here down."""
    # Ray reads its environment at import: start_local_ray and join_ray set it first.
    owned = 'ray' not in sys.modules or not _import_ray().is_initialized()
    if owned:
        ray = join_ray(address) if address else start_local_ray(workers or os.cpu_count() or 1)
    else:
        ray = _import_ray()
    try:
        capacity = workers or max(int(ray.cluster_resources().get('CPU', 1)), 1)
        capacity = min(capacity, len(DOMAIN_IDS))
        bar = PointBar(len(points), summary.skipped) if progress else None
        try:
            _dispatch(ray, sweep, scenario, out_dir, todo, points, rows, summary, capacity,
                      bar, stop, on_outcome)
        finally:
            if bar is not None:
                bar.close()
    finally:
        if owned:
            ray.shutdown()


def _dispatch(
    ray: Any, sweep: Sweep, scenario: Scenario, out_dir: Path, todo: list[SweepPoint],
    points: Sequence[SweepPoint], rows: dict[str, dict[str, str]], summary: SweepSummary,
    capacity: int, bar: PointBar | None, stop: StopEvent | None,
    on_outcome: Callable[[Mapping[str, Any]], None] | None,
) -> None:
    """Keep ``capacity`` point tasks in flight until all ran or a stop arrives."""
    task = ray.remote(num_cpus=1, max_retries=0)(point_task)
    stop_flag = start_stop_flag(ray, stop)
    duration_s = sweep.duration_s if sweep.duration_s is not None else scenario.duration_s
    pending = list(todo)
    free_domains = list(DOMAIN_IDS[:capacity])
    in_flight: dict[Any, tuple[SweepPoint, int]] = {}
    try:
        while pending or in_flight:
            if stop is not None and stop.is_set():
                raise KeyboardInterrupt
            while pending and free_domains:
                point = pending.pop(0)
                domain = free_domains.pop(0)
                request = point_request(sweep, scenario, point, duration_s)
                ref = task.remote(request, domain, sweep.timeout_s, stop_flag)
                in_flight[ref] = (point, domain)
            ready, _ = ray.wait(list(in_flight), num_returns=1, timeout=_WAIT_S)
            if stop is not None and stop.is_set():
                raise KeyboardInterrupt
            for ref in ready:
                point, domain = in_flight.pop(ref)
                free_domains.append(domain)
                outcome = _outcome(ray, ref, point)
                _record(sweep, out_dir, point, outcome, points, rows, summary)
                if bar is not None:
                    bar.point_done(outcome['status'] != 'done')
                if on_outcome is not None:
                    on_outcome(outcome)
    except KeyboardInterrupt:
        summary.interrupted = True
        _stop_in_flight(ray, stop_flag, in_flight, sweep, out_dir, points, rows, summary)
    finally:
        if stop_flag is not None:
            ray.kill(stop_flag)


def sweep_points(sweep: Sweep, scenario: Scenario) -> list[SweepPoint]:
    """The sweep's points over its base scenario, keyed with what is set over the file.

    The parameter files and ``--ideal-devices`` are in ``scenario.overrides`` over the
    scenario file's own; what they change is part of each point's key (``point_id``).
    """
    duration_s = sweep.duration_s if sweep.duration_s is not None else scenario.duration_s
    set_over = overrides_set_over(load_scenario(scenario.path).overrides, scenario.overrides)
    return sweep.points(scenario.name, duration_s, scenario.seed, set_over)


def point_request(
    sweep: Sweep, scenario: Scenario, point: SweepPoint, duration_s: float
) -> dict[str, Any]:
    """What the point process needs: base scenario, its parameters, seed and duration.

    The overrides are the base scenario's as given (its file's, with what the command line
    set over them: ``--ideal-devices``), then the point's axes.
    """
    overrides = {node: dict(values) for node, values in scenario.overrides.items()}
    for axis in sweep.axes:
        overrides.setdefault(axis.node, {})[axis.parameter] = point.values[axis.name]
    return {'point_id': point.point_id, 'scenario_path': str(scenario.path.resolve()),
            'duration_s': duration_s, 'seed': point.seed, 'overrides': overrides,
            'record': sweep.record}


def _outcome(ray: Any, ref: Any, point: SweepPoint) -> dict[str, Any]:
    """The task's outcome; a failed point when Ray itself failed (worker died, ...)."""
    try:
        return dict(ray.get(ref))
    except ray.exceptions.RayError as exc:
        return {'point_id': point.point_id, 'status': 'failed',
                'reason': f'Ray: {ray_error_line(exc)}', 'metrics': {}}


def _record(
    sweep: Sweep, out_dir: Path, point: SweepPoint, outcome: Mapping[str, Any],
    points: Sequence[SweepPoint], rows: dict[str, dict[str, str]], summary: SweepSummary,
) -> None:
    """Keep a finished point: its MCAP or log, its row, and the table rewritten."""
    if outcome.get('mcap'):
        (out_dir / 'mcap').mkdir(exist_ok=True)
        (out_dir / 'mcap' / f'{point.point_id}.mcap').write_bytes(outcome['mcap'])
    if outcome['status'] != 'done' and outcome.get('log'):
        (out_dir / 'logs').mkdir(exist_ok=True)
        (out_dir / 'logs' / f'{point.point_id}.log').write_text(outcome['log'] + '\n',
                                                                encoding='utf-8')
    finished = datetime.datetime.now(datetime.UTC).strftime('%Y-%m-%dT%H:%M:%SZ')
    rows[point.point_id] = outcome_row(sweep, point.values, point.seed, outcome, finished)
    summary.ran += 1
    summary.failed += int(outcome['status'] != 'done')
    summary.ran_ids.append(point.point_id)
    write_table(out_dir, sweep, _ordered(points, rows))


def _stop_in_flight(
    ray: Any, stop_flag: Any, in_flight: Mapping[Any, tuple[SweepPoint, int]], sweep: Sweep,
    out_dir: Path, points: Sequence[SweepPoint], rows: dict[str, dict[str, str]],
    summary: SweepSummary,
) -> None:
    """Stop the running points, keep those done meanwhile, and force-kill what is left.

    A point that failed while the sweep stopped is not recorded: the stop may be its cause,
    and the next run tries it again either way.
    """
    if stop_flag is not None:
        stop_flag.set.remote()
    deadline = time.monotonic() + CANCEL_GRACE_S
    left = list(in_flight)
    while left and time.monotonic() < deadline:
        ready, left = ray.wait(left, num_returns=len(left), timeout=0.2)
        for ref in ready:
            point, _ = in_flight[ref]
            outcome = _outcome(ray, ref, point)
            if outcome['status'] == 'done':
                _record(sweep, out_dir, point, outcome, points, rows, summary)
    for ref in left:
        ray.cancel(ref, force=True)


def _ordered(
    points: Sequence[SweepPoint], rows: Mapping[str, dict[str, str]]
) -> list[dict[str, str]]:
    """Rows in grid order, then rows of points no longer in the grid (kept, not lost)."""
    ids = [point.point_id for point in points]
    known = set(ids)
    return [rows[i] for i in ids if i in rows] + [
        row for key, row in rows.items() if key not in known
    ]
