"""ArduSub telemetry is stamped when the autopilot sent it (its clock), not when it was read."""

from __future__ import annotations

import bisect
import contextlib
import statistics
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import rclpy
from geometry_msgs.msg import PoseWithCovarianceStamped
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from sensor_msgs.msg import Imu
from uvms_hardware.ardusub_bridge_node import ArduSubBridgeNode
from uvms_twins.ardusub_twin import ArduSubTwin

ROBOT = 'bluerov2_alpha5'
#: The issue's bound on the stamp error where the protocol has a device clock (s).
STAMP_ERROR_BOUND_S = 0.002


@contextlib.contextmanager
def busy_loops(count: int) -> Iterator[None]:
    """``count`` processes spinning on a core each (a loaded machine)."""
    loops = [subprocess.Popen([sys.executable, '-c', 'while True: pass']) for _ in range(count)]
    try:
        yield
    finally:
        for loop in loops:
            loop.kill()
            loop.wait()


def stamp_errors_s(stamps_s: list[float], sent_s: list[float]) -> list[float]:
    """Each stamp minus the nearest send time (sends are 20-50 ms apart: unambiguous)."""
    sent = sorted(sent_s)
    errors = []
    for stamp in stamps_s:
        i = bisect.bisect_left(sent, stamp)
        nearest = min(sent[max(i - 1, 0):i + 1], key=lambda t: abs(t - stamp))
        errors.append(stamp - nearest)
    return errors


def test_imu_and_depth_stamps_are_the_autopilot_send_times_under_load(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Beside 2 busy loops: the median |stamp - the twin's send time| of imu and depth < 2 ms.

    The bridge reads its socket once per override period (60 Hz), so arrival stamps would be
    0-17 ms late (median about 8 ms); the autopilot's own time, mapped through the
    minimum-delay envelope, is not. The median is asserted, the 95th percentile printed: on a
    machine already oversubscribed by other work the process can miss whole buckets of the
    envelope, and the tail then says more about that machine than about the stamps.
    """
    monkeypatch.setenv('UVMS_JOURNAL_DIR', str(tmp_path))
    context = Context()
    rclpy.init(args=[], context=context)
    executor = SingleThreadedExecutor(context=context)
    probe = rclpy.create_node('probe', namespace='uvms', context=context)
    executor.add_node(probe)
    received: dict[str, list[Any]] = {'imu': [], 'depth': []}
    probe.create_subscription(Imu, 'imu', received['imu'].append, 100)
    probe.create_subscription(PoseWithCovarianceStamped, 'depth', received['depth'].append, 100)
    with ArduSubTwin() as twin:
        bridge = ArduSubBridgeNode(namespace='uvms', context=context, parameter_overrides=[
            Parameter(k, value=v) for k, v in {'robot_name': ROBOT, 'mavlink_url': twin.url,
                                               'heartbeat_timeout_s': 3.0,
                                               'script_wait_s': 0.0}.items()])
        executor.add_node(bridge)
        try:
            with busy_loops(2):
                end = time.monotonic() + 4.0  # the envelope's first buckets
                while time.monotonic() < end:
                    executor.spin_once(timeout_sec=0.005)
                for messages in received.values():
                    messages.clear()
                end = time.monotonic() + 6.0
                while time.monotonic() < end:
                    executor.spin_once(timeout_sec=0.005)
            report = bridge.stamper.report()
        finally:
            executor.remove_node(bridge)
            bridge.destroy_node()
            executor.shutdown()
            probe.destroy_node()
            rclpy.try_shutdown(context=context)
        sent = {'imu': twin.sent_times('RAW_IMU'), 'depth': twin.sent_times('SCALED_PRESSURE2')}
    lines = []
    for topic, messages in received.items():
        stamps = [m.header.stamp.sec + m.header.stamp.nanosec * 1e-9 for m in messages]
        errors = sorted(abs(e) for e in stamp_errors_s(stamps, sent[topic]))
        assert len(errors) > 20, f'{len(errors)} {topic} messages, {len(sent[topic])} sent'
        p95 = errors[int(0.95 * (len(errors) - 1))]
        lines.append(f'{topic}: {len(errors)} stamps, |error| median '
                     f'{statistics.median(errors) * 1e3:.2f} ms, p95 {p95 * 1e3:.2f} ms, max '
                     f'{errors[-1] * 1e3:.2f} ms')
        assert statistics.median(errors) < STAMP_ERROR_BOUND_S, lines[-1]
    print('\n'.join(lines), f"\nclock offset {report['clock_offset_s']}, arrival jitter "
          f"{report['arrival_jitter_s']}, stamped at arrival {report['stamped_at_arrival']}")
    assert report['stamped_at_arrival'] == 0 and report['clock_rates_agree']
