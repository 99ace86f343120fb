"""``uvms identify plan --level`` keeps the vehicle level: the trim, surge and sway.

Until 2026-12-07 the plan's surge experiment on the shipped BlueROV2 Heavy tumbled the
vehicle in the simulator alone (pitch 1.44 rad, roll 1.73 rad, the arm's joints swung over
-4.3..4.6 rad): nothing trimmed the arm's weight (0.19 rad pitch with every thruster at 0 N),
at 0.75 m/s the hull's Munk moment outgrew the restoring moment (statically unstable above
0.36 m/s), and the controller's arm reaches for its world-fixed hold point when the vehicle
moves. `--level` now trims and stays below the Munk speed; the arm is the controller's
(docs/identification.md, "Why the vehicle tumbles"), so the surge and sway check is an
expected failure until the controller holds the arm in joint space during a plan. The runs
are lockstep; the ground truth (``/uvms/odometry``) is read for the checks only.
"""

from __future__ import annotations

import argparse
import json
import os
import queue
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest
from numpy.typing import NDArray
from uvms_identify.known_terms import start_joints, trim_wrench
from uvms_identify.plan import MAX_EXCURSION, Experiment, scenario, trim_thrusts
from uvms_identify.robot_data import load_robot
from uvms_identify.signals import euler_zyx, quaternion_to_matrix
from uvms_recording.mcap_reader import open_recording
from uvms_recording.typestore import uvms_typestore

from uvms_identify import cli as identify_cli

ROBOT = 'bluerov2_alpha5'
UVMS = [sys.executable, '-c', 'import sys; from uvms_cli.cli import main; sys.exit(main())']
SECOND_DOMAIN_OFFSET = 36
#: Largest swing of any arm joint from its start angle (rad): the arm holds its pose.
MAX_JOINT_SWING_RAD = 0.5
#: The stated surge or sway excursion may be exceeded by this factor (the statement is the
#: axis alone; the recording has the arm, the coupling and the thrusters' lag).
EXCURSION_FACTOR = 1.5

pytestmark = pytest.mark.slow


def ground_truth(path: Path) -> tuple[NDArray[np.float64], NDArray[np.float64],
                                      NDArray[np.float64]]:
    """Positions (N, 3) and roll, pitch, yaw (N, 3) of /uvms/odometry; joints (M, n)."""
    recording = open_recording(path)
    typestore = uvms_typestore()
    wanted = {'/uvms/odometry', '/uvms/joint_states'}
    poses, quaternions, joints = [], [], []
    for message in recording.messages(wanted):
        msg = typestore.deserialize_cdr(message.data, message.type_name)
        if message.topic == '/uvms/odometry':
            p, o = msg.pose.pose.position, msg.pose.pose.orientation
            poses.append([p.x, p.y, p.z])
            quaternions.append([o.x, o.y, o.z, o.w])
        else:
            joints.append(list(msg.position))
    rpy = euler_zyx(quaternion_to_matrix(np.array(quaternions, float)))
    return np.array(poses, float), rpy, np.array(joints, float)


def stated_excursion(scenario: Path) -> float:
    """The excursion the scenario's description states (m)."""
    text = scenario.read_text(encoding='utf-8').replace('\n', ' ')
    after = text.split('excursion ', 1)[1]
    return float(after.split(' ', 1)[0])


@pytest.mark.timeout(300)
def test_the_planned_trim_holds_the_vehicle_level(tmp_path: Path,
                                                  module_ros_domain: int) -> None:
    """Every thruster at its trim for 5 s: level within 0.02 rad (no trim: 0.19 rad at 1 s).

    Only 5 s: after that, with the vehicle at rest, the controller's arm loop (its vehicle
    commands reach no thruster) grows in roll and yaw by itself, joints 1 and 4 with it
    (roll 0.014 rad at 6 s, 0.36 rad at 11 s): docs/identification.md.
    """
    robot = load_robot(ROBOT)
    trim = trim_thrusts(robot, trim_wrench(robot))
    rest = Experiment(0, np.zeros(1), np.zeros(1), trim[None, :], 0.0, 0.0)
    data = scenario(robot, rest, ROBOT, start_joints(robot, 4))
    data['duration_s'] = 5.0
    path = tmp_path / 'identify_trim.yaml'
    path.write_text(json.dumps(data), encoding='utf-8')  # JSON is YAML
    recording = tmp_path / 'trim.mcap'
    done = subprocess.run([*UVMS, 'run', str(path), '--output', str(recording), '--quiet'],
                          capture_output=True, text=True, timeout=280, check=False,
                          env={**os.environ, 'ROS_DOMAIN_ID': str(module_ros_domain)})
    assert done.returncode == 0, done.stderr[-2000:]
    _, rpy, joints = ground_truth(recording)
    assert np.abs(rpy[:, :2]).max() <= 0.02, np.abs(rpy[:, :2]).max(axis=0)
    assert np.abs(joints - joints[0]).max() <= 0.05


@pytest.mark.xfail(strict=True, reason=(
    'the controller reaches with the arm for its world-fixed hold point when the vehicle '
    'moves (0.2-0.3 rad of pitch per rad of joint 2): docs/identification.md, "Why the '
    'vehicle tumbles"; remove this mark once the controller holds the arm during a plan'))
@pytest.mark.timeout(900)
def test_surge_and_sway_stay_level_with_the_arm_still(tmp_path: Path,
                                                      module_ros_domain: int) -> None:
    """``--level``: |roll|, |pitch| within the plan's 0.35 rad, the arm within 0.5 rad.

    Measured 2026-12-07: surge pitch 0.58 rad, sway roll 0.72 rad (the old plan: 1.44 and
    1.73 rad in surge); joint swings of several radians.
    """
    parser = argparse.ArgumentParser()
    identify_cli.add_parser(parser.add_subparsers(dest='command'))
    plan = tmp_path / 'plan'
    assert identify_cli.run(parser.parse_args(
        ['identify', 'plan', '--robot', ROBOT, '--out', str(plan), '--level'])) == 0
    scenarios = [plan / 'identify_surge.yaml', plan / 'identify_sway.yaml']
    recordings = [tmp_path / f'{s.stem}.mcap' for s in scenarios]
    domains: queue.Queue[int] = queue.Queue()
    low, high = (int(x) for x in os.environ.get('UVMS_TEST_DOMAINS', '1-100').split('-'))
    domains.put(module_ros_domain)
    domains.put(low + (module_ros_domain - low + SECOND_DOMAIN_OFFSET) % (high - low + 1))

    def run(scenario: Path, recording: Path) -> subprocess.CompletedProcess[str]:
        domain = domains.get()
        try:
            return subprocess.run([*UVMS, 'run', str(scenario), '--output', str(recording),
                                   '--quiet'], capture_output=True, text=True, timeout=800,
                                  check=False, env={**os.environ, 'ROS_DOMAIN_ID': str(domain)})
        finally:
            domains.put(domain)

    with ThreadPoolExecutor(max_workers=2) as pool:
        for done in pool.map(run, scenarios, recordings):
            assert done.returncode == 0, done.stderr[-2000:]
    for axis, (planned, recording) in enumerate(zip(scenarios, recordings, strict=True)):
        positions, rpy, joints = ground_truth(recording)
        tilt = np.abs(rpy[:, :2]).max(axis=0)
        assert tilt[0] <= MAX_EXCURSION[3] and tilt[1] <= MAX_EXCURSION[4], (
            planned.name, 'roll, pitch', tilt)
        swing = np.abs(joints - joints[0]).max(axis=0)
        assert swing.max() <= MAX_JOINT_SWING_RAD, (planned.name, 'joint swing', swing)
        travel = float(np.abs(positions[:, axis] - positions[0, axis]).max())
        assert travel <= EXCURSION_FACTOR * stated_excursion(planned), (
            planned.name, travel, stated_excursion(planned))
