"""Callback groups: which callbacks an executor may run at the same time."""

from __future__ import annotations

import threading
import weakref
from typing import Any


class CallbackGroup:
    """Base of the callback groups: holds weak references to its entities."""

    def __init__(self) -> None:
        self.entities: set[weakref.ref[Any]] = set()

    def add_entity(self, entity: Any) -> None:
        """Add a subscription, timer, guard condition... to the group."""
        self.entities.add(weakref.ref(entity))

    def has_entity(self, entity: Any) -> bool:
        """Tell whether ``entity`` belongs to the group."""
        return weakref.ref(entity) in self.entities

    def can_execute(self, entity: Any) -> bool:
        """Tell whether ``entity``'s callback may start now."""
        raise NotImplementedError()

    def beginning_execution(self, entity: Any) -> bool:
        """Claim the group for ``entity``'s callback; False if it may not start now."""
        raise NotImplementedError()

    def ending_execution(self, entity: Any) -> None:
        """Release the group after ``entity``'s callback."""
        raise NotImplementedError()


class ReentrantCallbackGroup(CallbackGroup):
    """Callbacks of this group may run in parallel, even several of one entity."""

    def can_execute(self, entity: Any) -> bool:
        """Always True."""
        return True

    def beginning_execution(self, entity: Any) -> bool:
        """Always True."""
        return True

    def ending_execution(self, entity: Any) -> None:
        """Nothing to release."""


class MutuallyExclusiveCallbackGroup(CallbackGroup):
    """At most one callback of this group runs at a time (the default group of a node)."""

    def __init__(self) -> None:
        super().__init__()
        self._active_entity: Any = None
        self._lock = threading.Lock()

    def can_execute(self, entity: Any) -> bool:
        """True when no callback of the group is running."""
        return self._active_entity is None

    def beginning_execution(self, entity: Any) -> bool:
        """Claim the group for ``entity``; False if another callback of it is running."""
        with self._lock:
            if self._active_entity is None:
                self._active_entity = entity
                return True
        return False

    def ending_execution(self, entity: Any) -> None:
        """Release the group."""
        with self._lock:
            self._active_entity = None
