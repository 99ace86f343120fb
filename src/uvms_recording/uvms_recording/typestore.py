"""rosbags typestore with the ROS 2 Jazzy interfaces plus our uvms_msgs, for MCAP schemas."""

from __future__ import annotations

import functools
import re
from pathlib import Path
from typing import TYPE_CHECKING

from rosbags.typesys import Stores, get_types_from_msg, get_typestore

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

#: Package whose .msg files are registered on top of the Jazzy store.
UVMS_MSGS_PACKAGE = 'uvms_msgs'

_TYPE_NAME = re.compile(r'^([A-Za-z][A-Za-z0-9_]*)/(?:msg/)?([A-Za-z][A-Za-z0-9_]*)$')


class InterfaceError(LookupError):
    """A message type, or the .msg files that define it, cannot be found."""


def normalize_type_name(type_name: str) -> str:
    """Return the ROS 2 form 'pkg/msg/Type' of 'pkg/msg/Type' or 'pkg/Type'.

    Raises:
        InterfaceError: The name has neither form.

    """
    match = _TYPE_NAME.match(type_name)
    if match is None:
        msg = f"message type name {type_name!r} is not of the form 'pkg/msg/Type'"
        raise InterfaceError(msg)
    return f'{match.group(1)}/msg/{match.group(2)}'


def _ament_share_msg_directory() -> Path | None:
    """uvms_msgs' msg directory from the ament index of a sourced ROS 2 install, if any."""
    try:
        from ament_index_python.packages import get_package_share_directory
    except ImportError:
        return None
    try:
        return Path(get_package_share_directory(UVMS_MSGS_PACKAGE)) / 'msg'
    except (LookupError, OSError, ValueError):
        # PackageNotFoundError is a KeyError; an unset AMENT_PREFIX_PATH is an OSError.
        return None


def uvms_msgs_directory() -> Path:
    """Directory holding the uvms_msgs .msg files.

    Looked up, in order: the ament index (share/uvms_msgs/msg of a sourced install, or of
    the venv the interfaces were built into), the source tree (src/uvms_msgs/msg next to
    this package).

    Raises:
        InterfaceError: None of these holds .msg files.

    """
    candidates = [
        _ament_share_msg_directory(),
        Path(__file__).resolve().parents[2] / UVMS_MSGS_PACKAGE / 'msg',
    ]
    tried: list[str] = []
    for candidate in candidates:
        if candidate is None:
            continue
        if candidate.is_dir() and any(candidate.glob('*.msg')):
            return candidate
        tried.append(str(candidate))
    msg = f'cannot find the {UVMS_MSGS_PACKAGE} .msg files; looked in: ' + ', '.join(tried)
    raise InterfaceError(msg)


@functools.cache
def uvms_typestore() -> Typestore:
    """Typestore with every ROS 2 Jazzy type (rosbags) and the uvms_msgs types.

    The instance is shared: read from it, do not register further types into it.

    Raises:
        InterfaceError: The uvms_msgs .msg files cannot be found.

    """
    store = get_typestore(Stores.ROS2_JAZZY)
    directory = uvms_msgs_directory()
    types = {}
    for path in sorted(directory.glob('*.msg')):
        type_name = f'{UVMS_MSGS_PACKAGE}/msg/{path.stem}'
        types.update(get_types_from_msg(path.read_text(encoding='utf-8'), type_name))
    store.register(types)
    return store


def _known_type(type_name: str) -> str:
    """Normalize type_name and check that the typestore knows it."""
    name = normalize_type_name(type_name)
    if name not in uvms_typestore().fielddefs:
        msg = (
            f'message type {type_name!r} is neither a ROS 2 Jazzy type nor one of '
            f'{UVMS_MSGS_PACKAGE} (in {uvms_msgs_directory()})'
        )
        raise InterfaceError(msg)
    return name


@functools.cache
def message_definition(type_name: str) -> str:
    """Full ros2msg schema text of a type with its dependencies, as rosbag2 stores it in MCAP.

    The type's own definition comes first, then each dependency once, each after a line of
    80 '=' and a line 'MSG: pkg/Type' (e.g. 'MSG: std_msgs/Header'), the delimiter that
    rosbag2_storage_mcap writes and Foxglove's ros2msg parser expects.

    Args:
        type_name: 'pkg/msg/Type' (or 'pkg/Type').

    Raises:
        InterfaceError: Unknown type.

    """
    text, _ = uvms_typestore().generate_msgdef(_known_type(type_name), ros_version=2)
    return text


@functools.cache
def type_hash(type_name: str) -> str:
    """Type description hash 'RIHS01_<sha256 hex>' of a type (REP-2011), as ROS 2 Jazzy reports it.

    Args:
        type_name: 'pkg/msg/Type' (or 'pkg/Type').

    Raises:
        InterfaceError: Unknown type.

    """
    return uvms_typestore().hash_rihs01(_known_type(type_name))
