"""How long rclpy's and Fast DDS's teardown takes at a node's stop, under load (issue 48).

Pairs of processes (an action server with a reliable publisher, an action client with a
subscription, as the controller and the mission are) discover each other, exchange messages
for ``--run-s`` seconds, then the client side tears down as ``run_node`` did: executor
shutdown, ``destroy_node`` (which destroys the action client), ``rclpy.try_shutdown``; each
step is timed. Beside ``--loads`` busy loops. Prints one row per pair, then the worst and the
count over ``--slow-s``.

Usage::

    tools/loopback-netns .venv/bin/python bench/bench_stop_teardown.py --pairs 20 --loads 2
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time

SIDE = r"""
import json, sys, time
import rclpy
from rclpy.action import ActionClient, ActionServer
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.signals import SignalHandlerOptions
from std_msgs.msg import String
from uvms_msgs.action import ContactTask
from uvms_common.node_main import make_executor
from uvms_common.ros_environment import ros_environment_defaults

ros_environment_defaults()
role, run_s, topic = sys.argv[1], float(sys.argv[2]), sys.argv[3]
rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
node = Node('teardown_' + role)
qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
found = None
t0 = time.monotonic()
if role == 'server':
    server = ActionServer(node, ContactTask, topic + '_action', lambda handle: None)
    pub = node.create_publisher(String, topic, qos)
    timer = node.create_timer(0.002, lambda: pub.publish(String(data='x' * 200)))
else:
    client = ActionClient(node, ContactTask, topic + '_action')
    sub = node.create_subscription(String, topic, lambda msg: None, qos)
executor = make_executor()
executor.add_node(node)
end = time.monotonic() + run_s
while time.monotonic() < end:
    executor.spin_once(timeout_sec=0.05)
    if role == 'client' and found is None and client.server_is_ready():
        found = time.monotonic() - t0
times = {'found_s': found}
t = time.monotonic(); executor.remove_node(node); executor.shutdown()
times['executor_s'] = time.monotonic() - t
t = time.monotonic()
if role == 'client':
    client.destroy()
times['action_destroy_s'] = time.monotonic() - t
t = time.monotonic(); node.destroy_node(); times['destroy_node_s'] = time.monotonic() - t
t = time.monotonic(); rclpy.try_shutdown(); times['shutdown_s'] = time.monotonic() - t
print(json.dumps(times), flush=True)
"""


def main() -> int:
    """Run the pairs and print their teardown times."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--pairs', type=int, default=20)
    parser.add_argument('--loads', type=int, default=2)
    parser.add_argument('--run-s', type=float, default=2.0)
    parser.add_argument('--slow-s', type=float, default=0.5)
    args = parser.parse_args()
    loads = [subprocess.Popen([sys.executable, '-c', 'while True:\n    pass\n'])
             for _ in range(args.loads)]
    worst: dict[str, float] = {}
    slow = 0
    try:
        for index in range(args.pairs):
            topic = f'teardown_{index}'
            server = subprocess.Popen([sys.executable, '-c', SIDE, 'server',
                                       str(args.run_s + 1.0), topic], stdout=subprocess.PIPE,
                                      text=True)
            client = subprocess.Popen([sys.executable, '-c', SIDE, 'client', str(args.run_s),
                                       topic], stdout=subprocess.PIPE, text=True)
            started = time.monotonic()
            try:
                out, _ = client.communicate(timeout=60)
                elapsed = time.monotonic() - started
                server.communicate(timeout=60)
            except subprocess.TimeoutExpired:
                print(f'pair {index}: client hung (killed)')
                client.kill()
                server.kill()
                slow += 1
                continue
            row = json.loads(out.strip().splitlines()[-1]) if out.strip() else {}
            teardown = sum(v for k, v in row.items() if k != 'found_s' and v is not None)
            for key, value in row.items():
                if value is not None:
                    worst[key] = max(worst.get(key, 0.0), value)
            slow += teardown > args.slow_s
            print(f'pair {index:3d}: status {client.returncode} total {elapsed:5.2f} s '
                  + ' '.join(f'{k} {v:.3f}' if v is not None else f'{k} -'
                             for k, v in row.items()), flush=True)
    finally:
        for load in loads:
            load.kill()
    print('worst: ' + ' '.join(f'{k} {v:.3f}' for k, v in worst.items()))
    print(f'teardowns over {args.slow_s} s (or hung): {slow} of {args.pairs}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
