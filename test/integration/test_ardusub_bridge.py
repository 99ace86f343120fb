"""The ardusub_bridge node against the ArduSub twin: overrides, watchdog, restore, telemetry."""

from __future__ import annotations

import faulthandler
import math
import os
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import PoseWithCovarianceStamped
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.lifecycle import TransitionCallbackReturn
from rclpy.parameter import Parameter
from sensor_msgs.msg import BatteryState, Imu
from std_srvs.srv import Trigger
from uvms_hardware.ardusub_bridge_node import ArduSubBridgeNode
from uvms_hardware.t200_curve import robot_curve
from uvms_twins.ardusub_twin import ArduSubTwin

from uvms_msgs.msg import ActuatorCommand

REPO = Path(__file__).resolve().parents[2]
SOURCES = [REPO / 'src' / name for name in ('uvms_common', 'uvms_description', 'uvms_model',
                                             'uvms_hardware')]
ROBOT = 'bluerov2_alpha5'
MOTORS = [32.0 + n for n in range(1, 9)]
RCIN = [50.0 + n for n in range(1, 9)]


class Rig:
    """A twin, a probe node publishing commands and collecting topics, and the bridge."""

    def __init__(self, twin: ArduSubTwin) -> None:
        self.twin = twin
        self.context = Context()
        rclpy.init(args=[], context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.probe = rclpy.create_node('probe', namespace='uvms', context=self.context)
        self.executor.add_node(self.probe)
        self.command = self.probe.create_publisher(ActuatorCommand, 'command/actuators', 10)
        self.received: dict[str, list[Any]] = {}
        self.bridge: ArduSubBridgeNode | None = None
        self._last_publish_s = -math.inf

    def collect(self, topic: str, msg_type: Any) -> list[Any]:
        """Messages of a topic, in arrival order."""
        self.received[topic] = []
        self.probe.create_subscription(msg_type, topic, self.received[topic].append, 100)
        return self.received[topic]

    def start_bridge(self, **parameters: Any) -> ArduSubBridgeNode:
        """The bridge on the twin (heartbeat wait 3 s), with parameter overrides."""
        values = {'robot_name': ROBOT, 'mavlink_url': self.twin.url, 'heartbeat_timeout_s': 3.0,
                  **parameters}
        self.bridge = ArduSubBridgeNode(namespace='uvms', context=self.context,
                                        parameter_overrides=[Parameter(k, value=v)
                                                             for k, v in values.items()])
        self.executor.add_node(self.bridge)
        return self.bridge

    def spin_for(self, duration_s: float, each: Callable[[], None] | None = None) -> None:
        """Spin for a wall-clock duration, calling ``each`` every turn."""
        end = time.monotonic() + duration_s
        while time.monotonic() < end:
            if each is not None:
                each()
            self.executor.spin_once(timeout_sec=0.005)

    def spin_until(self, done: Callable[[], bool], timeout_s: float, what: str) -> float:
        """Spin until done(); the seconds it took (fails after the timeout)."""
        start = time.monotonic()
        while not done():
            assert time.monotonic() - start < timeout_s, f'timed out waiting for {what}'
            self.executor.spin_once(timeout_sec=0.002)
        return time.monotonic() - start

    def publish(self, thrusts: list[float]) -> None:
        """A command/actuators message at most every 5 ms (a 200 Hz controller)."""
        now_s = time.monotonic()
        if now_s - self._last_publish_s >= 0.005:
            self._last_publish_s = now_s
            self.command.publish(ActuatorCommand(thrust=thrusts))

    def close(self) -> None:
        """Destroy the nodes and the context."""
        if self.bridge is not None:
            self.executor.remove_node(self.bridge)
            self.bridge.destroy_node()
        self.executor.shutdown()
        self.probe.destroy_node()
        rclpy.try_shutdown(context=self.context)


@pytest.fixture(autouse=True)
def journal_dir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """Journals of original values go to the test's folder (and its bridge processes')."""
    monkeypatch.setenv('UVMS_JOURNAL_DIR', str(tmp_path))
    return tmp_path


@pytest.fixture
def rig() -> Iterator[Rig]:
    """A running twin and a rig around it."""
    with ArduSubTwin() as twin:
        made = Rig(twin)
        yield made
        faulthandler.dump_traceback_later(8.0)
        made.close()
        faulthandler.cancel_dump_traceback_later()


def functions(twin: ArduSubTwin) -> list[float]:
    """SERVO1..8_FUNCTION of the twin now."""
    return [twin.param(f'SERVO{n}_FUNCTION') for n in range(1, 9)]


THRUSTS = [10.0, -10.0, 0.0, 25.0, -5.0, 5.0, 1.0, -1.0]


def test_commands_become_overrides_at_50_hz_from_the_gcs_id(rig: Rig) -> None:
    """Decoded by pymavlink in the twin: system 255, our PWM on channels 1-8, >= 50 Hz."""
    bridge = rig.start_bridge()
    assert rig.twin.armed and functions(rig.twin) == RCIN
    rig.spin_for(1.5, lambda: rig.publish(THRUSTS))
    t_end = time.monotonic()
    records = [r for r in rig.twin.overrides() if t_end - 1.0 <= r.t_s <= t_end]
    assert len(records) >= 50, f'{len(records)} overrides in the last second'
    curve, voltage_v = robot_curve(), 16.0
    expected = tuple(round(curve.pwm_from_thrust(f, voltage_v)) for f in THRUSTS)
    last = records[-1]
    assert (last.src_system, last.obeyed) == (255, True)
    assert last.channels[:8] == expected and last.channels[8:] == (0,) * 10
    assert all(1100 <= pwm <= 1900 for pwm in last.channels[:8])
    assert rig.twin.servo_outputs_us()[:8] == list(expected)
    assert bridge.watchdog.trips == 0


def test_watchdog_puts_every_thruster_neutral_within_0_2_s(rig: Rig) -> None:
    """Commands stop: every thruster output is 1500 within 0.2 s and stays there."""
    rig.start_bridge()
    rig.spin_for(0.5, lambda: rig.publish([30.0] * 8))
    assert all(pwm > 1600 for pwm in rig.twin.servo_outputs_us()[:8])
    elapsed_s = rig.spin_until(lambda: rig.twin.servo_outputs_us()[:8] == [1500] * 8, 1.0,
                               'neutral outputs')
    assert elapsed_s <= 0.2
    rig.spin_for(0.5)
    assert rig.twin.servo_outputs_us()[:8] == [1500] * 8
    rig.spin_for(0.3, lambda: rig.publish([30.0] * 8))
    assert all(pwm > 1600 for pwm in rig.twin.servo_outputs_us()[:8])


def test_deactivate_puts_the_vehicle_back(rig: Rig) -> None:
    """Neutral, disarmed, SERVOn_FUNCTION 33..40 again, overrides released (0 on 1-8)."""
    bridge = rig.start_bridge()
    rig.spin_for(0.3, lambda: rig.publish(THRUSTS))
    assert bridge.trigger_deactivate() == TransitionCallbackReturn.SUCCESS
    assert functions(rig.twin) == MOTORS and not rig.twin.armed
    rig.spin_until(lambda: rig.twin.overrides()[-1].channels[:8] == (0,) * 8, 1.0,
                   'the release of channels 1-8')
    neutral = [r for r in rig.twin.overrides() if r.channels[:8] == (1500,) * 8]
    assert neutral, 'no neutral override before the release'
    assert rig.twin.servo_outputs_us()[:8] == [1500] * 8


def test_an_activate_that_raises_half_way_puts_everything_back(
        rig: Rig, journal_dir: Path) -> None:
    """Arm raises after passthrough was set: Motor1..8 again, disarmed, overrides released."""
    bridge = rig.start_bridge(autostart=False)
    assert bridge.trigger_configure() == TransitionCallbackReturn.SUCCESS
    assert bridge.link is not None
    link = bridge.link

    def arm_raises(armed: bool, end_s: float = math.inf) -> None:
        assert functions(rig.twin) == RCIN  # passthrough is on: this is half-way
        raise RuntimeError('arm failed half-way (injected)')

    link.arm = arm_raises  # type: ignore[method-assign]
    assert bridge.trigger_activate() != TransitionCallbackReturn.SUCCESS
    assert functions(rig.twin) == MOTORS and not rig.twin.armed
    rig.spin_until(lambda: rig.twin.overrides()[-1].channels[:8] == (0,) * 8, 1.0,
                   'the release of channels 1-8')
    assert not list(journal_dir.glob('*.json')), 'the journal outlived a complete restore'
    assert bridge.refusal.startswith('RuntimeError: arm failed half-way')


def test_gcs_id_mismatch_refuses_configure(rig: Rig) -> None:
    """gcs_system_id 254 against MAV_GCS_SYSID 255: configure fails, nothing changed."""
    bridge = rig.start_bridge(gcs_system_id=254, autostart=False)
    assert bridge.trigger_configure() == TransitionCallbackReturn.FAILURE
    assert functions(rig.twin) == MOTORS and not rig.twin.armed


def test_a_vehicle_that_never_answers_refuses_configure(rig: Rig) -> None:
    """No HEARTBEAT within heartbeat_timeout_s: configure fails."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.bind(('127.0.0.1', 0))
        port = sock.getsockname()[1]
    bridge = rig.start_bridge(mavlink_url=f'udpout:127.0.0.1:{port}', heartbeat_timeout_s=0.5,
                              autostart=False)
    assert bridge.trigger_configure() == TransitionCallbackReturn.FAILURE


def test_a_vehicle_that_stops_answering_is_an_error_on_diagnostics(rig: Rig) -> None:
    """The twin goes silent: /diagnostics says ERROR for the bridge's vehicle check."""
    statuses = rig.collect('/diagnostics', DiagnosticArray)
    rig.start_bridge(link_timeout_s=0.5)
    rig.twin.silent = True

    def error_seen() -> bool:
        return any(s.level == DiagnosticStatus.ERROR and 'vehicle silent' in s.message
                   for array in statuses for s in array.status)

    rig.spin_until(error_seen, 5.0, 'an ERROR status')


def test_telemetry_is_published_as_the_simulator_publishes_it(rig: Rig) -> None:
    """Imu in base_link_frd (FRD, -g on z), depth in map_ned (z down), battery in volts."""
    imu, depth = rig.collect('imu', Imu), rig.collect('depth', PoseWithCovarianceStamped)
    battery = rig.collect('battery', BatteryState)
    half = math.sqrt(0.5)
    rig.twin.set_plant_state(quaternion_wxyz=(half, 0.0, 0.0, half), rates_rad_s=(0.1, 0.0, 0.0),
                             depth_m=2.0, voltage_v=15.2)
    rig.start_bridge()
    rig.spin_until(lambda: bool(imu and depth and battery), 5.0, 'imu, depth and battery')
    msg = imu[-1]
    assert msg.header.frame_id == 'base_link_frd'
    assert (msg.orientation.w, msg.orientation.z) == pytest.approx((half, half), abs=1e-6)
    assert msg.linear_acceleration.z == pytest.approx(-9.80665, abs=0.01)
    assert msg.angular_velocity.x == pytest.approx(0.1, abs=1e-3)
    assert depth[-1].header.frame_id == 'map_ned'
    assert depth[-1].pose.pose.position.z == pytest.approx(2.0, abs=1e-3)
    assert depth[-1].pose.covariance[14] < 1.0 < depth[-1].pose.covariance[0]
    assert battery[-1].voltage == pytest.approx(15.2, abs=1e-3)


def test_zero_depth_takes_the_pressure_now_as_the_surface(rig: Rig) -> None:
    """~/zero_depth at 0.5 m of plant depth: depth reads 0 there and 0.5 m deeper reads 0.5."""
    depth = rig.collect('depth', PoseWithCovarianceStamped)
    rig.twin.set_plant_state(depth_m=0.5)
    rig.start_bridge()
    rig.spin_until(lambda: bool(depth), 5.0, 'depth')
    client = rig.probe.create_client(Trigger, 'ardusub_bridge/zero_depth')
    future = client.call_async(Trigger.Request())
    rig.spin_until(future.done, 5.0, 'the zero_depth answer')
    assert future.result().success, future.result().message
    rig.twin.set_plant_state(depth_m=1.0)
    depth.clear()
    rig.spin_until(lambda: bool(depth) and depth[-1].pose.pose.position.z > 0.4, 5.0,
                   'the deeper depth')
    assert depth[-1].pose.pose.position.z == pytest.approx(0.5, abs=1e-3)


def _bridge_process(twin: ArduSubTwin) -> subprocess.Popen[str]:
    env = dict(os.environ)
    env['PYTHONPATH'] = os.pathsep.join([*map(str, SOURCES), env.get('PYTHONPATH', '')])
    env['PYTHONUNBUFFERED'] = '1'
    code = 'from uvms_hardware.entry_points import ardusub_bridge; ardusub_bridge()'
    return subprocess.Popen(
        [sys.executable, '-c', code, '--ros-args', '-r', '__ns:=/uvms', '-p',
         f'mavlink_url:={twin.url}', '-p', 'heartbeat_timeout_s:=5.0', '-p',
         f'robot_name:={ROBOT}'],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)


@pytest.mark.parametrize('sig', [signal.SIGINT, signal.SIGTERM])
def test_a_signalled_bridge_process_puts_the_vehicle_back(sig: int) -> None:
    """SIGINT / SIGTERM of the console script: exit 0, disarmed, functions restored."""
    with ArduSubTwin() as twin:
        process = _bridge_process(twin)
        deadline = time.monotonic() + 30.0
        while not (twin.armed and functions(twin) == RCIN):
            assert process.poll() is None, process.communicate()[1]
            assert time.monotonic() < deadline, 'the bridge did not activate'
            time.sleep(0.05)
        time.sleep(0.3)
        process.send_signal(sig)
        try:
            _, err = process.communicate(timeout=20.0)
        except subprocess.TimeoutExpired:
            process.kill()
            pytest.fail(f'the bridge did not stop on {sig}: {process.communicate()[1]}')
        assert process.returncode == 0, err
        assert functions(twin) == MOTORS and not twin.armed, err
        assert twin.overrides()[-1].channels[:8] == (0,) * 8
        assert twin.servo_outputs_us()[:8] == [1500] * 8
