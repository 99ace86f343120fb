"""Issue 50's acceptance through the twin stand: the hull identified from the bridges' data.

The same altered copy of bluerov2_alpha5 as ``test_identify_acceptance`` (its hull's added
mass and damping changed by 30-50 %, buoyancy by 2 N) plays the user's robot, but the plan's
experiments run with ``uvms launch --hardware twin --robot PATH`` at real-time factor 1: the
thrusts go out as RC overrides through the ArduSub bridge to its twin (PWM, the T200 curve, the
thrusters' dynamics), the IMU, depth and DVL come back through their bridges at the devices'
rates and stamped on arrival, the controller runs on the estimate. ``uvms identify fit``'s
core fits the *shipped* folder to those recordings, and the terms these axes excite well must
be within 20 % of the copy's. The recordings must be the bridges' (the IMU at the ArduSub
stream's rate, not the simulator's 200 Hz): a broken twin path, or recordings of the
simulator's own sensors, fail here. Plan, two 43 s runs at factor 1 and the fit: 2 min 30 s
on the 2-core machine at load average 8-10 (2026-12-06; 4 min 7 s with the held-out
prediction, which the test leaves out): marked slow.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
from test_identify_acceptance import ROBOT, UVMS, altered_robot, write_plan
from uvms_identify.identify import identify
from uvms_identify.regressor import PARAMETER_NAMES
from uvms_identify.robot_data import load_robot
from uvms_recording.mcap_reader import open_recording

AXES = ('roll', 'yaw')
#: The terms these two experiments excite well through the twin stand (docs/identification.md,
#: "Through the twin stand"), each within 20 % of the altered copy's value. Not the roll's
#: quadratic damping: -5.7 % in one pair of runs, unidentifiable (1.5 +- 0.79) in another.
CHECKED = ('added_mass_roll', 'added_mass_yaw', 'quadratic_damping_yaw', 'buoyancy_n',
           'buoyancy_moment_x_n_m')
TOLERANCE = 0.2
#: Above this IMU rate the recording holds the simulator's IMU (200 Hz), not the ArduSub
#: bridge's stream (imu_rate_hz 50, RAW_IMU as it arrives).
BRIDGE_IMU_MAX_HZ = 80.0

pytestmark = pytest.mark.slow


def imu_rate_hz(recording: Path) -> float:
    """Messages per second on the recording's IMU topic."""
    info = open_recording(recording).topics['/uvms/imu']
    return info.message_count / 43.0


@pytest.mark.timeout(900)
def test_the_twin_stand_recordings_recover_the_hull(tmp_path: Path,
                                                    module_ros_domain: int) -> None:
    """Roll and yaw through the twins: the terms they excite well within 20 % of the truth."""
    folder = altered_robot(tmp_path)
    plan = write_plan(tmp_path / 'plan')
    recordings = []
    for axis in AXES:
        recording = tmp_path / f'{axis}.mcap'
        done = subprocess.run([*UVMS, 'launch', str(plan / f'identify_{axis}.yaml'),
                               '--hardware', 'twin', '--robot', str(folder),
                               '--output', str(recording), '--quiet'],
                              capture_output=True, text=True, timeout=300, check=False)
        assert done.returncode == 0, done.stderr[-2000:]
        assert imu_rate_hz(recording) < BRIDGE_IMU_MAX_HZ, "the IMU is not the bridge's"
        recordings.append(recording)
    # The terms only (the held-out prediction is the simulator acceptance's check): all data.
    result = identify(recordings, load_robot(ROBOT), predict=False)
    truth = load_robot(str(folder)).prior_theta()
    shipped = load_robot(ROBOT).prior_theta()
    # What the recordings lost (left out of the fit), for a failure's message.
    lost = f'gaps left out: {result.gaps_s}'
    for name in CHECKED:
        j = PARAMETER_NAMES.index(name)
        assert result.fit.identified(j), (name, result.fit.status[j], lost)
        assert abs(result.fit.theta[j] - truth[j]) <= TOLERANCE * abs(truth[j]), (
            name, result.fit.theta[j], truth[j], lost)
        # The altered hull reached the simulator behind the twins: nearer it than the shipped.
        assert abs(result.fit.theta[j] - truth[j]) < abs(result.fit.theta[j] - shipped[j]), (
            name, result.fit.theta[j], truth[j], shipped[j], lost)
