"""``uvms identify plan``'s scenarios run unchanged with ``uvms run``; the fit reads them.

The recordings hold the robot's own topics (IMU, DVL, joint states, thrusts), which is
what ``uvms identify fit`` reads; never the ground truth.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pytest
from uvms_bringup.declared import check_scenario_overrides
from uvms_identify.recording import read_series
from uvms_identify.robot_data import load_robot
from uvms_scenarios.scenario import load_scenario

from uvms_cli import cli
from uvms_identify import cli as identify_cli

ROBOT = 'bluerov2_alpha5'


@pytest.fixture(scope='module')
def plan(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The shipped BlueROV2 Heavy's plan."""
    out = tmp_path_factory.mktemp('plan')
    parser = argparse.ArgumentParser()
    identify_cli.add_parser(parser.add_subparsers(dest='command'))
    assert identify_cli.run(parser.parse_args(
        ['identify', 'plan', '--robot', ROBOT, '--out', str(out)])) == 0
    return out


def test_every_planned_override_is_a_declared_parameter(plan: Path) -> None:
    """The nodes declare every parameter the planned scenarios set, with that type."""
    for path in sorted(plan.glob('identify_*.yaml')):
        check_scenario_overrides(load_scenario(path))


def test_a_planned_scenario_runs_and_its_recording_is_what_the_fit_reads(
        plan: Path, tmp_path: Path) -> None:
    """8 s of the surge experiment: the vehicle surges on the planned thrusts, open loop."""
    recording = tmp_path / 'surge.mcap'
    status = cli.main(['run', str(plan / 'identify_surge.yaml'), '--duration', '8',
                       '--output', str(recording), '--quiet'])
    assert status == 0
    robot = load_robot(ROBOT)
    series = read_series(recording, robot)
    assert series.t_s[-1] > 6.0
    surge = series.tau[:, 0]
    assert np.abs(surge).max() > 20.0  # the planned 27 N, then 54 N steps
    assert np.abs(series.nu[:, 0]).max() > 0.2  # it moved: open-loop thrust, not the hold
    # The surge force is steered by the plan's thrusts: forward while the step is positive.
    positive = (series.t_s > 1.5) & (series.t_s < 2.4)
    assert (series.nu[positive, 0] > 0.1).all()
