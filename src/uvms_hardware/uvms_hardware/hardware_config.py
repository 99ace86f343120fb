"""The ``ardusub`` and ``dvl`` sections of a robot folder's ``hardware.yaml``, read as plain data.

``hardware.yaml`` is not a ROS parameter file: each bridge reads its own top-level section
here and turns it into its parameters' defaults; ``-p`` and parameter files still win.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from uvms_hardware.errors import HardwareError

#: The file in each robot folder (``uvms_description/robots/<name>/``).
HARDWARE_FILE = 'hardware.yaml'


def robot_folder(robot_name: str) -> Path:
    """The folder of robot ``robot_name`` (uvms_description's robots/<name>/)."""
    from uvms_description.robots import robot_files

    return robot_files(robot_name).directory


def hardware_section(robot_name: str, section: str, folder: Path | None = None) -> dict[str, Any]:
    """Section ``section`` of the robot's ``hardware.yaml`` as a dict.

    Raises:
        HardwareError: No such file or section, or YAML that does not parse (message names
            the file).
    """
    path = (folder if folder is not None else robot_folder(robot_name)) / HARDWARE_FILE
    try:
        tree = yaml.safe_load(path.read_text(encoding='utf-8'))
    except (OSError, yaml.YAMLError) as exc:
        raise HardwareError(f'{path}: cannot read: {exc}') from exc
    if not isinstance(tree, dict) or not isinstance(tree.get(section), dict):
        raise HardwareError(f'{path}: no mapping {section!r} at the top level')
    return dict(tree[section])


@dataclass(frozen=True)
class Spec:
    """A bridge parameter: name, default, description with its unit, valid range."""

    name: str
    default: Any
    description: str
    min_value: float | None = None
    max_value: float | None = None
