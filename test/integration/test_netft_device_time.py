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
from uvms_common.scheduling import Scheduling, apply_scheduling
from uvms_hardware.netft_bridge_node import NetFtBridgeNode
from uvms_twins.netft_twin import NetFtTwin

IDENTITY = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
RATE_HZ = 200.0
PERIOD_S = 1.0 / RATE_HZ
HERE = str(Path(__file__).parent)
#: The twin's SCHED_FIFO priority: above the busy loops and the bridge (normal), as a box's own
#: processor is.
TWIN_RT_PRIORITY = 10


class CountingTwin(NetFtTwin):
    """A twin whose Fx counts are the record's sample number, Fy its stream's (to match)."""

    def __init__(self) -> None:
        super().__init__(port=0, rate_hz=RATE_HZ, clock=time.time, http_port=0)
        self.stream_starts: list[float] = []
        #: (sample time, how late its record left) (s) of each record sent.
        self.lateness: list[tuple[float, float]] = []

    def handle(self, datagram: bytes, sender: tuple[str, int]) -> None:
        """Note each stream's start."""
        super().handle(datagram, sender)
        with self._lock:
            if self._client is not None and self._sample == 0:
                self.stream_starts.append(self._stream_start_s)

    def _record(self) -> bytes:
        self._counts = (self._sample, len(self.stream_starts), 0, 0, 0, 0)
        sampled_s = self._stream_start_s + self._sample * self.period_s
        self.lateness.append((sampled_s, self.clock() - sampled_s))
        return super()._record()


def serve_twin() -> None:
    """The twin in its own process, at SCHED_FIFO where allowed.

    A box's timing is its own hardware's, which our host's load does not reach. Ports out;
    stream starts and lateness at EOF.
    """
    outcome = apply_scheduling(Scheduling(priority=TWIN_RT_PRIORITY))
    twin = CountingTwin()
    twin.start()
    print(json.dumps([twin.port, twin.http_port, outcome.refused or ', '.join(outcome.applied)]),
          flush=True)
    sys.stdin.read()
    twin.stop()
    print(json.dumps({'starts': twin.stream_starts, 'lateness': twin.lateness}), flush=True)


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

    The twin runs in a process of its own, as the box is a device of its own; the bridge at
    normal priority beside the busy loops.
    """
    twin = subprocess.Popen([sys.executable, '-c', f'import sys; sys.path.insert(0, {HERE!r}); '
                             'import test_netft_device_time as t; t.serve_twin()'],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    assert twin.stdin is not None and twin.stdout is not None
    port, http_port, twin_scheduling = json.loads(twin.stdout.readline())
    print(f'twin: {twin_scheduling}')
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
              f'streams, {core.stale_episodes} stale; received {len(received)}; box clock '
              f'{core.clock.report()}')
    finally:
        executor.shutdown()
        bridge.destroy_node()
        rclpy.try_shutdown(context=context)
        twin_out, _ = twin.communicate(timeout=10.0)
    starts = json.loads(twin_out)['starts']
    lateness = json.loads(twin_out)['lateness']
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
    # The claim is the 2 ms on the median (arrival stamps: median 6.9 ms late, and 0 ms
    # apart within a poll, which the spacing checks refuse). One fresh-clone CI run (stop 58)
    # saw 2.54 ms, with the fit on the polls' times and the twin at normal priority beside the
    # loops (its lateness then unrecorded); the fit now rests on the kernel's arrival stamps,
    # and the twin's own lateness, which no stamp can see, is printed below.
    errors_sorted = sorted(abs(e) for e in errors_s)
    p99_s = errors_sorted[int(0.99 * (len(errors_sorted) - 1))]
    print(f'netft |stamp error| p99 {p99_s * 1e3:.3f} ms')
    # How late the twin's own records left, the least of each 0.1 s (what the bridge's
    # minimum-delay estimate rests on): no stamp can be better than these.
    settled_from_s = settled[0][3]
    floors: dict[int, float] = {}
    for sampled_s, late_s in lateness:
        if sampled_s >= settled_from_s:
            key = int((sampled_s - settled_from_s) / 0.1)
            floors[key] = min(floors.get(key, late_s), late_s)
    print(f'twin: its records left late by at least {statistics.median(floors.values()) * 1e3:.3f}'
          f' ms (median of 0.1 s), at most {max(floors.values()) * 1e3:.3f} ms')
    assert statistics.median(errors_sorted) < 0.002
