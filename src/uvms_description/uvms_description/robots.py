"""Robot folders: find them, check that their files exist, read their parameter files.

A robot is a folder ``robots/<name>/`` of the share directory (docs/robots.md, "Adding a
robot"). Its URDF (``robot.urdf``, or ``robot.urdf.xacro`` expanded here with the PyPI
``xacro`` package) and ``hydrodynamics.yaml`` are read by ``uvms_model.description``; its
``thrusters.yaml``, ``sensor.yaml``, ``controller.yaml``, ``navigation.yaml`` and ``start.yaml``
(its default start: the simulator's ``initial.*``) are ROS 2 parameter files whose values a
node takes as its defaults (``robot_parameters``). Pure Python: no rclpy.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from uvms_description import DEFAULT_ROBOT, robots_directory

URDF_FILES = ('robot.urdf', 'robot.urdf.xacro')
"""A robot's URDF: exactly one of these."""
HYDRODYNAMICS_FILE = 'hydrodynamics.yaml'
START_FILE = 'start.yaml'
"""The robot's default start: the simulator's ``initial.*`` where a scenario sets none."""
START_PREFIX = 'initial.'
PARAMETER_FILES = ('thrusters.yaml', 'sensor.yaml', 'controller.yaml', 'navigation.yaml',
                   START_FILE)
"""The robot's ROS 2 parameter files, in the order their values are merged."""
DEVICE_TIMING_FILE = 'device_timing.yaml'
"""Optional: the robot's device timing (the simulator's ``devices.*``); none: ideal devices."""
OPTIONAL_PARAMETER_FILES = (DEVICE_TIMING_FILE,)
"""Parameter files a robot folder may have, merged after ``PARAMETER_FILES`` when present."""
_NAME = re.compile(r'^[A-Za-z_][A-Za-z0-9_]*$')
_SECTION = re.compile(r'^(/\*\*|/\*\*/(?P<node>[A-Za-z_][A-Za-z0-9_]*))$')


class RobotFolderError(ValueError):
    """A robot folder is unknown, incomplete or holds a file that cannot be read."""


@dataclass(frozen=True)
class RobotFiles:
    """The files of one robot folder, all present.

    Attributes:
        name: The robot's name (its folder's name).
        directory: The folder.
        urdf: ``robot.urdf`` or ``robot.urdf.xacro``.
        hydrodynamics: ``hydrodynamics.yaml``.
        parameter_files: ``thrusters.yaml``, ``sensor.yaml``, ``controller.yaml``,
            ``navigation.yaml``, ``start.yaml``, then ``device_timing.yaml`` if present.
    """

    name: str
    directory: Path
    urdf: Path
    hydrodynamics: Path
    parameter_files: tuple[Path, ...]


@dataclass(frozen=True)
class RobotParameter:
    """One value of a robot's parameter files and the file that gives it."""

    value: Any
    source: Path


def robot_names(directory: Path | None = None) -> tuple[str, ...]:
    """Names of the robot folders, sorted (every sub-folder with a valid name)."""
    root = directory if directory is not None else robots_directory()
    if not root.is_dir():
        return ()
    return tuple(sorted(p.name for p in root.iterdir() if p.is_dir() and _NAME.match(p.name)))


def robot_files(name: str = DEFAULT_ROBOT, directory: Path | None = None) -> RobotFiles:
    """The files of robot ``name``, checked to exist.

    Args:
        name: The robot's folder name under ``robots/``, or a path to a robot folder
            anywhere (any name with a ``/``: ``./my_robot``, ``/data/robots/mine``).
        directory: Folder of the robot folders (``robots_directory()`` if None).

    Raises:
        RobotFolderError: An unknown robot (the message lists the known ones), or a folder
            without one of its files; the message names the folder and the file.
    """
    if '/' in name:
        folder = Path(name).expanduser().resolve()
        if not folder.is_dir():
            raise RobotFolderError(f'{folder}: no such robot folder')
        name = folder.name
    else:
        root = directory if directory is not None else robots_directory()
        known = robot_names(root)
        if name not in known:
            msg = (f"unknown robot {name!r}: the robots in {root} are "
                   f"{', '.join(known) if known else '(none)'}")
            raise RobotFolderError(msg)
        folder = root / name
    urdfs = [folder / f for f in URDF_FILES if (folder / f).is_file()]
    if len(urdfs) != 1:
        which = 'both' if urdfs else 'neither'
        joiner = ' and ' if urdfs else ' nor '
        msg = f'{folder}: the folder of robot {name!r} has {which} {joiner.join(URDF_FILES)}'
        raise RobotFolderError(msg)
    for file in (HYDRODYNAMICS_FILE, *PARAMETER_FILES):
        if not (folder / file).is_file():
            msg = f'{folder / file}: missing file of robot {name!r} (docs/robots.md)'
            raise RobotFolderError(msg)
    optional = tuple(folder / f for f in OPTIONAL_PARAMETER_FILES if (folder / f).is_file())
    return RobotFiles(name, folder, urdfs[0], folder / HYDRODYNAMICS_FILE,
                      (*(folder / f for f in PARAMETER_FILES), *optional))


def urdf_text(path: Path) -> str:
    """The URDF of ``path`` as text; a ``.xacro`` file is expanded first (no arguments).

    Raises:
        RobotFolderError: The file cannot be read or the xacro expansion fails.
    """
    if path.suffix != '.xacro':
        try:
            return path.read_text(encoding='utf-8')
        except OSError as exc:
            msg = f'{path}: cannot read the URDF: {exc.strerror or exc}'
            raise RobotFolderError(msg) from exc
    import xacro  # type: ignore[import-untyped]

    try:
        document = xacro.process_file(str(path))
    except Exception as exc:  # xacro raises XacroException, OSError, ExpatError, ...
        text = str(exc).replace('\n', ' ')
        msg = f'{path}: xacro expansion failed: {type(exc).__name__}: {text}'
        raise RobotFolderError(msg) from exc
    return str(document.toprettyxml(indent='  '))


def parameter_file_values(path: Path, node: str) -> dict[str, RobotParameter]:
    """Flat dotted parameter values of a ROS 2 parameter file for node ``node``.

    Sections ``/**`` apply to every node, ``/**/<node>`` to that node; values of the node's
    own section win over ``/**``.

    Raises:
        RobotFolderError: Unreadable YAML, a section of another form, or a section without
            a ``ros__parameters`` mapping; the message names the file and the section.
    """
    try:
        tree = yaml.safe_load(path.read_text(encoding='utf-8'))
    except OSError as exc:
        raise RobotFolderError(f'{path}: cannot read: {exc.strerror or exc}') from exc
    except yaml.YAMLError as exc:
        text = str(exc).replace('\n', ' ')
        raise RobotFolderError(f'{path}: malformed YAML: {text}') from exc
    if tree is None:
        return {}
    if not isinstance(tree, Mapping):
        raise RobotFolderError(f'{path}: expected a mapping of sections (/**: ...)')
    common: dict[str, RobotParameter] = {}
    own: dict[str, RobotParameter] = {}
    for section, body in tree.items():
        match = _SECTION.match(str(section))
        if match is None:
            msg = (f'{path}: section {section!r}: expected /** (every node) or /**/<node> '
                   '(docs/robots.md)')
            raise RobotFolderError(msg)
        if not isinstance(body, Mapping) or not isinstance(body.get('ros__parameters'), Mapping):
            msg = f'{path}: section {section!r}: expected a ros__parameters mapping'
            raise RobotFolderError(msg)
        if set(body) != {'ros__parameters'}:
            msg = f'{path}: section {section!r}: only ros__parameters is allowed, got {list(body)}'
            raise RobotFolderError(msg)
        target = match.group('node')
        if target is None:
            _flatten(body['ros__parameters'], '', common, path)
        elif target == node:
            _flatten(body['ros__parameters'], '', own, path)
    return {**common, **own}


def robot_parameters(
    name: str = DEFAULT_ROBOT, node: str = '', directory: Path | None = None
) -> dict[str, RobotParameter]:
    """The values a node takes as defaults from robot ``name``'s parameter files.

    Every value of ``thrusters.yaml``, ``sensor.yaml``, ``controller.yaml``,
    ``navigation.yaml``, ``start.yaml`` and ``device_timing.yaml`` (if present) for ``node``
    (flat dotted names). The URDF and
    hydrodynamics paths are not among them (a recording would carry this machine's paths):
    ``with_description_paths`` fills them in.

    Raises:
        RobotFolderError: See ``robot_files`` and ``parameter_file_values``; also a name given
            by two of the files, a start parameter (``initial.*``) outside ``start.yaml`` or
            another parameter in it.
    """
    files = robot_files(name, directory)
    values: dict[str, RobotParameter] = {}
    for path in files.parameter_files:
        for key, item in parameter_file_values(path, node).items():
            if (path.name == START_FILE) != key.startswith(START_PREFIX):
                msg = (f'{path}: parameter {key!r}: the start parameters ({START_PREFIX}*) '
                       f'belong in {START_FILE}, and only they (docs/robots.md)')
                raise RobotFolderError(msg)
            if key in values:
                msg = f'{path}: parameter {key!r} is also given by {values[key].source}'
                raise RobotFolderError(msg)
            values[key] = item
    return values


def robot_start(name: str = DEFAULT_ROBOT, directory: Path | None = None) -> dict[str, Any]:
    """Robot ``name``'s default start: the simulator's ``initial.*`` values of ``start.yaml``.

    Raises:
        RobotFolderError: See ``robot_parameters``.
    """
    return {key: item.value for key, item in robot_parameters(name, 'simulator', directory).items()
            if key.startswith(START_PREFIX)}


def with_description_paths(values: Mapping[str, Any], name: str = DEFAULT_ROBOT,
                           directory: Path | None = None) -> dict[str, Any]:
    """``values`` with empty ``description.*_path`` entries set to robot ``name``'s files.

    A path given explicitly (``description.urdf_path``, ``description.hydrodynamics_path``)
    is kept.

    Raises:
        RobotFolderError: See ``robot_files``.
    """
    files = robot_files(name, directory)
    filled = dict(values)
    for key, path in (('description.urdf_path', files.urdf),
                      ('description.hydrodynamics_path', files.hydrodynamics)):
        if not filled.get(key):
            filled[key] = str(path)
    return filled


def _flatten(tree: Mapping[Any, Any], prefix: str, out: dict[str, RobotParameter],
             path: Path) -> None:
    """Nested mappings as dotted names, each value with its file."""
    for key, value in tree.items():
        if not isinstance(key, str) or not _NAME.match(key):
            raise RobotFolderError(f'{path}: parameter name {prefix}{key!r} is not a name')
        if isinstance(value, Mapping):
            _flatten(value, f'{prefix}{key}.', out, path)
        else:
            out[f'{prefix}{key}'] = RobotParameter(value, path)
