"""The ``visualizer`` node: markers of the wall, contact force, X_d and end-effector trail.

It listens to /uvms/controller/state (X, X_d) and /uvms/contact (wall position, contact
force, taken at the state's stamp) and publishes a visualization_msgs/MarkerArray on
``markers`` every 1/``marker_rate_hz`` of *simulated* time, on the stamp of a controller
state. Both arrive at the control rate (500 Hz) but are used at the marker rate (20 Hz), so
they are subscribed raw and only the ones used are deserialized. The markers depend on
message contents only, so lockstep runs stay deterministic; the hot path of the graph
(simulator, controller, allocator) does not wait for this node. ``/diagnostics`` reports
the rates of controller states received and marker arrays published (per node-clock second;
under ``use_sim_time`` the node clock is the last controller state's stamp, not ``/clock``).
"""

from __future__ import annotations

import math
import sys
from typing import Any

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rclpy.exceptions import ParameterException
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message
from uvms_common.diagnostics import OK, WARN, DiagnosticsPublisher, RateMeter, Report
from uvms_common.node_construction import destroyed_if_construction_fails
from uvms_common.node_main import run_node
from uvms_common.raw_clock import take_clock_raw
from visualization_msgs.msg import MarkerArray

from uvms_msgs.msg import ContactState, ControllerState
from uvms_viz import conversions
from uvms_viz.marker_geometry import (
    ContactHistory,
    MarkerGeometryError,
    MarkerSettings,
    Trail,
    marker_scene,
)


class VisualizerNode(Node):
    """Markers for RViz and Foxglove, decimated to ``marker_rate_hz`` of simulated time."""

    @destroyed_if_construction_fails
    def __init__(self, **kwargs: Any) -> None:
        super().__init__('visualizer', **kwargs)
        # Under use_sim_time the node clock follows the controller states' stamps (it only
        # times /diagnostics): no /clock subscription, 500 messages a second fewer.
        self._clock_source = take_clock_raw(self)
        self._clock_source.feed_from_node()
        rate_hz = self.declare_parameter(
            'marker_rate_hz', 20.0, ParameterDescriptor(
                description='Marker publications per simulated second (Hz)', read_only=True,
                floating_point_range=[FloatingPointRange(from_value=0.1, to_value=500.0,
                                                         step=0.0)])).value
        trail_length = self.declare_parameter(
            'trail_length', 400, ParameterDescriptor(
                description='Most end-effector positions in the trail (points, one per marker '
                            'publication)', read_only=True,
                integer_range=[IntegerRange(from_value=2, to_value=100_000, step=1)])).value
        force_scale = self.declare_parameter(
            'force_scale_m_per_n', 0.02, ParameterDescriptor(
                description='Length of the contact force arrow per newton (m/N)',
                read_only=True)).value
        wall_size = self.declare_parameter(
            'wall_size_m', [2.0, 2.0], ParameterDescriptor(
                description='Drawn wall extent along map_ned y and z (m)', read_only=True)).value
        wall_center = self.declare_parameter(
            'wall_center_yz_m', [0.0, 0.0], ParameterDescriptor(
                description='Centre of the drawn wall on its plane, map_ned y and z (m)',
                read_only=True)).value
        self._settings = MarkerSettings(
            force_scale_m_per_n=float(force_scale), trail_length=int(trail_length),
            wall_size_m=tuple(float(v) for v in wall_size),  # type: ignore[arg-type]
            wall_center_yz_m=tuple(float(v) for v in wall_center),  # type: ignore[arg-type]
        )
        self._period_ns = round(1e9 / rate_hz)
        self._next_due_ns = 0
        self._trail = Trail(self._settings.trail_length)
        self._contacts: ContactHistory[bytes] = ContactHistory()

        reliable = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        self._publisher = self.create_publisher(MarkerArray, 'markers', reliable)
        self.create_subscription(ContactState, 'contact', self._on_contact, reliable, raw=True)
        self.create_subscription(ControllerState, 'controller/state', self._on_state, reliable,
                                 raw=True)
        self._states = self._published = 0
        self._meters = (RateMeter(), RateMeter())
        self._diagnostics = DiagnosticsPublisher(self)
        self._diagnostics.add('markers', self._report)
        self.get_logger().info(f'markers on {self.resolve_topic_name("markers")} at '
                               f'{rate_hz:g} Hz of simulated time, frame map_ned')

    def _on_contact(self, data: bytes) -> None:
        """Keep the serialized contact of its stamp."""
        try:
            self._contacts.add(conversions.header_stamp_ns(data), data)
        except ValueError as exc:
            self.get_logger().error(f'ignored contact: {exc}', throttle_duration_sec=5.0)

    def _on_state(self, data: bytes) -> None:
        """Publish the markers when the state's stamp reaches the next marker instant."""
        try:
            t_ns = conversions.header_stamp_ns(data)
        except ValueError as exc:
            self.get_logger().error(f'ignored controller state: {exc}', throttle_duration_sec=5.0)
            return
        self._states += 1
        self._clock_source.advance(t_ns)
        if t_ns < self._next_due_ns:
            return
        self._next_due_ns = (t_ns // self._period_ns + 1) * self._period_ns
        state = deserialize_message(data, ControllerState)
        p_ee = conversions.xyz(state.position)
        self._trail.append(p_ee)
        force: tuple[float, float, float] = (0.0, 0.0, 0.0)
        wall_position_m = math.nan
        contact_cdr = self._contacts.at(t_ns)
        if contact_cdr is not None:
            contact = deserialize_message(contact_cdr, ContactState)
            force, wall_position_m = conversions.xyz(contact.force), float(contact.wall_position)
        scene = marker_scene(p_ee, conversions.xyz(state.desired_position), force,
                             wall_position_m, self._trail, self._settings)
        self._publisher.publish(conversions.marker_array(scene, t_ns))
        self._published += 1

    def _report(self) -> Report:
        """/diagnostics: 'running' with the state and marker rates, WARN without states."""
        now_ns = self.get_clock().now().nanoseconds
        values = {'controller_state_rate_hz': self._meters[0].rate_hz(self._states, now_ns),
                  'marker_rate_hz': self._meters[1].rate_hz(self._published, now_ns),
                  'marker_arrays_published': self._published}
        if self._states == 0:
            return Report(WARN, 'waiting for controller/state', values)
        return Report(OK, 'running', values)


def main(args: list[str] | None = None) -> None:
    """Run the visualizer node until SIGINT/SIGTERM."""
    sys.exit(run_node(VisualizerNode, args, 'visualizer',
                      (MarkerGeometryError, ParameterException)))


if __name__ == '__main__':
    main()
