"""``uvms identify fit`` on recordings: the robot's own topics in, its hull terms out.

The recordings are made by the robot folder's own model (``synthetic_recordings``), noise
free, with IMU, DVL (10 Hz), depth, joint states and thrusts: what the robot records.
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import numpy as np
import pytest
import synthetic_recordings as synthetic
import yaml
from uvms_identify.errors import IdentifyError
from uvms_identify.identify import identify
from uvms_identify.recording import read_series
from uvms_identify.regressor import PARAMETER_NAMES
from uvms_identify.robot_data import RobotData, load_robot
from uvms_model.hydrodynamics_file import read_hydrodynamics

from uvms_identify import cli

ROBOT = 'bluerov2_alpha5'


@pytest.fixture(scope='module')
def robot() -> RobotData:
    """The shipped BlueROV2 Heavy + Alpha 5 folder."""
    return load_robot(ROBOT)


@pytest.fixture(scope='module')
def run(robot: RobotData) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """20 s of every axis excited, the shipped hull: times, thrusts and states."""
    t, thrusts = synthetic.excitation(robot, 20.0)
    return t, thrusts, synthetic.simulate(robot, dict(robot.hull), t, thrusts)


@pytest.fixture(scope='module')
def recording(robot: RobotData, run: tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]],
              tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The run recorded, noise free."""
    return synthetic.write(tmp_path_factory.mktemp('identify') / 'all_axes.mcap', robot, *run)


def test_a_noise_free_recording_gives_the_well_excited_terms_back(robot: RobotData,
                                                                  recording: Path) -> None:
    """Every term the fit calls well determined is within 5 % of the model that made the data.

    (Only the smoothing differentiator of the 10 Hz DVL stands between the data and the
    model; the synthetic regressor test recovers them exactly.)
    """
    result = identify([recording], robot, predict=False)
    truth = robot.prior_theta()
    well = [j for j in range(len(PARAMETER_NAMES)) if result.fit.well_determined(j)]
    assert len(well) >= 14, result.fit.status
    for j in well:
        assert abs(result.fit.theta[j] - truth[j]) <= 0.05 * abs(truth[j]), PARAMETER_NAMES[j]
    assert (result.fit.theta[:19] >= 0.0).all()


def test_holes_in_the_imu_are_left_out_not_interpolated_across(
        robot: RobotData, run: tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]],
        tmp_path: Path) -> None:
    """A recorder that fell behind: four 0.4 s holes in the IMU, named and left out.

    Interpolated across, the holes smoothed the accelerations: 6 terms well determined, the
    pitch added mass -7 %.
    """
    holes = [(start, start + 0.4) for start in (2.0, 7.0, 12.0, 17.0)]
    path = synthetic.write(tmp_path / 'holes.mcap', robot, *run, holes_s={'/uvms/imu': holes})
    series = read_series(path, robot)
    assert series.gaps_s == pytest.approx({'IMU (attitude, rates)': 1.6}, abs=0.05)
    result = identify([path], robot, predict=False)
    assert result.gaps_s == series.gaps_s
    truth = robot.prior_theta()
    well = [j for j in range(len(PARAMETER_NAMES)) if result.fit.well_determined(j)]
    assert len(well) >= 14, result.fit.status
    for j in well:
        assert abs(result.fit.theta[j] - truth[j]) <= 0.05 * abs(truth[j]), PARAMETER_NAMES[j]


def test_a_recording_all_holes_is_refused_naming_the_signal(
        robot: RobotData, run: tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]],
        tmp_path: Path) -> None:
    """Holes every second: no 2 s stretch has every signal; the refusal names the IMU's."""
    holes = [(start, start + 0.3) for start in np.arange(0.5, 20.0, 1.0)]
    path = synthetic.write(tmp_path / 'holes.mcap', robot, *run,
                           holes_s={'/uvms/imu': holes})
    with pytest.raises(IdentifyError, match=r'time in gaps: IMU \(attitude, rates\) 5\.\d s'):
        identify([path], robot, predict=False)


def test_fit_writes_a_hydrodynamics_file_the_robot_folder_takes(
        robot: RobotData, recording: Path, tmp_path: Path,
        capsys: pytest.CaptureFixture[str]) -> None:
    """The CLI's fit: hydrodynamics.yaml readable by uvms_model, report and figures beside."""
    parser = argparse.ArgumentParser()
    cli.add_parser(parser.add_subparsers(dest='command'))
    out = tmp_path / 'fit'
    args = parser.parse_args(['identify', 'fit', str(recording), '--robot', ROBOT,
                              '--out', str(out)])
    assert cli.run(args) == 0
    hull, links = read_hydrodynamics(out / 'hydrodynamics.yaml', 'base_link_frd',
                                     ('link_1', 'link_2', 'link_3', 'link_4'))
    assert hull.added_mass == 'coefficients' and len(links) == 4
    text = (out / 'hydrodynamics.yaml').read_text(encoding='utf-8')
    assert str(recording) in text and 'commit' in text
    report = (out / 'report.md').read_text(encoding='utf-8')
    assert 'held-out 10 s' in report and '95 % CI' in report
    assert list(out.glob('*.png'))
    assert 'terms identified' in capsys.readouterr().out


@pytest.mark.parametrize(('topics', 'duration_s', 'thrust', 'expected'), [
    (('/uvms/imu', '/uvms/joint_states', '/uvms/command/actuators'), 8.0, 1.0,
     'not in the recording: dvl (DVL velocity)'),
    (tuple(synthetic.TOPICS), 3.0, 1.0, 'too short'),
    (tuple(synthetic.TOPICS), 8.0, 0.0, 'no excitation'),
])
def test_a_bad_recording_is_refused_in_one_line_naming_what_is_missing(
        robot: RobotData, tmp_path: Path, topics: tuple[str, ...], duration_s: float,
        thrust: float, expected: str, capsys: pytest.CaptureFixture[str]) -> None:
    """Missing topic, too short, no excitation: refused, the file and the cause named."""
    t, thrusts = synthetic.excitation(robot, duration_s)
    thrusts *= thrust
    states = synthetic.simulate(robot, dict(robot.hull), t, thrusts)
    path = synthetic.write(tmp_path / 'bad.mcap', robot, t, thrusts, states, topics)
    with pytest.raises(IdentifyError, match=re.escape(expected)) as error:
        read_series(path, robot)
    assert '\n' not in str(error.value) and str(path) in str(error.value)
    parser = argparse.ArgumentParser()
    cli.add_parser(parser.add_subparsers(dest='command'))
    args = parser.parse_args(['identify', 'fit', str(path), '--robot', ROBOT,
                              '--out', str(tmp_path / 'out')])
    assert cli.run(args) == 2
    assert capsys.readouterr().err.count('\n') == 1


def test_plan_writes_scenarios_within_the_thrust_limits(robot: RobotData, tmp_path: Path) -> None:
    """One scenario per axis, each valid, at most 60 s, every thrust within the limits."""
    from uvms_scenarios.scenario import load_scenario
    from uvms_thrusters.thruster_faults import parse_faults

    parser = argparse.ArgumentParser()
    cli.add_parser(parser.add_subparsers(dest='command'))
    assert cli.run(parser.parse_args(['identify', 'plan', '--robot', ROBOT, '--out',
                                      str(tmp_path)])) == 0
    paths = sorted(tmp_path.glob('identify_*.yaml'))
    assert [p.stem for p in paths] == sorted(
        f'identify_{a}' for a in ('surge', 'sway', 'heave', 'roll', 'pitch', 'yaw'))
    for path in paths:
        scenario = load_scenario(path)
        assert scenario.duration_s <= 60.0 and scenario.robot == ROBOT
        assert 'expected' in scenario.description.lower() and 'excursion' in scenario.description
        faults = parse_faults(scenario.overrides['thruster_allocator']
                              ['fault_injection.thrusters'], 8)
        values = np.array([f.value for f in faults])
        assert all(f.kind == 'stuck' for f in faults)
        assert np.all(np.abs(values) <= robot.max_thrust_n[0])
        assert {f.index for f in faults if f.at_s == 0.0} == set(range(8))
    data = yaml.safe_load(paths[0].read_text(encoding='utf-8'))
    assert data['simulator']['navigation']['enabled'] is True
