"""The tuned gains as a ROS 2 parameter file with their provenance, and ``--apply``.

The file is the controller's section of a ROS 2 parameter file (``/**/controller:
ros__parameters:`` with nested names, as robots/NAME/controller.yaml), loadable by
``controller --ros-args --params-file FILE``; its ``ros__parameters`` mapping is also what a
scenario's ``controller:`` section takes. The provenance (tune file, trial, every scenario's
figures, stability margin, git commit) is in its header comments, and whole in
``provenance.json`` beside it: a ROS 2 parameter file has no place for other keys.
"""

from __future__ import annotations

import datetime
import json
import subprocess
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import yaml

#: The tuned gains in the output folder.
GAINS_FILE = 'tuned_gains.yaml'
#: Their provenance in full (JSON).
PROVENANCE_FILE = 'provenance.json'
#: The tuned gains in a robot folder (``--apply``), beside the hand-tuned controller.yaml.
ROBOT_TUNED_FILE = 'controller_tuned.yaml'


def git_commit(directory: Path) -> str:
    """The commit checked out at ``directory`` (with ``-dirty``), or 'unknown'."""
    try:
        commit = subprocess.run(['git', 'describe', '--always', '--dirty', '--abbrev=12'],
                                cwd=directory, capture_output=True, text=True, check=True,
                                timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return 'unknown'
    return commit or 'unknown'


def nested(values: Mapping[str, Any]) -> dict[str, Any]:
    """Flat dotted names to nested mappings, as a parameter file writes them."""
    tree: dict[str, Any] = {}
    for name in sorted(values):
        node = tree
        *parents, leaf = name.split('.')
        for part in parents:
            node = node.setdefault(part, {})
        node[leaf] = values[name]
    return tree


def parameter_file_text(values: Mapping[str, Any], provenance: Mapping[str, Any]) -> str:
    """The parameter file: provenance as comments, then ``/**/controller: ros__parameters``."""
    lines = ['# Controller gains tuned by `uvms tune` (docs/tuning.md). ROS 2 parameter file:',
             '#   controller --ros-args --params-file THIS_FILE',
             "# or paste the ros__parameters mapping under a scenario's `controller:` section.",
             f"# robot: {provenance['robot']}; tune file: {provenance['tune_file']}",
             f"# trial {provenance['trial']} of {provenance['trials']}, objective "
             f"{provenance['objective']:.6g}, stability margin "
             f"{provenance['stability_margin']:.4g} (1 - largest spectral radius)",
             f"# commit {provenance['commit']}, written {provenance['written_utc']}",
             '# training figures (RMS force error N, overshoot %, settling s):']
    for figure in provenance['figures']:
        lines.append(f"#   {figure['label']}: {_fmt(figure.get('force_rms_error_N'))}, "
                     f"{_fmt(figure.get('overshoot_percent'))}, "
                     f"{_fmt(figure.get('settling_time_s'))}")
    lines.append(f"# full provenance: {PROVENANCE_FILE} of the tune's output folder")
    body = yaml.safe_dump({'/**/controller': {'ros__parameters': nested(values)}},
                          sort_keys=False, default_flow_style=None, width=99)
    return '\n'.join(lines) + '\n' + body


def _fmt(value: Any) -> str:
    return 'n/a' if value is None else f'{float(value):.4g}'


def write_gains(out_dir: Path, values: Mapping[str, Any],
                provenance: Mapping[str, Any]) -> Path:
    """Write the parameter file and provenance.json into ``out_dir``; the file's path."""
    full = {**provenance, 'controller': dict(values),
            'written_utc': datetime.datetime.now(datetime.UTC).strftime('%Y-%m-%dT%H:%M:%SZ')}
    path = out_dir / GAINS_FILE
    path.write_text(parameter_file_text(values, full), encoding='utf-8')
    (out_dir / PROVENANCE_FILE).write_text(json.dumps(full, indent=2, default=str) + '\n',
                                           encoding='utf-8')
    return path


def apply_to_robot(gains_file: Path, robot_directory: Path) -> Path:
    """Copy the tuned parameter file into the robot folder, beside (never over) controller.yaml.

    Returns:
        robots/NAME/controller_tuned.yaml.
    """
    target = robot_directory / ROBOT_TUNED_FILE
    target.write_text(gains_file.read_text(encoding='utf-8'), encoding='utf-8')
    return target


def read_gains(path: Path) -> dict[str, Any]:
    """The flat controller parameters of a parameter file written by ``write_gains``."""
    tree = yaml.safe_load(path.read_text(encoding='utf-8'))
    flat: dict[str, Any] = {}

    def walk(node: Mapping[str, Any], prefix: str) -> None:
        for key, value in node.items():
            if isinstance(value, Mapping):
                walk(value, f'{prefix}{key}.')
            else:
                flat[f'{prefix}{key}'] = value

    walk(tree['/**/controller']['ros__parameters'], '')
    return flat
