"""The thrusters stop without us: the autopilot's watchdog script against the ArduSub twin."""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.lifecycle import TransitionCallbackReturn
from rclpy.parameter import Parameter
from uvms_hardware.ardusub_bridge_node import ArduSubBridgeNode
from uvms_hardware.ardusub_watchdog import ScriptSettings
from uvms_twins.ardusub_twin import ArduSubTwin

from uvms_msgs.msg import ActuatorCommand

REPO = Path(__file__).resolve().parents[2]
SOURCES = [REPO / 'src' / name for name in ('uvms_common', 'uvms_description', 'uvms_model',
                                             'uvms_hardware')]
ROBOT = 'bluerov2_alpha5'
MOTORS = [32.0 + n for n in range(1, 9)]
NEUTRAL = [1500] * 8
#: The script's own timeout (read from it) and what the test allows on top (twin period, poll).
TIMEOUT_S = ScriptSettings.from_source().timeout_ms * 1e-3
MARGIN_S = 0.1


def functions(twin: ArduSubTwin) -> list[float]:
    """SERVO1..8_FUNCTION of the twin now."""
    return [twin.param(f'SERVO{n}_FUNCTION') for n in range(1, 9)]


class Graph:
    """A context with a probe publishing command/actuators, and optionally the bridge in it."""

    def __init__(self) -> None:
        self.context = Context()
        rclpy.init(args=[], context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.probe = rclpy.create_node('probe', namespace='uvms', context=self.context)
        self.executor.add_node(self.probe)
        self.command = self.probe.create_publisher(ActuatorCommand, 'command/actuators', 10)
        self.bridge: ArduSubBridgeNode | None = None
        self._last_publish_s = -math.inf

    def start_bridge(self, twin: ArduSubTwin, **parameters: Any) -> ArduSubBridgeNode:
        """The bridge in this process."""
        values = {'robot_name': ROBOT, 'mavlink_url': twin.url, 'heartbeat_timeout_s': 3.0,
                  **parameters}
        self.bridge = ArduSubBridgeNode(namespace='uvms', context=self.context,
                                        parameter_overrides=[Parameter(k, value=v)
                                                             for k, v in values.items()])
        self.executor.add_node(self.bridge)
        return self.bridge

    def publish(self, thrusts: list[float]) -> None:
        """A command at most every 5 ms (a 200 Hz controller)."""
        now_s = time.monotonic()
        if now_s - self._last_publish_s >= 0.005:
            self._last_publish_s = now_s
            self.command.publish(ActuatorCommand(thrust=thrusts))

    def spin_until(self, done: Callable[[], bool], timeout_s: float, what: str,
                   each: Callable[[], None] | None = None) -> float:
        """Spin (calling ``each``) until done(); the seconds it took (fails after timeout)."""
        start = time.monotonic()
        while not done():
            assert time.monotonic() - start < timeout_s, f'timed out waiting for {what}'
            if each is not None:
                each()
            self.executor.spin_once(timeout_sec=0.002)
        return time.monotonic() - start

    def close(self) -> None:
        """Destroy the nodes and the context."""
        if self.bridge is not None:
            self.executor.remove_node(self.bridge)
            self.bridge.destroy_node()
        self.executor.shutdown()
        self.probe.destroy_node()
        rclpy.try_shutdown(context=self.context)


@pytest.fixture
def graph(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Graph]:
    """A graph whose journals go to the test's folder."""
    monkeypatch.setenv('UVMS_JOURNAL_DIR', str(tmp_path))
    made = Graph()
    yield made
    made.close()


def _bridge_process(twin: ArduSubTwin, journal_dir: Path) -> subprocess.Popen[str]:
    env = dict(os.environ)
    env['PYTHONPATH'] = os.pathsep.join([*map(str, SOURCES), env.get('PYTHONPATH', '')])
    env['UVMS_JOURNAL_DIR'] = str(journal_dir)
    code = 'from uvms_hardware.entry_points import ardusub_bridge; ardusub_bridge()'
    return subprocess.Popen(
        [sys.executable, '-c', code, '--ros-args', '-r', '__ns:=/uvms', '-p',
         f'mavlink_url:={twin.url}', '-p', 'heartbeat_timeout_s:=5.0', '-p',
         f'robot_name:={ROBOT}'],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env)


def test_a_sigkilled_bridge_leaves_the_thrusters_neutral_within_the_script_timeout(
        graph: Graph, tmp_path: Path) -> None:
    """SIGKILL mid-command at 30 N: every thruster output at 1500 within 0.1 s (+0.1 s)."""
    with ArduSubTwin(watchdog_script=True) as twin:
        process = _bridge_process(twin, tmp_path)
        try:
            graph.spin_until(lambda: all(p > 1600 for p in twin.servo_outputs_us()[:8]), 40.0,
                             'thrust on every output', lambda: graph.publish([30.0] * 8))
            assert process.poll() is None
            end = time.monotonic() + 0.3
            while time.monotonic() < end:  # commands keep coming right up to the kill
                graph.publish([30.0] * 8)
                graph.executor.spin_once(timeout_sec=0.002)
            assert all(p > 1600 for p in twin.servo_outputs_us()[:8])
        finally:
            process.send_signal(signal.SIGKILL)
        killed_s = time.monotonic()
        while twin.servo_outputs_us()[:8] != NEUTRAL:
            assert time.monotonic() - killed_s < 5.0, 'the thrusters kept their last PWM'
            time.sleep(0.002)
        neutral_after_s = time.monotonic() - killed_s
        output, _ = process.communicate(timeout=10.0)
        print(f'neutral {neutral_after_s * 1e3:.0f} ms after the SIGKILL '
              f'(script timeout {TIMEOUT_S * 1e3:.0f} ms)')
        assert neutral_after_s <= TIMEOUT_S + MARGIN_S, output
        assert not twin.state.param_sets, 'script mode changed a parameter'
        assert functions(twin) == MOTORS
        assert twin.armed  # what the script does not need: ArduSub's GCS failsafe disarms


def test_script_mode_changes_nothing_and_drives_the_outputs(graph: Graph) -> None:
    """Script heard: no parameter set, pilot inputs neutral, PWMs on RC 9-16 with the toggle."""
    with ArduSubTwin(watchdog_script=True) as twin:
        bridge = graph.start_bridge(twin)
        assert bridge.link is not None and bridge.link.mode == 'script'
        graph.spin_until(lambda: all(p > 1600 for p in twin.servo_outputs_us()[:8]), 5.0,
                         'thrust on every output', lambda: graph.publish([30.0] * 8))
        records = twin.overrides()[-10:]
        assert all(r.channels[:8] == (1500,) * 6 + (65535,) * 2 for r in records)
        assert len({r.channels[8] % 2 for r in records}) == 2, 'no toggle on the wire'
        assert not twin.state.param_sets and functions(twin) == MOTORS
        assert bridge.trigger_deactivate() == TransitionCallbackReturn.SUCCESS
        assert not twin.armed
        graph.spin_until(lambda: twin.overrides()[-1].channels[:16] == (0,) * 6 + (
            65535,) * 2 + (65534,) * 8, 1.0, 'the release of RC 1-6 (0) and 9-16 (65534)')
        graph.spin_until(lambda: twin.servo_outputs_us()[:8] == NEUTRAL, TIMEOUT_S + MARGIN_S,
                         'neutral after the deactivate')


def test_the_outputs_return_to_their_motor_function_when_the_script_dies(
        graph: Graph) -> None:
    """The script stops (an error on the autopilot): its overrides expire, outputs neutral."""
    with ArduSubTwin(watchdog_script=True) as twin:
        graph.start_bridge(twin)
        graph.spin_until(lambda: all(p > 1600 for p in twin.servo_outputs_us()[:8]), 5.0,
                         'thrust on every output', lambda: graph.publish([30.0] * 8))
        twin.stop_script()
        elapsed_s = graph.spin_until(lambda: twin.servo_outputs_us()[:8] == NEUTRAL, 1.0,
                                     'the Motor function', lambda: graph.publish([30.0] * 8))
        assert elapsed_s <= TIMEOUT_S + MARGIN_S


def test_without_the_script_the_bridge_falls_back_to_passthrough(graph: Graph) -> None:
    """No announcement heard: passthrough mode (functions RCIN while active)."""
    with ArduSubTwin() as twin:
        bridge = graph.start_bridge(twin)
        assert bridge.link is not None and bridge.link.mode == 'passthrough'
        assert functions(twin) == [50.0 + n for n in range(1, 9)]


def test_a_required_script_that_is_missing_refuses_configure(graph: Graph) -> None:
    """autopilot_watchdog = script and no announcement: refused naming the script."""
    with ArduSubTwin() as twin:
        bridge = graph.start_bridge(twin, autostart=False, autopilot_watchdog='script',
                                    script_wait_s=0.5)
        assert bridge.trigger_configure() == TransitionCallbackReturn.FAILURE
        assert 'uvms_thruster_watchdog.lua not heard' in bridge.refusal
