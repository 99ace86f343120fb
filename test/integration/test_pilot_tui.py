"""``uvms pilot`` driven in tmux: keys sent, screen read, pilot topics observed by a subscriber.

The pilot runs in a tmux server of the test's own (its own socket, so it lives in the test's
network namespace and ROS domain); keys arrive as a terminal delivers a held key (a press,
then auto-repeats ~33 ms apart). A subscriber in the test takes the pilot topics with their
arrival times; a latched mode, an odometry and a /diagnostics message from the test must
show on the screen.
"""

from __future__ import annotations

import os
import shlex
import shutil
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

pytestmark = pytest.mark.skipif(shutil.which('tmux') is None,
                                reason='tmux is not installed (apt-get install tmux)')

REPO = Path(__file__).resolve().parents[2]
#: The pilot's default limits at the first gear (25 %): surge 0.3 m/s * 0.25.
SURGE_GEAR1_M_S = 0.075
SWAY_GEAR1_M_S = 0.075


@dataclass
class Received:
    """Pilot messages with their arrival time (time.monotonic, s)."""

    vehicle: list[tuple[float, object]] = field(default_factory=list)
    ee: list[tuple[float, object]] = field(default_factory=list)
    lock: threading.Lock = field(default_factory=threading.Lock)

    def since(self, t0: float) -> list[tuple[float, object]]:
        """Vehicle twists that arrived after t0."""
        with self.lock:
            return [(t, m) for t, m in self.vehicle if t > t0]


class Tmux:
    """A tmux server of the test's own, with one window running a command."""

    def __init__(self, socket: Path, command: str) -> None:
        self.base = ['tmux', '-S', str(socket)]
        subprocess.run([*self.base, 'new-session', '-d', '-s', 'pilot', '-x', '110', '-y',
                        '30', command], check=True)

    def keys(self, *keys: str) -> None:
        """Send keys to the window (tmux key names: w, Space, C-c)."""
        subprocess.run([*self.base, 'send-keys', '-t', 'pilot', *keys], check=True)

    def screen(self) -> str:
        """The window's text now."""
        return subprocess.run([*self.base, 'capture-pane', '-p', '-t', 'pilot'], check=True,
                              capture_output=True, text=True).stdout

    def wait_for(self, text: str, timeout_s: float) -> str:
        """The screen once it shows ``text``; fails with the screen after timeout_s."""
        deadline = time.monotonic() + timeout_s
        screen = ''
        while time.monotonic() < deadline:
            screen = self.screen()
            if text in screen:
                return screen
            time.sleep(0.1)
        pytest.fail(f'{text!r} not on the screen within {timeout_s} s:\n{screen}')

    def alive(self) -> bool:
        """Whether the session still runs."""
        return subprocess.run([*self.base, 'has-session', '-t', 'pilot'],
                              capture_output=True).returncode == 0

    def kill(self) -> None:
        """Stop the server."""
        subprocess.run([*self.base, 'kill-server'], capture_output=True)


def spin_in_thread(executor: Any) -> Callable[[], None]:
    """Spin in short turns in a thread; the returned call stops and joins it.

    (``executor.spin`` in a thread races ``executor.shutdown``: rclpy then raises in it.)
    """
    stop = threading.Event()

    def spin() -> None:
        while not stop.is_set():
            executor.spin_once(timeout_sec=0.05)

    thread = threading.Thread(target=spin, daemon=True)
    thread.start()

    def end() -> None:
        stop.set()
        thread.join(timeout=5.0)
    return end


@pytest.fixture(scope='module')
def graph() -> Iterator[tuple[object, Received]]:
    """A node in /uvms taking the pilot topics, spun in a thread; (node, received)."""
    import rclpy
    from geometry_msgs.msg import TwistStamped
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node

    context = rclpy.Context()
    rclpy.init(context=context)
    node = Node('pilot_test_graph', namespace='uvms', context=context)
    received = Received()

    def keep(store: list[tuple[float, object]]) -> Callable[[TwistStamped], None]:
        def on_message(msg: TwistStamped) -> None:
            with received.lock:
                store.append((time.monotonic(), msg))
        return on_message

    node.create_subscription(TwistStamped, 'pilot/vehicle_twist', keep(received.vehicle), 10)
    node.create_subscription(TwistStamped, 'pilot/ee_twist', keep(received.ee), 10)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    end = spin_in_thread(executor)
    yield node, received
    end()
    executor.shutdown(timeout_sec=2.0)
    node.destroy_node()
    rclpy.try_shutdown(context=context)


@pytest.fixture(scope='module')
def pilot(graph: tuple[object, Received], tmp_path_factory: pytest.TempPathFactory,
          ) -> Iterator[Tmux]:
    """``uvms pilot`` in tmux, its screen up."""
    folder = tmp_path_factory.mktemp('tmux')
    env = {key: os.environ[key] for key in ('ROS_DOMAIN_ID', 'RMW_IMPLEMENTATION',
                                            'FASTRTPS_DEFAULT_PROFILES_FILE',
                                            'ROS_AUTOMATIC_DISCOVERY_RANGE', 'PYTHONPATH')
           if key in os.environ}
    command = ' '.join([
        'env', *(f'{key}={shlex.quote(value)}' for key, value in env.items()),
        shlex.quote(sys.executable), '-m', 'uvms_pilot.cli', '--use-sim-time', 'false',
        '2>', shlex.quote(str(folder / 'stderr.txt')), '||', 'sleep 30'])
    tmux = Tmux(folder / 'socket', f'cd {shlex.quote(str(REPO))} && {command}')
    try:
        tmux.wait_for('space STOP', 60.0)  # a loaded machine: imports take long
        yield tmux
    finally:
        tmux.kill()


def hold_key(tmux: Tmux, key: str, seconds: float) -> float:
    """Send ``key`` as a held key does (auto-repeat ~33 ms); the monotonic time of the last."""
    end = time.monotonic() + seconds
    last = time.monotonic()
    while time.monotonic() < end:
        tmux.keys(key)
        last = time.monotonic()
        time.sleep(0.03)
    return last


def test_held_key_drives_and_release_gives_zero_within_half_a_second(
        pilot: Tmux, graph: tuple[object, Received]) -> None:
    """Key w held: surge at the first gear, ~20 Hz; let go: one zero within 0.5 s, then silence.

    The silence is what lets the controller's deadman hold the pose.
    """
    _, received = graph
    t0 = time.monotonic()
    last_key = hold_key(pilot, 'w', 1.5)
    screen = pilot.screen()
    time.sleep(1.5)
    messages = received.since(t0)
    moving = [(t, m) for t, m in messages if m.twist.linear.x != 0.0]  # type: ignore[attr-defined]
    zeros = [(t, m) for t, m in messages if t > last_key
             and m.twist.linear.x == 0.0]  # type: ignore[attr-defined]
    assert len(moving) >= 15, f'{len(moving)} moving messages in 1.5 s at 20 Hz'
    assert all(m.twist.linear.x == pytest.approx(SURGE_GEAR1_M_S)  # type: ignore[attr-defined]
               for _, m in moving)
    assert 'surge +0.075 m/s' in screen
    assert zeros, 'no zero after the key stopped'
    assert zeros[0][0] - last_key < 0.5, f'zero {zeros[0][0] - last_key:.3f} s after the key'
    after_zero = [t for t, _ in messages if t > zeros[0][0]]
    assert not after_zero, f'{len(after_zero)} messages after the zero: the deadman never fires'


def test_space_stops_at_once(pilot: Tmux, graph: tuple[object, Received]) -> None:
    """Key d held, then space: a zero sway arrives within 0.2 s (not after the hold window)."""
    _, received = graph
    t0 = time.monotonic()
    hold_key(pilot, 'd', 0.8)
    pilot.keys('Space')
    t_space = time.monotonic()
    time.sleep(0.6)
    messages = received.since(t0)
    assert any(m.twist.linear.y == pytest.approx(SWAY_GEAR1_M_S)  # type: ignore[attr-defined]
               for _, m in messages)
    zero = next(t for t, m in messages if t > t_space - 0.05
                and m.twist.linear.y == 0.0)  # type: ignore[attr-defined]
    assert zero - t_space < 0.2


def test_gear_and_arm_keys(pilot: Tmux, graph: tuple[object, Received]) -> None:
    """Gear 3 then i held: the end effector at the full 0.05 m/s along x of base_link_frd."""
    _, received = graph
    pilot.keys('3')
    pilot.wait_for('[100%]', 5.0)
    t0 = time.monotonic()
    hold_key(pilot, 'i', 0.6)
    time.sleep(0.6)
    pilot.keys('1')
    with received.lock:
        ee = [m for t, m in received.ee if t > t0]
    assert ee and ee[0].twist.linear.x == pytest.approx(0.05)  # type: ignore[attr-defined]
    assert ee[0].header.frame_id == 'base_link_frd'  # type: ignore[attr-defined]
    assert ee[-1].twist.linear.x == 0.0  # type: ignore[attr-defined]


def test_live_state_and_hold_answer_on_screen(pilot: Tmux, graph: tuple[object, Received],
                                              ) -> None:
    """Mode (latched), depth, heading and the worst /diagnostics line show on the screen.

    Key h without a controller says there is no hold service.
    """
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
    from nav_msgs.msg import Odometry
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from std_msgs.msg import String

    node, _ = graph
    latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
    mode = node.create_publisher(String, 'controller/mode', latched)  # type: ignore[attr-defined]
    odometry = node.create_publisher(Odometry, 'odometry', 10)  # type: ignore[attr-defined]
    diagnostics = node.create_publisher(  # type: ignore[attr-defined]
        DiagnosticArray, '/diagnostics', 10)
    mode.publish(String(data='hold'))
    msg = Odometry()
    msg.pose.pose.position.z = 2.5
    msg.pose.pose.orientation.z, msg.pose.pose.orientation.w = 0.7071068, 0.7071068  # 90 deg
    array = DiagnosticArray(status=[
        DiagnosticStatus(level=DiagnosticStatus.OK, name='controller: loop', message='ok'),
        DiagnosticStatus(level=DiagnosticStatus.WARN, name='estimator: dvl',
                         message='dvl stale 0.4 s')])
    for _ in range(10):
        odometry.publish(msg)
        diagnostics.publish(array)
        time.sleep(0.1)
    screen = pilot.wait_for('mode: hold', 5.0)
    screen = pilot.wait_for('depth 2.50 m', 5.0)
    assert 'heading 90.0 deg' in screen
    assert 'WARN estimator: dvl: dvl stale 0.4 s' in screen
    pilot.keys('h')
    pilot.wait_for('hold: no service /uvms/controller/hold', 5.0)


def test_ctrl_c_leaves(pilot: Tmux) -> None:
    """Ctrl-C ends the pilot (the window closes with it)."""
    pilot.keys('C-c')
    deadline = time.monotonic() + 10.0
    while pilot.alive() and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not pilot.alive()
