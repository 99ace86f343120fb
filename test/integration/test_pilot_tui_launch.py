"""``uvms pilot`` in tmux moves the robot of ``uvms launch``; input stopped: zero, then hold.

The graph is ``uvms launch`` of open water (real time, the default robot paper_uvms, no
wall) on the module's ROS domain; the pilot runs in a tmux server of the test's own
(``test_pilot_tui.Tmux``). A node of the test takes the vehicle's odometry, the controller's
mode and the pilot's twists.
"""

from __future__ import annotations

import math
import os
import shlex
import shutil
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import pytest
from test_pilot_tui import Tmux, hold_key, spin_in_thread

pytestmark = pytest.mark.skipif(shutil.which('tmux') is None,
                                reason='tmux is not installed (apt-get install tmux)')

REPO = Path(__file__).resolve().parents[2]
#: The pilot's zero after the last key the test sent (s): see the assertion.
ZERO_AFTER_LAST_KEY_S = 1.0
#: paper_uvms: pilot.max_vehicle_speed_m_s surge 0.3 m/s, the first gear 25 %.
SURGE_GEAR1_M_S = 0.075
#: A motion-only task of the t key: a 2 cm half circle over 20 s from wherever X_d is.
TASK = """\
name: pilot_test_arc
half_circle:
  radius_m: 0.02
  duration_s: 20.0
normal: [1.0, 0.0, 0.0]
force_n: 0.0
require_contact: false
"""


@dataclass
class Observed:
    """Odometry (t, u m/s, x m), modes (t, mode) and pilot twists (t, u) with arrival times."""

    odometry: list[tuple[float, float, float]] = field(default_factory=list)
    modes: list[tuple[float, str]] = field(default_factory=list)
    twists: list[tuple[float, float]] = field(default_factory=list)
    lock: threading.Lock = field(default_factory=threading.Lock)


#: Open water: the keys drive the vehicle forward and the task key's arc must not meet the
#: Case I wall (with it, a suite run's arc met it after the drive: FORCE_LIMIT, not CANCELED).
OPEN_WATER = """\
name: pilot_open_water
description: the paper robot in open water, no mission; the pilot drives it
duration_s: 20.0
simulator:
  wall_enabled: false
"""


@pytest.fixture(scope='module')
def launched(tmp_path_factory: pytest.TempPathFactory) -> Iterator[subprocess.Popen[str]]:
    """``uvms launch`` of open water until SIGINT."""
    scenario = tmp_path_factory.mktemp('open_water') / 'pilot_open_water.yaml'
    scenario.write_text(OPEN_WATER, encoding='utf-8')
    process = subprocess.Popen([sys.executable, '-m', 'uvms_cli.cli', 'launch', str(scenario),
                                '--duration', '0', '--quiet'],
                               cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                               text=True, env=dict(os.environ, PYTHONUNBUFFERED='1'))
    yield process
    process.send_signal(signal.SIGINT)
    try:
        process.wait(timeout=30)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()


@pytest.fixture(scope='module')
def observed(launched: subprocess.Popen[str]) -> Iterator[Observed]:
    """A node in /uvms taking odometry, mode and the pilot's vehicle twists, spun in a thread."""
    import rclpy
    from geometry_msgs.msg import TwistStamped
    from nav_msgs.msg import Odometry
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from std_msgs.msg import String

    context = rclpy.Context()
    rclpy.init(context=context)
    node = Node('pilot_launch_observer', namespace='uvms', context=context)
    seen = Observed()

    def on_odometry(msg: Odometry) -> None:
        with seen.lock:
            seen.odometry.append((time.monotonic(), msg.twist.twist.linear.x,
                                  msg.pose.pose.position.x))

    def on_mode(msg: String) -> None:
        with seen.lock:
            seen.modes.append((time.monotonic(), msg.data))

    def on_twist(msg: TwistStamped) -> None:
        with seen.lock:
            seen.twists.append((time.monotonic(), msg.twist.linear.x))

    node.create_subscription(Odometry, 'odometry', on_odometry, 10)
    node.create_subscription(String, 'controller/mode', on_mode, QoSProfile(
        depth=1, reliability=ReliabilityPolicy.RELIABLE,
        durability=DurabilityPolicy.TRANSIENT_LOCAL))
    node.create_subscription(TwistStamped, 'pilot/vehicle_twist', on_twist, 10)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    end = spin_in_thread(executor)
    deadline = time.monotonic() + 120.0
    while not seen.odometry and time.monotonic() < deadline:
        assert launched.poll() is None, launched.stdout.read() if launched.stdout else ''
        time.sleep(0.2)
    assert seen.odometry, 'no odometry from uvms launch in 120 s'
    yield seen
    end()
    executor.shutdown(timeout_sec=2.0)
    node.destroy_node()
    rclpy.try_shutdown(context=context)


@pytest.fixture(scope='module')
def pilot(observed: Observed, tmp_path_factory: pytest.TempPathFactory) -> Iterator[Tmux]:
    """``uvms pilot`` in tmux on the launched graph (sim time found from /clock)."""
    folder = tmp_path_factory.mktemp('tmux')
    (folder / 'task.yaml').write_text(TASK)
    env = {key: os.environ[key] for key in ('ROS_DOMAIN_ID', 'RMW_IMPLEMENTATION',
                                            'FASTRTPS_DEFAULT_PROFILES_FILE',
                                            'ROS_AUTOMATIC_DISCOVERY_RANGE', 'PYTHONPATH')
           if key in os.environ}
    command = ' '.join([
        'env', *(f'{key}={shlex.quote(value)}' for key, value in env.items()),
        shlex.quote(sys.executable), '-m', 'uvms_pilot.cli', '--task',
        shlex.quote(str(folder / 'task.yaml')),
        '2>', shlex.quote(str(folder / 'stderr.txt')), '||', 'sleep 30'])
    tmux = Tmux(folder / 'socket', f'cd {shlex.quote(str(REPO))} && {command}')
    try:
        tmux.wait_for('space STOP', 60.0)
        tmux.wait_for('paper_uvms', 10.0)  # the robot named by the running controller
        yield tmux
    finally:
        tmux.kill()


def _mode_after(seen: Observed, t0: float, mode: str) -> float | None:
    with seen.lock:
        return next((t for t, m in seen.modes if t > t0 and m == mode), None)


def test_keys_move_the_launched_robot_and_release_holds_it(pilot: Tmux,
                                                          observed: Observed) -> None:
    """Key w held 3 s: mode pilot, the vehicle moves forward; let go: zero, hold, it stops.

    The pilot asks for the first gear's 0.075 m/s; the vehicle follows the controller's
    rate-limited reference (0.049-0.060 m/s seen at the end of the 3 s on a loaded machine).
    Let go: the pilot's zero within 1 s of the last key sent (0.3 s of it the pilot's own), the
    controller in hold within 1.5 s (the deadman's 0.3 s after the zero), the vehicle under
    5 mm/s within 2 s (0.27-0.43 s, 0.28-0.87 s and 0.52-0.96 s seen at load averages of
    12-38 on 2 cores; the zero 0.84 s once at load 38, 0.62 s in a CI run).
    """
    screen = pilot.wait_for('depth ', 10.0)
    with observed.lock:
        x_start = observed.odometry[-1][2]
    t0 = time.monotonic()
    last_key = hold_key(pilot, 'w', 3.0)
    screen = pilot.screen()
    time.sleep(3.0)
    with observed.lock:
        twists = [(t, u) for t, u in observed.twists if t > t0]
        during = [(t, u, x) for t, u, x in observed.odometry if t0 + 2.0 < t <= last_key]
        after = [(t, u, x) for t, u, x in observed.odometry if t > last_key]
    pilot_at = _mode_after(observed, t0, 'pilot')
    hold_at = _mode_after(observed, last_key, 'hold')
    zero_at = next((t for t, u in twists if t > last_key and u == 0.0), None)
    peak_u = max(u for _, u, _ in during)
    stopped_at = next((t for t, u, _ in after if abs(u) < 0.005), None)
    print(f'peak surge {peak_u:.4f} m/s; pilot zero {zero_at - last_key if zero_at else None} s,'
          f' hold {hold_at - last_key if hold_at else None} s, |u| < 5 mm/s '
          f'{stopped_at - last_key if stopped_at else None} s after the last key; moved '
          f'{after[-1][2] - x_start:.3f} m')
    assert 'mode: pilot' in screen or pilot_at is not None
    assert pilot_at is not None and pilot_at < t0 + 2.0
    with observed.lock:
        asked = [u for t, u in observed.twists if t0 < t <= last_key]
    # A key arriving later than the repeat window (send-keys under load) is a release: a zero
    # then. Only the gear's speed or zero is ever asked, and mostly the speed.
    assert asked and all(u in (0.0, pytest.approx(SURGE_GEAR1_M_S)) for u in asked)
    assert sum(u != 0.0 for u in asked) >= 0.8 * len(asked), asked
    assert SURGE_GEAR1_M_S / 2 < peak_u < SURGE_GEAR1_M_S * 1.1
    assert after[-1][2] - x_start > 0.1
    # The pilot's own part is 0.3 s (REPEAT_HOLD_S and a 20 Hz tick); the rest is the path
    # from tmux send-keys to the TUI, at normal priority beside the graph's SCHED_FIFO
    # processes, which take most of the 2 cores: 0.62 s in the CI of 2026-12-07, 0.84 s
    # once at load 38.
    assert zero_at is not None and zero_at - last_key < ZERO_AFTER_LAST_KEY_S
    assert hold_at is not None and hold_at - last_key < 1.5
    assert stopped_at is not None and stopped_at - last_key < 2.0
    assert all(math.isfinite(u) for _, u, _ in after)
    pilot.wait_for('mode: hold', 5.0)


def test_hold_key_gets_the_controllers_answer(pilot: Tmux) -> None:
    """Key h: the controller's hold service answers, and the answer is on the screen."""
    pilot.keys('h')
    screen = pilot.wait_for('> hold', 5.0)
    deadline = time.monotonic() + 5.0
    while 'hold: asked' in screen and time.monotonic() < deadline:
        time.sleep(0.1)
        screen = pilot.screen()
    assert '> hold' in screen and 'no service' not in screen, screen


def test_task_key_starts_the_task_file_and_cancel_key_cancels_it(pilot: Tmux,
                                                                  observed: Observed) -> None:
    """Key t sends the task file (mode task, its feedback on screen); c cancels it (CANCELED)."""
    t0 = time.monotonic()
    pilot.keys('t')
    pilot.wait_for('pilot_test_arc', 10.0)
    deadline = time.monotonic() + 10.0
    while _mode_after(observed, t0, 'task') is None and time.monotonic() < deadline:
        time.sleep(0.1)
    assert _mode_after(observed, t0, 'task') is not None
    time.sleep(1.0)
    pilot.keys('c')
    pilot.wait_for('> cancel: asked', 5.0)
    screen = pilot.wait_for('CANCELED', 30.0)  # after the retreat, slower under load
    assert 'pilot_test_arc: CANCELED' in screen, screen
    deadline = time.monotonic() + 10.0
    while not _hold_now(observed) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert _hold_now(observed)


def test_leaving_the_pilot_leaves_the_robot_held(pilot: Tmux, observed: Observed) -> None:
    """Ctrl-C while moving: the pilot's last message is a zero; the controller holds."""
    t0 = time.monotonic()
    hold_key(pilot, 'd', 1.0)
    pilot.keys('C-c')
    deadline = time.monotonic() + 10.0
    while pilot.alive() and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not pilot.alive()
    assert _mode_after(observed, t0 + 1.0, 'hold') is not None or _hold_now(observed)


def _hold_now(seen: Observed) -> bool:
    with seen.lock:
        return bool(seen.modes) and seen.modes[-1][1] == 'hold'



