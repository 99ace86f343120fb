"""Raw CDR codecs of messages whose variable lengths are fixed at start-up.

A ROS 2 message on the wire is a 4-byte encapsulation header (``00 01``: CDR, little endian,
then two option bytes) followed by its fields, each aligned to its own size relative to the
byte after the header; a string is a uint32 length counting its NUL, the bytes and the NUL; a
sequence is a uint32 count, then its elements. Once the strings (frame ids, joint names) and
the sequence lengths (n joints, p thrusters) are fixed, every number sits at a fixed offset:
encoding is writing numbers into a preallocated buffer, decoding is a view of the bytes.

`MessageCodec` builds that layout from the message class's own rosidl description
(``SLOT_TYPES``, the type rclpy and the C type support are generated from) and the values
fixed for one robot. `RawDecoder` takes a payload of a raw subscription: by the layout when
it fits, else (another publisher's frame id or joint order) by rclpy's deserializer, else it
is malformed (`MalformedPayloadError`, counted).

Example:
    >>> from geometry_msgs.msg import WrenchStamped
    >>> codec = MessageCodec(WrenchStamped, {'header.frame_id': 'ft_sensor_link'})
    >>> out = codec.message()
    >>> write_stamp(out, 1_500_000_000)
    >>> codec.pack('wrench', out, (1.0, 2.0, 3.0, 0.0, 0.0, 0.0))
    >>> data = bytes(out)
    >>> read_stamp_ns(data), codec.view(data)['wrench.force.y'].item()
    (1500000000, 2.0)
"""

from __future__ import annotations

import importlib
import itertools
import struct
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

#: Encapsulation of the payloads we write and read: CDR, little endian.
CDR_LE = b'\x00\x01'
#: Bytes before the first field (encapsulation kind and options).
ENCAPSULATION_SIZE = 4
#: Trailing bytes a writer may add to round a payload up to 4 bytes (XCDR padding).
MAX_TRAILING = 3

_STAMP = struct.Struct('<iI')
_BASIC = {  # rosidl basic type: (numpy/struct code, size)
    'double': ('d', 8), 'float': ('f', 4), 'int64': ('q', 8), 'uint64': ('Q', 8),
    'int32': ('i', 4), 'uint32': ('I', 4), 'int16': ('h', 2), 'uint16': ('H', 2),
    'int8': ('b', 1), 'uint8': ('B', 1), 'octet': ('B', 1), 'char': ('B', 1),
    'boolean': ('?', 1),
}


class CodecError(ValueError):
    """A message type whose layout cannot be fixed (a length not given, a type not handled)."""


class MalformedPayloadError(ValueError):
    """A payload that is not a message of its topic's type (length, encapsulation, content)."""


@dataclass(frozen=True)
class Leaf:
    """A run of numbers at a fixed byte offset of the payload (from the payload's start)."""

    path: str
    offset: int
    code: str  # struct / numpy type code
    count: int  # 1 for a scalar field

    @property
    def size(self) -> int:
        """Bytes the run occupies."""
        return struct.calcsize('<' + self.code) * self.count


class _Builder:
    """Walks a rosidl type description and lays its fields out as CDR does."""

    def __init__(self, fixed: Mapping[str, Any]) -> None:
        self.fixed = dict(fixed)
        self.used: set[str] = set()
        self.body = bytearray()
        self.leaves: list[Leaf] = []
        self.groups: list[Leaf] = []
        self.constant: list[tuple[int, int]] = []  # byte ranges fixed by the layout

    def align(self, size: int) -> None:
        self.body.extend(bytes(-len(self.body) % size))

    def take(self, path: str) -> Any:
        if path not in self.fixed:
            msg = f'the length or value of {path!r} must be fixed to build its codec'
            raise CodecError(msg)
        self.used.add(path)
        return self.fixed[path]

    def constant_bytes(self, data: bytes) -> None:
        start = len(self.body)
        self.body.extend(data)
        self.constant.append((start, len(self.body)))

    def count(self, value: int) -> None:
        self.align(4)
        self.constant_bytes(struct.pack('<I', value))

    def string(self, text: str) -> None:
        raw = text.encode() + b'\0'
        self.count(len(raw))
        self.constant_bytes(raw)

    def numbers(self, path: str, typename: str, count: int) -> None:
        code, size = _BASIC[typename]
        self.align(size)
        if count:
            self.leaves.append(Leaf(path, ENCAPSULATION_SIZE + len(self.body), code, count))
        self.body.extend(bytes(size * count))

    def message(self, prefix: str, msg_type: type) -> None:
        first = len(self.leaves)
        names = msg_type.get_fields_and_field_types()  # type: ignore[attr-defined]
        for name, slot in zip(names, msg_type.SLOT_TYPES, strict=True):  # type: ignore[attr-defined]
            self.field(f'{prefix}{name}', slot)
        runs = self.leaves[first:]
        if prefix and len(runs) > 1 and len({leaf.code for leaf in runs}) == 1 and all(
                a.offset + a.size == b.offset for a, b in itertools.pairwise(runs)):
            self.groups.append(Leaf(prefix[:-1], runs[0].offset, runs[0].code,
                                    sum(leaf.count for leaf in runs)))

    def field(self, path: str, slot: Any) -> None:
        kind = type(slot).__name__
        if kind == 'BasicType':
            self.numbers(path, slot.typename, 1)
        elif kind in ('UnboundedString', 'BoundedString'):
            self.string(str(self.take(path)))
        elif kind == 'NamespacedType':
            module = importlib.import_module('.'.join(slot.namespaces))
            self.message(f'{path}.', getattr(module, slot.name))
        elif kind == 'Array' and type(slot.value_type).__name__ == 'BasicType':
            self.numbers(path, slot.value_type.typename, slot.size)
        elif kind in ('UnboundedSequence', 'BoundedSequence'):
            element = type(slot.value_type).__name__
            if element == 'BasicType':
                count = int(self.take(path))
                self.count(count)
                self.numbers(path, slot.value_type.typename, count)
            elif element in ('UnboundedString', 'BoundedString'):
                texts = [str(t) for t in self.take(path)]
                self.count(len(texts))
                for text in texts:
                    self.string(text)
            else:
                raise CodecError(f'{path!r}: sequences of {element} are not handled')
        else:
            raise CodecError(f'{path!r}: fields of kind {kind} are not handled')


class MessageCodec:
    """The fixed CDR layout of one message type for one robot.

    Args:
        msg_type: The rosidl Python class (e.g. ``sensor_msgs.msg.JointState``).
        fixed: Dotted field path to its fixed value: a string for a string field (frame
            ids), a list of strings for a string sequence (joint names), a count for a
            number sequence (``'position': 3``). Every variable-length field needs one.

    Attributes:
        fixed: The fixed values the layout was built with.
        fields: Every number field (a scalar, a fixed array or a sequence), payload order.
        leaves: The fields and the groups, by dotted path.
        size: Payload length in bytes, header included.
        template: A payload of zeros with the fixed strings and counts written in.
        dtype: numpy structured type over a payload: every number field by its dotted path,
            and every sub-message made of numbers of one type, contiguous, as one array
            (``'pose.pose'``: position then orientation, 7 doubles).

    Raises:
        CodecError: A variable-length field without a fixed value, a fixed value for a field
            the type does not have, or a field kind not handled (sequences of messages).
    """

    def __init__(self, msg_type: type, fixed: Mapping[str, Any] | None = None) -> None:
        builder = _Builder(fixed or {})
        builder.message('', msg_type)
        unused = sorted(set(builder.fixed) - builder.used)
        if unused:
            raise CodecError(f'{msg_type.__name__} has no variable field {unused[0]!r}')
        self.msg_type = msg_type
        self.fixed = dict(builder.fixed)
        self.size = ENCAPSULATION_SIZE + len(builder.body)
        self.template = CDR_LE + b'\0\0' + bytes(builder.body)
        self.fields = tuple(builder.leaves)
        self.leaves = {leaf.path: leaf for leaf in (*builder.leaves, *builder.groups)}
        self._constant = [(start + ENCAPSULATION_SIZE, end + ENCAPSULATION_SIZE)
                          for start, end in _merged(builder.constant)]
        leaves = list(self.leaves.values())
        self.dtype = np.dtype({
            'names': [leaf.path for leaf in leaves],
            'formats': [('<' + leaf.code, (leaf.count,)) if leaf.count > 1
                        else '<' + leaf.code for leaf in leaves],
            'offsets': [leaf.offset for leaf in leaves],
            'itemsize': self.size})

    def message(self) -> bytearray:
        """A new payload to fill (the template's bytes: fixed strings and counts in place)."""
        return bytearray(self.template)

    def struct(self, paths: Sequence[str], write: bool = False) -> tuple[int, struct.Struct]:
        """Offset and `struct.Struct` reading (or writing) the given fields in one call.

        The fields must be in payload order; a read skips the gaps between them. A write
        fills the gaps with zeros, so with ``write`` a gap may hold padding only, not a fixed
        count or string. Example: ``codec.struct(['weight', 'phase', 'contact_force'])``.

        Raises:
            CodecError: Fields out of order, or (``write``) a gap over fixed bytes.
        """
        leaves = [self.leaves[path] for path in paths]
        fmt, end = '<', leaves[0].offset
        for leaf in leaves:
            if leaf.offset < end:
                raise CodecError(f'{leaf.path!r} overlaps or precedes the field before it')
            if write and any(start < leaf.offset and stop > end
                             for start, stop in self._constant):
                raise CodecError(f'fixed bytes before {leaf.path!r}: write it on its own')
            fmt += f'{leaf.offset - end}x' if leaf.offset > end else ''
            fmt += f'{leaf.count}{leaf.code}'
            end = leaf.offset + leaf.size
        return leaves[0].offset, struct.Struct(fmt)

    def pack(self, path: str, out: bytearray, values: Sequence[float]) -> None:
        """Write one field (or group) of ``out`` from plain numbers (slow path: tests, set-up)."""
        offset, fields = self.struct([path], write=True)
        fields.pack_into(out, offset, *values)

    def check(self, data: bytes) -> str | None:
        """Why ``data`` does not fit this layout, or None when it does."""
        if not isinstance(data, bytes | bytearray | memoryview):
            return f'a payload is bytes, not {type(data).__name__}'
        if not self.size <= len(data) <= self.size + MAX_TRAILING:
            return f'{len(data)} bytes, expected {self.size}'
        if data[:2] != CDR_LE:
            return f'encapsulation {bytes(data[:2]).hex()}, expected {CDR_LE.hex()} (CDR_LE)'
        template = self.template
        for start, end in self._constant:
            if data[start:end] != template[start:end]:
                return f'bytes {start}-{end} (frame ids, names or counts) differ'
        return None

    def view(self, data: bytes) -> np.ndarray:
        """The numbers of a payload as a read-only structured view, fields by dotted path.

        Raises:
            MalformedPayloadError: The payload does not fit the layout (says why).
        """
        reason = self.check(data)
        if reason is not None:
            raise MalformedPayloadError(f'{self.msg_type.__name__}: {reason}')
        return np.ndarray((), self.dtype, buffer=data)


def _merged(ranges: list[tuple[int, int]]) -> list[tuple[int, int]]:
    """Adjacent byte ranges joined, so that a check compares few slices."""
    out: list[tuple[int, int]] = []
    for start, end in ranges:
        if out and out[-1][1] == start:
            out[-1] = (out[-1][0], end)
        else:
            out.append((start, end))
    return out


def write_stamp(out: bytearray, t_ns: int) -> None:
    """Write ``header.stamp`` (or ``clock``: the first field of every stamped type) in ns."""
    _STAMP.pack_into(out, ENCAPSULATION_SIZE, *divmod(int(t_ns), 1_000_000_000))


def read_stamp_ns(data: bytes) -> int:
    """The first field's stamp (``header.stamp``) in ns; the payload must be checked first."""
    sec, nanosec = _STAMP.unpack_from(data, ENCAPSULATION_SIZE)
    return int(sec * 1_000_000_000 + nanosec)


class PayloadWriter:
    """One topic's preallocated payload and the structs that write its numbers.

    Args:
        codec: The topic's layout.
        groups: Runs of fields written by one ``struct.pack_into`` each (padding between
            the fields of a run only), e.g. ``['pose.pose'], ['twist.twist']``.
    """

    def __init__(self, codec: MessageCodec, *groups: Sequence[str]) -> None:
        self.buffer = codec.message()
        self.structs = [codec.struct(paths, write=True) for paths in groups]

    def fill(self, t_ns: int, *values: Sequence[float]) -> bytes:
        """The payload stamped t_ns with the numbers of each group, as bytes to publish."""
        buffer = self.buffer
        write_stamp(buffer, t_ns)
        for (offset, fields), numbers in zip(self.structs, values, strict=True):
            fields.pack_into(buffer, offset, *numbers)
        return bytes(buffer)


class Decoded(NamedTuple):
    """A payload taken from a raw subscription: its stamp, and its view or its message."""

    stamp_ns: int
    view: bytes | None  # the payload, when it fits the codec's layout
    message: Any  # the deserialized message otherwise (another publisher's layout)


class RawDecoder:
    """Decodes one topic's raw payloads: by the layout, else by rclpy, else malformed.

    A payload of another layout (a frame id of '' or names in another order from another
    publisher) is deserialized by rclpy, so that the node's typed checks decide on it as
    before; one that neither reads is malformed: counted in ``malformed``, its reason kept in
    ``last_error``.
    """

    def __init__(self, codec: MessageCodec) -> None:
        self.codec = codec
        self.malformed = 0
        self.last_error = ''

    def decode(self, data: bytes) -> Decoded:
        """Decode one payload.

        Raises:
            MalformedPayloadError: Neither the layout nor rclpy's deserializer reads it.
        """
        if self.codec.check(data) is None:
            return Decoded(read_stamp_ns(data), data, None)
        from rclpy.serialization import deserialize_message

        try:
            message = deserialize_message(bytes(data), self.codec.msg_type)
            stamp = message.header.stamp
        except Exception as error:  # rclpy raises RMWError / TypeError, by version
            self.malformed += 1
            reason = self.codec.check(data)
            self.last_error = f'{self.codec.msg_type.__name__}: {reason}'
            raise MalformedPayloadError(self.last_error) from error
        return Decoded(int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec), None, message)


class RawReader:
    """One input topic: decode a payload, then convert it (in place, or typed as before).

    Args:
        codec: The layout our graph publishes on the topic.
        fast: A payload in that layout (its ``struct`` reads) to the value.
        typed: A node's typed reader, the reference, for a message of any other layout.
    """

    def __init__(self, codec: MessageCodec, fast: Callable[[bytes], Any],
                 typed: Callable[[Any], Any]) -> None:
        self.decoder = RawDecoder(codec)
        self._fast = fast
        self._typed = typed

    def decode(self, data: bytes) -> Decoded:
        """Stamp and payload or message (raises `MalformedPayloadError`, counted)."""
        return self.decoder.decode(data)

    def value(self, decoded: Decoded) -> Any:
        """The converted value (the converters' own errors pass through)."""
        if decoded.view is not None:
            return self._fast(decoded.view)
        return self._typed(decoded.message)

    def read(self, data: bytes) -> tuple[int, Any]:
        """Stamp (ns) and value of one payload."""
        decoded = self.decode(data)
        return decoded.stamp_ns, self.value(decoded)
