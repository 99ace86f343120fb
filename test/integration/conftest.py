"""Integration tests: what each test leaves to the garbage collector is collected at its end.

A test's rclpy context is shut down when it ends, but its DDS participant lives until the
context object is freed, and a destroyed lifecycle node stays in the graph until its state
machine is: rclpy leaves both to the collector (measured on Jazzy: three lifecycle nodes
destroyed in earlier contexts of one process were still listed beside the live one, and
went at a ``gc.collect()``). Left to it, they pile up within a module (one domain, one
process: a participant per test, discovering each other) and are freed at whatever moment
the collector runs, inside a later test. Fast DDS has livelocked destroying one of many such
participants (test/conftest.py), a refused node freed that way hung a test process in C (CI
of 2026-12-06), and in the CI of 2026-12-07 a lifecycle service that was up went unfound
for 5 s (test_allocator_lifecycle). Collected here, at most the last test's participants are
alive, and they go between tests. About 35 ms per test.
"""

import gc
from collections.abc import Iterator

import pytest


@pytest.fixture(autouse=True)
def garbage_collected_after_the_test() -> Iterator[None]:
    """Collect the test's garbage (its participants and lifecycle nodes) when it ends."""
    yield
    gc.collect()
