"""Node parameters: typed name/value pairs (rclpy.parameter)."""

from __future__ import annotations

import array
from enum import Enum
from typing import Any

import yaml

PARAMETER_SEPARATOR_STRING = '.'

#: A value a parameter may hold.
AllowableParameterValue = Any


class Parameter:
    """A named, typed parameter value.

    Args:
        name: Parameter name (dots separate namespaces).
        type_: Parameter.Type; inferred from ``value`` if None.
        value: The value (None for NOT_SET).

    Raises:
        TypeError: If no type can be inferred from ``value`` or ``type_`` is not a Type.
        ValueError: If ``value`` does not agree with ``type_``.
    """

    class Type(Enum):
        """Parameter types (values as ``rcl_interfaces/msg/ParameterType``)."""

        NOT_SET = 0
        BOOL = 1
        INTEGER = 2
        DOUBLE = 3
        STRING = 4
        BYTE_ARRAY = 5
        BOOL_ARRAY = 6
        INTEGER_ARRAY = 7
        DOUBLE_ARRAY = 8
        STRING_ARRAY = 9

        @classmethod
        def from_parameter_value(cls, parameter_value: Any) -> Parameter.Type:
            """Return the type of a value.

            Raises:
                TypeError: If the value is not of an allowed type.
            """
            if parameter_value is None:
                return Parameter.Type.NOT_SET
            if isinstance(parameter_value, bool):
                return Parameter.Type.BOOL
            if isinstance(parameter_value, int):
                return Parameter.Type.INTEGER
            if isinstance(parameter_value, float):
                return Parameter.Type.DOUBLE
            if isinstance(parameter_value, str):
                return Parameter.Type.STRING
            if isinstance(parameter_value, (list, tuple, array.array)):
                if all(isinstance(v, bytes) for v in parameter_value):
                    return Parameter.Type.BYTE_ARRAY
                if all(isinstance(v, bool) for v in parameter_value):
                    return Parameter.Type.BOOL_ARRAY
                if all(isinstance(v, int) for v in parameter_value):
                    return Parameter.Type.INTEGER_ARRAY
                if all(isinstance(v, float) for v in parameter_value):
                    return Parameter.Type.DOUBLE_ARRAY
                if all(isinstance(v, str) for v in parameter_value):
                    return Parameter.Type.STRING_ARRAY
                raise TypeError(
                    'The given value is not a list of one of the allowed types '
                    f"'{parameter_value}'."
                )
            raise TypeError(
                f"The given value is not one of the allowed types '{parameter_value}'."
            )

        def check(self, parameter_value: Any) -> bool:
            """Tell whether a value agrees with this type."""
            t = Parameter.Type
            if self == t.NOT_SET:
                return parameter_value is None
            if self == t.BOOL:
                return isinstance(parameter_value, bool)
            if self == t.INTEGER:
                return isinstance(parameter_value, int)
            if self == t.DOUBLE:
                return isinstance(parameter_value, float)
            if self == t.STRING:
                return isinstance(parameter_value, str)
            if self == t.BYTE_ARRAY:
                return isinstance(parameter_value, (list, tuple)) and all(
                    isinstance(v, bytes) and len(v) == 1 for v in parameter_value
                )
            if self == t.BOOL_ARRAY:
                return isinstance(parameter_value, (list, tuple)) and all(
                    isinstance(v, bool) for v in parameter_value
                )
            if self == t.INTEGER_ARRAY:
                return isinstance(parameter_value, (list, tuple, array.array)) and all(
                    isinstance(v, int) for v in parameter_value
                )
            if self == t.DOUBLE_ARRAY:
                return isinstance(parameter_value, (list, tuple, array.array)) and all(
                    isinstance(v, float) for v in parameter_value
                )
            if self == t.STRING_ARRAY:
                return isinstance(parameter_value, (list, tuple)) and all(
                    isinstance(v, str) for v in parameter_value
                )
            return False

    @classmethod
    def from_parameter_msg(cls, param_msg: Any) -> Parameter:
        """Build a Parameter from an ``rcl_interfaces/msg/Parameter``."""
        type_ = Parameter.Type(param_msg.value.type)
        value = parameter_value_to_python(param_msg.value)
        if type_ in (Parameter.Type.INTEGER_ARRAY, Parameter.Type.DOUBLE_ARRAY,
                     Parameter.Type.BOOL_ARRAY, Parameter.Type.STRING_ARRAY,
                     Parameter.Type.BYTE_ARRAY):
            value = list(value)
        return cls(param_msg.name, type_, value)

    def __init__(self, name: str, type_: Parameter.Type | None = None, value: Any = None) -> None:
        if type_ is None:
            type_ = Parameter.Type.from_parameter_value(value)
        if not isinstance(type_, Parameter.Type):
            raise TypeError(f"type must be an instance of '{Parameter.Type!r}'")
        if not type_.check(value):
            raise ValueError(f"Type '{type_}' and value '{value}' do not agree")
        self._type_ = type_
        self._name = name
        self._value = value

    @property
    def name(self) -> str:
        """Name of the parameter."""
        return self._name

    @property
    def type_(self) -> Parameter.Type:
        """Type of the parameter."""
        return self._type_

    @property
    def value(self) -> Any:
        """Value of the parameter (None if NOT_SET)."""
        return self._value

    def __repr__(self) -> str:
        return f'Parameter(name={self._name!r}, type_={self._type_}, value={self._value!r})'

    def get_parameter_value(self) -> Any:
        """Return the value as an ``rcl_interfaces/msg/ParameterValue``."""
        from rcl_interfaces.msg import ParameterValue

        parameter_value = ParameterValue(type=self._type_.value)
        field = _VALUE_FIELDS.get(self._type_)
        if field is not None:
            setattr(parameter_value, field, self._value)
        return parameter_value

    def to_parameter_msg(self) -> Any:
        """Return the parameter as an ``rcl_interfaces/msg/Parameter``."""
        from rcl_interfaces.msg import Parameter as ParameterMsg

        return ParameterMsg(name=self._name, value=self.get_parameter_value())


_VALUE_FIELDS = {
    Parameter.Type.BOOL: 'bool_value',
    Parameter.Type.INTEGER: 'integer_value',
    Parameter.Type.DOUBLE: 'double_value',
    Parameter.Type.STRING: 'string_value',
    Parameter.Type.BYTE_ARRAY: 'byte_array_value',
    Parameter.Type.BOOL_ARRAY: 'bool_array_value',
    Parameter.Type.INTEGER_ARRAY: 'integer_array_value',
    Parameter.Type.DOUBLE_ARRAY: 'double_array_value',
    Parameter.Type.STRING_ARRAY: 'string_array_value',
}


def get_parameter_value(string_value: str) -> Any:
    """Guess the type of a parameter from a string, as ``ros2 param set`` does.

    Returns:
        An ``rcl_interfaces/msg/ParameterValue``.
    """
    from rcl_interfaces.msg import ParameterType, ParameterValue

    value = ParameterValue()
    try:
        yaml_value = yaml.safe_load(string_value)
    except yaml.YAMLError:
        yaml_value = string_value
    if isinstance(yaml_value, bool):
        value.type = ParameterType.PARAMETER_BOOL
        value.bool_value = yaml_value
    elif isinstance(yaml_value, int):
        value.type = ParameterType.PARAMETER_INTEGER
        value.integer_value = yaml_value
    elif isinstance(yaml_value, float):
        value.type = ParameterType.PARAMETER_DOUBLE
        value.double_value = yaml_value
    elif isinstance(yaml_value, list):
        if all(isinstance(v, bool) for v in yaml_value):
            value.type = ParameterType.PARAMETER_BOOL_ARRAY
            value.bool_array_value = yaml_value
        elif all(isinstance(v, int) for v in yaml_value):
            value.type = ParameterType.PARAMETER_INTEGER_ARRAY
            value.integer_array_value = yaml_value
        elif all(isinstance(v, float) for v in yaml_value):
            value.type = ParameterType.PARAMETER_DOUBLE_ARRAY
            value.double_array_value = yaml_value
        elif all(isinstance(v, str) for v in yaml_value):
            value.type = ParameterType.PARAMETER_STRING_ARRAY
            value.string_array_value = yaml_value
        else:
            value.type = ParameterType.PARAMETER_STRING
            value.string_value = string_value
    else:
        value.type = ParameterType.PARAMETER_STRING
        value.string_value = yaml_value if yaml_value is not None else string_value
    return value


def parameter_value_to_python(parameter_value: Any) -> Any:
    """Return the Python value held by an ``rcl_interfaces/msg/ParameterValue``.

    Raises:
        RuntimeError: If the message's type is unknown.
    """
    try:
        type_ = Parameter.Type(parameter_value.type)
    except ValueError:
        raise RuntimeError(f'unexpected parameter type {parameter_value.type}') from None
    if type_ == Parameter.Type.NOT_SET:
        return None
    value = getattr(parameter_value, _VALUE_FIELDS[type_])
    if type_ in (Parameter.Type.BYTE_ARRAY, Parameter.Type.BOOL_ARRAY,
                 Parameter.Type.INTEGER_ARRAY, Parameter.Type.DOUBLE_ARRAY,
                 Parameter.Type.STRING_ARRAY):
        return list(value)
    return value


def parameter_dict_from_yaml_file(
    parameter_file: str,
    use_wildcard: bool = False,
    target_nodes: list[str] | None = None,
    namespace: str = '',
) -> dict[str, Any]:
    """Build a dict of ``rcl_interfaces/msg/Parameter`` from a parameter file, as rclpy does.

    Args:
        parameter_file: Path of the YAML file.
        use_wildcard: Include the ``/**`` entries.
        target_nodes: Node keys to read (all if None or empty).
        namespace: Prefix for every parameter name.

    Raises:
        RuntimeError: If a target node is not in the file or the file is not a parameter file.
    """
    with open(parameter_file, encoding='utf-8') as f:
        param_file = yaml.safe_load(f)
    param_keys: list[str] = []
    param_dict: dict[str, Any] = {}
    if use_wildcard and '/**' in param_file:
        param_keys.append('/**')
    if target_nodes:
        for node in target_nodes:
            if node not in param_file:
                raise RuntimeError(
                    f'Param file does not contain parameters for {node}, '
                    f'only for nodes: {list(param_file.keys())} '
                )
            param_keys.append(node)
    else:
        param_keys.extend(key for key in param_file if key != '/**')
    if not param_keys:
        raise RuntimeError('Param file does not contain selected parameters')
    for key in param_keys:
        value = param_file[key]
        if not isinstance(value, dict) or 'ros__parameters' not in value:
            raise RuntimeError(f'YAML file is not a valid ROS parameter file for node {key}')
        param_dict.update(value['ros__parameters'])
    return _unpack_parameter_dict(namespace, param_dict)


def _unpack_parameter_dict(namespace: str, parameter_dict: dict[str, Any]) -> dict[str, Any]:
    from rcl_interfaces.msg import Parameter as ParameterMsg

    parameters: dict[str, Any] = {}
    for param_name, param_value in parameter_dict.items():
        full_param_name = namespace + param_name
        if isinstance(param_value, dict):
            parameters.update(
                _unpack_parameter_dict(full_param_name + PARAMETER_SEPARATOR_STRING, param_value)
            )
        else:
            parameter = ParameterMsg()
            parameter.name = full_param_name
            parameter.value = get_parameter_value(str(param_value))
            parameters[full_param_name] = parameter
    return parameters
