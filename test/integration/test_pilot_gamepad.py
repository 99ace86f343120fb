"""The gamepad path: input events through the reader and the shipped mapping onto ROS topics.

Events are python-evdev ``InputEvent`` objects as the kernel delivers them, from a stand-in
device (a pipe the reader selects on) and, where /dev/uinput exists, from a virtual device
the kernel creates. A subscriber in the test takes /joy and the pilot topics.
"""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from evdev import AbsInfo, InputEvent, ecodes
from test_pilot_tui import spin_in_thread

REPO = Path(__file__).resolve().parents[2]
SHIPPED = REPO / 'config' / 'pilot' / 'xbox.yaml'
XPAD_RANGES = {
    ecodes.ABS_X: (-32768, 32767), ecodes.ABS_Y: (-32768, 32767),
    ecodes.ABS_RX: (-32768, 32767), ecodes.ABS_RY: (-32768, 32767),
    ecodes.ABS_Z: (0, 255), ecodes.ABS_RZ: (0, 255),
}


class PipeDevice:
    """A stand-in input device: events queued by the test, readable through a pipe's fd."""

    path = '/dev/input/event-test'

    def __init__(self) -> None:
        self.fd, self._write = os.pipe()
        self._events: list[InputEvent] = []
        self._lock = threading.Lock()
        self.gone = False

    def send(self, *events: tuple[int, int, int]) -> None:
        """Queue events (type, code, value) and a SYN_REPORT, as one kernel report."""
        with self._lock:
            self._events += [InputEvent(0, 0, *event) for event in events]
            self._events.append(InputEvent(0, 0, ecodes.EV_SYN, ecodes.SYN_REPORT, 0))
        os.write(self._write, b'x')

    def unplug(self) -> None:
        """The next read fails as an unplugged device's does (ENODEV)."""
        self.gone = True
        os.write(self._write, b'x')

    def read(self) -> list[InputEvent]:
        """The queued events (evdev's InputDevice.read)."""
        os.read(self.fd, 4096)
        if self.gone:
            raise OSError(19, 'No such device')
        with self._lock:
            events, self._events = self._events, []
        return events

    def close(self) -> None:
        """Close both ends."""
        os.close(self.fd)
        os.close(self._write)


class Graph:
    """The pilot's link and session on a node in /uvms, and a subscriber node, both spun."""

    def __init__(self, context: Any) -> None:
        from geometry_msgs.msg import TwistStamped
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.node import Node
        from sensor_msgs.msg import Joy
        from uvms_pilot.gamepad_mapping import load_mapping
        from uvms_pilot.gamepad_state import GamepadState
        from uvms_pilot.limits import pilot_limits
        from uvms_pilot.link import PilotLink
        from uvms_pilot.session import PilotSession

        self.pilot_node = Node('pilot_under_test', namespace='uvms', context=context)
        self.listener = Node('listener', namespace='uvms', context=context)
        self.link = PilotLink(self.pilot_node, 'base_link_frd', joy=True)
        self.mapping = load_mapping(SHIPPED)
        self.session = PilotSession(self.link, pilot_limits('paper_uvms'), None,
                                    GamepadState(self.mapping, XPAD_RANGES))
        self.joy: list[Any] = []
        self.twists: list[Any] = []
        self.lock = threading.Lock()
        self.listener.create_subscription(Joy, '/joy', self._keep(self.joy), 10)
        self.listener.create_subscription(TwistStamped, 'pilot/vehicle_twist',
                                          self._keep(self.twists), 10)
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.pilot_node)
        self.executor.add_node(self.listener)
        self._end_spin = spin_in_thread(self.executor)

    def _keep(self, store: list[Any]) -> Callable[[Any], None]:
        def on_message(msg: Any) -> None:
            with self.lock:
                store.append(msg)
        return on_message

    def wait(self, done: Callable[[], bool], timeout_s: float = 5.0) -> bool:
        """Poll done() until it holds or the timeout (s)."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            with self.lock:
                if done():
                    return True
            time.sleep(0.02)
        return False

    def close(self) -> None:
        """Stop spinning and destroy the nodes."""
        self._end_spin()
        self.executor.shutdown(timeout_sec=2.0)
        self.link.destroy()
        self.pilot_node.destroy_node()
        self.listener.destroy_node()


@pytest.fixture
def graph() -> Iterator[Graph]:
    """A fresh context with the pilot's graph side and a listener."""
    import rclpy

    context = rclpy.Context()
    rclpy.init(context=context)
    graph = Graph(context)
    # Let the listener and the pilot discover each other before the first message.
    assert graph.wait(lambda: graph.listener.count_publishers('/joy') > 0)
    time.sleep(0.3)
    yield graph
    graph.close()
    rclpy.try_shutdown(context=context)


def axis_index(graph: Graph, name: str) -> int:
    """Index of a named axis in /joy (the mapping's order)."""
    return [spec.name for spec in graph.mapping.axes].index(name)


def test_synthetic_events_reach_joy_and_the_vehicle_twist(graph: Graph) -> None:
    """Left stick up and A pressed: /joy has them, the twist is full surge at gear 1."""
    from uvms_pilot.gamepad import GamepadReader

    device = PipeDevice()
    reader = GamepadReader(device, graph.session.gamepad_event,
                           lambda why: (graph.session.gamepad_lost(), graph.link.note(why)))
    reader.start()
    try:
        device.send((ecodes.EV_ABS, ecodes.ABS_Y, -32768), (ecodes.EV_KEY, ecodes.BTN_TR, 1))
        assert graph.wait(lambda: any(j.axes[axis_index(graph, 'left_y')] == -1.0
                                      for j in graph.joy))
        with graph.lock:
            joy = graph.joy[-1]
        assert len(joy.axes) == 8 and len(joy.buttons) == 11
        assert joy.buttons[5] == 1  # rb, the sixth button of the file
        graph.session.tick(time.monotonic())
        assert graph.wait(lambda: bool(graph.twists))
        with graph.lock:
            twist = graph.twists[-1].twist
        assert twist.linear.x == pytest.approx(0.075)  # paper_uvms: 0.3 m/s at 25 %
        device.send((ecodes.EV_ABS, ecodes.ABS_Y, 0))
        # The reader's thread takes the event; the tick after it (not before) publishes zero.
        assert graph.wait(lambda: graph.joy[-1].axes[axis_index(graph, 'left_y')] == 0.0)
        graph.session.tick(time.monotonic())
        assert graph.wait(lambda: graph.twists[-1].twist.linear.x == 0.0)
    finally:
        reader.stop()


def test_unplugged_gamepad_gives_zero_and_says_so(graph: Graph) -> None:
    """A device that goes away mid-stick: the next tick publishes zero, a note names it."""
    from uvms_pilot.gamepad import GamepadReader

    device = PipeDevice()
    reader = GamepadReader(device, graph.session.gamepad_event,
                           lambda why: (graph.session.gamepad_lost(), graph.link.note(why)))
    reader.start()
    try:
        device.send((ecodes.EV_ABS, ecodes.ABS_RX, 32767))
        assert graph.wait(lambda: bool(graph.joy))
        graph.session.tick(time.monotonic())
        assert graph.wait(lambda: bool(graph.twists) and graph.twists[-1].twist.angular.z > 0)
        device.unplug()
        assert graph.wait(lambda: 'lost' in (graph.link.live.note or ''))
        graph.session.tick(time.monotonic())
        assert graph.wait(lambda: graph.twists[-1].twist.angular.z == 0.0)
        assert 'No such device' in (graph.link.live.note or '')
    finally:
        reader.stop()


def test_button_actions_act_at_the_next_tick(graph: Graph) -> None:
    """Y steps the gear up; B (stop) publishes a zero on every part at once."""
    from uvms_pilot.gamepad import GamepadReader

    device = PipeDevice()
    reader = GamepadReader(device, graph.session.gamepad_event, lambda why: None)
    reader.start()
    try:
        device.send((ecodes.EV_KEY, ecodes.BTN_Y, 1))
        assert graph.wait(lambda: bool(graph.joy))
        graph.session.tick(time.monotonic())
        assert graph.session.gear == 0.5
        device.send((ecodes.EV_KEY, ecodes.BTN_Y, 0), (ecodes.EV_KEY, ecodes.BTN_EAST, 1))
        assert graph.wait(lambda: len(graph.joy) >= 2)
        graph.session.tick(time.monotonic())
        assert graph.wait(lambda: bool(graph.twists))
        with graph.lock:
            assert graph.twists[-1].twist.linear.x == 0.0
    finally:
        reader.stop()


@pytest.mark.skipif(not os.path.exists('/dev/uinput'),
                    reason='no /dev/uinput here (a container without the uinput module): the '
                           'virtual-device case needs it; the stand-in device cases cover the '
                           'same path above')
def test_virtual_uinput_gamepad_drives_the_twist(graph: Graph) -> None:
    """A kernel virtual gamepad (uinput) found, opened with its ranges, and read."""
    from evdev import UInput
    from uvms_pilot.gamepad import GamepadReader, open_gamepad

    stick = AbsInfo(value=0, min=-32768, max=32767, fuzz=16, flat=128, resolution=0)
    trigger = AbsInfo(value=0, min=0, max=255, fuzz=0, flat=0, resolution=0)
    hat = AbsInfo(value=0, min=-1, max=1, fuzz=0, flat=0, resolution=0)
    capabilities = {
        ecodes.EV_KEY: [spec.code for spec in graph.mapping.buttons],
        ecodes.EV_ABS: [(ecodes.ABS_X, stick), (ecodes.ABS_Y, stick), (ecodes.ABS_Z, trigger),
                        (ecodes.ABS_RX, stick), (ecodes.ABS_RY, stick),
                        (ecodes.ABS_RZ, trigger), (ecodes.ABS_HAT0X, hat),
                        (ecodes.ABS_HAT0Y, hat)],
    }
    with UInput(capabilities, name='uvms test gamepad') as virtual:
        time.sleep(0.5)  # udev makes the node
        device, ranges = open_gamepad(virtual.device.path)
        assert ranges[ecodes.ABS_Y] == (-32768, 32767)
        reader = GamepadReader(device, graph.session.gamepad_event, lambda why: None)
        reader.start()
        try:
            virtual.write(ecodes.EV_ABS, ecodes.ABS_Y, -32768)
            virtual.syn()
            assert graph.wait(lambda: any(j.axes[axis_index(graph, 'left_y')] == -1.0
                                          for j in graph.joy))
            graph.session.tick(time.monotonic())
            assert graph.wait(lambda: bool(graph.twists)
                              and graph.twists[-1].twist.linear.x == pytest.approx(0.075))
        finally:
            reader.stop()


def run_pilot(*args: str) -> subprocess.CompletedProcess[str]:
    """``uvms pilot`` with arguments, as the uvms command delegates to it."""
    return subprocess.run([sys.executable, '-m', 'uvms_pilot.cli', *args], capture_output=True,
                          text=True, cwd=REPO, timeout=60)


def test_bad_mapping_file_is_refused_before_joining_the_graph(tmp_path: Path) -> None:
    """A mapping with a wrong field: exit 2, one line naming file and field."""
    bad = tmp_path / 'pad.yaml'
    bad.write_text(SHIPPED.read_text().replace('dead_zone: 0.12}', 'dead_zone: 2}', 1))
    result = run_pilot('--gamepad', '/dev/null', '--mapping', str(bad), '--no-tui')
    assert result.returncode == 2
    assert f'{bad}: axes[0].dead_zone' in result.stderr


def test_missing_gamepad_device_is_refused() -> None:
    """A device path that does not exist: exit 2 naming it."""
    result = run_pilot('--gamepad', '/dev/input/event-none', '--no-tui')
    assert result.returncode == 2
    assert 'gamepad /dev/input/event-none: cannot open' in result.stderr
