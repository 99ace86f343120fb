"""CDR serializers and deserializers generated per message type, byte-identical to ROS 2.

The wire format is what rmw_fastrtps (ROS 2 Jazzy's default) writes for
``rclpy.serialization.serialize_message``: the 4-byte encapsulation header
``00 01 00 00`` (CDR, little endian), then the fields in order, each primitive aligned to
its size (at most 8) relative to the end of the header; strings are a uint32 length
including the terminating NUL, the bytes, the NUL; sequences a uint32 count then the
elements; an empty structure is one zero byte. rosbags' ``serialize_cdr`` writes the same
bytes and is the test oracle.

For speed each message type gets straight-line Python source: the alignment is tracked at
generation time, so consecutive fixed-size fields (with their padding) become one
``struct.Struct.pack``/``unpack_from`` call, nested messages are inlined, and numeric
sequences and arrays are copied as raw buffers.
"""

from __future__ import annotations

import array
import struct
import sys
import threading
from typing import TYPE_CHECKING, Any

import numpy as np

from ros2_compat._messages import (
    _EMPTY_MEMBER,
    CHECK_FIELDS_DEFAULT,
    PRIMITIVES,
    get_class,
    type_fields,
)

if TYPE_CHECKING:
    from collections.abc import Callable

HEADER = b'\x00\x01\x00\x00'
_LITTLE = sys.byteorder == 'little'


class CdrError(ValueError):
    """A message could not be converted to or from CDR."""


def _seq_bytes(values: Any, typecode: str) -> bytes:
    """Return the little-endian bytes of a numeric sequence of any container type."""
    result = array.array(typecode, values)
    if not _LITTLE:
        result.byteswap()
    return result.tobytes()


def _array_le_bytes(values: array.array[Any]) -> bytes:
    """Return the little-endian bytes of an array.array on a big-endian host."""
    swapped = array.array(values.typecode, values)
    swapped.byteswap()
    return swapped.tobytes()


def _fix_ndarray(value: Any, dtype: str, size: int, name: str) -> np.ndarray[Any, Any]:
    """Return a fixed-size array field as a little-endian numpy array of its exact length."""
    result = np.asarray(value, dtype=np.dtype(dtype).newbyteorder('<')).reshape(-1)
    if result.shape != (size,):
        msg = f"field '{name}' must hold {size} values, not {result.size}"
        raise CdrError(msg)
    return result


def _check_len(value: Any, size: int, name: str) -> Any:
    """Return a fixed-size array field after checking its length."""
    if len(value) != size:
        msg = f"field '{name}' must hold {size} values, not {len(value)}"
        raise CdrError(msg)
    return value


def _octets(value: Any) -> bytes:
    """Return the bytes of a byte[] field: a list of 1-byte bytes objects, or bytes."""
    if isinstance(value, bytes | bytearray | memoryview):
        return bytes(value)
    return b''.join(value)


def _le_array(typecode: str, raw: bytes) -> array.array[Any]:
    """Return an array.array from little-endian bytes."""
    result = array.array(typecode)
    result.frombytes(raw)
    if not _LITTLE:
        result.byteswap()
    return result


_HELPERS: dict[str, object] = {
    '_PAD': tuple(b'\x00' * n for n in range(8)),
    '_U32': struct.Struct('<I'),
    '_HEADER': HEADER,
    '_array': array.array,
    '_ndarray': np.ndarray,
    '_np': np,
    '_new': object.__new__,
    '_seq_bytes': _seq_bytes,
    '_array_le_bytes': _array_le_bytes,
    '_fix_ndarray': _fix_ndarray,
    '_check_len': _check_len,
    '_octets': _octets,
    '_le_array': _le_array,
    '_CHECK': CHECK_FIELDS_DEFAULT,
    'CdrError': CdrError,
}


class _Writer:
    """Source writer shared by serializers and deserializers: alignment state and groups.

    The alignment state says that the payload offset is ``res`` modulo ``mod``; while that
    settles a field's padding, the field joins the pending struct group.
    """

    def __init__(self, entry_mod: int) -> None:
        self.lines: list[str] = []
        self.namespace: dict[str, object] = dict(_HELPERS)
        self.fmt: list[str] = []
        self.items: list[str] = []
        self.post: list[str] = []
        self.mod = entry_mod
        self.res = 0
        self.indent = 1
        self.counter = 0

    def var(self, prefix: str) -> str:
        """Return a fresh local variable name."""
        self.counter += 1
        return f'{prefix}{self.counter}'

    def ref(self, obj: object, prefix: str) -> str:
        """Return the namespace name of an object used by the generated code."""
        for name, value in self.namespace.items():
            if value is obj and name.startswith(prefix):
                return name
        name = f'{prefix}{len(self.namespace)}'
        self.namespace[name] = obj
        return name

    def now(self, line: str) -> None:
        """Emit a line before the pending group (it must not depend on the buffer position)."""
        self.lines.append('    ' * self.indent + line)

    def emit(self, line: str) -> None:
        """Flush the pending group, then emit a line."""
        self.flush()
        self.now(line)

    def flush(self) -> None:
        """Emit the pending group of fixed-size fields as one struct call."""
        raise NotImplementedError

    def unknown(self) -> None:
        """Forget the alignment (after variable-length data)."""
        self.mod, self.res = 1, 0

    def advance(self, size: int) -> None:
        """Account for size bytes in the alignment state."""
        self.res = (self.res + size) % self.mod

    def dynamic_align(self, size: int) -> None:
        """Emit run-time padding to a multiple of size."""
        raise NotImplementedError

    def align(self, size: int) -> None:
        """Align to size: static padding in the group when known, else at run time."""
        if size <= 1:
            return
        if self.mod >= size:
            pad = -self.res % size
            if pad:
                self.fmt.append(f'{pad}x')
                self.advance(pad)
        else:
            self.flush()
            self.dynamic_align(size)
            self.mod, self.res = size, 0

    def after_count_state(self, element_size: int) -> None:
        """Set the state after a sequence of elements of element_size bytes."""
        self.mod, self.res = min(max(element_size, 1), 4), 0


class _Serializer(_Writer):
    """Writes a function appending a message's CDR bytes to ``buf``."""

    def flush(self) -> None:
        if not self.fmt:
            return
        packer = struct.Struct('<' + ''.join(self.fmt))
        name = self.ref(packer, '_S')
        self.lines.append('    ' * self.indent + f'buf += {name}.pack({", ".join(self.items)})')
        self.fmt, self.items = [], []

    def dynamic_align(self, size: int) -> None:
        self.now(f'buf += _PAD[(4 - len(buf)) & {size - 1}]')

    def primitive(self, base: str, expr: str) -> None:
        prim = PRIMITIVES[base]
        self.align(prim.size)
        self.fmt.append(prim.struct)
        self.items.append(expr)
        self.advance(prim.size)

    def string(self, expr: str) -> None:
        encoded = self.var('s')
        self.now(f'{encoded} = {expr}.encode()')
        self.primitive('uint32', f'len({encoded}) + 1')
        self.emit(f'buf += {encoded}')
        self.now("buf += b'\\x00'")
        self.unknown()

    def fields(self, typename: str, var: str) -> None:
        specs = type_fields(typename)
        for spec in specs:
            expr = f'{var}._{spec.name}'
            if spec.name == _EMPTY_MEMBER and len(specs) == 1:
                self.fmt.append('x')
                self.advance(1)
            elif spec.kind == 'base':
                assert spec.base is not None
                if spec.base == 'string':
                    self.string(expr)
                else:
                    self.primitive(spec.base, expr)
            elif spec.kind == 'msg':
                assert spec.msgtype is not None
                nested = self.var('m')
                self.now(f'{nested} = {expr}')
                self.fields(spec.msgtype, nested)
            elif spec.kind == 'sequence':
                self.sequence(spec.base, spec.msgtype, expr)
            else:
                self.fixed_array(spec.base, spec.msgtype, spec.size, spec.name, expr)

    def sequence(self, base: str | None, msgtype: str | None, expr: str) -> None:
        value = self.var('q')
        self.now(f'{value} = {expr}')
        self.primitive('uint32', f'len({value})')
        if base is None:
            assert msgtype is not None
            self.element_loop(msgtype, value)
        elif base == 'string':
            self.string_loop(value)
        elif base == 'bool':
            self.emit(f'buf += bytes(map(bool, {value}))')
            self.unknown()
        elif base == 'byte':
            self.emit(f'buf += _octets({value})')
            self.unknown()
        else:
            prim = PRIMITIVES[base]
            self.flush()
            if prim.size > 4:
                if self.mod >= prim.size:
                    padding = b'\x00' * (-self.res % prim.size)
                    if padding:
                        self.now(f'if {value}: buf += {padding!r}')
                else:
                    self.now(f'if {value}: buf += _PAD[(4 - len(buf)) & {prim.size - 1}]')
            raw = f'{value}.tobytes()' if _LITTLE else f'_array_le_bytes({value})'
            self.now(
                f'buf += {raw} if {value}.__class__ is _array '
                f"else _seq_bytes({value}, '{prim.typecode}')"
            )
            self.after_count_state(prim.size)

    def string_loop(self, value: str) -> None:
        item, encoded = self.var('e'), self.var('s')
        self.emit(f'for {item} in {value}:')
        self.indent += 1
        self.now(f'{encoded} = {item}.encode()')
        self.now('buf += _PAD[(4 - len(buf)) & 3]')
        self.now(f'buf += _U32.pack(len({encoded}) + 1)')
        self.now(f'buf += {encoded}')
        self.now("buf += b'\\x00'")
        self.indent -= 1
        self.unknown()

    def element_loop(self, msgtype: str, value: str) -> None:
        func = self.ref(element_serializer(msgtype), '_ser_')
        item = self.var('e')
        self.emit(f'for {item} in {value}:')
        self.now(f'    {func}(buf, {item})')
        self.unknown()

    def fixed_array(
        self, base: str | None, msgtype: str | None, size: int, name: str, expr: str
    ) -> None:
        value = self.var('a')
        self.now(f'{value} = {expr}')
        if base is not None and PRIMITIVES.get(base) and PRIMITIVES[base].typecode:
            prim = PRIMITIVES[base]
            dtype = self.ref(np.dtype(prim.dtype), '_DN')
            self.now(
                f'if {value}.__class__ is not _ndarray or {value}.dtype is not {dtype} or '
                f'{value}.shape != ({size},): '
                f'{value} = _fix_ndarray({value}, {prim.dtype!r}, {size}, {name!r})'
            )
            self.align(prim.size)
            self.fmt.append(f'{size * prim.size}s')
            self.items.append(f'{value}.tobytes()')
            self.advance(size * prim.size)
            return
        self.now(f'_check_len({value}, {size}, {name!r})')
        if base == 'bool':
            self.fmt.append(f'{size}?')
            self.items.append(f'*{value}')
            self.advance(size)
        elif base == 'byte':
            self.fmt.append(f'{size}s')
            self.items.append(f'_octets({value})')
            self.advance(size)
        elif base == 'string':
            self.string_loop(value)
        else:
            assert msgtype is not None
            self.element_loop(msgtype, value)


class _Deserializer(_Writer):
    """Writes a function reading a message from ``data`` at ``pos``."""

    def flush(self) -> None:
        if not self.fmt:
            return
        unpacker = struct.Struct('<' + ''.join(self.fmt))
        name = self.ref(unpacker, '_S')
        pad = '    ' * self.indent
        if self.items:
            self.lines.append(f'{pad}{", ".join(self.items)}, = {name}.unpack_from(data, pos)')
        self.lines.append(f'{pad}pos += {unpacker.size}')
        self.lines.extend(pad + line for line in self.post)
        self.fmt, self.items, self.post = [], [], []

    def dynamic_align(self, size: int) -> None:
        self.now(f'pos += (4 - pos) & {size - 1}')

    def primitive(self, base: str, target: str) -> None:
        prim = PRIMITIVES[base]
        self.align(prim.size)
        self.fmt.append(prim.struct)
        self.items.append(target)
        self.advance(prim.size)

    def string(self, target: str) -> None:
        length = self.var('n')
        self.primitive('uint32', length)
        self.emit(f'{target} = data[pos:pos + {length} - 1].decode()')
        self.now(f'pos += {length}')
        self.unknown()

    def new_message(self, msgtype: str, var: str) -> None:
        cls = self.ref(get_class(msgtype), '_C')
        self.now(f'{var} = _new({cls})')
        self.now(f'{var}._check_fields = _CHECK')

    def fields(self, typename: str, var: str) -> None:
        specs = type_fields(typename)
        for spec in specs:
            target = f'{var}._{spec.name}'
            if spec.name == _EMPTY_MEMBER and len(specs) == 1:
                self.fmt.append('x')
                self.advance(1)
            elif spec.kind == 'base':
                assert spec.base is not None
                if spec.base == 'string':
                    self.string(target)
                else:
                    self.primitive(spec.base, target)
            elif spec.kind == 'msg':
                assert spec.msgtype is not None
                nested = self.var('m')
                self.new_message(spec.msgtype, nested)
                self.now(f'{target} = {nested}')
                self.fields(spec.msgtype, nested)
            elif spec.kind == 'sequence':
                self.sequence(spec.base, spec.msgtype, target)
            else:
                self.fixed_array(spec.base, spec.msgtype, spec.size, target)

    def sequence(self, base: str | None, msgtype: str | None, target: str) -> None:
        count = self.var('n')
        self.primitive('uint32', count)
        if base is None:
            assert msgtype is not None
            self.element_loop(msgtype, count, target)
        elif base == 'string':
            self.string_loop(count, target)
        elif base == 'bool':
            self.emit(f'{target} = [b != 0 for b in data[pos:pos + {count}]]')
            self.now(f'pos += {count}')
            self.unknown()
        elif base == 'byte':
            self.emit(f'{target} = [data[i:i + 1] for i in range(pos, pos + {count})]')
            self.now(f'pos += {count}')
            self.unknown()
        else:
            prim = PRIMITIVES[base]
            self.flush()
            if prim.size > 4:
                if self.mod >= prim.size:
                    pad = -self.res % prim.size
                    if pad:
                        self.now(f'if {count}: pos += {pad}')
                else:
                    self.now(f'if {count}: pos += (4 - pos) & {prim.size - 1}')
            end = self.var('z')
            self.now(f'{end} = pos + {count} * {prim.size}')
            self.now(f"{target} = _le_array('{prim.typecode}', data[pos:{end}])")
            self.now(f'pos = {end}')
            self.after_count_state(prim.size)

    def string_loop(self, count: str | int, target: str) -> None:
        items, length = self.var('l'), self.var('k')
        self.emit(f'{items} = []')
        self.now(f'for _ in range({count}):')
        self.indent += 1
        self.now('pos += (4 - pos) & 3')
        self.now(f'{length}, = _U32.unpack_from(data, pos)')
        self.now(f'{items}.append(data[pos + 4:pos + 3 + {length}].decode())')
        self.now(f'pos += 4 + {length}')
        self.indent -= 1
        self.now(f'{target} = {items}')
        self.unknown()

    def element_loop(self, msgtype: str, count: str | int, target: str) -> None:
        func = self.ref(element_deserializer(msgtype), '_de_')
        items, item = self.var('l'), self.var('e')
        self.emit(f'{items} = []')
        self.now(f'for _ in range({count}):')
        self.now(f'    {item}, pos = {func}(data, pos)')
        self.now(f'    {items}.append({item})')
        self.now(f'{target} = {items}')
        self.unknown()

    def fixed_array(self, base: str | None, msgtype: str | None, size: int, target: str) -> None:
        if base is not None and PRIMITIVES.get(base) and PRIMITIVES[base].typecode:
            prim = PRIMITIVES[base]
            dtype = self.ref(np.dtype(prim.dtype).newbyteorder('<'), '_DT')
            native = self.ref(np.dtype(prim.dtype), '_DN')
            raw = self.var('b')
            self.align(prim.size)
            self.fmt.append(f'{size * prim.size}s')
            self.items.append(raw)
            self.post.append(f'{target} = _np.frombuffer({raw}, {dtype}).astype({native})')
            self.advance(size * prim.size)
        elif base == 'bool':
            raw = self.var('b')
            self.fmt.append(f'{size}s')
            self.items.append(raw)
            self.post.append(f'{target} = [b != 0 for b in {raw}]')
            self.advance(size)
        elif base == 'byte':
            raw = self.var('b')
            self.fmt.append(f'{size}s')
            self.items.append(raw)
            self.post.append(f'{target} = [{raw}[i:i + 1] for i in range({size})]')
            self.advance(size)
        elif base == 'string':
            self.string_loop(size, target)
        else:
            assert msgtype is not None
            self.element_loop(msgtype, size, target)


_lock = threading.RLock()
_serializers: dict[str, Callable[[Any], bytes]] = {}
_deserializers: dict[str, Callable[[bytes], Any]] = {}
_element_serializers: dict[str, Callable[[bytearray, Any], None]] = {}
_element_deserializers: dict[str, Callable[[bytes, int], tuple[Any, int]]] = {}


def _compile(writer: _Writer, header: list[str], footer: list[str], name: str, what: str) -> Any:
    writer.flush()
    source = '\n'.join([*header, *writer.lines, *footer]) + '\n'
    code = compile(source, f'<ros2_compat {what}>', 'exec')
    exec(code, writer.namespace)
    func = writer.namespace[name]
    func.__source__ = source  # type: ignore[attr-defined]
    return func


def serializer_source(typename: str) -> str:
    """Return the generated source of a type's top-level serializer (for inspection)."""
    return serializer(typename).__source__  # type: ignore[attr-defined, no-any-return]


def serializer(typename: str) -> Callable[[Any], bytes]:
    """Return the function serializing a message of typename to CDR bytes (with header)."""
    func = _serializers.get(typename)
    if func is None:
        with _lock:
            writer = _Serializer(entry_mod=8)
            writer.fields(typename, 'm0')
            func = _compile(
                writer,
                ['def serialize(m0):', '    buf = bytearray(_HEADER)'],
                ['    return bytes(buf)'],
                'serialize',
                f'serializer {typename}',
            )
            _serializers[typename] = func
    return func


def element_serializer(typename: str) -> Callable[[bytearray, Any], None]:
    """Return the function appending one message (at any alignment) to a buffer."""
    func = _element_serializers.get(typename)
    if func is None:
        with _lock:
            writer = _Serializer(entry_mod=1)
            writer.fields(typename, 'm0')
            func = _compile(
                writer,
                ['def serialize_element(buf, m0):'],
                ['    return None'],
                'serialize_element',
                f'element serializer {typename}',
            )
            _element_serializers[typename] = func
    return func


def deserializer(typename: str) -> Callable[[bytes], Any]:
    """Return the function building a message of typename from CDR bytes (with header)."""
    func = _deserializers.get(typename)
    if func is None:
        with _lock:
            writer = _Deserializer(entry_mod=8)
            writer.new_message(typename, 'm0')
            writer.fields(typename, 'm0')
            func = _compile(
                writer,
                ['def deserialize(data):', '    pos = 4'],
                [
                    '    if pos > len(data):',
                    "        raise CdrError('serialized data is truncated')",
                    '    return m0',
                ],
                'deserialize',
                f'deserializer {typename}',
            )
            _deserializers[typename] = func
    return func


def element_deserializer(typename: str) -> Callable[[bytes, int], tuple[Any, int]]:
    """Return the function reading one message at pos (any alignment): (message, new pos)."""
    func = _element_deserializers.get(typename)
    if func is None:
        with _lock:
            writer = _Deserializer(entry_mod=1)
            writer.new_message(typename, 'm0')
            writer.fields(typename, 'm0')
            func = _compile(
                writer,
                ['def deserialize_element(data, pos):'],
                ['    return m0, pos'],
                'deserialize_element',
                f'element deserializer {typename}',
            )
            _element_deserializers[typename] = func
    return func


_CONVERSION_ERRORS = (
    struct.error,
    AttributeError,
    TypeError,
    ValueError,
    OverflowError,
    UnicodeError,
    IndexError,
)


def serialize(msg: Any) -> bytes:
    """Serialize a compat message to CDR bytes, as rclpy's serialize_message does.

    Raises:
        CdrError: A field holds a value its type cannot take.
    """
    typename = type(msg)._TYPE_NAME
    func = _serializers.get(typename) or serializer(typename)
    try:
        return func(msg)
    except CdrError:
        raise
    except _CONVERSION_ERRORS as exc:
        msg_text = f'cannot serialize {typename}: {exc}'
        raise CdrError(msg_text) from exc


def deserialize(data: bytes | bytearray | memoryview, cls: type) -> Any:
    """Build a compat message of class cls from CDR bytes.

    Raises:
        CdrError: The data is not a valid little-endian CDR encoding of the type.
    """
    typename: str = cls._TYPE_NAME  # type: ignore[attr-defined]
    if not isinstance(data, bytes):
        data = bytes(data)
    if data[:2] != HEADER[:2]:
        msg = f'cannot deserialize {typename}: not little-endian CDR (header {data[:4]!r})'
        raise CdrError(msg)
    func = _deserializers.get(typename) or deserializer(typename)
    try:
        return func(data)
    except CdrError:
        raise
    except _CONVERSION_ERRORS as exc:
        msg = f'cannot deserialize {typename}: {exc}'
        raise CdrError(msg) from exc
