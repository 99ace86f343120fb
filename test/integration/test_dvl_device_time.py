"""The dvl_bridge stamps each report with its own time of validity, on a busy computer too."""

from __future__ import annotations

import statistics
import subprocess
import sys
import threading
import time
from collections.abc import Iterator

import pytest
import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import TwistWithCovarianceStamped
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from uvms_hardware.dvl_bridge_node import DvlBridgeNode
from uvms_twins.dvl_twin import DvlTwin

#: The centre of the ping before the report is sent (Water Linked's example report: 189 ms).
PING_TO_SEND_S = 0.1
REPORT_PERIOD_S = 0.05


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


def run_bridge_beside(twin: DvlTwin, seconds: float, diagnostics: list[DiagnosticArray]
                      ) -> list[TwistWithCovarianceStamped]:
    """The bridge on the twin for ``seconds`` while a plant reports every 50 ms; its dvl."""
    context = Context()
    rclpy.init(args=[], context=context)
    executor = SingleThreadedExecutor(context=context)
    probe = rclpy.create_node('probe', namespace='uvms', context=context)
    received: list[TwistWithCovarianceStamped] = []
    probe.create_subscription(TwistWithCovarianceStamped, 'dvl', received.append, 1000)
    probe.create_subscription(DiagnosticArray, '/diagnostics', diagnostics.append, 100)
    bridge = DvlBridgeNode(namespace='uvms', context=context, parameter_overrides=[
        Parameter('robot_name', value='bluerov2_alpha5'), Parameter('address', value=twin.url)])
    executor.add_node(probe)
    executor.add_node(bridge)
    stop = threading.Event()

    def plant() -> None:
        i = 0
        while not stop.wait(REPORT_PERIOD_S):
            i += 1
            twin.report((0.001 * i, 0.0, 0.0), time_of_validity_s=twin.clock() - PING_TO_SEND_S)

    feeder = threading.Thread(target=plant)
    feeder.start()
    try:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            executor.spin_once(timeout_sec=0.01)
    finally:
        stop.set()
        feeder.join()
        executor.shutdown()
        bridge.destroy_node()
        probe.destroy_node()
        rclpy.try_shutdown(context=context)
    return received


def test_dvl_stamps_are_the_reports_time_of_validity_under_two_busy_loops(
        busy_loops: None) -> None:
    """Each stamp within 2 ms of the twin's time_of_validity (arrival stamps: 100 ms late)."""
    diagnostics: list[DiagnosticArray] = []
    with DvlTwin(rate_hz=1.0) as twin:
        received = run_bridge_beside(twin, 6.0, diagnostics)
        sent = {round(vx, 6): validity_s for validity_s, _, vx in twin.sent_log}
    errors_s = [msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
                - sent[round(msg.twist.twist.linear.x, 6)] for msg in received
                if round(msg.twist.twist.linear.x, 6) in sent]
    settled = errors_s[20:]  # the first second: the offset's window still filling
    print(f'dvl stamp error against the twin time_of_validity under 2 busy loops: '
          f'{len(settled)} reports, median {statistics.median(settled) * 1e3:.3f} ms, '
          f'max |error| {max(abs(e) for e in settled) * 1e3:.3f} ms')
    assert len(settled) >= 40
    assert max(abs(e) for e in settled) < 0.002
    values = {kv.key: kv.value for a in diagnostics for s in a.status
              if s.name == 'dvl_bridge: dvl' for kv in s.values}
    assert {'clock_offset_s', 'clock_offset_spread_s', 'arrival_jitter_s'} <= set(values)
