"""Lockstep inputs of the controller gathered per stamp, so that no stray input stalls it."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, NamedTuple


class Input(NamedTuple):
    """One input of the controller: its stamp, node-clock arrival (ns) and converted value."""

    stamp_ns: int
    arrival_ns: int
    value: Any  # None when the message was rejected


@dataclass
class _PendingEntry:
    """The inputs of one stamp that have arrived (None: arrived but rejected)."""

    values: dict[str, Any] = field(default_factory=dict)
    valid: int = 0
    complete: bool = False


class PendingStamps:
    """Lockstep inputs gathered per stamp, so that inputs of other stamps cannot disturb one.

    A stamp is complete when every topic has arrived for it and at least one of them was
    valid: a rejected input at the stamp of the running exchange is then answered with the
    last safe command, while rejected inputs of stamps nothing valid asked for never complete
    and never evict an entry that holds valid inputs. At most ``capacity`` stamps are kept.
    """

    def __init__(self, topics: tuple[str, ...], capacity: int = 16) -> None:
        self._topics = topics
        self._capacity = capacity
        self._entries: dict[int, _PendingEntry] = {}

    def arrive(self, stamp_ns: int, topic: str, value: Any) -> _PendingEntry:
        """Record one input (None if it was rejected); return the entry of its stamp."""
        entry = self._entries.get(stamp_ns)
        if entry is None:
            if len(self._entries) >= self._capacity:
                self._evict()
            entry = self._entries[stamp_ns] = _PendingEntry()
        if value is not None and entry.values.get(topic) is None:
            entry.valid += 1
        if value is not None or topic not in entry.values:
            entry.values[topic] = value
        entry.complete = entry.valid > 0 and len(entry.values) == len(self._topics)
        return entry

    def finish(self, stamp_ns: int) -> None:
        """Forget a computed stamp and every older one (the exchange has moved past them)."""
        for stamp in [s for s in self._entries if s <= stamp_ns]:
            del self._entries[stamp]

    def _evict(self) -> None:
        """Drop the oldest entry without a valid input, else the oldest entry."""
        invalid = [s for s, e in self._entries.items() if e.valid == 0]
        del self._entries[invalid[0] if invalid else next(iter(self._entries))]
