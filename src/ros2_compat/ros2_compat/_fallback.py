"""Imported from ros2_compat_fallback.pth at interpreter start: registers the fallback finder."""

from ros2_compat import activate

activate()
