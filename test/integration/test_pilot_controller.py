"""The pilot interface of the real controller in the lockstep graph (issue 51).

``idle_wall`` (the paper's robot at point A, the Case I wall) in one process on simulated
time, with a probe node that acts as a pilot would: TwistStamped on ``/uvms/pilot/*`` stamped
with its (simulated) clock, the ``controller/hold`` service, a ContactTask goal, and the
``controller/mode`` it watches; bad messages (NaN, a huge value, an unknown frame, a stale
stamp) among the good ones.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from action_msgs.msg import GoalStatus
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Point, TwistStamped, Vector3
from nav_msgs.msg import Odometry
from rcl_interfaces.msg import Log
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import String
from std_srvs.srv import Trigger
from uvms_run.graph import Graph, build_graph, run_graph
from uvms_scenarios.scenario import load_scenario
from uvms_tasks.client import ContactTaskClient

from uvms_msgs.action import ContactTask
from uvms_msgs.msg import ControllerState

SCENARIOS = Path(__file__).resolve().parents[2] / 'config' / 'scenarios'
X0 = (1.70, 0.0, -0.10)
WALL_X = 1.7771
LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)


@dataclass
class Pilot:
    """What the probe saw."""

    node: Node
    graph: Graph
    modes: list[tuple[float, str]] = field(default_factory=list)
    late_modes: list[str] = field(default_factory=list)
    odometry: list[tuple[float, np.ndarray]] = field(default_factory=list)
    desired: list[tuple[float, np.ndarray]] = field(default_factory=list)
    logs: list[str] = field(default_factory=list)
    diagnostics: list[dict[str, str]] = field(default_factory=list)
    results: dict[str, tuple[int, Any]] = field(default_factory=dict)
    hold: list[Any] = field(default_factory=list)

    def now_s(self) -> float:
        """Simulated time (s)."""
        return float(self.graph.simulator.sim_time_ns) * 1e-9


def twist(node: Node, linear: tuple[float, float, float], frame: str = 'base_link_frd',
          yaw_rate: float = 0.0, age_s: float = 0.0) -> TwistStamped:
    """A TwistStamped stamped with the node's clock now (minus age_s)."""
    msg = TwistStamped()
    stamp = node.get_clock().now().nanoseconds - round(age_s * 1e9)
    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(max(stamp, 0), 1_000_000_000)
    msg.header.frame_id = frame
    msg.twist.linear = Vector3(x=linear[0], y=linear[1], z=linear[2])
    msg.twist.angular.z = yaw_rate
    return msg


def press_goal(start_s: float) -> ContactTask.Goal:
    """To 2.3 cm past the wall from point A (a transit first), 100 N, 3 s along it."""
    goal = ContactTask.Goal()
    goal.header.frame_id = 'map_ned'
    goal.header.stamp.sec, goal.header.stamp.nanosec = int(start_s), round(start_s % 1 * 1e9)
    points = [X0, (WALL_X + 0.023, 0.0, -0.10), (WALL_X + 0.023, 0.0, -0.08)]
    goal.path = [Point(x=x, y=y, z=z) for x, y, z in points]
    goal.time_from_start_s = [0.0, 1.5, 4.5]
    goal.normal = Vector3(x=1.0, y=0.0, z=0.0)
    goal.force_n = 100.0
    goal.force_ramp_s = 0.5
    goal.require_contact = True
    return goal


def session() -> Pilot:
    """Back off 0.2 m/s for 2 s, bad messages, release; hold; a task; pilot input cancels it."""
    scenario = load_scenario(SCENARIOS / 'idle_wall.yaml').with_changes(duration_s=12.0)
    graph = build_graph(scenario, 'lockstep')
    node = Node('pilot_probe', namespace='/uvms', context=graph.context,
                parameter_overrides=[Parameter('use_sim_time', value=True)])
    probe = Pilot(node, graph)
    vehicle = node.create_publisher(TwistStamped, 'pilot/vehicle_twist', 10)
    node.create_subscription(String, 'controller/mode',
                             lambda m: probe.modes.append((probe.now_s(), m.data)), LATCHED)
    node.create_subscription(Odometry, 'odometry', lambda m: probe.odometry.append(
        (probe.now_s(), np.array([m.pose.pose.position.x, m.pose.pose.position.y,
                                  m.pose.pose.position.z]))), 100)
    node.create_subscription(ControllerState, 'controller/state', lambda m: probe.desired.append(
        (probe.now_s(), np.array([m.desired_position.x, m.desired_position.y,
                                  m.desired_position.z]))), 100)
    node.create_subscription(Log, '/rosout', lambda m: probe.logs.append(m.msg)
                             if m.name.endswith('controller') else None, 100)
    node.create_subscription(DiagnosticArray, '/diagnostics', lambda m: probe.diagnostics.extend(
        {'name': s.name, 'message': s.message, **{v.key: v.value for v in s.values}}
        for s in m.status if s.name.endswith('controller: pilot')), 10)
    hold = node.create_client(Trigger, 'controller/hold')
    client = ContactTaskClient(node)
    graph.nodes['pilot_probe'] = node
    done: set[str] = set()

    def once(name: str, when: float) -> bool:
        if name in done or probe.now_s() < when:
            return False
        done.add(name)
        return True

    sent = [-1.0]

    def stick(t: float, linear: tuple[float, float, float]) -> None:
        if t - sent[0] >= 0.02:  # 50 Hz, as a gamepad tool sends
            sent[0] = t
            vehicle.publish(twist(node, linear))

    def on_spin(_: Graph) -> None:
        t = probe.now_s()
        if 0.5 <= t < 2.5:  # a stick held back, 0.2 m/s astern
            stick(t, (-0.2, 0.0, 0.0))
        if once('bad', 1.0):
            vehicle.publish(twist(node, (math.nan, 0.0, 0.0)))
            vehicle.publish(twist(node, (-0.2, 0.0, 0.0), frame='map_ned'))
            vehicle.publish(twist(node, (-0.2, 0.0, 0.0), age_s=5.0))
        if once('huge', 1.5):
            vehicle.publish(twist(node, (-1.0e9, 0.0, 0.0)))
        if once('hold', 6.0):
            hold.call_async(Trigger.Request()).add_done_callback(
                lambda f: probe.hold.append(f.result()))
        if once('task', 6.2) and client.server_is_ready():
            future = client.send_goal_async(press_goal(6.3))
            future.add_done_callback(lambda f: f.result().get_result_async().add_done_callback(
                lambda r: probe.results.__setitem__('press', (r.result().status,
                                                              r.result().result))))
        if 7.5 <= t < 7.6:  # the pilot takes back control mid-task
            stick(t, (-0.1, 0.0, 0.0))
        if once('late', 11.5):
            node.create_subscription(String, 'controller/mode',
                                     lambda m: probe.late_modes.append(m.data), LATCHED)

    result = run_graph(graph, on_spin=on_spin)
    assert not result.interrupted
    return probe


@pytest.fixture(scope='module')
def pilot() -> Pilot:
    """One 12 s pilot session on the lockstep graph."""
    return session()


def position_at(probe: Pilot, t_s: float) -> np.ndarray:
    """The vehicle position (m, map_ned) at the first odometry at or after t_s."""
    return next(p for t, p in probe.odometry if t >= t_s)


def test_the_mode_follows_the_owner_and_is_latched(pilot: Pilot) -> None:
    """hold, pilot (driving), hold (released), task (a goal), hold (canceled by the pilot)."""
    assert [mode for _, mode in pilot.modes] == ['hold', 'pilot', 'hold', 'task', 'hold']
    times = [t for t, _ in pilot.modes]
    assert times[1] == pytest.approx(0.5, abs=0.01)
    assert times[2] == pytest.approx(2.5 + 0.3, abs=0.01)  # the deadman after the last message
    assert pilot.late_modes == ['hold']  # a late subscriber reads the owner at once


def test_the_pilot_drives_the_vehicle_and_it_holds_where_released(pilot: Pilot) -> None:
    """Astern 0.2 m/s: the vehicle moves the distance of the ramped command, then holds."""
    start, released = position_at(pilot, 0.4), position_at(pilot, 4.5)
    # 1 s ramp (0.1 m), 1.3 s at speed (0.26 m), 1 s ramp down (0.1 m): 0.46 m astern
    assert released[0] - start[0] == pytest.approx(-0.46, abs=0.02)
    held = [p for t, p in pilot.odometry if 4.5 <= t <= 6.0]
    assert max(np.linalg.norm(p - released) for p in held) < 0.01
    x_d = next(x for t, x in pilot.desired if t >= 4.5)
    assert x_d[0] == pytest.approx(X0[0] - 0.46, abs=0.02)  # the arm rode along


def test_bad_messages_are_refused_or_clipped_and_named_once(pilot: Pilot) -> None:
    """NaN, a map_ned vehicle twist, a stale stamp: refused; -1e9 m/s: scaled to the limit."""
    for words in ('values must be finite', "frame 'map_ned' refused",
                  'older than the controller clock', 'beyond the pilot limits'):
        assert sum(words in line for line in pilot.logs) == 1, words
    piloted = [x for t, x in pilot.desired if t < 6.0]  # before the task's own path
    steps = np.linalg.norm(np.diff(piloted, axis=0), axis=1)
    assert np.max(steps) < 0.3 * 0.002 * 1.01  # no jump: at most the speed limit per step


def test_a_goal_takes_control_and_pilot_input_cancels_it(pilot: Pilot) -> None:
    """The hold service answers; the goal owns the robot; pilot input ends it CANCELED."""
    assert pilot.hold and pilot.hold[0].success
    status, result = pilot.results['press']
    assert status == GoalStatus.STATUS_ABORTED
    assert result.error_code == ContactTask.Result.CANCELED, result.error_string
    assert any('canceled as a cancel does' in line for line in pilot.logs)
    assert any(line.startswith('mode task') for line in pilot.logs)


def test_every_switch_is_on_diagnostics(pilot: Pilot) -> None:
    """The controller's 'pilot' status names the owner and the last switch."""
    modes = [status['mode'] for status in pilot.diagnostics]
    for mode in ('pilot', 'hold', 'task'):
        assert mode in modes
    assert 'not finite' in pilot.diagnostics[-1]['refused_inputs']
