"""The rosbags type store of the interfaces we use: ROS 2 Jazzy plus our uvms_msgs.

Plain module: importing it neither activates the compat overlay nor imports any message
package, so recorders and plotting code can decode recordings without a ROS 2 install.
"""

from __future__ import annotations

import ast
import functools
import re
import threading
from pathlib import Path
from typing import TYPE_CHECKING

from rosbags.typesys import Stores, get_types_from_msg, get_typestore

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

_PACKAGE_DIR = Path(__file__).resolve().parent

#: Where the uvms_msgs .msg files are: inside an installed wheel (pyproject force-includes
#: them there), then the source tree (src/uvms_msgs/msg beside src/ros2_compat).
UVMS_MSGS_DIRS = (
    _PACKAGE_DIR / '_interfaces' / 'uvms_msgs' / 'msg',
    _PACKAGE_DIR.parent.parent / 'uvms_msgs' / 'msg',
)


#: Field default values of the Jazzy .msg files, which rosbags does not keep
#: (common_interfaces and rcl_interfaces, Jazzy branch). Keyed by (type, field).
JAZZY_DEFAULTS: dict[tuple[str, str], object] = {
    ('geometry_msgs/msg/Quaternion', 'x'): 0.0,
    ('geometry_msgs/msg/Quaternion', 'y'): 0.0,
    ('geometry_msgs/msg/Quaternion', 'z'): 0.0,
    ('geometry_msgs/msg/Quaternion', 'w'): 1.0,
    ('sensor_msgs/msg/NavSatStatus', 'status'): -2,
    ('rcl_interfaces/msg/ParameterDescriptor', 'read_only'): False,
    ('rcl_interfaces/msg/ParameterDescriptor', 'dynamic_typing'): False,
}

_lock = threading.Lock()
_defaults: dict[tuple[str, str], object] = dict(JAZZY_DEFAULTS)


class InterfaceNotFoundError(FileNotFoundError):
    """The uvms_msgs .msg files are neither installed nor in the source tree."""


def _ament_msg_dir() -> Path | None:
    """Return share/uvms_msgs/msg of a sourced ROS 2 workspace, if there is one."""
    try:
        from ament_index_python.packages import get_package_share_directory
    except ImportError:
        return None
    try:
        return Path(get_package_share_directory('uvms_msgs')) / 'msg'
    except (LookupError, OSError, ValueError):
        return None


def uvms_msgs_dir() -> Path:
    """Return the directory holding the uvms_msgs .msg files.

    Looked up in an installed wheel, the source tree, then a sourced ROS 2 workspace.

    Raises:
        InterfaceNotFoundError: None of them has the files.
    """
    for candidate in (*UVMS_MSGS_DIRS, _ament_msg_dir()):
        if candidate is not None and candidate.is_dir() and any(candidate.glob('*.msg')):
            return candidate
    tried = ', '.join(str(path) for path in UVMS_MSGS_DIRS)
    msg = f'uvms_msgs .msg files not found (looked in {tried})'
    raise InterfaceNotFoundError(msg)


_FIELD_LINE = re.compile(r'^\s*([A-Za-z][\w/]*(?:<=\d+)?(?:\[[^\]]*\])?)\s+([a-z]\w*)\s+(\S.*)$')


def _parse_msg_defaults(text: str) -> dict[str, object]:
    """Return the default values of the fields of one .msg text (`float64 w 1.0` lines)."""
    defaults: dict[str, object] = {}
    for raw in text.splitlines():
        line = raw.split('#', 1)[0].rstrip()
        match = _FIELD_LINE.match(line)
        if not match or '=' in line:
            continue
        typ, name, literal = match.groups()
        literal = literal.strip()
        if typ == 'bool':
            defaults[name] = literal.lower() in {'true', '1'}
        elif typ.startswith('string') and not typ.endswith(']'):
            defaults[name] = ast.literal_eval(literal) if literal[0] in '"\'' else literal
        else:
            value = ast.literal_eval(literal.replace('true', 'True').replace('false', 'False'))
            if typ.startswith('float'):
                value = float(value)
            defaults[name] = value
    return defaults


def field_default(typename: str, field: str) -> object | None:
    """Return the .msg default value of a field, or None when the field has none."""
    uvms_typestore()
    return _defaults.get((typename, field))


@functools.cache
def uvms_typestore() -> Typestore:
    """Return a rosbags type store with every ROS 2 Jazzy type plus uvms_msgs registered.

    The store is built once per process and shared: treat it as read-only.

    Returns:
        The type store; ``store.types`` and ``store.fielddefs`` are keyed by 'pkg/msg/Type'.
    """
    with _lock:
        store = get_typestore(Stores.ROS2_JAZZY)
        directory = uvms_msgs_dir()
        for path in sorted(directory.glob('*.msg')):
            typename = f'uvms_msgs/msg/{path.stem}'
            text = path.read_text(encoding='utf-8')
            store.register(get_types_from_msg(text, typename))
            for field, value in _parse_msg_defaults(text).items():
                _defaults[(typename, field)] = value
        return store


def message_names(package: str) -> list[str]:
    """Return the sorted 'pkg/msg/Type' names of one package's messages in the store."""
    prefix = f'{package}/msg/'
    return sorted(name for name in uvms_typestore().fielddefs if name.startswith(prefix))
