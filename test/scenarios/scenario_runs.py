"""Recorded runs of the paper's scenarios for the scenario tests, each run at most once.

A scenario run is the whole node graph in lockstep (``uvms run SCENARIO --output F.mcap``),
recorded to MCAP in a session temporary directory and read back with
``uvms_analysis.series``. The runs are CPU-bound Python, so they go to separate processes:
when the first scenario fixture is requested, every scenario that the selected tests need is
started, at most ``WORKERS`` at a time in the order the tests use them, and each fixture
then waits only for its own run.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from uvms_analysis.metrics import RunMetrics, compute_metrics
from uvms_analysis.series import Run, load_run

SCENARIO_DIR = Path(__file__).resolve().parents[2] / 'config' / 'scenarios'
#: Concurrent scenario processes: the CI machine has two cores.
WORKERS = 2
#: Wall-clock limit of one scenario run (s); a 20 s run takes about 15 s on one core.
RUN_TIMEOUT_S = 600.0
#: Simulated duration per scenario where a test needs less than the scenario file's (s).
#: hybrid_only touches the wall 0.45 s after its task starts (t = 2 s: the mission's start)
#: and its claim is about the first 0.5 s of contact.
#: The current scenarios (issue 30) need contact, settling and some force tracking: first
#: touch at 8.05 s, settled within 1 s, released at about 12.4 s. idle_wall holds for an hour.
SHORTENED_S = {'hybrid_only': 5.0, 'case1_current': 14.0, 'bluerov2_alpha5_current': 14.0,
               'idle_wall': 5.0}
#: ROS domains of the scenario runs (each run gets the next one): the range tools/run_suite.py
#: gives the scenario group's lane (UVMS_TEST_DOMAINS, ``LOW-HIGH``; a lane runs one group at
#: a time), else 71-100. Never above 100: a domain's ports are 7400 + 250 d + ..., and from
#: d = 102 on they fall in Linux's ephemeral range, where the tests' UDP sockets live.
SCENARIO_DOMAINS = tuple(int(x) for x in os.environ.get('UVMS_TEST_DOMAINS', '71-100').split('-'))


@dataclass(frozen=True)
class ScenarioResult:
    """One recorded scenario run and its metrics.

    Attributes:
        name: Scenario name (file stem in config/scenarios).
        path: The MCAP recording.
        run: Its series (``uvms_analysis.series.load_run``).
        metrics: Its metrics (``uvms_analysis.metrics.compute_metrics``).
    """

    name: str
    path: Path
    run: Run
    metrics: RunMetrics


class ScenarioRuns:
    """Scenario runs of one session, started in worker processes, read on demand."""

    def __init__(self, directory: Path, wanted: list[str]) -> None:
        self.directory = directory
        self._pending = list(wanted)
        self._running: dict[str, subprocess.Popen[bytes]] = {}
        self._exit_status: dict[str, int] = {}
        self._done: dict[str, ScenarioResult] = {}
        self._domains = 0
        self._start_more()

    def get(self, name: str) -> ScenarioResult:
        """The run of a scenario; started now if no selected test announced it."""
        if name in self._done:
            return self._done[name]
        if name not in self._running and name not in self._exit_status:
            if name in self._pending:
                self._pending.remove(name)
            self._running[name] = self._start(name)
        deadline = time.monotonic() + RUN_TIMEOUT_S
        while name not in self._exit_status:
            if time.monotonic() > deadline:
                msg = f'uvms run {name} took longer than {RUN_TIMEOUT_S} s'
                raise TimeoutError(msg)
            time.sleep(0.1)
            self._reap()
        if self._exit_status[name] != 0:
            log = self._path(name).with_suffix('.log').read_text(errors='replace')[-2000:]
            msg = f'uvms run {name} failed with exit status {self._exit_status[name]}:\n{log}'
            raise RuntimeError(msg)
        run = load_run(self._path(name))
        self._done[name] = ScenarioResult(name, self._path(name), run, compute_metrics(run))
        return self._done[name]

    def close(self) -> None:
        """Stop runs that no test asked for (a session ended early)."""
        for process in self._running.values():
            process.kill()
            process.wait()
        self._running.clear()
        self._pending.clear()

    def _reap(self) -> None:
        """Collect finished runs and start pending ones in the freed slots."""
        for name, process in list(self._running.items()):
            status = process.poll()
            if status is not None:
                self._exit_status[name] = status
                del self._running[name]
        self._start_more()

    def _path(self, name: str) -> Path:
        return self.directory / f'{name}.mcap'

    def _start_more(self) -> None:
        while self._pending and len(self._running) < WORKERS:
            name = self._pending.pop(0)
            self._running[name] = self._start(name)

    def _start(self, name: str) -> subprocess.Popen[bytes]:
        command = [sys.executable, '-m', 'uvms_cli.cli', 'run',
                   str(SCENARIO_DIR / f'{name}.yaml'), '--output', str(self._path(name)),
                   '--quiet']
        if name in SHORTENED_S:
            command += ['--duration', str(SHORTENED_S[name])]
        # The child finds the sources as this process does (pytest's pythonpath setting).
        # A DDS domain of its own: two lockstep graphs in one domain would hear each other's
        # commands (same node names, same stamps from t = 0).
        self._domains += 1
        env = {**os.environ, 'PYTHONPATH': os.pathsep.join(p for p in sys.path if p),
               'ROS_DOMAIN_ID': str(SCENARIO_DOMAINS[0] + self._domains % (
                   SCENARIO_DOMAINS[1] - SCENARIO_DOMAINS[0] + 1))}
        with self._path(name).with_suffix('.log').open('wb') as log:
            return subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT, env=env)


def first_force_peak(result: ScenarioResult) -> tuple[float, float]:
    """The first local maximum of the true normal force after the first touch: (delay s, N).

    The transient of the touch, wherever it ends: an impact spike that falls back before
    the force builds up, or the set-point overshoot if the force rises without one. A
    sample counts if it is at least its predecessor and above its successor (flat tops
    count once). The simulator's ground truth carries no noise, so no smoothing is needed.
    """
    contact = result.run.contact
    assert contact is not None
    touch = int(np.flatnonzero(contact.in_contact)[0])
    force = contact.force[touch:, 0]
    rising = (force[1:-1] >= force[:-2]) & (force[1:-1] > force[2:])
    peaks = np.flatnonzero(rising) + 1
    assert peaks.size, f'{result.name}: the force has no local maximum after the touch'
    k = int(peaks[0])
    return float(contact.t[touch + k] - contact.t[touch]), float(force[k])
