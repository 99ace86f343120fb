"""ROS 2 parameter files on every point of a sweep: ``params_files:`` and ``--params-file``.

As ``uvms run --params-file``: the files' values reach every point's run over the base
scenario's, later files win, the axes come over them, and every name is checked against what
the nodes declare before any point runs; a wrong file, section or name stops the sweep naming
the sweep file's key or the option's file.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest
from uvms_bringup.declared import declared_parameters
from uvms_scenarios.scenario import ScenarioError
from uvms_sweep.engine import point_request, sweep_points
from uvms_sweep.ideal_devices import with_ideal_devices
from uvms_sweep.sweep_file import SweepError, load_sweep
from uvms_sweep.validate import check_sweep

from uvms_description import robots_directory
from uvms_sweep import cli as sweep_cli
from uvms_sweep import validate

REPO = Path(__file__).resolve().parents[3]
TIMED = """\
/**/simulator:
  ros__parameters:
    devices:
      ideal: false
"""
SWEEP = """\
name: t
scenario: bluerov2_alpha5_contact
duration_s: 0.5
params_files: [timed.yaml, robots/bluerov2_alpha5/controller_device_timing.yaml]
axes:
  simulator.devices.thrusts.rate_hz: [25, 50.0]
metrics: [force_rms_error_N]
"""


@pytest.fixture(scope='module')
def declared() -> dict[str, Any]:
    """What the nodes declare, read once (each read builds every node)."""
    return declared_parameters()


@pytest.fixture(autouse=True)
def _declared_once(declared: dict[str, Any], monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    monkeypatch.setattr(validate, 'declared_parameters', lambda: declared)
    yield


def write(directory: Path, text: str, name: str) -> Path:
    """A file of this text in the directory."""
    path = directory / name
    path.write_text(text, encoding='utf-8')
    return path


def test_params_files_resolve_beside_the_sweep_file_and_in_the_robot_folders(
    tmp_path: Path,
) -> None:
    """A relative entry is the sweep file's neighbour; robots/NAME/FILE a robot folder's file."""
    write(tmp_path, TIMED, 'timed.yaml')
    sweep = load_sweep(write(tmp_path, SWEEP, 'sweep.yaml'))
    assert sweep.params_files == (
        tmp_path / 'timed.yaml',
        robots_directory() / 'bluerov2_alpha5' / 'controller_device_timing.yaml')


def test_every_point_gets_the_files_values_under_its_axes(tmp_path: Path) -> None:
    """devices.ideal false and the controller's held-slot keys reach each point's request."""
    write(tmp_path, TIMED, 'timed.yaml')
    write(tmp_path, '/**/simulator:\n  ros__parameters:\n    devices:\n      thrusts:\n'
                    '        rate_hz: 400.0\n', 'thrusts.yaml')
    sweep, scenario = check_sweep(load_sweep(write(tmp_path, SWEEP, 'sweep.yaml')))
    point = sweep.points(scenario.name, 0.5, scenario.seed)[0]
    overrides = point_request(sweep, scenario, point, 0.5)['overrides']
    assert overrides['simulator']['devices.ideal'] is False
    assert overrides['controller']['arm.command_rate_hz'] == 77.0
    assert overrides['controller']['arm.force_latency_s'] == 0.002
    assert overrides['simulator']['devices.thrusts.rate_hz'] == 25.0  # the axis wins


def test_params_file_option_applies_after_the_sweep_files(tmp_path: Path) -> None:
    """`uvms sweep --params-file`: later than params_files, so its values win."""
    write(tmp_path, TIMED, 'timed.yaml')
    again = write(tmp_path, TIMED.replace('false', 'true'), 'ideal.yaml')
    _, scenario = check_sweep(load_sweep(write(tmp_path, SWEEP, 'sweep.yaml')), [again])
    assert scenario.overrides['simulator']['devices.ideal'] is True


def test_a_points_key_holds_what_the_files_and_ideal_devices_set(tmp_path: Path) -> None:
    """Other parameter files or --ideal-devices: other keys, so a resume runs the points again.

    A sweep without either keeps the keys it always had (its done points stay done).
    """
    write(tmp_path, TIMED, 'timed.yaml')
    plain_text = SWEEP.replace(
        'params_files: [timed.yaml, robots/bluerov2_alpha5/controller_device_timing.yaml]\n', '')
    plain, plain_scenario = check_sweep(load_sweep(write(tmp_path, plain_text, 'plain.yaml')))
    timed, timed_scenario = check_sweep(load_sweep(write(tmp_path, SWEEP, 'sweep.yaml')))
    faster = write(tmp_path, TIMED + '      arm_commands:\n        rate_hz: 100.0\n',
                   'faster.yaml')
    _, faster_scenario = check_sweep(load_sweep(tmp_path / 'sweep.yaml'), [faster])
    ideal_scenario = replace(plain_scenario,
                             overrides=with_ideal_devices(plain_scenario.overrides))

    def keys(sweep: Any, scenario: Any) -> list[str]:
        return [point.point_id for point in sweep_points(sweep, scenario)]

    unchanged = [p.point_id for p in plain.points(plain_scenario.name, 0.5, plain_scenario.seed)]
    assert keys(plain, plain_scenario) == unchanged
    runs = [keys(plain, plain_scenario), keys(timed, timed_scenario),
            keys(timed, faster_scenario), keys(plain, ideal_scenario)]
    assert len({key for run in runs for key in run}) == 4 * len(unchanged)


def test_shipped_device_rates_sweep_runs_with_device_timing() -> None:
    """config/sweeps/device_rates.yaml: device timing on every point, with the controller's keys.

    Its axes changed nothing while device timing stayed off (devices.ideal true).
    """
    sweep, scenario = check_sweep(load_sweep(REPO / 'config' / 'sweeps' / 'device_rates.yaml'))
    assert scenario.overrides['simulator']['devices.ideal'] is False
    assert scenario.overrides['controller']['arm.command_rate_hz'] > 0.0
    assert len(sweep.points(scenario.name, 1.0, scenario.seed)) == 20


@pytest.mark.parametrize(('entry', 'expected'), [
    ('[missing.yaml]', "key 'params_files[0]': no file 'missing.yaml'"),
    ('[robots/no_robot/x.yaml]', "key 'params_files[0]': no file 'robots/no_robot/x.yaml'"),
    ('timed.yaml', "key 'params_files'"),
    ('[]', "key 'params_files'"),
    ('[timed.yaml, 3]', "key 'params_files[1]'"),
])
def test_bad_params_files_entry_names_the_key(tmp_path: Path, entry: str, expected: str) -> None:
    """A missing file or a value that is not a list of paths: the sweep file and the key."""
    write(tmp_path, TIMED, 'timed.yaml')
    text = SWEEP.replace(
        '[timed.yaml, robots/bluerov2_alpha5/controller_device_timing.yaml]', entry)
    path = write(tmp_path, text, 'sweep.yaml')
    with pytest.raises(SweepError) as error:
        load_sweep(path)
    assert str(path) in str(error.value)
    assert expected in str(error.value)


@pytest.mark.parametrize(('text', 'expected'), [
    ('/**/simulator:\n  ros__parameters:\n    devices:\n      idael: false\n',
     "section '/**/simulator': the simulator node has no parameter 'devices.idael'; "
     'did you mean devices.ideal'),
    ('/**/simulator:\n  ros__parameters:\n    devices:\n      ideal: 3\n',
     "section '/**/simulator': devices.ideal: expected bool"),
    ('/**/planner:\n  ros__parameters:\n    gain: 1.0\n',
     "section '/**/planner' matches no node of the run"),
    ('just text\n', 'expected a ROS 2 parameter file'),
])
def test_bad_params_file_is_refused_naming_the_key_file_and_section(
    tmp_path: Path, text: str, expected: str,
) -> None:
    """A name the nodes do not declare, a wrong type, a section for no node: refused."""
    timed = write(tmp_path, text, 'timed.yaml')
    path = write(tmp_path, SWEEP, 'sweep.yaml')
    with pytest.raises(ScenarioError) as error:
        check_sweep(load_sweep(path))
    assert f"{path}: key 'params_files[0]' ({timed})" in str(error.value)
    assert expected in str(error.value)


def test_bad_params_file_option_stops_uvms_sweep_before_any_point(
    tmp_path: Path, capsys: pytest.CaptureFixture[str],
) -> None:
    """`uvms sweep --params-file` with a name no node declares: exit 2, the file named."""
    write(tmp_path, TIMED, 'timed.yaml')
    sweep = write(tmp_path, SWEEP, 'sweep.yaml')
    bad = write(tmp_path, '/**/controller:\n  ros__parameters:\n    arm:\n      rate: 1.0\n',
                'bad.yaml')
    status = sweep_cli.main([str(sweep), '--out', str(tmp_path / 'out'), '-q',
                             '--params-file', str(bad)])
    assert status == sweep_cli.EXIT_USAGE
    err = capsys.readouterr().err
    assert f"--params-file {bad}: section '/**/controller': the controller node has no " \
           "parameter 'arm.rate'" in err
    assert not (tmp_path / 'out').exists()
