"""The recorder process's CPU per message: taken in batches vs. one callback per message.

The twin stand's recorder receives about 3500 messages a second (six topics at the control
rate, the wrench, /clock, the slower devices). This bench publishes a stream like it from a
process of its own (``--topics`` topics of WrenchStamped at ``--rate-hz`` each) and records
it with the recorder node, built in a process of its own, spun in turn:

- ``per message``: by an EventsExecutor, which calls each subscription's callback once per
  message (the recorder's process before ``uvms_recording.batched_take``);
- ``batches``: by a SingleThreadedExecutor, which leaves the subscriptions to the node's
  batches every ``take_period_s`` (the recorder's process now).

Per round and way it reads the recorder process's CPU (all its threads, from
``/proc/PID/stat``, over a window in the middle of the stream) and the messages in its file
(beside about how many were sent), and prints CPU in % of one core, us per message, and the
batches' figures as ratios to the per-message ones of the same round (rounds alternate the
order). Only ratios travel between machines. It asserts nothing.

Usage::

    tools/loopback-netns .venv/bin/python bench/bench_recorder.py [--rounds N]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

WAYS = {'per message': 'events', 'batches': 'single'}
TICKS_PER_S = os.sysconf('SC_CLK_TCK')


def publish(topics: int, rate_hz: float, seconds: float) -> None:
    """Child: publish ``topics`` WrenchStamped topics at ``rate_hz`` for ``seconds``."""
    import rclpy
    from geometry_msgs.msg import WrenchStamped
    from rclpy.serialization import serialize_message

    rclpy.init()
    node = rclpy.create_node('bench_publisher', namespace='/uvms')
    publishers = [node.create_publisher(WrenchStamped, f'bench_{k}', 10) for k in range(topics)]
    data = serialize_message(WrenchStamped())
    period_s = 1.0 / rate_hz
    next_s = time.monotonic()
    end_s = next_s + seconds
    while next_s < end_s:
        for publisher in publishers:
            publisher.publish(data)
        next_s += period_s
        time.sleep(max(0.0, next_s - time.monotonic()))
    node.destroy_node()
    rclpy.try_shutdown()


def record(kind: str, output: str, topics: int, seconds: float) -> None:
    """Child: the recorder node spun by executor ``kind`` for ``seconds``, then closed."""
    import rclpy
    from rclpy.parameter import Parameter
    from uvms_common.node_main import make_executor
    from uvms_recording.recorder_node import RecorderNode

    rclpy.init()
    specs = [f'bench_{k}:geometry_msgs/msg/WrenchStamped' for k in range(topics)]
    node = RecorderNode(namespace='/uvms', parameter_overrides=[
        Parameter('output_path', value=output), Parameter('topics', value=specs)])
    executor = make_executor(kind)
    executor.add_node(node)
    end_s = time.monotonic() + seconds
    while time.monotonic() < end_s:
        executor.spin_once(timeout_sec=0.05)
    node.close()
    executor.shutdown()
    node.destroy_node()
    rclpy.try_shutdown()


def cpu_ticks(pid: int) -> int:
    """User + system CPU of a process, all threads (clock ticks)."""
    fields = Path(f'/proc/{pid}/stat').read_text().rsplit(')', 1)[1].split()
    return int(fields[11]) + int(fields[12])


def one_run(kind: str, topics: int, rate_hz: float, directory: Path,
            window_s: float) -> tuple[float, int, int]:
    """CPU of the recorder (% of one core) over the window, messages recorded and sent."""
    from uvms_recording.mcap_reader import open_recording

    output = directory / f'{kind}.mcap'
    stream_s = window_s + 6.0
    me = [sys.executable, __file__]
    recorder = subprocess.Popen([*me, '--child-record', kind, str(output), str(topics),
                                 str(stream_s + 4.0)])
    time.sleep(3.0)  # built and subscribed
    publisher = subprocess.Popen([*me, '--child-publish', str(topics), str(rate_hz),
                                  str(stream_s)])
    time.sleep(3.0)  # matched, steady
    before, start = cpu_ticks(recorder.pid), time.monotonic()
    time.sleep(window_s)
    used = (cpu_ticks(recorder.pid) - before) / TICKS_PER_S
    cpu = 100.0 * used / (time.monotonic() - start)
    publisher.wait()
    recorder.wait()
    recorded = sum(1 for _ in open_recording(output).messages())
    return cpu, recorded, round(stream_s * rate_hz) * topics


def main() -> None:
    """Alternate the two ways for ``--rounds`` rounds; print each run and the ratios."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--rounds', type=int, default=3)
    parser.add_argument('--topics', type=int, default=7)
    parser.add_argument('--rate-hz', type=float, default=500.0)
    parser.add_argument('--window-s', type=float, default=8.0)
    parser.add_argument('--child-publish', nargs=3, help=argparse.SUPPRESS)
    parser.add_argument('--child-record', nargs=4, help=argparse.SUPPRESS)
    args = parser.parse_args()
    from uvms_common.ros_environment import ros_environment_defaults

    ros_environment_defaults()
    if args.child_publish:
        topics, rate_hz, seconds = args.child_publish
        publish(int(topics), float(rate_hz), float(seconds))
        return
    if args.child_record:
        kind, output, topics, seconds = args.child_record
        record(kind, output, int(topics), float(seconds))
        return
    rate = args.topics * args.rate_hz
    print(f'load before: {" ".join(f"{x:.2f}" for x in os.getloadavg())}; '
          f'{args.topics} topics at {args.rate_hz:g} Hz ({rate:g} messages/s)')
    print('| round | way | recorder CPU, % of one core | us per message | recorded / sent |')
    print('| --- | --- | --- | --- | --- |')
    ratios = []
    with tempfile.TemporaryDirectory() as tmp:
        for round_ in range(1, args.rounds + 1):
            order = list(WAYS) if round_ % 2 else list(reversed(WAYS))
            cpu = {}
            for way in order:
                cpu[way], recorded, sent = one_run(WAYS[way], args.topics, args.rate_hz,
                                                   Path(tmp), args.window_s)
                print(f'| {round_} | {way} | {cpu[way]:.1f} | {cpu[way] * 1e4 / rate:.1f} | '
                      f'{recorded} / about {sent} |', flush=True)
            ratios.append(cpu['batches'] / cpu['per message'])
    print(f'batches / per message, round by round: {", ".join(f"{r:.2f}" for r in ratios)} '
          f'(median {statistics.median(ratios):.2f})')
    print(f'load after: {" ".join(f"{x:.2f}" for x in os.getloadavg())}')


if __name__ == '__main__':
    main()
