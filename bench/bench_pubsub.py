"""Messages per second and latency of in-process pub/sub through a SingleThreadedExecutor.

Run: ``.venv/bin/python bench/bench_pubsub.py``. A publisher node sends sensor_msgs/JointState
(9 joints) to a subscriber node, both spun by one SingleThreadedExecutor of the compat rclpy.
Three patterns:

- ``publish+spin_once``: publish one message, then ``executor.spin_once(timeout_sec=0)`` runs
  the subscription callback; throughput and latency from just before ``publish`` to the start
  of the callback (mean and p99, µs);
- ``burst``: publish a batch of 100 (queue depth 100), then spin until all were delivered;
- ``timer``: a 0-period timer publishes, the subscription receives, ``spin_once`` in a loop
  (two callbacks per message, as in a timer-driven node).

Also prints the cost of ``copy_message`` (each subscription receives its own copy) as a
reference. Figures only, no pass/fail; the target is at least 50,000 messages/s.
"""

from __future__ import annotations

import statistics
import time

import numpy as np

import ros2_compat

ros2_compat.activate()

import rclpy  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.node import Node  # noqa: E402
from ros2_compat.message_support import copy_message  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402
from std_msgs.msg import Header  # noqa: E402

JOINTS = 9
DURATION_S = 1.0
REPEATS = 3


def joint_state() -> JointState:
    """JointState of 9 joints with names, positions, velocities and efforts."""
    return JointState(
        header=Header(frame_id='base_link_frd'),
        name=[f'joint_{i + 1}' for i in range(JOINTS)],
        position=np.linspace(-1.0, 1.0, JOINTS),
        velocity=np.linspace(-0.5, 0.5, JOINTS),
        effort=np.linspace(-10.0, 10.0, JOINTS),
    )


def publish_then_spin(
    executor: SingleThreadedExecutor, publisher_node: Node, subscriber_node: Node
) -> tuple[float, list[float]]:
    """Return (messages/s, latencies in µs) for publish followed by spin_once."""
    latencies_ns: list[int] = []
    sent_at = [0]
    clock = time.perf_counter_ns

    def on_message(_msg: JointState) -> None:
        latencies_ns.append(clock() - sent_at[0])

    subscription = subscriber_node.create_subscription(
        JointState, 'joint_states', on_message, 10
    )
    publisher = publisher_node.create_publisher(JointState, 'joint_states', 10)
    msg = joint_state()
    spin_once = executor.spin_once
    publish = publisher.publish
    deadline = time.perf_counter() + DURATION_S
    start = time.perf_counter()
    count = 0
    while time.perf_counter() < deadline:
        for _ in range(1000):
            sent_at[0] = clock()
            publish(msg)
            spin_once(timeout_sec=0)
        count += 1000
    elapsed = time.perf_counter() - start
    subscriber_node.destroy_subscription(subscription)
    publisher_node.destroy_publisher(publisher)
    assert len(latencies_ns) == count, f'delivered {len(latencies_ns)} of {count}'
    return count / elapsed, [ns / 1000 for ns in latencies_ns]


def burst(
    executor: SingleThreadedExecutor, publisher_node: Node, subscriber_node: Node
) -> float:
    """Return messages/s for batches of 100 published then spun."""
    received = [0]

    def on_message(_msg: JointState) -> None:
        received[0] += 1

    subscription = subscriber_node.create_subscription(
        JointState, 'joint_states', on_message, 100
    )
    publisher = publisher_node.create_publisher(JointState, 'joint_states', 100)
    msg = joint_state()
    deadline = time.perf_counter() + DURATION_S
    start = time.perf_counter()
    sent = 0
    while time.perf_counter() < deadline:
        for _ in range(100):
            publisher.publish(msg)
        sent += 100
        while received[0] < sent:
            executor.spin_once(timeout_sec=0)
    elapsed = time.perf_counter() - start
    subscriber_node.destroy_subscription(subscription)
    publisher_node.destroy_publisher(publisher)
    return sent / elapsed


def timer_driven(
    executor: SingleThreadedExecutor, publisher_node: Node, subscriber_node: Node
) -> float:
    """Return messages/s when a 0-period timer publishes and spin_once runs both callbacks."""
    received = [0]
    msg = joint_state()
    publisher = publisher_node.create_publisher(JointState, 'joint_states', 10)
    timer = publisher_node.create_timer(0.0, lambda: publisher.publish(msg))

    def on_message(_msg: JointState) -> None:
        received[0] += 1

    subscription = subscriber_node.create_subscription(
        JointState, 'joint_states', on_message, 10
    )
    deadline = time.perf_counter() + DURATION_S
    start = time.perf_counter()
    while time.perf_counter() < deadline:
        for _ in range(1000):
            executor.spin_once(timeout_sec=0)
    elapsed = time.perf_counter() - start
    publisher_node.destroy_timer(timer)
    subscriber_node.destroy_subscription(subscription)
    publisher_node.destroy_publisher(publisher)
    return received[0] / elapsed


def copy_rate() -> float:
    """Return copy_message calls per second for the JointState."""
    msg = joint_state()
    count = 20000
    start = time.perf_counter()
    for _ in range(count):
        copy_message(msg)
    return count / (time.perf_counter() - start)


def main() -> None:
    """Run the patterns and print the figures."""
    rclpy.init(args=[])
    try:
        publisher_node = Node('bench_publisher')
        subscriber_node = Node('bench_subscriber')
        executor = SingleThreadedExecutor()
        executor.add_node(publisher_node)
        executor.add_node(subscriber_node)
        print(f'JointState ({JOINTS} joints), SingleThreadedExecutor, in process; '
              f'best of {REPEATS} runs of {DURATION_S:.0f} s')
        best = (0.0, [0.0])
        for _ in range(REPEATS):
            result = publish_then_spin(executor, publisher_node, subscriber_node)
            if result[0] > best[0]:
                best = result
        rate, latencies = best
        latencies.sort()
        p99 = latencies[int(0.99 * (len(latencies) - 1))]
        print(f'  publish+spin_once : {rate:10,.0f} msg/s   latency mean '
              f'{statistics.fmean(latencies):6.1f} µs, p99 {p99:6.1f} µs')
        burst_rate = max(burst(executor, publisher_node, subscriber_node)
                         for _ in range(REPEATS))
        print(f'  burst of 100      : {burst_rate:10,.0f} msg/s')
        timer_rate = max(timer_driven(executor, publisher_node, subscriber_node)
                         for _ in range(REPEATS))
        print(f'  timer -> pub -> sub: {timer_rate:10,.0f} msg/s')
        print(f'  copy_message alone: {copy_rate():10,.0f} copies/s (one per subscription)')
        print(f'  target            : {50_000:10,} msg/s -> '
              f'{rate / 50_000:.2f}x (publish+spin_once)')
        executor.shutdown()
        publisher_node.destroy_node()
        subscriber_node.destroy_node()
    finally:
        rclpy.try_shutdown()


if __name__ == '__main__':
    main()
