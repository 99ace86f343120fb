"""The twin stand's arm tripped, recovered with the documented commands, holds without a new trip.

Issue 52 item 3: after ``tripped: joint_3 ...``, ``deactivate`` and ``activate`` both exited 0
and the arm tripped again at once, and after ``uvms lifecycle controller reset`` the next safe
hold said ``|X_d - X| = 1.795 m``. docs/hardware.md, "Recovering the arm after a trip":
``uvms hardware reset-trip`` (the controller reset, then the trip cleared 0.5 s later). The
test trips the arm by sending it a large joint torque beside the controller, runs the command
as a user would once the twin's arm, held by its VELOCITY 0, is under 0.5 rad/s (asked again
when refused), and watches the hold for 10 s of wall time: joint states flow, every joint
under the trip speed, no new trip.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState

from uvms_msgs.msg import ActuatorCommand

JOINTS = ['joint_1', 'joint_2', 'joint_3', 'joint_4']
#: 1.5 x the URDF's 0.5 rad/s.
TRIP_RAD_S = 0.75
#: A command line beside the SCHED_FIFO graph on 2 cores waits its turn (71 s seen).
CLI_TIMEOUT_S = 300.0


class Probe:
    """Joint states of the bridge and of the plant; a publisher of arm torques."""

    def __init__(self) -> None:
        self.context = Context()
        rclpy.init(args=[], context=self.context)
        # On the graph's clock (/clock), as the bridge stamps its joint states.
        self.node = rclpy.create_node('recover_probe', namespace='uvms', context=self.context,
                                      parameter_overrides=[Parameter('use_sim_time', value=True)])
        qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
        #: The bridge's joint states: (header stamp on the graph's clock s, velocities).
        self.bridge_states: list[tuple[float, list[float]]] = []
        self.plant_states: list[tuple[float, list[float]]] = []
        self.node.create_subscription(JointState, 'joint_states', lambda m: self.bridge_states
                                      .append((m.header.stamp.sec + 1e-9 * m.header.stamp
                                               .nanosec, list(m.velocity))), qos)
        self.node.create_subscription(JointState, '/plant/joint_states', lambda m: self
                                      .plant_states.append((time.monotonic(),
                                                            list(m.velocity)[:4])), qos)
        self.command = self.node.create_publisher(ActuatorCommand, 'command/actuators', qos)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        while not self._stop.is_set():
            self.executor.spin_once(timeout_sec=0.02)

    def still(self, since_s: float) -> bool:
        """The plant's arm under 0.5 rad/s at every joint for its last 25 states (0.1 s)."""
        recent = [v for t, v in self.plant_states[-25:] if t >= since_s]
        return len(recent) == 25 and all(abs(x) < 0.5 for v in recent for x in v)

    def close(self) -> None:
        """Spinning stopped, node and context gone."""
        self._stop.set()
        self._thread.join(timeout=2.0)
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)


def uvms(env: dict[str, str], *args: str) -> subprocess.CompletedProcess[str]:
    """One ``uvms`` command as a user types it beside the launch."""
    return subprocess.run([sys.executable, '-m', 'uvms_cli.cli', *args], env=env,
                          capture_output=True, text=True, timeout=CLI_TIMEOUT_S,
                          stdin=subprocess.DEVNULL)


def wait_for(done: object, timeout_s: float, what: str | Callable[[], str], log: Path) -> None:
    """Poll ``done()`` until true, or fail naming ``what`` with the launch's last lines."""
    deadline = time.monotonic() + timeout_s
    while not done():  # type: ignore[operator]
        if time.monotonic() >= deadline:
            said = what() if callable(what) else what
            raise AssertionError(f'{said}:\n{log.read_text()[-3000:]}')
        time.sleep(0.1)


# At a quarter speed: at half speed the stand wants 188 % of 2 cores (SCHED_FIFO), and the
# control path stalled a few times a minute beside 2 busy loops, the recovered arm falling
# meanwhile; with the estimator's start fixed (docs/hardware.md, "What the twin test stand
# shows") 3 runs of 3 quiet and 3 of 3 beside 2 busy loops held (2026-12-06), where at half
# speed 6 of 11 had.
#: One process per node with the twins apart: the test trips the arm with a second publisher
#: on command/actuators and watches /plant/joint_states. The robot loop (the default) takes
#: the arm's command from the allocator alone, by call, and the in-process twins publish no
#: /plant topics, so neither way in exists there.
LAYOUT = ('--compose', 'none', '--twins-apart')


def test_a_tripped_twin_arm_recovers_with_the_documented_commands(tmp_path: Path) -> None:
    """Trip, then reset-trip: the hold goes on for 10 s without a new trip."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p),
               PYTHONUNBUFFERED='1')
    log = tmp_path / 'launch.log'
    with log.open('w') as out:
        launch = subprocess.Popen(
            [sys.executable, '-m', 'uvms_cli.cli', 'launch', 'idle_wall', '--robot',
             'bluerov2_alpha5', '--hardware', 'twin', '--real-time-factor', '0.25', '--duration',
             '0', *LAYOUT], env=env, stdout=out, stderr=subprocess.STDOUT,
            stdin=subprocess.DEVNULL)
    probe = Probe()
    try:
        wait_for(lambda: launch.poll() is not None
                 or 'actuator commands to the plant' in log.read_text(), 180.0,
                 'physics never started', log)
        assert launch.poll() is None, f'the launch ended:\n{log.read_text()[-3000:]}'
        # Pushed until it trips: physics may start seconds after the plant takes the bridges'
        # commands (7.3 s of start-up at this speed), and a 0.5 s push ended before it in a
        # run of 2026-12-07, the arm never moving. The log is read every 50th push.
        end_s = time.monotonic() + 15.0
        pushes = 0
        while time.monotonic() < end_s and not (pushes % 50 == 0
                                                 and 'tripped:' in log.read_text()):
            probe.command.publish(ActuatorCommand(joint_names=JOINTS,
                                                  joint_torques=[0.0, 0.0, 3.0, 0.0]))
            pushes += 1
            time.sleep(0.002)
        wait_for(lambda: 'tripped:' in log.read_text(), 30.0, 'the arm did not trip', log)
        reset_s = time.monotonic()
        for _ in range(3):  # refused while a joint is over the trip speed: wait, ask again
            wait_for(lambda s=reset_s: probe.still(s), 120.0,
                     lambda: 'the tripped arm is not held still (last plant joint rates, '
                     f'rad/s: {probe.plant_states[-3:]})', log)
            cleared = uvms(env, 'hardware', 'reset-trip', '--timeout', '60')
            if cleared.returncode == 0:
                break
            assert 'wait until the arm is still' in cleared.stdout, cleared.stdout
            reset_s = time.monotonic()
        assert cleared.returncode == 0, cleared.stdout + cleared.stderr
        assert 'trip cleared' in cleared.stdout
        trips = log.read_text().count('alpha5_bridge]: tripped:')
        recovered_s = probe.node.get_clock().now().nanoseconds * 1e-9  # the graph's clock
        time.sleep(10.0)
        # Judged by the states' own stamps, 1 s (graph time) after the trip was cleared: this
        # busy process takes messages late, and a state of the trip once came after it.
        after = [v for t, v in probe.bridge_states if t >= recovered_s + 1.0]
        assert len(after) > 50, (f'{len(after)} joint states after the reset of '
                                  f'{len(probe.bridge_states)}; {cleared.stdout}\n'
                                  + log.read_text()[-4000:])
        text = log.read_text()
        assert text.count('alpha5_bridge]: tripped:') == trips, text[-3000:]
        fastest = max(abs(x) for v in after for x in v)
        assert fastest < TRIP_RAD_S, (fastest, text[-3000:])
    finally:
        probe.close()
        launch.send_signal(signal.SIGINT)
        try:
            launch.wait(timeout=60.0)
        except subprocess.TimeoutExpired:
            launch.kill()
    assert launch.returncode == 130, log.read_text()[-3000:]
