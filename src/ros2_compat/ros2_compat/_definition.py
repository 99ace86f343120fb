"""Stand-ins for the rosidl_parser.definition types that message classes list in SLOT_TYPES.

rosidl-generated classes describe each field with a ``rosidl_parser.definition`` object
(``BasicType('double')``, ``UnboundedSequence(BasicType('double'))``, ...). Code that walks
messages generically (rosidl_runtime_py style) reads their class names and attributes, so
these carry the same names and attributes.
"""

from __future__ import annotations


class AbstractType:
    """Base of every field type description."""

    __slots__ = ()

    def _key(self) -> tuple[object, ...]:
        return ()

    def __eq__(self, other: object) -> bool:
        return type(self) is type(other) and self._key() == other._key()  # type: ignore[attr-defined]

    def __hash__(self) -> int:
        return hash((type(self).__name__, self._key()))

    def __repr__(self) -> str:
        args = ', '.join(repr(part) for part in self._key())
        return f'{type(self).__name__}({args})'


class BasicType(AbstractType):
    """A primitive type by its IDL name: 'double', 'int32', 'boolean', 'octet', ..."""

    __slots__ = ('typename',)

    def __init__(self, typename: str) -> None:
        self.typename = typename

    def _key(self) -> tuple[object, ...]:
        return (self.typename,)


class NamespacedType(AbstractType):
    """A message type: namespaces ['std_msgs', 'msg'] and name 'Header'."""

    __slots__ = ('name', 'namespaces')

    def __init__(self, namespaces: list[str], name: str) -> None:
        self.namespaces = list(namespaces)
        self.name = name

    def namespaced_name(self) -> tuple[str, ...]:
        """Return the namespaces followed by the name."""
        return (*self.namespaces, self.name)

    def _key(self) -> tuple[object, ...]:
        return (self.namespaces, self.name)


class AbstractGenericString(AbstractType):
    """Base of string types."""

    __slots__ = ()

    def has_maximum_size(self) -> bool:
        """Tell whether the string is bounded."""
        return False


class UnboundedString(AbstractGenericString):
    """An unbounded string."""

    __slots__ = ()


class BoundedString(AbstractGenericString):
    """A string of at most maximum_size characters."""

    __slots__ = ('maximum_size',)

    def __init__(self, maximum_size: int) -> None:
        self.maximum_size = maximum_size

    def has_maximum_size(self) -> bool:
        """Tell whether the string is bounded."""
        return True

    def _key(self) -> tuple[object, ...]:
        return (self.maximum_size,)


class AbstractNestedType(AbstractType):
    """Base of arrays and sequences, with the element type in value_type."""

    __slots__ = ('value_type',)

    def __init__(self, value_type: AbstractType) -> None:
        self.value_type = value_type

    def _key(self) -> tuple[object, ...]:
        return (self.value_type,)


class Array(AbstractNestedType):
    """A fixed-size array of size elements."""

    __slots__ = ('size',)

    def __init__(self, value_type: AbstractType, size: int) -> None:
        super().__init__(value_type)
        self.size = size

    def _key(self) -> tuple[object, ...]:
        return (self.value_type, self.size)


class AbstractSequence(AbstractNestedType):
    """Base of sequences."""

    __slots__ = ()


class UnboundedSequence(AbstractSequence):
    """A sequence of any length."""

    __slots__ = ()


class BoundedSequence(AbstractSequence):
    """A sequence of at most maximum_size elements."""

    __slots__ = ('maximum_size',)

    def __init__(self, value_type: AbstractType, maximum_size: int) -> None:
        super().__init__(value_type)
        self.maximum_size = maximum_size

    def _key(self) -> tuple[object, ...]:
        return (self.value_type, self.maximum_size)
