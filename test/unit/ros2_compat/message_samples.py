"""Random message instances and their rosbags twins, for oracle tests of the compat classes.

Values are drawn from each class's public description (``SLOT_TYPES``), and the rosbags
objects are built from rosbags' own field definitions, so the oracle does not reuse the
code under test.
"""

from __future__ import annotations

import array
import string
from typing import Any

import numpy as np
from ros2_compat.message_support import get_message_class, message_type_name, uvms_typestore
from rosbags.interfaces import Nodetype

INT_RANGES = {
    'int8': (-(2**7), 2**7 - 1),
    'uint8': (0, 2**8 - 1),
    'int16': (-(2**15), 2**15 - 1),
    'uint16': (0, 2**16 - 1),
    'int32': (-(2**31), 2**31 - 1),
    'uint32': (0, 2**32 - 1),
    'int64': (-(2**63), 2**63 - 1),
    'uint64': (0, 2**64 - 1),
}
TYPECODES = {
    'int8': 'b',
    'uint8': 'B',
    'int16': 'h',
    'uint16': 'H',
    'int32': 'i',
    'uint32': 'I',
    'int64': 'q',
    'uint64': 'Q',
    'float': 'f',
    'double': 'd',
}
NUMPY_DTYPES = {
    'int8': np.int8,
    'uint8': np.uint8,
    'int16': np.int16,
    'uint16': np.uint16,
    'int32': np.int32,
    'uint32': np.uint32,
    'int64': np.int64,
    'uint64': np.uint64,
    'float': np.float32,
    'double': np.float64,
}
ROSBAGS_DTYPES = {
    'int8': np.int8,
    'uint8': np.uint8,
    'char': np.uint8,
    'int16': np.int16,
    'uint16': np.uint16,
    'int32': np.int32,
    'uint32': np.uint32,
    'int64': np.int64,
    'uint64': np.uint64,
    'float32': np.float32,
    'float64': np.float64,
    'bool': np.bool_,
}


def _random_string(rng: np.random.Generator, bound: int = 0) -> str:
    length = int(rng.integers(0, (bound or 12) + 1))
    alphabet = string.ascii_letters + string.digits + '_/ äπ'
    return ''.join(alphabet[int(i)] for i in rng.integers(0, len(alphabet), length))


def _random_scalar(slot_type: Any, rng: np.random.Generator) -> Any:
    kind = type(slot_type).__name__
    if kind == 'NamespacedType':
        cls = get_message_class('/'.join(slot_type.namespaced_name()))
        return random_message(cls, rng)
    if kind in {'UnboundedString', 'BoundedString'}:
        return _random_string(rng, getattr(slot_type, 'maximum_size', 0))
    typename = slot_type.typename
    if typename == 'boolean':
        return bool(rng.integers(0, 2))
    if typename == 'octet':
        return bytes([int(rng.integers(0, 256))])
    if typename == 'double':
        return float(rng.normal(0.0, 1e3))
    if typename == 'float':
        return float(np.float32(rng.normal(0.0, 1e3)))
    low, high = INT_RANGES[typename]
    return int(rng.integers(low, high, endpoint=True, dtype=np.int64 if low < 0 else np.uint64))


def random_field_value(slot_type: Any, rng: np.random.Generator) -> Any:
    """Return a random value of a field described by a SLOT_TYPES entry."""
    kind = type(slot_type).__name__
    if kind not in {'Array', 'UnboundedSequence', 'BoundedSequence'}:
        return _random_scalar(slot_type, rng)
    if kind == 'Array':
        length = slot_type.size
    elif kind == 'BoundedSequence':
        length = int(rng.integers(0, slot_type.maximum_size + 1))
    else:
        length = int(rng.integers(0, 5))
    values = [_random_scalar(slot_type.value_type, rng) for _ in range(length)]
    value_type = slot_type.value_type
    typename = getattr(value_type, 'typename', None)
    if typename in TYPECODES:
        if kind == 'Array':
            return np.array(values, dtype=NUMPY_DTYPES[typename])
        return array.array(TYPECODES[typename], values)
    return values


def random_message(cls: type, rng: np.random.Generator) -> Any:
    """Return an instance of a message class with every field set to a random value."""
    values = {
        name: random_field_value(slot_type, rng)
        for name, slot_type in zip(
            cls.get_fields_and_field_types(),  # type: ignore[attr-defined]
            cls.SLOT_TYPES,  # type: ignore[attr-defined]
            strict=True,
        )
    }
    return cls(**values)


def _to_rosbags_value(value: Any, desc: tuple[Any, Any], store: Any) -> Any:
    nodetype, rest = desc
    if nodetype == Nodetype.NAME:
        return to_rosbags(value, store, rest)
    if nodetype == Nodetype.BASE:
        if rest[0] == 'byte':
            return int(np.frombuffer(value, dtype=np.int8)[0])  # rosbags' byte is int8
        return value
    (subtype, subrest), _ = rest
    if subtype == Nodetype.NAME:
        return [to_rosbags(item, store, subrest) for item in value]
    base = subrest[0]
    if base == 'string':
        return list(value)
    if base == 'byte':
        return np.frombuffer(b''.join(value), dtype=np.int8).copy()
    return np.array(list(value), dtype=ROSBAGS_DTYPES[base])


def to_rosbags(msg: Any, store: Any = None, typename: str | None = None) -> Any:
    """Return the rosbags object with the field values of a compat message."""
    store = store or uvms_typestore()
    typename = typename or message_type_name(msg)
    _, fielddefs = store.fielddefs[typename]
    kwargs = {}
    for name, desc in fielddefs:
        if name == 'structure_needs_at_least_one_member':
            kwargs[name] = 0
        else:
            kwargs[name] = _to_rosbags_value(getattr(msg, name), desc, store)
    return store.types[typename](**kwargs)


def assert_same_values(msg: Any, other: Any, path: str = '') -> None:
    """Assert that a compat message and a rosbags object hold the same field values."""
    for name in msg.get_fields_and_field_types():
        mine, theirs = getattr(msg, name), getattr(other, name)
        where = f'{path}.{name}'
        if hasattr(mine, 'get_fields_and_field_types'):
            assert_same_values(mine, theirs, where)
        elif isinstance(mine, list) and mine and hasattr(mine[0], 'get_fields_and_field_types'):
            assert len(mine) == len(theirs), where
            for index, (item, twin) in enumerate(zip(mine, theirs, strict=True)):
                assert_same_values(item, twin, f'{where}[{index}]')
        elif isinstance(mine, bytes):
            assert mine[0] == int(theirs) & 0xFF, where
        elif isinstance(mine, list) and mine and isinstance(mine[0], bytes):
            assert [item[0] for item in mine] == [int(v) & 0xFF for v in theirs], where
        elif isinstance(mine, array.array | np.ndarray | list) and not isinstance(theirs, list):
            np.testing.assert_array_equal(np.asarray(list(mine)), np.asarray(theirs), where)
        else:
            assert mine == theirs, where
