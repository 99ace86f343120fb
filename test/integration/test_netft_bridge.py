"""The netft_bridge node against the Net F/T twin on 127.0.0.1, on a real rclpy executor."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest
import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import WrenchStamped
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.lifecycle import TransitionCallbackReturn
from rclpy.parameter import Parameter
from std_srvs.srv import Trigger
from uvms_common.lifecycle import state_label
from uvms_hardware.netft_bridge_node import NetFtBridgeNode
from uvms_twins.netft_twin import NetFtTwin

IDENTITY = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
FAILURE = TransitionCallbackReturn.FAILURE
SUCCESS = TransitionCallbackReturn.SUCCESS


class Rig:
    """A Net F/T twin at 200 Hz, a probe node and the bridge on one executor."""

    def __init__(self) -> None:
        self.twin = NetFtTwin(port=0, rate_hz=200.0, http_port=0)
        self.twin.start()
        self.context = Context()
        rclpy.init(args=[], context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.probe = rclpy.create_node('probe', namespace='uvms', context=self.context)
        self.executor.add_node(self.probe)
        self.wrenches: list[WrenchStamped] = []
        self.probe.create_subscription(WrenchStamped, 'wrench', self.wrenches.append, 1000)
        self.diagnostics: list[DiagnosticArray] = []
        self.probe.create_subscription(DiagnosticArray, '/diagnostics',
                                       self.diagnostics.append, 100)
        self.bridge: NetFtBridgeNode | None = None

    def start_bridge(self, **parameters: Any) -> NetFtBridgeNode:
        """The bridge on the twin's port with ``parameters``."""
        values = {'robot_name': 'bluerov2_alpha5', 'address': f'127.0.0.1:{self.twin.port}',
                  'http_port': self.twin.http_port or 0, **parameters}
        self.bridge = NetFtBridgeNode(namespace='uvms', context=self.context, parameter_overrides=[
            Parameter(k, value=v) for k, v in values.items()])
        self.executor.add_node(self.bridge)
        return self.bridge

    def spin_until(self, done: Callable[[], bool], timeout_s: float = 10.0) -> None:
        """Spin until done() or fail after the timeout."""
        deadline = time.monotonic() + timeout_s
        while not done():
            assert time.monotonic() < deadline, 'timed out spinning'
            self.executor.spin_once(timeout_sec=0.01)

    def status(self) -> DiagnosticStatus:
        """The next netft status published on /diagnostics."""
        self.diagnostics.clear()
        self.spin_until(lambda: any(s.name == 'netft_bridge: netft' for a in self.diagnostics
                                    for s in a.status), timeout_s=5.0)
        return next(s for a in self.diagnostics for s in a.status
                    if s.name == 'netft_bridge: netft')

    def close(self) -> None:
        """Bridge, probe, context and twin gone."""
        self.executor.shutdown()
        if self.bridge is not None:
            self.bridge.destroy_node()
        self.probe.destroy_node()
        rclpy.try_shutdown(context=self.context)
        self.twin.stop()


@pytest.fixture
def rig() -> Iterator[Rig]:
    """A fresh twin and executor, closed after the test."""
    made = Rig()
    yield made
    made.close()


def test_known_counts_give_the_known_wrench_on_uvms_wrench(rig: Rig) -> None:
    """(1.5, -2, 3) N and (0.1, 0.2, -0.3) N m at the box are that wrench in ft_sensor_link."""
    rig.twin.set_wrench((1.5, -2.0, 3.0), (0.1, 0.2, -0.3))
    rig.start_bridge(rot_link_from_sensor=IDENTITY)
    rig.spin_until(lambda: len(rig.wrenches) >= 3)
    msg = rig.wrenches[-1]
    assert msg.header.frame_id == 'ft_sensor_link'
    f, t = msg.wrench.force, msg.wrench.torque
    assert (f.x, f.y, f.z) == pytest.approx((1.5, -2.0, 3.0))
    assert (t.x, t.y, t.z) == pytest.approx((0.1, 0.2, -0.3))
    assert rig.probe.count_publishers('/uvms/wrench') == 1


def test_bias_service_zeroes_the_reading(rig: Rig) -> None:
    """~/bias takes the present wrench as zero; the following records read zero."""
    rig.twin.set_wrench((0.0, 0.0, 2.0), (0.0, 0.0, 0.0))
    rig.start_bridge()
    rig.spin_until(lambda: len(rig.wrenches) >= 2)
    assert rig.wrenches[-1].wrench.force.x == pytest.approx(2.0)  # sensor z: jaw approach x
    client = rig.probe.create_client(Trigger, 'netft_bridge/bias')
    future = client.call_async(Trigger.Request())
    rig.spin_until(future.done)
    assert future.result().success
    count = len(rig.wrenches)
    rig.spin_until(lambda: len(rig.wrenches) >= count + 3)
    assert rig.wrenches[-1].wrench.force.x == pytest.approx(0.0)


def test_silence_stops_publishing_and_reports_an_error(rig: Rig) -> None:
    """The box stops: no wrench after 0.1 s and /diagnostics turns ERROR."""
    rig.start_bridge()
    rig.spin_until(lambda: len(rig.wrenches) >= 2)
    rig.twin.stop()
    time.sleep(0.05)
    rig.spin_until(lambda: rig.bridge is not None and rig.bridge.core is not None
                   and rig.bridge.core.stale(rig.bridge.now_s()))
    count = len(rig.wrenches)
    status = rig.status()
    assert status.level == DiagnosticStatus.ERROR and 'no record' in status.message
    assert len(rig.wrenches) == count


def test_lost_records_are_counted_on_diagnostics(rig: Rig) -> None:
    """Five sequence numbers skipped by the box show as 5 lost records."""
    bridge = rig.start_bridge()
    rig.spin_until(lambda: len(rig.wrenches) >= 2)
    rig.twin.drop_records(5)
    rig.spin_until(lambda: bridge.core is not None and bridge.core.lost >= 5)
    values = {kv.key: kv.value for kv in rig.status().values}
    assert values['lost_records'] == '5'


def test_deactivate_stops_the_stream(rig: Rig) -> None:
    """Deactivate sends command 0: the twin stops streaming."""
    bridge = rig.start_bridge()
    rig.spin_until(lambda: len(rig.wrenches) >= 2)
    bridge.trigger_deactivate()
    deadline = time.monotonic() + 2.0
    while rig.twin.streaming and time.monotonic() < deadline:
        time.sleep(0.01)
    assert not rig.twin.streaming and state_label(bridge) == 'inactive'


def test_each_record_is_published_once_after_deactivate_and_activate(rig: Rig) -> None:
    """A second activation polls with the one timer of the configured link: no record twice."""
    bridge = rig.start_bridge()
    timers = len(list(bridge.timers))
    for _ in range(2):
        assert bridge.trigger_deactivate() == SUCCESS
        assert bridge.trigger_activate() == SUCCESS
    assert len(list(bridge.timers)) == timers
    rig.wrenches.clear()
    rig.spin_until(lambda: len(rig.wrenches) >= 20)
    stamps = [(w.header.stamp.sec, w.header.stamp.nanosec) for w in rig.wrenches]
    assert len(set(stamps)) == len(stamps)


def test_absent_box_is_refused_at_configure(rig: Rig) -> None:
    """Nothing at the address for startup_wait_s: configure fails naming it."""
    rig.twin.stop()
    bridge = rig.start_bridge(autostart=False, answer_timeout_s=0.2, startup_wait_s=0.5)
    started = time.monotonic()
    assert bridge.trigger_configure() == FAILURE
    assert time.monotonic() - started >= 0.5
    assert f'127.0.0.1:{rig.twin.port}' in bridge.refusal


def test_a_box_that_comes_up_after_the_bridge_is_found(rig: Rig) -> None:
    """Launch order: the box answers 1 s after configure began; configure waits for it."""
    port = rig.twin.port
    rig.twin.stop()
    late = NetFtTwin(port=port, rate_hz=200.0)
    timer = threading.Timer(1.0, late.start)
    timer.start()
    try:
        bridge = rig.start_bridge(autostart=False, answer_timeout_s=0.2, startup_wait_s=5.0)
        assert bridge.trigger_configure() == SUCCESS
    finally:
        timer.join()
        late.stop()


def test_the_calibration_is_the_boxs_own_page(rig: Rig) -> None:
    """A box at 2e6 counts/N and 4e5 counts/(N m): its page says so and the wrench is right."""
    rig.twin.stop()
    rig.twin = NetFtTwin(port=0, rate_hz=200.0, counts_per_force=2e6, counts_per_torque=4e5,
                         http_port=0)
    rig.twin.start()
    rig.twin.set_wrench((1.5, -2.0, 3.0), (0.1, 0.2, -0.3))
    bridge = rig.start_bridge(rot_link_from_sensor=IDENTITY)
    rig.spin_until(lambda: len(rig.wrenches) >= 3)
    f, t = rig.wrenches[-1].wrench.force, rig.wrenches[-1].wrench.torque
    assert (f.x, f.y, f.z) == pytest.approx((1.5, -2.0, 3.0))
    assert (t.x, t.y, t.z) == pytest.approx((0.1, 0.2, -0.3))
    assert f'127.0.0.1:{rig.twin.http_port}/netftapi2.xml' in bridge.calibration_source
    assert 'hardware.yaml' not in bridge.calibration_source


def test_without_the_page_the_hardware_files_calibration_is_used_and_named(rig: Rig) -> None:
    """http_port 0: counts and rate from bluerov2_alpha5's hardware.yaml, the file named."""
    bridge = rig.start_bridge(http_port=0)
    assert bridge.core is not None and bridge.core.rdt_rate_hz == 500.0
    assert bridge.core.counts_per_force == 1e6 and 'hardware.yaml' in bridge.calibration_source


def test_no_calibration_from_the_box_or_the_file_refuses_configure(rig: Rig) -> None:
    """No page and no counts per force given: refused, never a silent 1e6."""
    bridge = rig.start_bridge(autostart=False, http_port=0, counts_per_force=0.0)
    assert bridge.trigger_configure() == FAILURE
    assert 'no counts_per_force' in bridge.refusal and 'never assumed' in bridge.refusal


def test_a_silent_box_is_never_republished(rig: Rig) -> None:
    """The stream stops: one wrench per record received, none after, none stamped twice."""
    bridge = rig.start_bridge()
    rig.spin_until(lambda: len(rig.wrenches) >= 20)
    rig.twin.stop()
    rig.spin_until(lambda: bridge.core is not None and bridge.core.stale(bridge.now_s()))
    count = len(rig.wrenches)
    end = time.monotonic() + 1.0
    while time.monotonic() < end:
        rig.executor.spin_once(timeout_sec=0.01)
    assert bridge.core is not None
    assert len(rig.wrenches) == count == bridge.core.records
    stamps = [(m.header.stamp.sec, m.header.stamp.nanosec) for m in rig.wrenches]
    assert len(set(stamps)) == len(stamps)
