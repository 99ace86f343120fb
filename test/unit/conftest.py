"""Fixtures shared by the unit tests."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from uvms_common.direct_topics import Bus

from uvms_common import direct_topics


@pytest.fixture
def bus() -> Iterator[Bus]:
    """An installed direct-topics bus (the robot process's), uninstalled after the test."""
    installed = Bus()
    direct_topics.install(installed)
    yield installed
    direct_topics.uninstall()
