"""`uvms sweep` on a local Ray with 2 workers: table, failures, resume, timeout, Ctrl-C.

Every point is a genuine lockstep graph run (rclpy, Fast DDS on loopback) in its own process
and DDS domain, short (0.3 s simulated) so that the module stays cheap. One local Ray serves
the module (started once, as ``uvms sweep`` starts it); the Ctrl-C test runs the command in
a process of its own, which starts its own. The ``--address`` tests run the command against
heads started with ``ray start --head`` on 127.0.0.1, each with a HOME and Ray temp dir of its
own.
"""

from __future__ import annotations

import csv
import io
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import uuid
from collections.abc import Iterator
from contextlib import contextmanager, redirect_stdout
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from uvms_sweep.engine import SweepSummary, point_request, run_sweep, start_local_ray
from uvms_sweep.sweep_file import METRIC_KEYS, Sweep, load_sweep
from uvms_sweep.table import TABLE_NAME
from uvms_sweep.validate import check_sweep

from uvms_analysis import report
from uvms_sweep import cli as sweep_cli

K_E = 'simulator.contact.stiffness_n_m'
MASS = 'controller.model.mass_scale'
#: mass_scale's declared range is [0.1, 10]: 20 makes the controller refuse to start.
GRID = f"""\
name: grid
scenario: case1_ke1e4
duration_s: 0.3
record: true
timeout_s: 120.0
axes:
  {K_E}: [1.0e+4, 1.0e+5]
  {MASS}: [1.0, 20.0]
metrics: [vehicle_displacement_mm, max_error_z_mm]
"""
#: Set in the environment of this module's sweeps, which their point processes inherit: tells
#: them from the points of any other sweep running on the machine.
MARK = f'UVMS_SWEEP_TEST={uuid.uuid4().hex}'
#: Wall-clock limit of a whole `uvms sweep` process in these tests (s), a safety net only.
PROCESS_TIMEOUT_S = 300.0


def write(directory: Path, text: str, name: str = 'sweep.yaml') -> Path:
    """A sweep file with this text."""
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / name
    path.write_text(text, encoding='utf-8')
    return path


def read_rows(out: Path) -> list[dict[str, str]]:
    """Rows of DIR/points.csv, parsed by the csv module."""
    with (out / TABLE_NAME).open(newline='', encoding='utf-8') as file:
        return list(csv.DictReader(file))


def point_processes() -> list[int]:
    """Pids of point processes of this module's sweeps that still run (by MARK)."""
    pids = []
    for entry in Path('/proc').iterdir():
        if not entry.name.isdigit():
            continue
        try:
            cmdline = (entry / 'cmdline').read_bytes().split(b'\0')
            environ = (entry / 'environ').read_bytes().split(b'\0')
        except OSError:
            continue
        if b'uvms_sweep.point' in cmdline and MARK.encode() in environ:
            pids.append(int(entry.name))
    return pids


@pytest.fixture(scope='module')
def local_ray() -> Iterator[Any]:
    """One local Ray with 2 CPUs for the module, the environment restored afterwards."""
    saved = dict(os.environ)
    name, value = MARK.split('=')
    os.environ[name] = value
    ray = start_local_ray(2)
    try:
        yield ray
    finally:
        ray.shutdown()
        os.environ.clear()
        os.environ.update(saved)


def sweep_of(path: Path) -> tuple[Sweep, Any]:
    """A sweep file checked against the graph's parameters."""
    return check_sweep(load_sweep(path))


@pytest.fixture(scope='module')
def grid(
    local_ray: Any, tmp_path_factory: pytest.TempPathFactory
) -> tuple[Sweep, Path, SweepSummary, list[dict[str, str]]]:
    """The 2 x 2 sweep run once: its sweep, output directory, summary and table."""
    base = tmp_path_factory.mktemp('grid')
    sweep, scenario = sweep_of(write(base, GRID))
    out = base / 'out'
    summary = run_sweep(sweep, scenario, out, workers=2, progress=False)
    return sweep, out, summary, read_rows(out)


def test_every_grid_point_has_a_row_with_its_parameters(grid: Any) -> None:
    """2 x 2 points, 4 rows: each value combination once, with the scenario's seed."""
    _, _, summary, rows = grid
    assert summary.total == 4 and summary.ran == 4 and not summary.interrupted
    combos = {(float(row[K_E]), float(row[MASS])) for row in rows}
    assert combos == {(1e4, 1.0), (1e4, 20.0), (1e5, 1.0), (1e5, 20.0)}
    assert {row['seed'] for row in rows} == {'1'}


def test_point_that_cannot_start_is_failed_with_the_reason_and_the_rest_ran(grid: Any) -> None:
    """mass_scale 20 is out of range: those points fail naming it; the others are done."""
    _, out, summary, rows = grid
    failed = [row for row in rows if float(row[MASS]) == 20.0]
    done = [row for row in rows if float(row[MASS]) == 1.0]
    assert summary.failed == 2
    assert all(row['status'] == 'failed' for row in failed)
    assert all('model.mass_scale' in row['reason'] and 'out of range' in row['reason']
               for row in failed)
    assert all((out / 'logs' / f'{row["point_id"]}.log').is_file() for row in failed)
    assert all(row['status'] == 'done' and row['reason'] == '' for row in done)
    assert all(abs(float(row['sim_time_s']) - 0.3) < 1e-6 for row in done)


def test_table_metrics_are_those_uvms_report_reads_from_the_recording(grid: Any) -> None:
    """Each done point's MCAP, read back by `uvms report --format csv`, gives its row's metrics."""
    _, out, _, rows = grid
    for row in (row for row in rows if row['status'] == 'done'):
        stdout = io.StringIO()
        with redirect_stdout(stdout):
            assert report.main([str(out / 'mcap' / f'{row["point_id"]}.mcap'),
                                '--format', 'csv']) == 0
        reported = next(csv.DictReader(io.StringIO(stdout.getvalue())))
        for key in METRIC_KEYS:
            if reported[key] == 'n/a':
                assert row[key] == '', key
            else:
                assert float(row[key]) == pytest.approx(float(reported[key]), rel=1e-5), key


def test_a_figure_per_metric_is_written(grid: Any) -> None:
    """figures/METRIC.png for each metric of the sweep file, a PNG image."""
    from matplotlib.image import imread

    sweep, out, summary, _ = grid
    assert sorted(p.name for p in summary.figures) == sorted(f'{m}.png' for m in sweep.metrics)
    for metric in sweep.metrics:
        image = imread(out / 'figures' / f'{metric}.png')
        assert image.shape[0] > 100 and image.shape[1] > 100


def test_rerun_skips_done_points_and_runs_the_failed_ones_again(grid: Any) -> None:
    """The same sweep on the same directory runs only what is not done; done rows stay."""
    sweep, out, _, rows = grid
    scenario = check_sweep(sweep)[1]
    done = {row['point_id']: row for row in rows if row['status'] == 'done'}
    mtimes = {key: (out / 'mcap' / f'{key}.mcap').stat().st_mtime_ns for key in done}
    summary = run_sweep(sweep, scenario, out, workers=2, progress=False)
    assert summary.skipped == 2 and summary.ran == 2
    assert set(summary.ran_ids).isdisjoint(done)
    after = {row['point_id']: row for row in read_rows(out)}
    assert len(after) == 4
    for key, row in done.items():
        assert after[key] == row  # wall time and finish time too: not run again
        assert (out / 'mcap' / f'{key}.mcap').stat().st_mtime_ns == mtimes[key]


def test_point_past_its_timeout_fails_with_reason_timeout_and_is_killed(
    local_ray: Any, tmp_path: Path
) -> None:
    """A 30 s run with a 1 s wall-clock limit: failed, reason 'timeout', no process left."""
    text = GRID.replace('duration_s: 0.3', 'duration_s: 30.0').replace(
        'timeout_s: 120.0', 'timeout_s: 1.0').replace(f'{MASS}: [1.0, 20.0]', f'{MASS}: [1.0]')
    text = text.replace(f'{K_E}: [1.0e+4, 1.0e+5]', f'{K_E}: [1.0e+4]')
    sweep, scenario = sweep_of(write(tmp_path, text))
    summary = run_sweep(sweep, scenario, tmp_path / 'out', workers=2, progress=False)
    (row,) = read_rows(tmp_path / 'out')
    assert summary.failed == 1
    assert (row['status'], row['reason']) == ('failed', 'timeout')
    assert point_processes() == []


def test_point_asked_to_stop_is_killed_and_reported_interrupted(tmp_path: Path) -> None:
    """`should_stop` True (the sweep's Ctrl-C): the child is killed, the outcome says so."""
    from uvms_sweep.engine import DOMAIN_IDS
    from uvms_sweep.point import execute_point

    text = GRID.replace('duration_s: 0.3', 'duration_s: 30.0').replace(
        f'{MASS}: [1.0, 20.0]', f'{MASS}: [1.0]').replace(f'{K_E}: [1.0e+4, 1.0e+5]',
                                                         f'{K_E}: [1.0e+4]')
    sweep, scenario = sweep_of(write(tmp_path, text))
    (point,) = sweep.points(scenario.name, 30.0, scenario.seed)
    request = point_request(sweep, scenario, point, 30.0)
    asked: list[float] = []

    def should_stop() -> bool:
        asked.append(time.monotonic())
        return len(asked) >= 3

    name, value = MARK.split('=')
    saved = os.environ.get(name)
    os.environ[name] = value
    try:
        outcome = execute_point(request, DOMAIN_IDS[-1], 120.0, should_stop=should_stop)
    finally:
        if saved is None:
            os.environ.pop(name)
        else:
            os.environ[name] = saved
    assert (outcome['status'], outcome['reason']) == ('interrupted', 'interrupted')
    # Stopped at the third question, not run to its end: execute_point asks every
    # STOP_POLL_S while the child lives, and a 30 s run (1.75x real time here) would have been
    # asked dozens of times. Counted in questions, not timed: no wall-clock bound.
    assert len(asked) == 3
    assert outcome['sim_time_s'] is None  # set only by a run that finished
    assert point_processes() == []


def test_axis_that_names_no_parameter_is_rejected_with_a_suggestion(tmp_path: Path) -> None:
    """`uvms sweep` exits 2 naming the axis key and the close parameter names."""
    path = write(tmp_path, GRID.replace('model.mass_scale', 'model.mass_scal'))
    stderr = io.StringIO()
    from contextlib import redirect_stderr

    with redirect_stderr(stderr):
        status = sweep_cli.main([str(path), '--out', str(tmp_path / 'out')])
    assert status == 2
    message = stderr.getvalue()
    assert "key 'axes.controller.model.mass_scal'" in message
    assert 'did you mean model.mass_scale' in message
    assert not (tmp_path / 'out').exists()


def test_bad_sweep_file_stops_the_command_naming_the_key(tmp_path: Path) -> None:
    """A wrong value type exits 2 with one line naming file and key, before Ray starts."""
    path = write(tmp_path, GRID.replace('timeout_s: 120.0', 'timeout_s: soon'))
    process = subprocess.run(
        [sys.executable, '-m', 'uvms_cli.cli', 'sweep', str(path), '--out',
         str(tmp_path / 'out')], capture_output=True, text=True, timeout=PROCESS_TIMEOUT_S)
    assert process.returncode == 2
    assert process.stderr.strip().splitlines() == [
        f"uvms sweep: error: {path}: key 'timeout_s': expected a number > 0, got str 'soon'"]


def test_ctrl_c_stops_the_sweep_keeps_what_is_done_and_leaves_no_point_running(
    tmp_path: Path,
) -> None:
    """SIGINT after the first point: exit 130, a consistent table of finished points only."""
    text = GRID.replace('duration_s: 0.3', 'duration_s: 4.0').replace('record: true',
                                                                     'record: false')
    text = text.replace(f'{MASS}: [1.0, 20.0]', f'{MASS}: [1.0, 0.9, 1.1]')
    path = write(tmp_path, text)
    out = tmp_path / 'out'
    name, value = MARK.split('=')
    env = {**os.environ, 'PYTHONPATH': os.pathsep.join(p for p in sys.path if p), name: value}
    process = subprocess.Popen(
        [sys.executable, '-m', 'uvms_cli.cli', 'sweep', str(path), '--out', str(out),
         '--workers', '2', '--quiet'], stderr=subprocess.PIPE, text=True, env=env)
    deadline = time.monotonic() + PROCESS_TIMEOUT_S
    # A point done and another running: the check for left-over processes sees running ones.
    while not ((out / TABLE_NAME).is_file() and read_rows(out) and point_processes()):
        assert process.poll() is None, process.communicate()[1]
        assert time.monotonic() < deadline
        time.sleep(0.1)
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=PROCESS_TIMEOUT_S)
    assert process.returncode == 130, stderr
    rows = read_rows(out)
    assert 1 <= len(rows) < 6
    assert all(row['status'] == 'done' and row['point_id'] for row in rows)
    assert 're-run the same command to resume' in stderr
    assert point_processes() == []


def free_port() -> int:
    """A TCP port free on 127.0.0.1 right now."""
    import socket

    with socket.socket() as probe:
        probe.bind(('127.0.0.1', 0))
        return int(probe.getsockname()[1])


#: Two points, both done: the sweep run on a cluster started apart.
PAIR = GRID.replace('record: true', 'record: false').replace(f'{MASS}: [1.0, 20.0]',
                                                               f'{MASS}: [1.0]')
#: Wall-clock limit of a head node's start-up (s).
HEAD_START_S = 60.0


@dataclass
class RayHead:
    """A `ray start --head` of a test: its process, port, HOME and Ray temp dir."""

    process: subprocess.Popen[bytes]
    port: int
    home: Path
    temp_dir: Path


def command_environment(home: Path, **extra: str) -> dict[str, str]:
    """This environment without Ray's variables, with HOME, the project's sources and MARK.

    The local Ray of this module leaves RAY_AUTH_MODE=token (and RAY_CLIENT_MODE) here: the
    cluster tests' commands get only the Ray settings each test gives, as a user's would.
    """
    name, value = MARK.split('=')
    env = {key: text for key, text in os.environ.items() if not key.startswith('RAY_')}
    return {**env, 'HOME': str(home), 'PYTHONPATH': os.pathsep.join(p for p in sys.path if p),
            name: value, 'RAY_USAGE_STATS_ENABLED': '0', **extra}


def processes_of(temp_dir: Path) -> list[int]:
    """Pids of the processes whose command line names ``temp_dir`` (a head's Ray processes)."""
    pids = []
    for entry in Path('/proc').iterdir():
        try:
            if entry.name.isdigit() and str(temp_dir).encode() in (entry / 'cmdline').read_bytes():
                pids.append(int(entry.name))
        except OSError:
            continue
    return pids


@contextmanager
def ray_head(home: Path, **extra: str) -> Iterator[RayHead]:
    """`ray start --head` on 127.0.0.1 and a free port, 2 CPUs, stopped on exit.

    With HOME ``home`` (Ray's token file is $HOME/.ray/auth_token) and a Ray temp dir of its
    own (sessions, sockets, the address file), so that it meets no other Ray. It runs in the
    foreground (``--block``): SIGTERM to it stops exactly the processes it started, where
    `ray stop` would stop every Ray process on the machine, other tests' too.
    """
    port = free_port()
    temp_dir = Path(tempfile.mkdtemp(prefix='uvms-ray-', dir='/tmp'))  # socket paths <= 107
    ray_cli = Path(sys.executable).parent / 'ray'
    log = temp_dir / 'head.log'
    with log.open('wb') as file:
        process = subprocess.Popen(
            [str(ray_cli), 'start', '--head', '--block', '--node-ip-address=127.0.0.1',
             f'--port={port}', '--num-cpus=2', '--include-dashboard=false',
             f'--temp-dir={temp_dir}'], env=command_environment(home, **extra), stdout=file,
            stderr=subprocess.STDOUT)
    try:
        deadline = time.monotonic() + HEAD_START_S
        while not (temp_dir / 'ray_current_cluster').is_file():  # written once it runs
            assert process.poll() is None, log.read_text()
            assert time.monotonic() < deadline, log.read_text()
            time.sleep(0.2)
        yield RayHead(process, port, home, temp_dir)
    finally:
        process.send_signal(signal.SIGTERM)
        process.wait(timeout=PROCESS_TIMEOUT_S)
        deadline = time.monotonic() + 10.0
        while processes_of(temp_dir) and time.monotonic() < deadline:
            time.sleep(0.2)
        left = processes_of(temp_dir)
        for pid in left:
            os.kill(pid, signal.SIGKILL)
        shutil.rmtree(temp_dir, ignore_errors=True)
        assert left == [], f'Ray processes of {temp_dir} left after the head stopped'


@pytest.fixture(scope='module')
def token_head(tmp_path_factory: pytest.TempPathFactory) -> Iterator[RayHead]:
    """A head with Ray 2.60's default authentication where a token exists: token auth on.

    Its HOME holds ~/.ray/auth_token, written by `ray get-auth-token --generate` (as a first
    local `ray.init()`, `uvms sweep` without --address for one, would write it); `ray start`
    then turns token authentication on by itself. No RAY_AUTH_* variable is set.
    """
    home = tmp_path_factory.mktemp('head_home')
    subprocess.run([str(Path(sys.executable).parent / 'ray'), 'get-auth-token', '--generate'],
                   env=command_environment(home), capture_output=True, check=True,
                   timeout=PROCESS_TIMEOUT_S)
    with ray_head(home) as head:
        log = (head.temp_dir / 'head.log').read_text()
        assert 'Token authentication is enabled for this Ray cluster' in log, log
        yield head


def sweep_on(
    head: RayHead, out: Path, home: Path, **extra: str
) -> subprocess.CompletedProcess[str]:
    """`uvms sweep PAIR --address 127.0.0.1:PORT` run as a user would, with HOME ``home``."""
    path = write(out.parent, PAIR)
    return subprocess.run(
        [sys.executable, '-m', 'uvms_cli.cli', 'sweep', str(path), '--out', str(out),
         '--address', f'127.0.0.1:{head.port}', '--quiet'], capture_output=True, text=True,
        env=command_environment(home, **extra), timeout=PROCESS_TIMEOUT_S)


def test_address_joins_a_cluster_with_default_token_authentication(
    token_head: RayHead, tmp_path: Path
) -> None:
    """`--address` to a `ray start --head` with token auth: both points done there, head left up.

    The driver has only what a user on the head's machine has: ~/.ray/auth_token.
    """
    process = sweep_on(token_head, tmp_path / 'out', token_head.home)
    assert process.returncode == 0, process.stderr
    rows = read_rows(tmp_path / 'out')
    assert [row['status'] for row in rows] == ['done', 'done'], [row['reason'] for row in rows]
    assert token_head.process.poll() is None  # the cluster is the user's: still running
    assert point_processes() == []


def test_address_join_without_the_token_fails_naming_the_token_settings(
    token_head: RayHead, tmp_path: Path
) -> None:
    """A driver with no token (another HOME, no RAY_AUTH_*): exit 1, one line saying what to set.

    The head refuses every attempt alike, so one attempt instead of Ray's 20 (1 s apart).
    """
    home = tmp_path / 'home'
    home.mkdir()
    process = sweep_on(token_head, tmp_path / 'out', home, RAY_gcs_server_port_wait_time_s='1')
    assert process.returncode == 1, process.stderr
    errors = [line for line in process.stderr.splitlines() if 'uvms sweep: error' in line]
    assert errors == [process.stderr.strip().splitlines()[-1]], process.stderr
    (error,) = errors
    assert error.startswith(f'uvms sweep: error: cannot join the Ray cluster at '
                            f'127.0.0.1:{token_head.port}: it uses token authentication and '
                            'this driver has no token: '), error
    assert all(setting in error for setting in
               ('~/.ray/auth_token', 'RAY_AUTH_TOKEN=', 'RAY_AUTH_TOKEN_PATH=')), error
    assert not (tmp_path / 'out' / TABLE_NAME).exists()


def test_address_joins_a_cluster_without_authentication_though_a_token_is_here(
    token_head: RayHead, tmp_path: Path
) -> None:
    """A head with RAY_AUTH_MODE=disabled ignores the token the driver finds and sends."""
    with ray_head(token_head.home, RAY_AUTH_MODE='disabled') as head:
        process = sweep_on(head, tmp_path / 'out', token_head.home)
    assert process.returncode == 0, process.stderr
    rows = read_rows(tmp_path / 'out')
    assert [row['status'] for row in rows] == ['done', 'done'], [row['reason'] for row in rows]
    assert point_processes() == []
