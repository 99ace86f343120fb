"""Access to ros2_compat.message_support, imported on first use."""

from __future__ import annotations

from types import ModuleType

_module: ModuleType | None = None


def message_support() -> ModuleType:
    """Return ``ros2_compat.message_support`` (message copy, CDR, type names)."""
    global _module
    if _module is None:
        from ros2_compat import message_support as module

        _module = module
    return _module
