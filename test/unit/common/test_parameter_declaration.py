"""Parameters declared from specs: what ``ros2 param describe`` shows, and which value wins.

Checked on a real rclpy node, with the simulator's own specs for the choices and ranges.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
import rclpy
from rcl_interfaces.msg import ParameterType
from rclpy.context import Context
from rclpy.exceptions import ParameterException
from rclpy.node import Node
from rclpy.parameter import Parameter
from uvms_common.parameter_declaration import Spec, declare_specs
from uvms_sim.parameters import SIMULATOR_PARAMETERS

from uvms_description.robots import RobotParameter


@dataclass(frozen=True)
class TestSpec:
    """A spec as the nodes' spec classes give it."""

    __test__ = False
    name: str
    default: Any
    description: str
    min_value: float | None = None
    max_value: float | None = None
    read_only: bool = True


class NamedError(ValueError):
    """The node's own error, naming the parameter."""


def named_error(spec: Spec, exc: ParameterException) -> NamedError:
    """The error factory a node passes."""
    return NamedError(f'{spec.name}: {exc}')


@pytest.fixture
def context() -> Iterator[Context]:
    """An initialised rclpy context."""
    ctx = Context()
    rclpy.init(args=[], context=ctx)
    yield ctx
    rclpy.try_shutdown(context=ctx)


def node_with(context: Context, overrides: dict[str, Any] | None = None) -> Node:
    """A node given these parameter overrides (as a parameter file would)."""
    return Node('declaring', context=context, parameter_overrides=[
        Parameter(name, value=value) for name, value in (overrides or {}).items()])


def test_descriptors_carry_ranges_choices_and_the_read_only_flag(context: Context) -> None:
    """Float and integer ranges, bounds of a list, the simulator's mode choices, read-only."""
    node = node_with(context)
    specs = [TestSpec('rate_hz', 500.0, 'Control rate (Hz)', 1.0, 2000.0),
             TestSpec('count', 3, 'Count', 1, 9),
             TestSpec('gains', [1.0, 2.0], 'Gains (N/m)', 0.0, None, read_only=False),
             *[s for s in SIMULATOR_PARAMETERS if s.name == 'mode']]
    values = declare_specs(node, specs, None, named_error)
    rate, count, gains, mode = node.describe_parameters(list(values))
    assert (rate.floating_point_range[0].from_value, rate.floating_point_range[0].to_value) \
        == (1.0, 2000.0)
    assert rate.read_only and rate.description == 'Control rate (Hz)'
    assert (count.integer_range[0].from_value, count.integer_range[0].to_value) == (1, 9)
    assert gains.additional_constraints == 'each value in [0.0, inf]' and not gains.read_only
    assert gains.type == ParameterType.PARAMETER_DOUBLE_ARRAY
    assert mode.additional_constraints.startswith('one of: lockstep')
    assert values['gains'] == [1.0, 2.0] and isinstance(values['gains'], list)
    node.destroy_node()


def test_a_given_value_beats_the_robot_file_which_beats_the_default(context: Context) -> None:
    """An override (parameter file, -p) first, then the robot's folder, then the spec."""
    node = node_with(context, {'a': 7.0})
    robot = {name: RobotParameter(value, Path('robot/controller.yaml'))
             for name, value in (('a', 5.0), ('b', 6.0))}
    specs = [TestSpec(name, 1.0, name) for name in ('a', 'b', 'c')]
    assert declare_specs(node, specs, robot, named_error) == {'a': 7.0, 'b': 6.0, 'c': 1.0}
    node.destroy_node()


@pytest.mark.parametrize('value', [5000.0, 'fast'], ids=['out-of-range', 'wrong-type'])
def test_a_value_out_of_range_or_of_the_wrong_type_raises_the_nodes_error_naming_it(
    context: Context, value: Any
) -> None:
    """The node's own error class, its message starting with the parameter's name."""
    node = node_with(context, {'rate_hz': value})
    with pytest.raises(NamedError, match=r'^rate_hz: '):
        declare_specs(node, [TestSpec('rate_hz', 500.0, 'Rate (Hz)', 1.0, 2000.0)], None,
                      named_error)
    node.destroy_node()
