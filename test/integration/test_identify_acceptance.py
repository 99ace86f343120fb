"""Issue 50's acceptance: identify a robot whose hull is not the robot folder's model.

A copy of bluerov2_alpha5 with its hull's added mass and damping changed by 30-50 % and its
buoyancy by 2 N plays the user's robot: the plan of the *shipped* folder runs on it with
``uvms run --robot PATH``, and ``uvms identify fit`` fits the shipped folder to the
recordings. Every term the report calls well determined must be within 10 % of the copy's
value, and the held-out 10 s prediction error at most half the shipped model's on every
axis. About 6 minutes of CPU (six 43 s runs, two at a time, and the fit):
marked slow.
"""

from __future__ import annotations

import argparse
import os
import queue
import shutil
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest
import yaml
from uvms_identify.identify import identify
from uvms_identify.regressor import PARAMETER_NAMES
from uvms_identify.robot_data import load_robot

from uvms_description.robots import robot_files
from uvms_identify import cli as identify_cli

ROBOT = 'bluerov2_alpha5'
#: `uvms` of this interpreter (the module's entry point works in a bare checkout too).
UVMS = [sys.executable, '-c', 'import sys; from uvms_cli.cli import main; sys.exit(main())']
ADDED_MASS_FACTOR = (1.4, 0.65, 1.3, 1.5, 0.7, 1.35)
LINEAR_FACTOR = (1.3, 1.0, 0.65, 1.0, 1.4, 1.0)  # the shipped zeros stay zero
QUADRATIC_FACTOR = (0.6, 1.4, 0.65, 1.3, 1.5, 0.7)
BUOYANCY_CHANGE_N = 2.0
#: The second concurrent run's ROS domain: the module's plus this, within the lane's range
#: (UVMS_TEST_DOMAINS; never above 100: those domains' ports are in the ephemeral range, where
#: a participant can take a UDP socket's datagrams from a test running beside).
SECOND_DOMAIN_OFFSET = 35

pytestmark = pytest.mark.slow


def altered_robot(directory: Path) -> Path:
    """The shipped folder copied with its hull changed."""
    folder = directory / 'bluerov2_altered'
    shutil.copytree(robot_files(ROBOT).directory, folder)
    path = folder / 'hydrodynamics.yaml'
    tree = yaml.safe_load(path.read_text(encoding='utf-8'))
    hull = tree['base_link_frd']
    shipped = load_robot(ROBOT)
    buoyancy = shipped.hull_buoyancy_n() + BUOYANCY_CHANGE_N
    del hull['buoyancy_ratio']
    hull['added_mass_kg'] = [a * f for a, f in zip(hull['added_mass_kg'], ADDED_MASS_FACTOR,
                                                   strict=True)]
    hull['linear_damping'] = [d * f for d, f in zip(hull['linear_damping'], LINEAR_FACTOR,
                                                    strict=True)]
    hull['quadratic_damping'] = [d * f for d, f in zip(hull['quadratic_damping'],
                                                       QUADRATIC_FACTOR, strict=True)]
    hull['displaced_volume_m3'] = buoyancy / (shipped.water_density_kg_m3
                                              * shipped.gravity_m_s2)
    path.write_text(yaml.safe_dump(tree, sort_keys=False), encoding='utf-8')
    return folder


def write_plan(out: Path) -> Path:
    """``uvms identify plan --robot ROBOT --out OUT`` through the CLI's own parser; ``out``."""
    parser = argparse.ArgumentParser()
    identify_cli.add_parser(parser.add_subparsers(dest='command'))
    assert identify_cli.run(parser.parse_args(
        ['identify', 'plan', '--robot', ROBOT, '--out', str(out)])) == 0
    return out


@pytest.mark.timeout(1800)  # six runs and the fit: about 10 min on 2 loaded cores
def test_the_plan_on_another_robot_recovers_its_hull(tmp_path: Path,
                                                     module_ros_domain: int) -> None:
    """Well-determined terms within 10 %, the 10 s prediction error halved or better."""
    folder = altered_robot(tmp_path)
    plan = write_plan(tmp_path / 'plan')
    scenarios = sorted(plan.glob('identify_*.yaml'))
    recordings = [tmp_path / f'{scenario.stem}.mcap' for scenario in scenarios]

    # Two at a time, each on a ROS domain of its own (two graphs on one domain answer each
    # other's states): lockstep runs are deterministic whatever else the cores do, and the
    # experiments are independent (as a user may run them on two machines).
    domains: queue.Queue[int] = queue.Queue()
    low, high = (int(x) for x in os.environ.get('UVMS_TEST_DOMAINS', '1-100').split('-'))
    second = low + (module_ros_domain - low + SECOND_DOMAIN_OFFSET) % (high - low + 1)
    for domain in (module_ros_domain, second):
        domains.put(domain)

    def run(scenario: Path, recording: Path) -> subprocess.CompletedProcess[str]:
        # One `uvms run` process per experiment, as a user runs them (in one process, the
        # fourth run of a sequence once diverged where the same run alone did not).
        domain = domains.get()
        try:
            return subprocess.run([*UVMS, 'run', str(scenario), '--robot', str(folder),
                                   '--output', str(recording), '--quiet'],
                                  capture_output=True, text=True, timeout=900, check=False,
                                  env={**os.environ, 'ROS_DOMAIN_ID': str(domain)})
        finally:
            domains.put(domain)

    with ThreadPoolExecutor(max_workers=2) as pool:
        for done in pool.map(run, scenarios, recordings):
            assert done.returncode == 0, done.stderr[-2000:]
    result = identify(recordings, load_robot(ROBOT))
    truth = load_robot(str(folder)).prior_theta()
    well = [j for j in range(len(PARAMETER_NAMES)) if result.fit.well_determined(j)]
    assert len(well) >= 5, result.fit.status
    for j in well:
        assert abs(result.fit.theta[j] - truth[j]) <= 0.1 * abs(truth[j]), (
            PARAMETER_NAMES[j], result.fit.theta[j], truth[j])
    identified = result.errors[('identified', 10.0)]
    current = result.errors[('current', 10.0)]
    # Every axis: at most half the shipped model's error (pitch and yaw since the predictor
    # integrates the attitude: docs/identification.md, "Held-out prediction").
    for axis in range(6):
        assert identified[axis] <= 0.5 * current[axis], (axis, identified, current)
    assert np.all(result.errors[('identified', 1.0)] <= result.errors[('current', 1.0)])
