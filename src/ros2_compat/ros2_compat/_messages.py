"""Message classes that behave like rosidl-generated Python classes, built from the type store.

Each class is generated as Python source (one per message type, on first use) and executed,
the way rosidl_generator_py templates them: ``__slots__``, keyword constructor, typed property
setters with rosidl's assertion messages, constants as class attributes, ``__eq__``,
``__repr__``, ``get_fields_and_field_types()`` and ``SLOT_TYPES``. As in Jazzy, setters and the
constructor check values when ``check_fields`` is true (constructor keyword ``check_fields``,
else the ``ROS_PYTHON_CHECK_FIELDS`` environment variable read once at import). Unlike Jazzy,
an unset ``ROS_PYTHON_CHECK_FIELDS`` means checks on: the compat runtime is where node code is
developed and tested, so it catches wrong types early; ``ROS_PYTHON_CHECK_FIELDS=0`` gives
Jazzy's unchecked default.
"""

from __future__ import annotations

import array
import collections
import collections.abc
import copy
import math
import os
import re
import threading
from dataclasses import dataclass
from operator import attrgetter
from typing import TYPE_CHECKING, Any

import numpy as np

from ros2_compat import _definition
from ros2_compat._typestore import field_default, message_names, uvms_typestore

if TYPE_CHECKING:
    from collections.abc import Callable

#: Checks on unless ROS_PYTHON_CHECK_FIELDS is set to something other than '1' (see above).
CHECK_FIELDS_DEFAULT = os.environ.get('ROS_PYTHON_CHECK_FIELDS', '1') == '1'

_BASE, _NAME, _ARRAY, _SEQUENCE = 1, 2, 3, 4
_EMPTY_MEMBER = 'structure_needs_at_least_one_member'


@dataclass(frozen=True)
class Primitive:
    """How one .msg primitive type maps to IDL, Python, struct and array."""

    idl: str
    python: str
    struct: str
    size: int
    typecode: str | None
    dtype: str | None
    bounds: tuple[float, float] | None


_INT_BOUNDS = {bits: (-(2 ** (bits - 1)), 2 ** (bits - 1)) for bits in (8, 16, 32, 64)}
_UINT_BOUNDS = {bits: (0, 2**bits) for bits in (8, 16, 32, 64)}

#: .msg primitive -> mapping. `char` is uint8 and `byte` is octet in ROS 2 IDL.
PRIMITIVES: dict[str, Primitive] = {
    'bool': Primitive('boolean', 'bool', '?', 1, None, None, None),
    'byte': Primitive('octet', 'bytes', 'c', 1, None, None, None),
    'char': Primitive('uint8', 'int', 'B', 1, 'B', 'uint8', _UINT_BOUNDS[8]),
    'int8': Primitive('int8', 'int', 'b', 1, 'b', 'int8', _INT_BOUNDS[8]),
    'uint8': Primitive('uint8', 'int', 'B', 1, 'B', 'uint8', _UINT_BOUNDS[8]),
    'int16': Primitive('int16', 'int', 'h', 2, 'h', 'int16', _INT_BOUNDS[16]),
    'uint16': Primitive('uint16', 'int', 'H', 2, 'H', 'uint16', _UINT_BOUNDS[16]),
    'int32': Primitive('int32', 'int', 'i', 4, 'i', 'int32', _INT_BOUNDS[32]),
    'uint32': Primitive('uint32', 'int', 'I', 4, 'I', 'uint32', _UINT_BOUNDS[32]),
    'int64': Primitive('int64', 'int', 'q', 8, 'q', 'int64', _INT_BOUNDS[64]),
    'uint64': Primitive('uint64', 'int', 'Q', 8, 'Q', 'uint64', _UINT_BOUNDS[64]),
    'float32': Primitive('float', 'float', 'f', 4, 'f', 'float32', (3.402823466e38, 0.0)),
    'float64': Primitive('double', 'float', 'd', 8, 'd', 'float64', (1.7976931348623157e308, 0.0)),
}


@dataclass(frozen=True)
class FieldSpec:
    """One field of a message type.

    Attributes:
        name: Field name.
        kind: 'base' (primitive or string), 'msg' (nested message), 'array' (fixed size)
            or 'sequence'.
        base: For base fields and primitive/string elements: the .msg type ('float64',
            'string', ...); None for message elements.
        string_bound: Maximum string length, 0 when unbounded.
        msgtype: Nested message type 'pkg/msg/Type' of msg fields and message elements.
        size: Array length, or sequence bound (0 when unbounded).
        default: The .msg default value, or None.
    """

    name: str
    kind: str
    base: str | None
    string_bound: int
    msgtype: str | None
    size: int
    default: object = None

    @property
    def numeric_elements(self) -> bool:
        """Tell whether an array/sequence holds numbers (array.array / numpy storage)."""
        return (
            self.kind in {'array', 'sequence'}
            and self.base is not None
            and (PRIMITIVES.get(self.base, _STRING_PRIMITIVE).typecode is not None)
        )


_STRING_PRIMITIVE = Primitive('string', 'str', '', 0, None, None, None)


def type_fields(typename: str) -> list[FieldSpec]:
    """Return the fields of a message type, as in its .msg file (placeholder member included)."""
    _, fielddefs = uvms_typestore().fielddefs[typename]
    specs = []
    for name, desc in fielddefs:
        nodetype, rest = desc
        if nodetype == _BASE:
            base, bound = rest
            specs.append(
                FieldSpec(name, 'base', base, bound, None, 0, field_default(typename, name))
            )
        elif nodetype == _NAME:
            specs.append(FieldSpec(name, 'msg', None, 0, rest, 0))
        else:
            (subtype, subrest), count = rest
            kind = 'array' if nodetype == _ARRAY else 'sequence'
            if subtype == _BASE:
                base, bound = subrest
                specs.append(FieldSpec(name, kind, base, bound, None, count))
            else:
                specs.append(FieldSpec(name, kind, None, 0, subrest, count))
    return specs


def type_constants(typename: str) -> list[tuple[str, str, object]]:
    """Return the (name, type, value) constants of a message type."""
    return list(uvms_typestore().fielddefs[typename][0])


def class_fields(typename: str) -> list[FieldSpec]:
    """Return the fields a Python message class has (rosidl drops the empty-struct member)."""
    fields = type_fields(typename)
    if len(fields) == 1 and fields[0].name == _EMPTY_MEMBER:
        return []
    return fields


def short_type(msgtype: str) -> str:
    """Return 'pkg/Type' for 'pkg/msg/Type', as rosidl writes nested types."""
    pkg, _, name = msgtype.split('/')
    return f'{pkg}/{name}'


def field_type_string(spec: FieldSpec) -> str:
    """Return the rosidl type string of a field: 'double', 'sequence<double>', 'double[36]'..."""
    if spec.base is None:
        assert spec.msgtype is not None
        element = short_type(spec.msgtype)
    elif spec.base == 'string':
        element = f'string<{spec.string_bound}>' if spec.string_bound else 'string'
    else:
        element = PRIMITIVES[spec.base].idl
    if spec.kind == 'array':
        return f'{element}[{spec.size}]'
    if spec.kind == 'sequence':
        return f'sequence<{element}, {spec.size}>' if spec.size else f'sequence<{element}>'
    return element


def slot_type(spec: FieldSpec) -> _definition.AbstractType:
    """Return the rosidl_parser.definition-like description of a field."""
    element: _definition.AbstractType
    if spec.base is None:
        assert spec.msgtype is not None
        pkg, sub, name = spec.msgtype.split('/')
        element = _definition.NamespacedType([pkg, sub], name)
    elif spec.base == 'string':
        element = (
            _definition.BoundedString(spec.string_bound)
            if spec.string_bound
            else _definition.UnboundedString()
        )
    else:
        element = _definition.BasicType(PRIMITIVES[spec.base].idl)
    if spec.kind == 'array':
        return _definition.Array(element, spec.size)
    if spec.kind == 'sequence':
        if spec.size:
            return _definition.BoundedSequence(element, spec.size)
        return _definition.UnboundedSequence(element)
    return element


def module_name(typename: str) -> str:
    """Return the module rosidl puts a class in: 'sensor_msgs.msg._joint_state'."""
    pkg, sub, name = typename.split('/')
    snake = re.sub('(.)([A-Z][a-z]+)', r'\1_\2', name)
    snake = re.sub('([a-z0-9])([A-Z])', r'\1_\2', snake).lower()
    return f'{pkg}.{sub}._{snake}'


class MessageMeta(type):
    """Metaclass of every compat message class (rosidl has one per message).

    The type-support attributes are set so that rclpy-style checks
    (``msg_type._TYPE_SUPPORT is not None``) accept the class.
    """

    _CREATE_ROS_MESSAGE: object = 'ros2_compat'
    _CONVERT_FROM_PY: object = 'ros2_compat'
    _CONVERT_TO_PY: object = 'ros2_compat'
    _DESTROY_ROS_MESSAGE: object = 'ros2_compat'
    _TYPE_SUPPORT: object = 'ros2_compat'

    @classmethod
    def __import_type_support__(cls) -> None:
        """Nothing to import: the compat runtime serializes in Python."""


def _as_array(typecode: str, value: Any) -> array.array[Any]:
    """Return ``array.array(typecode, value)``, fast for numpy arrays of the matching type."""
    if type(value) is np.ndarray and value.ndim == 1 and value.dtype == _ARRAY_DTYPES[typecode]:
        result = array.array(typecode)
        result.frombytes(value.tobytes())
        return result
    return array.array(typecode, value)


_ARRAY_DTYPES = {
    prim.typecode: np.dtype(prim.dtype)
    for prim in PRIMITIVES.values()
    if prim.typecode is not None and prim.dtype is not None
}

_ARRAY_PREFIX = "array('X', "


def _repr(msg: Any) -> str:
    """Return rosidl's repr: 'sensor_msgs.msg.JointState(header=..., name=[], ...)'."""
    cls = type(msg)
    typename = cls.__module__.split('.')
    typename.pop()
    typename.append(cls.__name__)
    args = []
    for name, numeric_sequence in cls._REPR_FIELDS:
        field = getattr(msg, '_' + name)
        fieldstr = repr(field)
        if numeric_sequence:
            if len(field) == 0:
                fieldstr = '[]'
            elif fieldstr.startswith('array('):
                fieldstr = fieldstr[len(_ARRAY_PREFIX) : -1]
        args.append(f'{name}={fieldstr}')
    return '{}({})'.format('.'.join(typename), ', '.join(args))


def _slow_deepcopy(msg: Any, memo: dict[int, Any] | None) -> Any:
    """Deep-copy any message slot by slot (fallback when fields hold unexpected types)."""
    cls = type(msg)
    new = object.__new__(cls)
    for slot in cls.__slots__:
        object.__setattr__(new, slot, copy.deepcopy(getattr(msg, slot), memo))
    return new


def _unpickle(typename: str, state: tuple[Any, ...]) -> Any:
    """Rebuild a pickled message (classes live in generated modules pickle cannot import)."""
    cls = get_class(typename)
    msg = object.__new__(cls)
    for slot, value in zip(cls.__slots__, state, strict=True):
        object.__setattr__(msg, slot, value)
    return msg


_HELPERS: dict[str, object] = {
    '_array': array.array,
    '_np': np,
    '_isinf': math.isinf,
    '_Sequence': collections.abc.Sequence,
    '_Set': collections.abc.Set,
    '_UserList': collections.UserList,
    '_UserString': collections.UserString,
    '_as_array': _as_array,
    '_attrgetter': attrgetter,
    '_new': object.__new__,
    '_repr': _repr,
    '_slow_deepcopy': _slow_deepcopy,
    '_unpickle': _unpickle,
    '_Meta': MessageMeta,
    '_CHECK_DEFAULT': CHECK_FIELDS_DEFAULT,
}


class _ClassSource:
    """Writes the Python source of one message class."""

    def __init__(self, typename: str) -> None:
        self.typename = typename
        self.name = typename.rsplit('/', 1)[1]
        self.fields = class_fields(typename)
        self.constants = type_constants(typename)
        self.namespace: dict[str, object] = dict(_HELPERS)
        self.nested: dict[str, str] = {}
        self.lines: list[str] = []

    def nested_ref(self, msgtype: str) -> str:
        """Return the namespace name of a nested message class, loading the class."""
        if msgtype not in self.nested:
            ref = f'_M{len(self.nested)}_{msgtype.rsplit("/", 1)[1]}'
            self.nested[msgtype] = ref
            self.namespace[ref] = get_class(msgtype)
        return self.nested[msgtype]

    def default_expr(self, spec: FieldSpec) -> str:
        """Return an expression building the default value of a field."""
        if spec.kind == 'msg':
            assert spec.msgtype is not None
            return f'{self.nested_ref(spec.msgtype)}()'
        if spec.kind == 'base':
            assert spec.base is not None
            if spec.default is not None:
                return repr(spec.default)
            if spec.base == 'string':
                return "''"
            if spec.base == 'byte':
                return "b'\\x00'"
            return {'bool': 'False', 'float': '0.0', 'int': '0'}[PRIMITIVES[spec.base].python]
        if spec.kind == 'sequence':
            if spec.numeric_elements:
                assert spec.base is not None
                return f"_array('{PRIMITIVES[spec.base].typecode}')"
            return '[]'
        # Fixed-size array.
        if spec.numeric_elements:
            assert spec.base is not None
            return f'_np.zeros({spec.size}, dtype=_np.{PRIMITIVES[spec.base].dtype})'
        if spec.base is None:
            assert spec.msgtype is not None
            return f'[{self.nested_ref(spec.msgtype)}() for _ in range({spec.size})]'
        element = {'string': "''", 'byte': "b'\\x00'", 'bool': 'False'}[spec.base]
        return f'[{element}] * {spec.size}'

    def element_python_type(self, spec: FieldSpec) -> tuple[str, str]:
        """Return (expression, name in messages) of the Python type of a field's values."""
        if spec.base is None:
            assert spec.msgtype is not None
            return self.nested_ref(spec.msgtype), spec.msgtype.rsplit('/', 1)[1]
        if spec.base == 'string':
            return 'str', 'str'
        python = PRIMITIVES[spec.base].python
        return python, python

    def setter(self, spec: FieldSpec) -> list[str]:
        """Return the lines of a field's property setter."""
        name = spec.name
        lines = [f'    def _set_{name}(self, value):', '        if self._check_fields:']
        checks: list[str] = []
        prim = PRIMITIVES.get(spec.base or '', None)
        if spec.kind == 'msg':
            ref, short = self.element_python_type(spec)
            checks.append(
                f'assert isinstance(value, {ref}), '
                f"\"The '{name}' field must be a sub message of type '{short}'\""
            )
        elif spec.kind == 'base':
            checks.extend(self.scalar_checks(spec, prim))
        else:
            lines.extend(self.nested_checks(spec, prim))
        lines.extend(f'            {check}' for check in checks)
        if spec.kind in {'array', 'sequence'} and spec.numeric_elements:
            assert prim is not None
            if spec.kind == 'array':
                lines.append(f'        self._{name} = _np.array(value, dtype=_np.{prim.dtype})')
            else:
                lines.append(f"        self._{name} = _as_array('{prim.typecode}', value)")
        else:
            lines.append(f'        self._{name} = value')
        return lines

    def scalar_checks(self, spec: FieldSpec, prim: Primitive | None) -> list[str]:
        """Return the assertions on a primitive or string value."""
        name = spec.name
        if spec.base == 'string':
            if spec.string_bound:
                return [
                    f'assert (isinstance(value, (str, _UserString)) and '
                    f'len(value) <= {spec.string_bound}), '
                    f'"The \'{name}\' field must be string value "'
                    f" 'not longer than {spec.string_bound}'"
                ]
            return [f"assert isinstance(value, str), \"The '{name}' field must be of type 'str'\""]
        assert prim is not None
        if spec.base == 'byte':
            return [
                f'assert (isinstance(value, (bytes, bytearray)) and len(value) == 1), '
                f"\"The '{name}' field must be of type 'bytes' or 'ByteString' with length 1\""
            ]
        checks = [
            f'assert isinstance(value, {prim.python}), '
            f"\"The '{name}' field must be of type '{prim.python}'\""
        ]
        if prim.python == 'float':
            assert prim.bounds is not None
            bound = prim.bounds[0]
            checks.append(
                f'assert not (value < -{bound!r} or value > {bound!r}) or _isinf(value), '
                f'"The \'{name}\' field must be a {prim.idl} in [-{bound!r}, {bound!r}]"'
            )
        elif prim.python == 'int':
            assert prim.bounds is not None
            low, high = prim.bounds
            kind = 'an unsigned integer' if low == 0 else 'an integer'
            checks.append(
                f'assert value >= {low} and value < {high}, '
                f'"The \'{name}\' field must be {kind} in [{low}, {high - 1}]"'
            )
        return checks

    def nested_checks(self, spec: FieldSpec, prim: Primitive | None) -> list[str]:
        """Return the setter lines checking an array or sequence value."""
        name = spec.name
        lines: list[str] = []
        if spec.numeric_elements:
            assert prim is not None
            if spec.kind == 'array':
                lines += [
                    '            if isinstance(value, _np.ndarray):',
                    f'                assert value.dtype == _np.{prim.dtype}, '
                    f"\"The '{name}' numpy.ndarray() must have the dtype of "
                    f"'numpy.{prim.dtype}'\"",
                    f'                assert value.size == {spec.size}, '
                    f'"The \'{name}\' numpy.ndarray() must have a size of {spec.size}"',
                    f'                self._{name} = value',
                    '                return',
                ]
            else:
                lines += [
                    '            if isinstance(value, _array):',
                    f"                assert value.typecode == '{prim.typecode}', "
                    f"\"The '{name}' array.array() must have the type code of "
                    f"'{prim.typecode}'\"",
                ]
                if spec.size:
                    lines.append(
                        f'                assert len(value) <= {spec.size}, '
                        f'"The \'{name}\' array.array() must have a size <= {spec.size}"'
                    )
                lines += [f'                self._{name} = value', '                return']
                # Compat leniency: Jazzy's default (unchecked) setter takes numpy arrays,
                # so the checked compat default does too (rosidl's checked one would not).
                kinds = 'fiu' if prim.python == 'float' else 'iub'
                lines.append(
                    '            if isinstance(value, _np.ndarray) and value.ndim == 1 '
                    f"and value.dtype.kind in '{kinds}':"
                )
                if spec.size:
                    lines.append(
                        f'                assert len(value) <= {spec.size}, '
                        f'"The \'{name}\' numpy.ndarray() must have a size <= {spec.size}"'
                    )
                lines += [
                    f"                self._{name} = _as_array('{prim.typecode}', value)",
                    '                return',
                ]
        ref, short = self.element_python_type(spec)
        conditions = [
            '((isinstance(value, _Sequence) or isinstance(value, _Set) or '
            'isinstance(value, _UserList))',
            'not isinstance(value, str)',
            'not isinstance(value, _UserString)',
        ]
        suffixes = ['a set or sequence']
        if spec.base == 'string' and spec.string_bound:
            conditions.append(f'all(len(val) <= {spec.string_bound} for val in value)')
            suffixes.append(f'and each string value not longer than {spec.string_bound}')
        if spec.kind == 'array':
            conditions.append(f'len(value) == {spec.size}')
            suffixes.insert(1, f'with length {spec.size}')
        elif spec.size:
            conditions.append(f'len(value) <= {spec.size}')
            suffixes.insert(1, f'with length <= {spec.size}')
        conditions.append(f'all(isinstance(v, {ref}) for v in value)')
        suffixes.append(f"and each value of type '{short}'")
        if prim is not None and prim.bounds is not None and prim.python == 'int':
            low, high = prim.bounds
            conditions.append(f'all(val >= {low} and val < {high} for val in value))')
            kind = 'unsigned integer' if low == 0 else 'integer'
            suffixes.append(f'and each {kind} in [{low}, {high - 1}]')
        elif prim is not None and prim.bounds is not None:
            bound = prim.bounds[0]
            conditions.append(
                f'all(not (val < -{bound!r} or val > {bound!r}) or _isinf(val) for val in value))'
            )
            suffixes.append(f'and each {prim.idl} in [{-bound:f}, {bound:f}]')
        else:
            conditions.append('True)')
        message = ' '.join(suffixes)
        lines.append(
            f'            assert {" and ".join(conditions)}, '
            f'"The \'{name}\' field must be {message}"'
        )
        return lines

    def init_lines(self) -> list[str]:
        """Return the lines of ``__init__``: a fast default path, then rosidl's keyword path."""
        lines = [
            '    def __init__(self, **kwargs):',
            '        if not kwargs:',
            '            self._check_fields = _CHECK_DEFAULT',
        ]
        lines += [f'            self._{f.name} = {self.default_expr(f)}' for f in self.fields]
        lines += [
            '            return',
            "        check = kwargs['check_fields'] if 'check_fields' in kwargs "
            'else _CHECK_DEFAULT',
            '        self._check_fields = check',
            '        if check:',
            "            assert all('_' + key in _SLOTSET for key in kwargs), \\",
            "                'Invalid arguments passed to constructor: %s' % \\",
            "                ', '.join(sorted(k for k in kwargs if '_' + k not in _SLOTSET))",
        ]
        for spec in self.fields:
            name = spec.name
            lines.append(f"        if '{name}' in kwargs:")
            if spec.kind == 'sequence' and spec.numeric_elements:
                assert spec.base is not None
                typecode = PRIMITIVES[spec.base].typecode
                lines.append(
                    f"            self.{name} = _as_array('{typecode}', kwargs['{name}'])"
                )
            elif spec.kind == 'array' and spec.numeric_elements:
                assert spec.base is not None
                dtype = PRIMITIVES[spec.base].dtype
                lines += [
                    f"            self.{name} = _np.array(kwargs['{name}'], dtype=_np.{dtype})",
                    f'            assert self._{name}.shape == ({spec.size}, )',
                ]
            else:
                lines.append(f"            self.{name} = kwargs['{name}']")
            lines += ['        else:', f'            self._{name} = {self.default_expr(spec)}']
        return lines

    def eq_lines(self) -> list[str]:
        """Return the lines of ``__eq__`` (numpy arrays compared element-wise)."""
        lines = [
            '    def __eq__(self, other):',
            '        if not isinstance(other, self.__class__):',
            '            return False',
        ]
        for spec in self.fields:
            if spec.kind == 'array' and spec.numeric_elements:
                lines.append(
                    f'        if not _np.array_equal(self._{spec.name}, other._{spec.name}):'
                )
            else:
                lines.append(f'        if self._{spec.name} != other._{spec.name}:')
            lines.append('            return False')
        lines.append('        return True')
        return lines

    def copy_lines(self) -> list[str]:
        """Return ``__copy__``, ``__deepcopy__`` and the module-level fast deep copy."""
        lines = [
            '    def __copy__(self):',
            f'        new = _new({self.name})',
            '        new._check_fields = self._check_fields',
        ]
        lines += [f'        new._{f.name} = self._{f.name}' for f in self.fields]
        lines += [
            '        return new',
            '',
            '    def __deepcopy__(self, memo=None):',
            '        try:',
            '            return _fast_deepcopy(self)',
            '        except Exception:',
            '            return _slow_deepcopy(self, memo)',
        ]
        return lines

    def fast_deepcopy_lines(self) -> list[str]:
        """Return a function deep-copying a well-formed message without checks."""
        lines = ['def _fast_deepcopy(m):', f'    n = _new({self.name})']
        lines.append('    n._check_fields = m._check_fields')
        for spec in self.fields:
            slot = f'_{spec.name}'
            if spec.kind == 'base':
                expr = f'm.{slot}'
            elif spec.kind == 'msg':
                assert spec.msgtype is not None
                expr = f'{self.nested_ref(spec.msgtype)}._fast_deepcopy(m.{slot})'
            elif spec.kind == 'array' and spec.numeric_elements:
                expr = f'm.{slot}.copy()'
            elif spec.base is None:
                assert spec.msgtype is not None
                ref = self.nested_ref(spec.msgtype)
                expr = f'[{ref}._fast_deepcopy(e) for e in m.{slot}]'
            else:
                expr = f'm.{slot}[:]'
            lines.append(f'    n.{slot} = {expr}')
        lines.append('    return n')
        return lines

    def source(self) -> str:
        """Return the module source defining the class."""
        slots = [f'_{f.name}' for f in self.fields] + ['_check_fields']
        self.namespace['_SLOTSET'] = frozenset(slots)
        self.namespace['_FIELDS_AND_TYPES'] = {f.name: field_type_string(f) for f in self.fields}
        self.namespace['_SLOT_TYPES'] = tuple(slot_type(f) for f in self.fields)
        doc = f"Message class '{self.name}'."
        if self.constants:
            names = '\n'.join(f'      {name}' for name, _, _ in self.constants)
            doc = f"\n    Message class '{self.name}'.\n\n    Constants:\n{names}\n    "
        lines = [
            f'class {self.name}(metaclass=_Meta):',
            f'    {doc!r}',
            f'    __module__ = {module_name(self.typename)!r}',
            f'    __slots__ = {slots!r}',
            '    _fields_and_field_types = _FIELDS_AND_TYPES',
            '    SLOT_TYPES = _SLOT_TYPES',
            f'    _TYPE_NAME = {self.typename!r}',
            '    _REPR_FIELDS = {!r}'.format(
                tuple((f.name, f.kind == 'sequence' and f.numeric_elements) for f in self.fields)
            ),
        ]
        for name, _, value in self.constants:
            lines.append(f'    {name} = {value!r}')
        for spec in self.fields:
            if spec.default is not None:
                lines.append(f'    {spec.name.upper()}__DEFAULT = {spec.default!r}')
        lines += ['', *self.init_lines(), '', *self.eq_lines(), '']
        lines += [
            '    def __reduce__(self):',
            '        return (_unpickle, (self._TYPE_NAME, '
            'tuple([getattr(self, slot) for slot in self.__slots__])))',
            '',
            '    def __repr__(self):',
            '        return _repr(self)',
            '',
            '    @classmethod',
            '    def get_fields_and_field_types(cls):',
            '        return dict(cls._fields_and_field_types)',
            '',
            *self.copy_lines(),
        ]
        for spec in self.fields:
            lines += ['', *self.setter(spec)]
            lines.append(
                f"    {spec.name} = property(_attrgetter('_{spec.name}'), _set_{spec.name}, "
                f'None, "Message field \'{spec.name}\'.")'
            )
            lines.append(f'    del _set_{spec.name}')
        lines += ['', '', *self.fast_deepcopy_lines()]
        lines += ['', '', f'{self.name}._fast_deepcopy = staticmethod(_fast_deepcopy)']
        return '\n'.join(lines) + '\n'


_lock = threading.RLock()
_classes: dict[str, type] = {}


def _build(typename: str) -> type:
    """Generate, execute and return the class of one message type."""
    writer = _ClassSource(typename)
    source = writer.source()
    code = compile(source, f'<ros2_compat message {typename}>', 'exec')
    exec(code, writer.namespace)
    cls = writer.namespace[writer.name]
    assert isinstance(cls, type)
    return cls


def get_class(typename: str) -> type:
    """Return the compat class of a 'pkg/msg/Type' name, generating it on first use.

    Raises:
        KeyError: The type store does not know the type.
    """
    cls = _classes.get(typename)
    if cls is None:
        with _lock:
            cls = _classes.get(typename)
            if cls is None:
                if typename not in uvms_typestore().fielddefs:
                    raise KeyError(typename)
                cls = _build(typename)
                _classes[typename] = cls
    return cls


def class_source(typename: str) -> str:
    """Return the generated source of a message class (for inspection and debugging)."""
    return _ClassSource(typename).source()


def is_compat_class(obj: object) -> bool:
    """Tell whether obj is a message class generated here."""
    return isinstance(obj, MessageMeta)


def fast_deepcopy(msg: Any) -> Any:
    """Deep-copy a compat message (generated code; falls back to copy.deepcopy rules)."""
    try:
        return type(msg)._fast_deepcopy(msg)
    except Exception:
        return _slow_deepcopy(msg, None)


def package_getattr(package: str) -> Callable[[str], Any]:
    """Return a module ``__getattr__`` serving a package's message classes lazily."""
    prefix = f'{package}/msg/'

    def __getattr__(name: str) -> Any:  # noqa: N807
        if name == '__all__':
            return [typename.rsplit('/', 1)[1] for typename in message_names(package)]
        typename = prefix + name
        if name.startswith('_') or typename not in uvms_typestore().fielddefs:
            msg = f"module '{package}.msg' has no attribute '{name}'"
            raise AttributeError(msg)
        return get_class(typename)

    return __getattr__


def package_dir(package: str) -> Callable[[], list[str]]:
    """Return a module ``__dir__`` listing a package's message classes."""

    def __dir__() -> list[str]:  # noqa: N807
        return [typename.rsplit('/', 1)[1] for typename in message_names(package)]

    return __dir__
