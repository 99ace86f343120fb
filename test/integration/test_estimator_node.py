"""Navigation topics of the simulator and the estimator node on them, in lockstep."""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import pytest
import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseWithCovarianceStamped, TwistWithCovarianceStamped
from nav_msgs.msg import Odometry
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from sensor_msgs.msg import Imu, JointState
from uvms_navigation.estimator_node import EstimatorNode
from uvms_sim.simulator_node import SimulatorNode

from uvms_msgs.msg import ActuatorCommand

NAV_TOPICS = {'imu': Imu, 'dvl': TwistWithCovarianceStamped, 'depth': PoseWithCovarianceStamped,
              'position_fix': PoseWithCovarianceStamped}
STATE_TOPICS = {'joint_states': JointState, 'odometry': Odometry}


def stamp_ns(msg: Any) -> int:
    """Header stamp of a message (ns)."""
    return msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec


class Graph:
    """Simulator (+ estimator) and a responder answering each state with a zero command."""

    def __init__(self) -> None:
        self.context = Context()
        rclpy.init(args=[], context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.probe = rclpy.create_node('probe', namespace='uvms', context=self.context)
        self.executor.add_node(self.probe)
        self.command = self.probe.create_publisher(ActuatorCommand, 'command/actuators', 10)
        self.probe.create_subscription(JointState, 'joint_states', self._answer, 100)
        self.received: dict[str, list[Any]] = {}
        self.nodes: list[Node] = [self.probe]

    def _answer(self, msg: JointState) -> None:
        command = ActuatorCommand(thrust=[0.0] * 8, joint_torques=[0.0] * 3)
        command.header.stamp = msg.header.stamp
        self.command.publish(command)

    def collect(self, topic: str, msg_type: Any) -> list[Any]:
        """Messages of a topic, in arrival order."""
        self.received[topic] = []
        self.probe.create_subscription(msg_type, topic, self.received[topic].append, 1000)
        return self.received[topic]

    def add(self, make: Callable[..., Node], **parameters: Any) -> Node:
        """Build a node in /uvms with parameter overrides and spin it."""
        overrides = [Parameter(name.replace('__', '.'), value=value)
                     for name, value in parameters.items()]
        node = make(namespace='uvms', context=self.context, parameter_overrides=overrides)
        self.nodes.append(node)
        self.executor.add_node(node)
        return node

    def spin_until(self, done: Callable[[], bool], timeout_s: float = 120.0) -> None:
        """Spin until done() or the wall-clock timeout fails the test."""
        deadline = time.monotonic() + timeout_s
        while not done():
            assert time.monotonic() < deadline, 'timed out spinning'
            self.executor.spin_once(timeout_sec=0.05)

    def close(self) -> None:
        """Destroy the nodes and the context."""
        self.executor.shutdown()
        for node in reversed(self.nodes):
            node.destroy_node()
        rclpy.try_shutdown(context=self.context)


@pytest.fixture
def graph() -> Iterator[Graph]:
    """A fresh graph, closed after the test."""
    made = Graph()
    yield made
    made.close()


def _run(graph: Graph, duration_s: float, **simulator: Any) -> SimulatorNode:
    sim = graph.add(SimulatorNode, duration_s=duration_s, **simulator)
    assert isinstance(sim, SimulatorNode)
    graph.spin_until(lambda: sim.finished)
    for _ in range(20):  # deliver what is still in flight
        graph.executor.spin_once(timeout_sec=0.01)
    return sim


def test_navigation_topics_are_off_by_default(graph: Graph) -> None:
    """Without navigation.enabled the simulator advertises none of the sensor topics."""
    imu = graph.collect('imu', Imu)
    sim = _run(graph, 0.05)
    assert all(sim.count_publishers(f'/uvms/{topic}') == 0 for topic in NAV_TOPICS)
    assert imu == []


def _state_messages(navigation: bool) -> list[tuple[int, Any]]:
    graph = Graph()
    try:
        states = [graph.collect(t, m) for t, m in STATE_TOPICS.items()]
        _run(graph, 0.1, sensor__noise_fraction=0.001, navigation__enabled=navigation,
             world__seabed_depth_m=5.0)
        # Messages, not rclpy's serialize_message bytes: Fast CDR leaves its alignment padding
        # uninitialized, so two serializations of equal messages can differ in those bytes.
        return [(stamp_ns(m), m) for topic in states for m in topic]
    finally:
        graph.close()


def test_navigation_sensors_leave_the_other_topics_unchanged() -> None:
    """Joint states and odometry (with wrist noise on) are identical with navigation on or off.

    The navigation sensors draw from their own random streams, so switching them on cannot
    change what a recording without them holds.
    """
    off, on = _state_messages(False), _state_messages(True)
    assert len(off) == len(on) > 50
    assert off == on


def test_estimator_tracks_the_simulated_vehicle(graph: Graph) -> None:
    """With a seabed 5 m down the estimate follows the truth and reports its health."""
    topics = {name: graph.collect(name, t) for name, t in NAV_TOPICS.items()}
    truth = graph.collect('odometry', Odometry)
    filtered = graph.collect('odometry/filtered', Odometry)
    diagnostics: list[DiagnosticArray] = []
    graph.probe.create_subscription(DiagnosticArray, '/diagnostics', diagnostics.append, 100)
    estimator = graph.add(EstimatorNode, use_sim_time=True)
    _run(graph, 3.0, navigation__enabled=True, world__seabed_depth_m=5.0,
         initial__vehicle_pose=[0.0, 0.0, 1.0, 0.0, 0.0, 0.3], initial__arm='joint_positions')
    assert 3.0 * 200 - 5 <= len(topics['imu']) <= 3.0 * 200 + 1
    assert 3.0 * 20 - 2 <= len(topics['depth']) <= 3.0 * 20 + 1
    assert len(topics['dvl']) >= 3.0 * 5  # altitude ~3.75 m: 5.5 Hz
    assert topics['position_fix'] == []
    assert topics['imu'][0].linear_acceleration.z == pytest.approx(-9.81, abs=0.2)
    by_stamp = {stamp_ns(m): m for m in truth}
    assert len(filtered) > 1000
    last = filtered[-1]
    reference = by_stamp[stamp_ns(last)]
    p = last.pose.pose.position
    q = reference.pose.pose.position
    error = math.dist((p.x, p.y, p.z), (q.x, q.y, q.z))
    cov = np.array(last.pose.covariance).reshape(6, 6)
    assert error < 3 * math.sqrt(cov[0, 0] + cov[1, 1] + cov[2, 2]) + 0.05
    assert abs(p.z - 1.0) < 0.1
    v = last.twist.twist.linear
    assert math.hypot(v.x, v.y) < 0.1
    assert last.header.frame_id == 'map_ned' and last.child_frame_id == 'base_link_frd'
    names = {s.name for array in diagnostics for s in array.status}
    assert 'estimator: estimate' in names
    assert estimator is not None


def test_malformed_navigation_payloads_are_counted_and_survived(
    graph: Graph, capfd: pytest.CaptureFixture[str]
) -> None:
    """Raw garbage on imu, dvl, depth and position_fix: counted, logged once, estimate goes on."""
    filtered = graph.collect('odometry/filtered', Odometry)
    estimator = graph.add(EstimatorNode, use_sim_time=True)
    assert isinstance(estimator, EstimatorNode)
    garbage = [b'', b'\x00\x01\x00\x00', b'\x7f\x7f' + bytes(300), bytes(range(256))]
    publishers = {topic: graph.probe.create_publisher(msg_type, topic, 10)
                  for topic, msg_type in NAV_TOPICS.items()}
    graph.spin_until(lambda: all(p.get_subscription_count() == 1 for p in publishers.values()))
    for publisher in publishers.values():
        for payload in garbage:
            publisher.publish(payload)
    graph.spin_until(lambda: estimator.malformed == len(garbage) * len(publishers),
                     timeout_s=10.0)
    _run(graph, 0.5, navigation__enabled=True, world__seabed_depth_m=5.0)
    assert len(filtered) > 200  # the filter started and answered the states after the garbage
    report = estimator._report()
    assert report.values['malformed_inputs'] == len(garbage) * len(publishers)
    assert capfd.readouterr().err.count('malformed input payloads') == 1


def test_the_estimate_starts_at_the_first_depth_never_at_the_start_guess(graph: Graph) -> None:
    """IMU readings without a depth: nothing published; the first estimate has the depth's z.

    Started on the IMU alone, the filter published the start guess's z = 0 and jumped to the
    depth a few periods later, and a controller holding its first estimate drove at the jump
    (the twin stand's arm tripped on it, docs/hardware.md).
    """
    from rosgraph_msgs.msg import Clock

    filtered = graph.collect('odometry/filtered', Odometry)
    estimator = graph.add(EstimatorNode, use_sim_time=True)
    assert isinstance(estimator, EstimatorNode)
    imu = graph.probe.create_publisher(Imu, 'imu', 10)
    depth = graph.probe.create_publisher(PoseWithCovarianceStamped, 'depth', 10)
    clock = graph.probe.create_publisher(Clock, '/clock', 10)
    graph.spin_until(lambda: imu.get_subscription_count() == 1
                     and depth.get_subscription_count() == 1, timeout_s=10.0)

    def step(t_ns: int, with_depth: bool) -> None:
        stamp = rclpy.time.Time(nanoseconds=t_ns).to_msg()
        reading = Imu()
        reading.header.stamp = stamp
        reading.orientation.w = 1.0
        reading.linear_acceleration.z = -9.80665
        imu.publish(reading)
        if with_depth:
            sample = PoseWithCovarianceStamped()
            sample.header.stamp = stamp
            sample.pose.pose.position.z = 2.5
            sample.pose.covariance[14] = 1e-4
            depth.publish(sample)
        clock.publish(Clock(clock=stamp))
        for _ in range(10):
            graph.executor.spin_once(timeout_sec=0.01)

    for k in range(10):
        step(k * 10_000_000, with_depth=False)
    assert filtered == []
    assert 'waiting for the first depth reading' in estimator._report().message
    step(100_000_000, with_depth=True)
    step(110_000_000, with_depth=False)
    graph.spin_until(lambda: len(filtered) > 0, timeout_s=10.0)
    assert filtered[0].pose.pose.position.z == pytest.approx(2.5, abs=1e-6)
