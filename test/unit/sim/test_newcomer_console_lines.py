"""A scenario's ocean current is said once on the console when the simulator starts (issue 52)."""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any

import pytest
import rclpy
from rclpy.context import Context
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile
from uvms_model.ocean_current import CurrentParameters
from uvms_sim.ocean_node import OceanCurrentInterface, describe_current


class FakePlant:
    """What OceanCurrentInterface reads and sets of the plant."""

    def __init__(self) -> None:
        self.current_parameters = CurrentParameters()

    def set_current(self, params: CurrentParameters) -> None:
        """Take the current, as the plant does."""
        self.current_parameters = params


@pytest.fixture
def context() -> Iterator[Context]:
    """A context of its own."""
    ctx = Context()
    rclpy.init(args=[], context=ctx)
    yield ctx
    rclpy.try_shutdown(context=ctx)


def test_the_current_line_says_speed_and_where_it_flows() -> None:
    """0.3 m/s toward east (pi/2 from north): degrees and the frame, then rad as set."""
    line = describe_current(CurrentParameters(mean_speed_m_s=0.3, direction_rad=math.pi / 2))
    assert line.startswith('ocean current on: 0.3 m/s toward 90 deg (map_ned, 0 = north')
    assert describe_current(CurrentParameters()) == 'ocean current: off (still water)'


@pytest.mark.parametrize('speed_m_s', [0.0, 0.3])
def test_a_scenarios_current_is_said_at_start_still_water_is_not(
        context: Context, capfd: pytest.CaptureFixture[str], speed_m_s: float) -> None:
    """With ocean.current.mean_speed_m_s set at start: one INFO line; without: none."""
    node = Node('simulator', context=context, parameter_overrides=[
        Parameter('ocean.current.mean_speed_m_s', value=speed_m_s)])
    try:
        plant: Any = FakePlant()
        OceanCurrentInterface(node, plant, QoSProfile(depth=10))
    finally:
        node.destroy_node()
    err = capfd.readouterr().err
    assert err.count('ocean current on: 0.3 m/s') == (1 if speed_m_s else 0)
