"""``uvms run --params-file``: tuned gains go in without pasting them into a scenario (issue 52).

Each run is a fraction of a simulated second in lockstep, on a ROS domain of this module.
"""

from __future__ import annotations

import os
import random
import subprocess
import sys
from pathlib import Path

import yaml
from uvms_common.ros_environment import ros_environment_defaults
from uvms_recording.mcap_reader import open_recording

ros_environment_defaults()

BIN = Path(sys.executable).parent
DOMAIN_ID = random.SystemRandom().randint(141, 180)
TIMEOUT_S = 240.0


def uvms(*args: str) -> subprocess.CompletedProcess[str]:
    """Run ``uvms`` on this module's domain."""
    env = {**os.environ, 'ROS_DOMAIN_ID': str(DOMAIN_ID)}
    return subprocess.run([str(BIN / 'uvms'), *args], capture_output=True, text=True, env=env,
                          timeout=TIMEOUT_S, check=False)


def test_params_files_set_the_nodes_parameters_later_files_winning(tmp_path: Path) -> None:
    """Two files (the second a wildcard one): the recorded controller parameters are theirs."""
    first = tmp_path / 'tuned.yaml'
    first.write_text('/**/controller:\n  ros__parameters:\n'
                     '    hybrid: {force_kp: 0.25, force_ki: 0.05}\n', encoding='utf-8')
    second = tmp_path / 'override.yaml'
    second.write_text('/**:\n  ros__parameters:\n    hybrid: {force_ki: 0.07}\n',
                      encoding='utf-8')
    output = tmp_path / 'run.mcap'
    result = uvms('run', 'free_motion', '--duration', '0.1', '-q', '--output', str(output),
                  '--params-file', str(first), '--params-file', str(second))
    assert result.returncode == 0, result.stderr[-3000:]
    parameters = yaml.safe_load(open_recording(output).metadata['uvms']['parameters'])
    hybrid = parameters['/uvms/controller']['ros__parameters']['hybrid']
    assert (hybrid['force_kp'], hybrid['force_ki']) == (0.25, 0.07)


def test_a_misspelt_gain_in_a_params_file_is_bad_usage_naming_it(tmp_path: Path) -> None:
    """Exit 2 before anything runs; the line names the file, the name and the closest one."""
    path = tmp_path / 'typo.yaml'
    path.write_text('/**/controller:\n  ros__parameters:\n    hybrid: {force_kpp: 0.25}\n',
                    encoding='utf-8')
    result = uvms('run', 'free_motion', '--duration', '0.1', '--params-file', str(path))
    assert result.returncode == 2
    assert result.stderr.strip().splitlines()[-1] == (
        f"uvms run: error: --params-file {path}: section '/**/controller': the controller node "
        "has no parameter 'hybrid.force_kpp'; did you mean hybrid.force_kp, hybrid.force_ki, "
        'hybrid.force_kd?')
