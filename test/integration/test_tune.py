"""`uvms tune` end to end: a tiny tune on a local Ray, its gains file, report and figures.

Two trials of one gain (K_fp) on one 12 s contact run of the BlueROV2 + Alpha 5, every run a
genuine lockstep graph (rclpy, Fast DDS on loopback) through the sweep's point runner. One
local Ray serves the module, started with PYTHONPATH set to this checkout's sources so that
its workers and their point processes import this worktree, not an installed copy.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from uvms_sweep.batch import PointBatches
from uvms_sweep.engine import start_local_ray
from uvms_tune.driver import Tuner
from uvms_tune.output import read_gains
from uvms_tune.tune_file import load_tune_file

from uvms_tune import cli as tune_cli

TINY = Path(__file__).resolve().parents[2] / 'config' / 'tunes' / 'tiny.yaml'
FIGURES = ('force_rms_error_N', 'overshoot_percent', 'settling_time_s')

pytestmark = pytest.mark.slow


@pytest.fixture(scope='module')
def local_ray() -> Iterator[Any]:
    """One local Ray with 2 CPUs whose workers import this checkout."""
    saved = dict(os.environ)
    os.environ['PYTHONPATH'] = os.pathsep.join(p for p in sys.path if p)
    ray = start_local_ray(2)
    try:
        yield ray
    finally:
        ray.shutdown()
        os.environ.clear()
        os.environ.update(saved)


@pytest.fixture(scope='module')
def tiny(local_ray: Any, tmp_path_factory: pytest.TempPathFactory) -> tuple[int, Path]:
    """The tiny tune run once through the command: its exit status and output folder."""
    out = tmp_path_factory.mktemp('tiny') / 'out'
    status = tune_cli.main([str(TINY), '--out', str(out), '--quiet'])
    return status, out


def test_tiny_tune_writes_gains_report_and_figures(tiny: tuple[int, Path]) -> None:
    """Exit 0; the parameter file, provenance, report table and three figures exist."""
    status, out = tiny
    assert status == 0
    assert 'hybrid.force_kp' in read_gains(out / 'tuned_gains.yaml')
    report = (out / 'report.md').read_text(encoding='utf-8')
    for row in ('| defaults | train |', '| hand_tuned | train |', '| tuned | train |'):
        assert row in report
    for name in ('best_objective.png', 'gains.png', 'force.png'):
        assert (out / 'figures' / name).stat().st_size > 0
    provenance = json.loads((out / 'provenance.json').read_text(encoding='utf-8'))
    assert provenance['trials'] == 2 and provenance['stability_margin'] > 0.0


def test_the_best_gains_reproduce_the_reported_figures(tiny: tuple[int, Path]) -> None:
    """The gains read back from the file, run again, give the provenance's figures."""
    _, out = tiny
    provenance = json.loads((out / 'provenance.json').read_text(encoding='utf-8'))
    tune = load_tune_file(TINY)
    with PointBatches(workers=2) as batches:
        tuner = Tuner(tune, out, batches.run, resume=True)
        figures = tuner.run_scenarios(read_gains(out / 'tuned_gains.yaml'), tune.train)
    for reported, again in zip(provenance['figures'], figures, strict=True):
        assert again.reason == ''
        for key in FIGURES:
            assert again.metrics[key] == pytest.approx(reported[key], rel=1e-6, abs=1e-9)
    for reported, again in zip(provenance['figures'], provenance['rerun_figures'], strict=False):
        for key in FIGURES:
            assert again[key] == pytest.approx(reported[key], rel=1e-6, abs=1e-9)


def test_the_tiny_report_states_what_it_lacks_and_its_reproduction(
        tiny: tuple[int, Path]) -> None:
    """Ground-truth force on every run, no held-out runs said so, the rerun reproduced."""
    _, out = tiny
    provenance = json.loads((out / 'provenance.json').read_text(encoding='utf-8'))
    report = (out / 'report.md').read_text(encoding='utf-8')
    assert [f['force_source'] for f in provenance['figures']] == ['contact']
    assert '**No held-out runs**' in report and '| held-out |' not in report
    assert provenance['rerun_differences'] == []
    assert "gave the trial's J, reason and figures again" in report


def test_a_finished_tune_resumed_runs_no_more_trials(tiny: tuple[int, Path]) -> None:
    """--resume on a tune that reached its budget asks nothing and keeps its trials."""
    _, out = tiny
    calls: list[Any] = []
    tuner = Tuner(load_tune_file(TINY), out, lambda r, t: calls.append(r) or [], resume=True)
    tuner.run(2)
    assert calls == [] and len(tuner.finished()) == 2


def _complete_trials(out: Path) -> list[tuple[dict[str, float], float]]:
    """(params, value) of the finished trials of the study in ``out``, in order."""
    import optuna
    from optuna.storages import JournalStorage
    from optuna.storages.journal import JournalFileBackend
    from optuna.trial import TrialState

    storage = JournalStorage(JournalFileBackend(str(out / 'journal.log')))
    study = optuna.load_study(study_name='tiny', storage=storage)
    return [(t.params, float(t.value or 0.0))
            for t in study.get_trials(states=(TrialState.COMPLETE,))]


def test_ctrl_c_then_resume_ends_where_an_uninterrupted_tune_does(
        tiny: tuple[int, Path], tmp_path: Path) -> None:
    """SIGINT after the first trial: exit 130; --resume finishes the same trials as `tiny`."""
    out = tmp_path / 'cut'
    command = [sys.executable, '-m', 'uvms_tune.cli', str(TINY), '--out', str(out), '--quiet']
    env = {**os.environ, 'PYTHONPATH': os.pathsep.join(p for p in sys.path if p)}
    process = subprocess.Popen(command, env=env, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 240.0
    while time.monotonic() < deadline and process.poll() is None:
        if (out / 'journal.log').exists() and len(_complete_trials(out)) >= 1:
            break
        time.sleep(0.5)
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=120)
    assert process.returncode == 130, stderr
    assert '--resume' in stderr
    resumed = subprocess.run([*command, '--resume'], env=env, capture_output=True, text=True,
                             timeout=400, check=False)
    assert resumed.returncode == 0, resumed.stderr
    assert _complete_trials(out) == _complete_trials(tiny[1])
