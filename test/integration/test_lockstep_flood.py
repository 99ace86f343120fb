"""A lockstep graph flooded by another process with bad and foreign inputs is not stalled.

Measured before the fix (issue 9): NaN wrenches and one-joint JointStates from another
process made the controller answer foreign stamps and the simulator wait out its lockstep
timeout every step (4 states in 8 s). Inputs that the exchange did not ask for are now
ignored or rejected: the run goes on at speed, with no timeout and no non-finite command.
"""

from __future__ import annotations

import math
import subprocess
import sys
import textwrap
import time
from pathlib import Path

from rosbags.highlevel import AnyReader
from uvms_run.graph import Graph, build_graph, run_graph
from uvms_scenarios.scenario import load_scenario

SCENARIOS = Path(__file__).resolve().parents[2] / 'config' / 'scenarios'

#: Publishes bad and foreign-stamped inputs on every topic of the lockstep exchange.
FLOOD = textwrap.dedent("""
    import math, sys, time
    import rclpy
    from geometry_msgs.msg import WrenchStamped
    from sensor_msgs.msg import JointState
    from uvms_msgs.msg import ActuatorCommand, GeneralizedForce
    from uvms_common.ros_environment import ros_environment_defaults

    ros_environment_defaults()
    rclpy.init()
    node = rclpy.create_node('flood', namespace='/uvms')
    wrench = node.create_publisher(WrenchStamped, 'wrench', 10)
    joints = node.create_publisher(JointState, 'joint_states', 10)
    force = node.create_publisher(GeneralizedForce, 'command/generalized_force', 10)
    actuators = node.create_publisher(ActuatorCommand, 'command/actuators', 10)
    print('ready', flush=True)
    end = time.monotonic() + float(sys.argv[1])
    k = 0
    while time.monotonic() < end:
        k += 1
        # Within the run's first 50 ms but never on its 2 ms grid: a rejected input at the
        # very stamp of the exchange is answered by holding the last command (by design).
        stamp_s = (k % 50) * 1e-3 + 0.5e-3
        w = WrenchStamped()
        w.header.stamp.nanosec = int(stamp_s * 1e9)
        w.header.frame_id = 'ft_sensor_link'
        w.wrench.force.x = math.nan
        wrench.publish(w)
        j = JointState(name=['joint_1'], position=[0.0], velocity=[0.0])
        j.header.stamp.nanosec = int(stamp_s * 1e9)
        joints.publish(j)
        g = GeneralizedForce()  # a valid command, stamped 100 s ahead of the run
        g.header.stamp.sec = 100
        g.header.frame_id = 'base_link_frd'
        g.vehicle_wrench.force.x = 50.0
        g.joint_names = ['joint_1', 'joint_2', 'joint_3']
        g.joint_torques = [0.0, 0.0, 0.0]
        force.publish(g)
        a = ActuatorCommand()  # valid but stamped at no state of the run
        a.header.stamp.sec = 7
        a.thrust = [200.0] * 8
        a.joint_names = ['joint_1', 'joint_2', 'joint_3']
        a.joint_torques = [0.0, 0.0, 0.0]
        actuators.publish(a)
        time.sleep(0.01)  # about 100 messages per second and topic, 400 in all
    print('sent', k, flush=True)
""")


def wait_until_the_flood_is_matched(graph: Graph, timeout_s: float = 20.0) -> None:
    """Wait until every flooded topic has a second publisher (the flood) besides the graph's."""
    node = graph.simulator
    deadline = time.monotonic() + timeout_s
    topics = ('/uvms/wrench', '/uvms/joint_states', '/uvms/command/generalized_force',
              '/uvms/command/actuators')
    while any(node.count_publishers(topic) < 2 for topic in topics):
        assert time.monotonic() < deadline, 'the flood process was not discovered'
        time.sleep(0.05)


def test_flood_of_bad_and_foreign_inputs_does_not_stall_or_steer_lockstep(
    tmp_path: Path,
) -> None:
    """With another process flooding every input topic, the run keeps pace and stays clean."""
    path = tmp_path / 'flooded.mcap'
    scenario = load_scenario(SCENARIOS / 'case1_ke1e4.yaml').with_changes(duration_s=1.0)
    graph = build_graph(scenario, 'lockstep', output_path=path)
    flood = subprocess.Popen([sys.executable, '-c', FLOOD, '60'], stdout=subprocess.PIPE,
                             text=True)
    try:
        assert flood.stdout is not None and flood.stdout.readline().strip() == 'ready'
        wait_until_the_flood_is_matched(graph)
        result = run_graph(graph)
        assert flood.poll() is None, 'the flood stopped before the run ended'
    finally:
        flood.terminate()
        flood.communicate(timeout=10)

    assert result.sim_time_s >= 1.0
    assert result.lockstep_timeouts == 0
    with AnyReader([path]) as reader:
        topics = ('/uvms/command/actuators', '/uvms/command/generalized_force')
        connections = [c for c in reader.connections if c.topic in topics]
        count = 0
        for connection, _, raw in reader.messages(connections=connections):
            msg = reader.deserialize(raw, connection.msgtype)
            if msg.header.stamp.sec >= 2:
                continue  # the flood's own messages, recorded on the same topics
            values = (list(msg.thrust) if connection.topic.endswith('actuators')
                      else [msg.vehicle_wrench.force.x, *msg.joint_torques])
            assert all(math.isfinite(v) for v in values)
            count += 1
    # One command of each kind per 2 ms control period: nothing skipped, nothing foreign.
    assert count >= 2 * 500


def test_commands_of_the_graph_are_the_same_with_and_without_a_flood(tmp_path: Path) -> None:
    """The flood changes nothing the graph computes: same actuator commands, byte for byte."""
    scenario = load_scenario(SCENARIOS / 'case1_ke1e4.yaml').with_changes(duration_s=0.3)

    def commands(path: Path, flood_s: float) -> list[bytes]:
        graph = build_graph(scenario, 'lockstep', output_path=path)
        flood = None
        if flood_s > 0.0:
            flood = subprocess.Popen([sys.executable, '-c', FLOOD, str(flood_s)],
                                     stdout=subprocess.PIPE, text=True)
            assert flood.stdout is not None and flood.stdout.readline().strip() == 'ready'
            wait_until_the_flood_is_matched(graph)
        try:
            run_graph(graph)
            assert flood is None or flood.poll() is None, 'the flood stopped too early'
        finally:
            if flood is not None:
                flood.terminate()
                flood.communicate(timeout=10)
        with AnyReader([path]) as reader:
            connections = [c for c in reader.connections if c.topic == '/uvms/command/actuators']
            # The graph's own commands (the flood's, stamped 7 s, are recorded too).
            return [raw for connection, _, raw in reader.messages(connections=connections)
                    if reader.deserialize(raw, connection.msgtype).header.stamp.sec < 2]

    quiet = commands(tmp_path / 'quiet.mcap', 0.0)
    flooded = commands(tmp_path / 'flooded.mcap', 60.0)
    assert len(quiet) >= 150
    assert flooded == quiet


def test_controller_answers_its_stamp_behind_a_burst_of_foreign_inputs() -> None:
    """A lockstep controller that falls behind still takes the exchange's inputs and answers.

    Issue 29: under load the flood test saw one lockstep timeout: the controller's executor
    fell behind, and a reader history of 10 let 100 Hz of foreign inputs push the graph's own
    joint state out (no command at t = 0.348 s). Here 50 foreign inputs per topic arrive
    after the genuine ones before the controller runs at all.
    """
    import rclpy
    from geometry_msgs.msg import WrenchStamped
    from nav_msgs.msg import Odometry
    from rclpy.context import Context
    from rclpy.parameter import Parameter
    from sensor_msgs.msg import JointState
    from uvms_common.node_main import make_executor
    from uvms_control.controller_node import ControllerNode

    from uvms_msgs.msg import GeneralizedForce

    config = Path(__file__).resolve().parents[2] / 'config'
    context = Context()
    rclpy.init(args=[], context=context)
    feeder = rclpy.create_node('feeder', namespace='uvms', context=context)
    controller = ControllerNode(
        namespace='uvms', context=context,
        cli_args=['--ros-args', '--params-file', str(config / 'robot.yaml'),
                  '--params-file', str(config / 'controller.yaml')],
        parameter_overrides=[Parameter('trigger_mode', value='lockstep')])
    executor = make_executor('events', context)
    try:
        answers: list[GeneralizedForce] = []
        feeder.create_subscription(GeneralizedForce, 'command/generalized_force',
                                   answers.append, 100)
        joints = feeder.create_publisher(JointState, 'joint_states', 100)
        odometry = feeder.create_publisher(Odometry, 'odometry', 100)
        wrench = feeder.create_publisher(WrenchStamped, 'wrench', 100)
        deadline = time.monotonic() + 10.0
        while any(controller.count_publishers(f'/uvms/{t}') < 1
                  for t in ('joint_states', 'odometry', 'wrench')):
            assert time.monotonic() < deadline, 'the controller did not match the feeder'
            time.sleep(0.05)
        time.sleep(0.5)  # the feeder's readers match the controller's publisher too
        odom = Odometry()
        odom.header.frame_id, odom.child_frame_id = 'map_ned', 'base_link_frd'
        odom.pose.pose.orientation.w = 1.0
        odometry.publish(odom)
        joints.publish(JointState(name=['joint_1', 'joint_2', 'joint_3'],
                                  position=[0.0, 0.4, -0.8], velocity=[0.0] * 3))
        genuine = WrenchStamped()
        genuine.header.frame_id = 'ft_sensor_link'
        wrench.publish(genuine)
        for k in range(50):  # foreign stamps, rejected content: nothing the exchange asked for
            bad = WrenchStamped()
            bad.header.stamp.nanosec = 500_000 + k * 1_000_000
            bad.wrench.force.x = math.nan
            wrench.publish(bad)
            one = JointState(name=['joint_1'], position=[0.0], velocity=[0.0])
            one.header.stamp.nanosec = 500_000 + k * 1_000_000
            joints.publish(one)
        time.sleep(0.5)  # delivered to the controller's reader histories, not yet taken
        executor.add_node(controller)
        executor.add_node(feeder)
        deadline = time.monotonic() + 10.0
        while not any(a.header.stamp.sec == 0 and a.header.stamp.nanosec == 0
                      for a in answers):
            assert time.monotonic() < deadline, 'no generalized force answered stamp 0'
            executor.spin_once(timeout_sec=0.05)
    finally:
        executor.shutdown()
        controller.destroy_node()
        feeder.destroy_node()
        rclpy.try_shutdown(context=context)
