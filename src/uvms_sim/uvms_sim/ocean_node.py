"""The simulator node's ocean current: its parameters on the node, run-time changes, its topic.

Declares ``ocean.current.*`` (``uvms_sim.ocean``) with their ranges, writable: ``ros2 param
set /uvms/simulator ocean.current.mean_speed_m_s 0.3`` or any set_parameters client. A change
is checked as a whole (a refused change names the parameter, value and range, and leaves the
current as it was) and applied to the plant at once (the process restarts at the new means).
The current the plant applies is published on ``ocean/current`` (geometry_msgs/TwistStamped,
map_ned, m/s) with the ground truth. In still water nothing is published until a current is
first set, so that a run without a current records exactly what it recorded before.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from geometry_msgs.msg import TwistStamped
from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor, SetParametersResult
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile
from uvms_model.ocean_current import CurrentParameters

from uvms_sim import conversions
from uvms_sim.errors import SimParameterError
from uvms_sim.ocean import OCEAN_PARAMETERS, PREFIX, current_parameters
from uvms_sim.plant import Plant


def describe_current(params: CurrentParameters) -> str:
    """The console line of the current in force: speed, where it flows, its variation."""
    if not params.enabled:
        return 'ocean current: off (still water)'
    toward = math.degrees(params.direction_rad) % 360.0
    return (f'ocean current on: {params.mean_speed_m_s:g} m/s toward {toward:.0f} deg '
            f'(map_ned, 0 = north, 90 = east; {params.direction_rad:g} rad), '
            f'sigma {params.sigma_m_s:g} m/s, T {params.time_constant_s:g} s')


class OceanCurrentInterface:
    """Parameters, run-time changes and the ``ocean/current`` topic of the plant's current.

    Args:
        node: The simulator node (declares the parameters, owns the publisher).
        plant: The plant whose current this sets and publishes.
        qos: QoS of the ``ocean/current`` publisher.

    Raises:
        SimParameterError: A start-up value is out of range, named.
    """

    def __init__(self, node: Node, plant: Plant, qos: QoSProfile) -> None:
        self._node, self._plant = node, plant
        values = {}
        for spec in OCEAN_PARAMETERS:
            assert spec.min_value is not None and spec.max_value is not None
            descriptor = ParameterDescriptor(
                description=spec.description, floating_point_range=[FloatingPointRange(
                    from_value=spec.min_value, to_value=spec.max_value, step=0.0)])
            values[spec.name] = node.declare_parameter(spec.name, spec.default, descriptor).value
        plant.set_current(current_parameters(values))
        self._publishing = plant.current_parameters.enabled
        if self._publishing:  # a scenario's current: said once, as a change at run time is
            node.get_logger().info(describe_current(plant.current_parameters))
        self._publisher = node.create_publisher(TwistStamped, 'ocean/current', qos)
        node.add_on_set_parameters_callback(self._on_set)

    def _on_set(self, parameters: Sequence[Parameter]) -> SetParametersResult:
        """Apply a change of ``ocean.current.*`` as a whole, or refuse it naming the value."""
        changed = {p.name: p.value for p in parameters if p.name.startswith(PREFIX)}
        if not changed:
            return SetParametersResult(successful=True)
        values = {spec.name: self._node.get_parameter(spec.name).value
                  for spec in OCEAN_PARAMETERS}
        values.update(changed)
        try:
            params = current_parameters(values)
        except SimParameterError as exc:
            self._node.get_logger().error(f'refused: {exc}')
            return SetParametersResult(successful=False, reason=str(exc))
        self._plant.set_current(params)
        self._publishing = self._publishing or params.enabled
        self._node.get_logger().info(describe_current(params))
        return SetParametersResult(successful=True)

    def publish(self, t_ns: int) -> None:
        """Publish the current the next step applies, stamped t_ns (once a current was set)."""
        if self._publishing:
            self._publisher.publish(conversions.current_message(t_ns, self._plant.current_ned))
