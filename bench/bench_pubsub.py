"""Messages per second of in-process pub/sub on genuine rclpy, both executors, and CDR rates.

Run: ``.venv/bin/python bench/bench_pubsub.py [--duration S] [--repeats N]``. A publisher
node sends sensor_msgs/JointState (9 joints) to a subscriber node (reliable, keep last 1000),
both in one rclpy context spun by one executor: the SingleThreadedExecutor, then the
EventsExecutor (``uvms_common.node_main.make_executor``), each in a fresh context of this
one process over rmw_fastrtps_cpp with the project's loopback-only profile. Two patterns:

- ``publish one``: publish one message, then ``spin_once`` until the subscription has taken
  it; throughput and latency from just before ``publish`` to the start of the callback
  (mean and p99, µs);
- ``burst of 100``: publish 100 messages, then spin until all 100 were taken.

Each figure is the best of ``--repeats`` runs of ``--duration`` seconds. Also printed: the
rates of ``rclpy.serialization.serialize_message`` and ``deserialize_message`` for the same
message, the costs below any pub/sub. Figures only, no pass/fail.
"""

from __future__ import annotations

import argparse
import os
import random
import statistics
import sys
import time
import timeit
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / 'src' / 'uvms_common'))

import rclpy  # noqa: E402
from rclpy.context import Context  # noqa: E402
from rclpy.executors import Executor  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy  # noqa: E402
from rclpy.serialization import deserialize_message, serialize_message  # noqa: E402
from rclpy.signals import SignalHandlerOptions  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402
from std_msgs.msg import Header  # noqa: E402
from uvms_common.node_main import make_executor  # noqa: E402
from uvms_common.ros_environment import ros_environment_defaults  # noqa: E402

JOINTS = 9
BURST = 100
QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1000,
                 reliability=ReliabilityPolicy.RELIABLE)
#: Longest wait of one spin_once for a message already published (s); a lost message
#: shows as a stall of this length, not as a hang.
SPIN_TIMEOUT_S = 1.0
EXECUTOR_LABELS = {'single': 'SingleThreadedExecutor', 'events': 'EventsExecutor'}
#: ROS_DOMAIN_IDs this bench picks from when none is set, away from the test suite's
#: (0, 1-100, 150-199): another process's publisher on joint_states would skew the counts.
DOMAINS = (101, 149)


@dataclass
class Result:
    """Figures of one executor (best of the repeats)."""

    one_rate: float = 0.0
    latencies_us: list[float] | None = None
    burst_rate: float = 0.0


def joint_state() -> JointState:
    """JointState of 9 joints with names, positions, velocities and efforts."""
    return JointState(
        header=Header(frame_id='base_link_frd'),
        name=[f'joint_{i + 1}' for i in range(JOINTS)],
        position=np.linspace(-1.0, 1.0, JOINTS),
        velocity=np.linspace(-0.5, 0.5, JOINTS),
        effort=np.linspace(-10.0, 10.0, JOINTS),
    )


class Pair:
    """A publisher node and a subscriber node on one topic, spun by one executor."""

    def __init__(self, executor: Executor, publisher_node: Node, subscriber_node: Node,
                 on_message: Callable[[JointState], None]) -> None:
        self.executor = executor
        self._publisher_node = publisher_node
        self._subscriber_node = subscriber_node
        self.subscription = subscriber_node.create_subscription(
            JointState, 'joint_states', on_message, QOS)
        self.publisher = publisher_node.create_publisher(JointState, 'joint_states', QOS)
        deadline = time.monotonic() + 5.0
        while self.publisher.get_subscription_count() < 1 and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.01)

    def close(self) -> None:
        """Destroy the subscription and the publisher."""
        self._subscriber_node.destroy_subscription(self.subscription)
        self._publisher_node.destroy_publisher(self.publisher)


def publish_one(executor: Executor, nodes: tuple[Node, Node],
                duration_s: float) -> tuple[float, list[float]]:
    """Return (messages/s, latencies in µs) for publish, then spin until taken."""
    latencies_ns: list[int] = []
    sent_at = [0]
    clock = time.perf_counter_ns

    def on_message(_msg: JointState) -> None:
        latencies_ns.append(clock() - sent_at[0])

    pair = Pair(executor, *nodes, on_message)
    msg = joint_state()
    spin_once, publish = executor.spin_once, pair.publisher.publish
    count = 0
    start = time.perf_counter()
    deadline = start + duration_s
    while time.perf_counter() < deadline:
        for _ in range(100):
            sent_at[0] = clock()
            publish(msg)
            count += 1
            while len(latencies_ns) < count:
                spin_once(timeout_sec=SPIN_TIMEOUT_S)
    elapsed = time.perf_counter() - start
    pair.close()
    return count / elapsed, [ns / 1000 for ns in latencies_ns]


def burst(executor: Executor, nodes: tuple[Node, Node], duration_s: float) -> float:
    """Return messages/s for batches of 100 published, then spun until all were taken."""
    received = [0]

    def on_message(_msg: JointState) -> None:
        received[0] += 1

    pair = Pair(executor, *nodes, on_message)
    msg = joint_state()
    spin_once, publish = executor.spin_once, pair.publisher.publish
    sent = 0
    start = time.perf_counter()
    deadline = start + duration_s
    while time.perf_counter() < deadline:
        for _ in range(BURST):
            publish(msg)
        sent += BURST
        while received[0] < sent:
            spin_once(timeout_sec=SPIN_TIMEOUT_S)
    elapsed = time.perf_counter() - start
    pair.close()
    return sent / elapsed


def measure(kind: str, duration_s: float, repeats: int) -> Result:
    """Both patterns on one executor kind, in a fresh context."""
    context = Context()
    rclpy.init(args=[], context=context, signal_handler_options=SignalHandlerOptions.NO)
    result = Result()
    try:
        nodes = (Node('bench_publisher', context=context),
                 Node('bench_subscriber', context=context))
        executor = make_executor(kind, context)
        for node in nodes:
            executor.add_node(node)
        for _ in range(repeats):
            rate, latencies = publish_one(executor, nodes, duration_s)
            if rate > result.one_rate:
                result.one_rate, result.latencies_us = rate, latencies
        result.burst_rate = max(burst(executor, nodes, duration_s) for _ in range(repeats))
        executor.shutdown()
        for node in nodes:
            node.destroy_node()
    finally:
        rclpy.try_shutdown(context=context)
    return result


def rate(func: Callable[[], Any], repeats: int) -> float:
    """Calls per second of func: best of ``repeats`` runs of about 0.2 s each."""
    timer = timeit.Timer(func)
    number, _ = timer.autorange()
    return number / min(timer.repeat(repeat=repeats, number=number))


def percentile(values: list[float], fraction: float) -> float:
    """The value below which ``fraction`` of the values lie (nearest rank)."""
    ordered = sorted(values)
    return ordered[int(fraction * (len(ordered) - 1))]


def main() -> None:
    """Run both executors and print the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--duration', type=float, default=1.0,
                        help='seconds per run (default 1)')
    parser.add_argument('--repeats', type=int, default=3, help='runs per figure (default 3)')
    args = parser.parse_args()
    ros_environment_defaults()
    if not os.environ.get('ROS_DOMAIN_ID'):
        os.environ['ROS_DOMAIN_ID'] = str(random.SystemRandom().randint(*DOMAINS))
    kinds = ('single', 'events')
    msg = joint_state()
    data = serialize_message(msg)
    print(f'JointState ({JOINTS} joints, {len(data)} B serialized), reliable, keep last '
          f'{QOS.depth}, one process (ROS_DOMAIN_ID {os.environ["ROS_DOMAIN_ID"]}); best of '
          f'{args.repeats} runs of {args.duration:g} s')
    results = {kind: measure(kind, args.duration, max(1, args.repeats)) for kind in kinds}

    width = 24
    print(f'{"":<28}' + ''.join(f'{EXECUTOR_LABELS[k]:>{width}}' for k in kinds))
    print(f'{"publish one, spin (msg/s)":<28}'
          + ''.join(f'{results[k].one_rate:>{width},.0f}' for k in kinds))
    for label, fraction in (('  latency mean (µs)', None), ('  latency p99 (µs)', 0.99)):
        cells = []
        for k in kinds:
            latencies = results[k].latencies_us or [float('nan')]
            value = (statistics.fmean(latencies) if fraction is None
                     else percentile(latencies, fraction))
            cells.append(f'{value:>{width}.1f}')
        print(f'{label:<28}' + ''.join(cells))
    print(f'{f"bursts of {BURST} (msg/s)":<28}'
          + ''.join(f'{results[k].burst_rate:>{width},.0f}' for k in kinds))
    single, events = results['single'], results['events']
    print(f'EventsExecutor / SingleThreadedExecutor: {events.one_rate / single.one_rate:.2f}x '
          f'(publish one), {events.burst_rate / single.burst_rate:.2f}x (bursts)')
    print()
    serialize_rate = rate(lambda: serialize_message(msg), args.repeats)
    print(f'{"serialize_message":<28}{serialize_rate:>{width},.0f} msg/s')
    print(f'{"deserialize_message":<28}'
          f'{rate(lambda: deserialize_message(data, JointState), args.repeats):>{width},.0f}'
          ' msg/s')


if __name__ == '__main__':
    main()
