"""ROS 2 parameter YAML with the typing rules of rcl_yaml_param_parser.

rcl reads parameter files and ``-p name:=value`` with its own scalar typing, which differs from
YAML 1.1 as PyYAML implements it: ``y``/``n`` are booleans, ``1e3`` is a double, ``1_000`` and
``null`` are strings, integers are read by ``strtoll(..., 0)`` (so ``010`` is octal 8), quoted
scalars are always strings, and a sequence must hold scalars of one type. PyYAML is used for the
syntax only (it reports line and column of syntax errors); the typing is done here.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import yaml

from rclpy.impl.implementation_singleton import RCLError

#: A parameter value as rcl produces it.
ParameterValue = bool | int | float | str | list[bool] | list[int] | list[float] | list[str]

_TRUE = frozenset(('Y', 'y', 'yes', 'Yes', 'YES', 'true', 'True', 'TRUE', 'on', 'On', 'ON'))
_FALSE = frozenset(('N', 'n', 'no', 'No', 'NO', 'false', 'False', 'FALSE', 'off', 'Off', 'OFF'))
_YAML_SPECIAL_FLOATS = frozenset(
    prefix + word
    for prefix in ('', '+', '-')
    for word in ('.nan', '.NaN', '.NAN', '.inf', '.Inf', '.INF')
)
_STR_TAG = 'tag:yaml.org,2002:str'
_C_INT = re.compile(r'[ \t\n\v\f\r]*([+-]?)(0[xX][0-9a-fA-F]+|0[0-7]*|[1-9][0-9]*)')
_C_DECIMAL_FLOAT = re.compile(
    r'[ \t\n\v\f\r]*[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?'
)
_C_HEX_FLOAT = re.compile(
    r'[ \t\n\v\f\r]*[+-]?0[xX](?:[0-9a-fA-F]+\.?[0-9a-fA-F]*|\.[0-9a-fA-F]+)(?:[pP][+-]?[0-9]+)?'
)
_C_INF_NAN = re.compile(r'[ \t\n\v\f\r]*[+-]?(?:inf(?:inity)?|nan(?:\([0-9A-Za-z_]*\))?)', re.I)
_INT64_MIN = -(2**63)
_INT64_MAX = 2**63 - 1
_TYPE_NAMES = {bool: 'bool', int: 'integer', float: 'double', str: 'string'}


@dataclass(frozen=True)
class ParameterOverride:
    """One parameter value from a parameter file or ``-p``, and where it came from."""

    value: ParameterValue
    source: str


class ParameterYamlError(RCLError):
    """A parameter file or ``-p`` value that rcl would refuse."""


def _c_int(text: str) -> int | None:
    """Parse like C ``strtoll(text, &end, 0)`` requiring the whole text; None if it fails."""
    match = _C_INT.fullmatch(text)
    if match is None:
        return None
    sign, digits = match.groups()
    if digits.startswith(('0x', '0X')):
        value = int(digits[2:], 16)
    elif digits.startswith('0') and len(digits) > 1:
        value = int(digits[1:], 8)
    else:
        value = int(digits)
    if sign == '-':
        value = -value
    if not _INT64_MIN <= value <= _INT64_MAX:
        return None  # strtoll sets ERANGE: rcl then tries a double
    return value


def _c_double(text: str) -> float | None:
    """Parse like C ``strtod`` requiring the whole text; None if it fails or is out of range."""
    if text in _YAML_SPECIAL_FLOATS:
        value = float(text.lstrip('+-').lstrip('.'))
        return -value if text.startswith('-') else value
    stripped = text.strip(' \t\n\v\f\r')
    if _C_DECIMAL_FLOAT.fullmatch(text):
        if not any(c.isdigit() for c in stripped):
            return None
        value = float(stripped)
    elif _C_HEX_FLOAT.fullmatch(text):
        body = stripped.lstrip('+-')
        if 'p' not in body.lower():
            body += 'p0'
        value = float.fromhex(body)
        if stripped.startswith('-'):
            value = -value
    elif _C_INF_NAN.fullmatch(text):
        word = stripped.lstrip('+-').lower()
        value = math.nan if word.startswith('nan') else math.inf
        if stripped.startswith('-'):
            value = -value
        return value
    else:
        return None
    if math.isinf(value):
        return None  # ERANGE
    if value == 0.0 and any(c in '123456789' for c in stripped.split('e')[0].split('E')[0]):
        return None  # underflow to zero: ERANGE
    return value


def _explicit_str_tag(loader: yaml.SafeLoader, node: yaml.ScalarNode) -> bool:
    if node.tag != _STR_TAG or node.style is not None:
        return False
    return loader.resolve(yaml.ScalarNode, node.value, (True, False)) != _STR_TAG


def _scalar_value(loader: yaml.SafeLoader, node: yaml.ScalarNode) -> bool | int | float | str:
    """Type a scalar as rcl's ``get_value`` does."""
    text = node.value
    if _explicit_str_tag(loader, node):
        return text
    if node.style not in ("'", '"'):
        if text in _TRUE:
            return True
        if text in _FALSE:
            return False
        as_int = _c_int(text)
        if as_int is not None:
            return as_int
        as_double = _c_double(text)
        if as_double is not None:
            return as_double
    return text


def _line(node: yaml.Node) -> int:
    return node.start_mark.line + 1


def _value(
    loader: yaml.SafeLoader, node: yaml.Node, name: str, where: str
) -> ParameterValue:
    """Type the value node of parameter ``name`` (a scalar or a sequence of scalars)."""
    if isinstance(node, yaml.ScalarNode):
        if node.value == '' and node.style is None:
            raise ParameterYamlError(f"{where}: no value for parameter '{name}'")
        return _scalar_value(loader, node)
    if isinstance(node, yaml.SequenceNode):
        if not node.value:
            raise ParameterYamlError(
                f"{where}: parameter '{name}' is an empty sequence; ROS 2 cannot tell the type "
                'of an empty array (give at least one element or leave the parameter out)'
            )
        items: list[bool | int | float | str] = []
        for item in node.value:
            if not isinstance(item, yaml.ScalarNode):
                raise ParameterYamlError(
                    f"{where}: parameter '{name}' holds a nested sequence or mapping at line "
                    f'{_line(item)}; ROS 2 parameters are scalars or flat arrays'
                )
            items.append(_scalar_value(loader, item))
        first = type(items[0])
        for item_node, item in zip(node.value, items, strict=True):
            if type(item) is not first:
                raise ParameterYamlError(
                    f"{where}: sequence '{name}' mixes types: {_TYPE_NAMES[type(item)]} "
                    f'{item_node.value!r} at line {_line(item_node)} in a sequence of '
                    f'{_TYPE_NAMES[first]} (ROS 2 arrays hold one type; write 1.0, not 1, '
                    'in a double array)'
                )
        return items  # type: ignore[return-value]
    raise ParameterYamlError(
        f"{where}: parameter '{name}' is a mapping; nested mappings become dotted names only "
        'under ros__parameters'
    )


def _compose(text: str, origin: str) -> tuple[yaml.SafeLoader, yaml.Node | None]:
    loader = yaml.SafeLoader(text)
    try:
        return loader, loader.get_single_node()
    except yaml.MarkedYAMLError as e:
        mark = e.problem_mark or e.context_mark
        position = f' line {mark.line + 1}, column {mark.column + 1}' if mark else ''
        problem = e.problem or e.context or 'invalid YAML'
        raise ParameterYamlError(f'{origin}:{position}: YAML syntax error: {problem}') from None
    except yaml.YAMLError as e:
        raise ParameterYamlError(f'{origin}: YAML syntax error: {e}') from None
    finally:
        loader.dispose()


def parse_parameter_value(text: str, name: str = 'value') -> ParameterValue:
    """Type the value of a ``-p name:=value`` rule as rcl does.

    Raises:
        ParameterYamlError: If the value is not a scalar or a flat, single-typed sequence.
    """
    where = f'-p {name}:={text}'
    if text == '':
        raise ParameterYamlError(f"{where}: no value for parameter '{name}'")
    loader, node = _compose(text, f"-p '{name}:={text}'")
    if node is None:
        raise ParameterYamlError(f"{where}: no value for parameter '{name}'")
    return _value(loader, node, name, f"'{where}'")


def _walk_parameters(
    loader: yaml.SafeLoader, node: yaml.Node, prefix: str, origin: str
) -> Iterator[tuple[str, ParameterValue, int]]:
    if not isinstance(node, yaml.MappingNode):
        raise ParameterYamlError(
            f'{origin} line {_line(node)}: ros__parameters must be a mapping of names to values'
        )
    for key_node, value_node in node.value:
        key = str(key_node.value)
        name = f'{prefix}.{key}' if prefix else key
        if isinstance(value_node, yaml.MappingNode):
            yield from _walk_parameters(loader, value_node, name, origin)
        else:
            where = f'{origin} line {_line(value_node)}'
            yield name, _value(loader, value_node, name, where), _line(value_node)


def _walk_nodes(
    loader: yaml.SafeLoader, node: yaml.Node, path: list[str], origin: str
) -> Iterator[tuple[str, str, ParameterValue, int]]:
    if not isinstance(node, yaml.MappingNode):
        level = '/'.join(path) or 'the top level'
        raise ParameterYamlError(
            f'{origin} line {_line(node)}: expected a mapping at {level} (node names, then '
            'ros__parameters)'
        )
    for key_node, value_node in node.value:
        key = str(key_node.value)
        if key == 'ros__parameters':
            if not path:
                raise ParameterYamlError(
                    f'{origin} line {_line(key_node)}: ros__parameters needs a node name above it '
                    "(use '/**' for every node)"
                )
            node_key = '/' + '/'.join(part.strip('/') for part in path if part.strip('/'))
            for name, value, line in _walk_parameters(loader, value_node, '', origin):
                yield node_key, name, value, line
        else:
            yield from _walk_nodes(loader, value_node, [*path, key], origin)


def load_parameter_file(path: str | Path) -> dict[str, dict[str, ParameterOverride]]:
    """Read a ROS 2 parameter file as rcl does.

    Args:
        path: File with top-level node names (``/ns/node``, ``node``, ``/**``, ``/**/node``)
            each holding ``ros__parameters``.

    Returns:
        ``{node_key: {parameter_name: ParameterOverride}}`` in file order; node keys start
        with ``/``; nested mappings under ``ros__parameters`` become dotted names.

    Raises:
        ParameterYamlError: If the file is missing, is not valid YAML (with line and column), or
            holds something rcl refuses (with the line).
    """
    file_path = Path(path)
    try:
        text = file_path.read_text(encoding='utf-8')
    except FileNotFoundError:
        raise ParameterYamlError(f"parameter file '{path}' does not exist") from None
    except OSError as e:
        raise ParameterYamlError(f"parameter file '{path}' cannot be read: {e.strerror}") from None
    origin = f"parameter file '{path}'"
    loader, root = _compose(text, origin)
    result: dict[str, dict[str, ParameterOverride]] = {}
    if root is None:
        return result
    for node_key, name, value, line in _walk_nodes(loader, root, [], origin):
        source = f"--params-file '{path}' line {line} (node key '{node_key}')"
        result.setdefault(node_key, {})[name] = ParameterOverride(value, source)
    return result


def node_key_matches(node_key: str, node_fqn: str) -> bool:
    """Tell whether a parameter-file node key applies to a node, as rclcpp and rclpy match.

    ``/*`` matches one name token and ``/**`` any number of them; other keys must equal the
    fully qualified node name (a key without a leading slash gets one).
    """
    key = node_key if node_key.startswith('/') else '/' + node_key
    if key == node_fqn:
        return True
    if '*' not in key:
        return False
    pattern = re.escape(key).replace(r'/\*\*', '(?:/\\w+)*').replace(r'/\*', '(?:/\\w+)')
    return re.fullmatch(pattern, node_fqn, flags=re.ASCII) is not None
