"""Guard conditions: trigger from any thread to have an executor run a callback."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from rclpy.exceptions import InvalidHandle

if TYPE_CHECKING:
    from rclpy.callback_groups import CallbackGroup
    from rclpy.context import Context


class GuardCondition:
    """A condition that, once triggered, makes the executor of its node call ``callback``.

    Args:
        callback: Called with no argument by the executor after each trigger.
        callback_group: Group the callback belongs to.
        context: Context of the guard condition (the default context if None).
    """

    def __init__(
        self,
        callback: Callable[[], Any] | None,
        callback_group: CallbackGroup | None,
        context: Context | None = None,
    ) -> None:
        from rclpy.utilities import get_default_context

        self._context = get_default_context() if context is None else context
        self.callback = callback
        self.callback_group = callback_group
        self._triggered = False
        self._executor_event = False
        self._node: Any = None
        self._destroyed = False

    @property
    def handle(self) -> GuardCondition:
        """Handle of the guard condition (usable in ``with``)."""
        if self._destroyed:
            raise InvalidHandle('cannot use Destroyable because destruction was requested')
        return self

    def __enter__(self) -> GuardCondition:
        return self

    def __exit__(self, *exc_info: object) -> None:
        return None

    def trigger(self) -> None:
        """Mark the condition triggered and wake the executor of its node."""
        if self._destroyed:
            raise InvalidHandle('cannot use Destroyable because destruction was requested')
        self._triggered = True
        node = self._node
        executor = node._executor if node is not None else None
        if executor is not None:
            executor._wake()

    def destroy(self) -> None:
        """Destroy the guard condition."""
        self._destroyed = True
