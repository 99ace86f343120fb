"""thruster_output desired (hardware) with an injected fault: the fault's demand is sent.

On the hardware path the real thrusters follow what the allocator sends, so a scenario's
``faults:`` (``fault_injection.thrusters``) must act on what is sent: `uvms identify plan`'s
experiments hold every thruster ``stuck`` at a planned thrust, and through the twin stand (or
on the robot) that thrust must reach the ESC. Before, the allocator sent the allocation's
desired thrusts and the injected fault acted only on its own thruster model, so the
experiments never happened on the hardware path.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest
from test_allocator_lifecycle import PERIOD_NS, Graph


@pytest.fixture
def graph() -> Iterator[Graph]:
    """A fresh in-process graph."""
    g = Graph()
    yield g
    g.close()


def test_a_stuck_thruster_is_sent_at_its_thrust_on_the_hardware_path(graph: Graph) -> None:
    """Before at_s the allocation goes out; from it the stuck thrust, the rest as allocated."""
    graph.allocator(thruster_output='desired',
                    **{'fault_injection.thrusters': 'index=2 kind=stuck value=-7.5 at_s=0.004'})
    before = graph.exchange(PERIOD_NS)
    after = graph.exchange(3 * PERIOD_NS)
    assert abs(before.thrust[2] - -7.5) > 1.0, before.thrust
    assert after.thrust[2] == -7.5
    others = [i for i in range(len(after.thrust)) if i != 2]
    np.testing.assert_allclose(np.asarray(after.thrust)[others],
                               np.asarray(before.thrust)[others])
