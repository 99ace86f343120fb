"""The dvl_bridge node against the DVL twin: dvl as the simulator publishes it, lock, silence."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest
import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import TwistWithCovarianceStamped
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.lifecycle import TransitionCallbackReturn
from rclpy.parameter import Parameter
from uvms_hardware.dvl_bridge_node import DvlBridgeNode
from uvms_twins.dvl_twin import DvlTwin

ROBOT = 'bluerov2_alpha5'


class Rig:
    """A DVL twin, a probe collecting topics, the bridge."""

    def __init__(self, twin: DvlTwin) -> None:
        self.twin = twin
        self.context = Context()
        rclpy.init(args=[], context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.probe = rclpy.create_node('probe', namespace='uvms', context=self.context)
        self.executor.add_node(self.probe)
        self.dvl: list[TwistWithCovarianceStamped] = []
        self.probe.create_subscription(TwistWithCovarianceStamped, 'dvl', self.dvl.append, 100)
        self.diagnostics: list[DiagnosticArray] = []
        self.probe.create_subscription(DiagnosticArray, '/diagnostics',
                                       self.diagnostics.append, 100)
        self.bridge: DvlBridgeNode | None = None

    def start_bridge(self, **parameters: Any) -> DvlBridgeNode:
        """The bridge on the twin, with parameter overrides."""
        values = {'robot_name': ROBOT, 'address': self.twin.url, 'reconnect_period_s': 0.1,
                  **parameters}
        self.bridge = DvlBridgeNode(namespace='uvms', context=self.context,
                                    parameter_overrides=[Parameter(k, value=v)
                                                         for k, v in values.items()])
        self.executor.add_node(self.bridge)
        return self.bridge

    def spin_until(self, done: Callable[[], bool], timeout_s: float, what: str) -> None:
        """Spin until done() (fails after the timeout naming what)."""
        end = time.monotonic() + timeout_s
        while not done():
            assert time.monotonic() < end, f'timed out waiting for {what}'
            self.executor.spin_once(timeout_sec=0.01)

    def status(self, level: bytes, text: str) -> bool:
        """A dvl_bridge status of that level whose message holds text arrived."""
        return any(s.level == level and text in s.message and 'dvl_bridge' in s.name
                   for array in self.diagnostics for s in array.status)

    def close(self) -> None:
        """Destroy the nodes and the context."""
        if self.bridge is not None:
            self.executor.remove_node(self.bridge)
            self.bridge.destroy_node()
        self.executor.shutdown()
        self.probe.destroy_node()
        rclpy.try_shutdown(context=self.context)


@pytest.fixture
def rig() -> Iterator[Rig]:
    """A DVL twin at 20 Hz and a rig around it."""
    with DvlTwin(rate_hz=20.0) as twin:
        made = Rig(twin)
        yield made
        made.close()


def test_locked_reports_are_published_in_dvl_link(rig: Rig) -> None:
    """dvl_link frame, the velocity, fom^2 variances, unused angular variances."""
    rig.twin.set_velocity((0.4, -0.2, 0.1), valid=True, fom=0.003)
    rig.start_bridge()
    rig.spin_until(lambda: len(rig.dvl) >= 3, 5.0, 'dvl messages')
    msg = rig.dvl[-1]
    assert msg.header.frame_id == 'dvl_link'
    lin = msg.twist.twist.linear
    assert (lin.x, lin.y, lin.z) == pytest.approx((0.4, -0.2, 0.1))
    assert msg.twist.covariance[0] == pytest.approx(0.003 ** 2)
    assert msg.twist.covariance[21] == pytest.approx(1.0e9)
    rig.spin_until(lambda: rig.status(DiagnosticStatus.OK, 'bottom lock'), 3.0, 'OK status')


def test_reports_without_lock_are_not_published_and_warned(rig: Rig) -> None:
    """velocity_valid false: nothing on dvl, WARN on /diagnostics."""
    rig.twin.set_velocity((0.0, 0.0, 0.0), valid=False)
    bridge = rig.start_bridge()
    rig.spin_until(lambda: rig.status(DiagnosticStatus.WARN, 'no bottom lock'), 4.0,
                   'a WARN for the lost lock')
    assert rig.dvl == [] and bridge.link is not None and bridge.link.parser.reports > 0


def test_malformed_json_is_survived_and_counted(rig: Rig) -> None:
    """Garbage lines: counted on the link, dvl keeps coming."""
    bridge = rig.start_bridge()
    rig.spin_until(lambda: rig.twin.client_count() == 1, 2.0, 'the connection')
    rig.twin.send_raw(b'{"type": "velocity", "vx":\n\x00\x01garbage\n')
    assert bridge.link is not None
    link = bridge.link
    rig.spin_until(lambda: link.parser.malformed == 2, 3.0, 'the malformed lines counted')
    count = len(rig.dvl)
    rig.spin_until(lambda: len(rig.dvl) > count + 2, 3.0, 'dvl after the garbage')


def test_a_silent_dvl_is_an_error_and_a_dropped_one_reconnects(rig: Rig) -> None:
    """Silence: ERROR; connection dropped: the bridge connects again and publishes."""
    bridge = rig.start_bridge(timeout_s=0.3)
    rig.spin_until(lambda: len(rig.dvl) >= 1, 3.0, 'dvl')
    rig.twin.silent = True
    rig.spin_until(lambda: rig.status(DiagnosticStatus.ERROR, 'DVL silent'), 4.0,
                   'an ERROR for the silent DVL')
    rig.twin.silent = False
    rig.twin.drop_clients()
    assert bridge.link is not None
    link = bridge.link
    rig.spin_until(lambda: link.connects >= 2, 3.0, 'a reconnection')
    count = len(rig.dvl)
    rig.spin_until(lambda: len(rig.dvl) > count + 2, 3.0, 'dvl after reconnecting')


def test_no_dvl_refuses_configure(rig: Rig) -> None:
    """Nothing at the address: configure fails within connect_timeout_s."""
    with DvlTwin() as gone:
        url = gone.url
    bridge = rig.start_bridge(address=url, connect_timeout_s=0.3, autostart=False)
    assert bridge.trigger_configure() == TransitionCallbackReturn.FAILURE


def test_deactivate_stops_publishing_and_cleanup_disconnects(rig: Rig) -> None:
    """The base's lifecycle: inactive publishes nothing; cleanup closes the TCP connection."""
    bridge = rig.start_bridge()
    rig.spin_until(lambda: len(rig.dvl) >= 1, 3.0, 'dvl')
    assert bridge.trigger_deactivate() == TransitionCallbackReturn.SUCCESS
    count = len(rig.dvl)
    end = time.monotonic() + 0.3
    while time.monotonic() < end:
        rig.executor.spin_once(timeout_sec=0.01)
    assert len(rig.dvl) == count
    assert bridge.trigger_cleanup() == TransitionCallbackReturn.SUCCESS
    rig.spin_until(lambda: rig.twin.client_count() == 0, 3.0, 'the connection closed')
    assert bridge.link is None


def test_a_silent_dvl_is_never_republished(rig: Rig) -> None:
    """The DVL goes quiet with its connection open: not one dvl message more, none repeated."""
    bridge = rig.start_bridge(timeout_s=0.3)
    rig.spin_until(lambda: len(rig.dvl) >= 3, 3.0, 'dvl')
    rig.twin.silent = True
    end = time.monotonic() + 0.2  # what was already on its way
    while time.monotonic() < end:
        rig.executor.spin_once(timeout_sec=0.01)
    count = len(rig.dvl)
    rig.spin_until(lambda: rig.status(DiagnosticStatus.ERROR, 'DVL silent'), 4.0,
                   'an ERROR for the silent DVL')
    end = time.monotonic() + 1.0
    while time.monotonic() < end:
        rig.executor.spin_once(timeout_sec=0.01)
    assert len(rig.dvl) == count and rig.twin.client_count() == 1
    assert bridge.published == count  # one message per report, never a repeat
    stamps = [(m.header.stamp.sec, m.header.stamp.nanosec) for m in rig.dvl]
    assert len(set(stamps)) == len(stamps)
