"""A restart after a bridge that did not end cleanly: leftovers refused, restored by a command."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import rclpy
from rclpy.context import Context
from rclpy.lifecycle import TransitionCallbackReturn
from rclpy.parameter import Parameter
from uvms_bringup.processes import SIGTERM_TIMEOUT_S
from uvms_cli.hardware import main as hardware_main
from uvms_common.node_main import SPIN_TURN_S, TEARDOWN_GRACE_S
from uvms_hardware.ardusub_bridge_node import ArduSubBridgeNode
from uvms_hardware.ardusub_link import ArduSubLink, LinkSettings
from uvms_hardware.ardusub_restore import find_leftovers
from uvms_hardware.device_journal import DeviceJournal
from uvms_hardware.t200_curve import robot_curve
from uvms_twins.ardusub_twin import ArduSubTwin

REPO = Path(__file__).resolve().parents[2]
SOURCES = [REPO / 'src' / name for name in ('uvms_common', 'uvms_description', 'uvms_model',
                                             'uvms_hardware')]
ROBOT = 'bluerov2_alpha5'
MOTORS = [32.0 + n for n in range(1, 9)]
RCIN = [50.0 + n for n in range(1, 9)]
LEFT_IN_PASSTHROUGH = {f'SERVO{n}_FUNCTION': 50.0 + n for n in range(1, 9)}


def functions(twin: ArduSubTwin) -> list[float]:
    """SERVO1..8_FUNCTION of the twin now."""
    return [twin.param(f'SERVO{n}_FUNCTION') for n in range(1, 9)]


@contextlib.contextmanager
def bridge_node(url: str, journal_dir: Path) -> Iterator[ArduSubBridgeNode]:
    """An ardusub_bridge (not started) on ``url`` with its journal in ``journal_dir``."""
    context = Context()
    rclpy.init(args=[], context=context)
    values = {'robot_name': ROBOT, 'mavlink_url': url, 'heartbeat_timeout_s': 3.0,
              'autostart': False, 'journal_dir': str(journal_dir), 'script_wait_s': 0.0}
    node = ArduSubBridgeNode(namespace='uvms', context=context, parameter_overrides=[
        Parameter(k, value=v) for k, v in values.items()])
    try:
        yield node
    finally:
        node.destroy_node()
        rclpy.try_shutdown(context=context)


def restore(url: str, journal_dir: Path) -> int:
    """``uvms hardware restore ardusub --url URL --journal-dir DIR``."""
    return hardware_main(['restore', 'ardusub', '--url', url, '--journal-dir', str(journal_dir),
                          '--heartbeat-timeout', '3'])


def message_order(twin: ArduSubTwin) -> list[str]:
    """What the twin receives from now on: 'release', 'override', 'PARAM_SET', ... in order."""
    order: list[str] = []
    original = twin._handle

    def record(msg: Any, now_s: float) -> None:
        kind = msg.get_type()
        if kind == 'RC_CHANNELS_OVERRIDE':
            kind = 'release' if msg.chan1_raw == 0 else 'override'
        order.append(kind)
        original(msg, now_s)

    twin._handle = record  # type: ignore[method-assign]
    return order


def test_leftovers_with_a_journal_are_refused_and_restored_from_it(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """RCIN on outputs 1-8 and a journal: refused naming the command; it restores the journal."""
    with ArduSubTwin(parameters=LEFT_IN_PASSTHROUGH) as twin:
        journal = DeviceJournal.for_device('ardusub', twin.url, str(tmp_path))
        originals = {f'SERVO{n}_FUNCTION': 32.0 + n for n in range(1, 8)}
        originals['SERVO8_FUNCTION'] = 0.0  # an output the user had disabled
        journal.record(originals)
        with bridge_node(twin.url, tmp_path) as node:
            assert node.trigger_configure() == TransitionCallbackReturn.FAILURE
            refusal = node.refusal
        assert 'left in RC passthrough' in refusal
        assert 'SERVO1_FUNCTION = 51 (restore 33)' in refusal
        assert 'SERVO8_FUNCTION = 58 (restore 0)' in refusal
        assert f'from the journal {journal.path}' in refusal
        assert f'uvms hardware restore ardusub --url {twin.url}' in refusal
        assert functions(twin) == RCIN and not twin.state.param_sets  # refused: nothing changed
        order = message_order(twin)
        assert restore(twin.url, tmp_path) == 0, capsys.readouterr().out
        assert functions(twin) == [*MOTORS[:7], 0.0]
        assert not journal.path.exists()
        assert 'release' in order and 'PARAM_SET' in order
        assert order.index('release') < order.index('PARAM_SET'), order
        with bridge_node(twin.url, tmp_path) as node:
            assert node.trigger_configure() == TransitionCallbackReturn.SUCCESS


def test_leftovers_without_a_journal_restore_the_firmware_defaults(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """No journal: the refusal says the firmware defaults Motor1..8 will be restored."""
    with ArduSubTwin(parameters=LEFT_IN_PASSTHROUGH) as twin:
        with bridge_node(twin.url, tmp_path) as node:
            assert node.trigger_configure() == TransitionCallbackReturn.FAILURE
            refusal = node.refusal
        assert 'the firmware defaults Motor1..8 = 33..40 (no journal at' in refusal
        assert f'uvms hardware restore ardusub --url {twin.url}' in refusal
        assert restore(twin.url, tmp_path) == 0
        out = capsys.readouterr().out
        assert functions(twin) == MOTORS, out
        assert 'restored and read back' in out
        assert restore(twin.url, tmp_path) == 0
        assert 'nothing left changed' in capsys.readouterr().out


def _bridge_process(twin: ArduSubTwin, journal_dir: Path) -> subprocess.Popen[str]:
    env = dict(os.environ)
    env['PYTHONPATH'] = os.pathsep.join([*map(str, SOURCES), env.get('PYTHONPATH', '')])
    env['UVMS_JOURNAL_DIR'] = str(journal_dir)
    code = 'from uvms_hardware.entry_points import ardusub_bridge; ardusub_bridge()'
    return subprocess.Popen(
        [sys.executable, '-c', code, '--ros-args', '-r', '__ns:=/uvms', '-p',
         f'mavlink_url:={twin.url}', '-p', 'heartbeat_timeout_s:=5.0', '-p',
         f'robot_name:={ROBOT}', '-p', 'script_wait_s:=0.0'],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env)


def test_a_restart_after_a_sigkill_is_refused_and_the_restore_puts_motors_back(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """SIGKILL of an active passthrough bridge: RCIN and its journal stay; restore undoes both."""
    with ArduSubTwin() as twin:
        process = _bridge_process(twin, tmp_path)
        try:
            deadline = time.monotonic() + 30.0
            while not (twin.armed and functions(twin) == RCIN):
                assert process.poll() is None, process.communicate()[0]
                assert time.monotonic() < deadline, 'the bridge did not activate'
                time.sleep(0.05)
            time.sleep(0.2)
        finally:
            process.send_signal(signal.SIGKILL)
            process.communicate(timeout=10.0)
        assert functions(twin) == RCIN
        journals = list(tmp_path.glob('*.json'))
        assert len(journals) == 1, 'the journal of the original functions is missing'
        with bridge_node(twin.url, tmp_path) as node:
            assert node.trigger_configure() == TransitionCallbackReturn.FAILURE
            assert f'uvms hardware restore ardusub --url {twin.url}' in node.refusal
            assert 'from the journal' in node.refusal
        assert restore(twin.url, tmp_path) == 0, capsys.readouterr().out
        assert functions(twin) == MOTORS and not twin.armed
        assert not list(tmp_path.glob('*.json'))


@contextlib.contextmanager
def busy_loops(count: int) -> Iterator[None]:
    """``count`` processes spinning on a core each (a loaded machine)."""
    loops = [subprocess.Popen([sys.executable, '-c', 'while True: pass']) for _ in range(count)]
    try:
        yield
    finally:
        for loop in loops:
            loop.kill()
            loop.wait()


def test_the_restore_ends_within_its_budget_when_nothing_answers_under_load(
        tmp_path: Path) -> None:
    """Disarm and parameter sets never answered, 2 busy loops: done within 3 s (+0.3 s).

    The bridge's stop is SIGINT; the launcher sends SIGTERM after SIGTERM_TIMEOUT_S (5 s) and
    SIGKILL 5 s later: the restore budget plus the process's teardown must end before both.
    """
    with ArduSubTwin(parameters=LEFT_IN_PASSTHROUGH) as twin:
        original = twin._handle

        def deaf(msg: Any, now_s: float) -> None:
            if msg.get_type() not in ('PARAM_SET', 'COMMAND_LONG'):
                original(msg, now_s)

        twin._handle = deaf  # type: ignore[method-assign]
        link = ArduSubLink(LinkSettings(twin.url, tuple(range(1, 9))), robot_curve(),
                           journal=DeviceJournal.for_device('ardusub', twin.url, str(tmp_path)))
        link.open()
        link.wait_vehicle(3.0)
        leftovers = find_leftovers(link)
        assert leftovers is not None
        link.changed_functions = dict(leftovers.restore_to)
        with busy_loops(2):
            start = time.monotonic()
            problems = link.restore()
            elapsed_s = time.monotonic() - start
        link.close()
    budget_s = link.settings.restore_budget_s
    print(f'worst-case restore: {elapsed_s:.3f} s (budget {budget_s:g} s)')
    assert elapsed_s <= budget_s + 0.3
    assert budget_s + 0.3 + SPIN_TURN_S + TEARDOWN_GRACE_S < SIGTERM_TIMEOUT_S
    assert len(problems) == 8 and all('not read back' in p for p in problems)


def test_a_sigint_with_nothing_answering_exits_before_the_launchers_sigterm(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Deaf vehicle, 2 busy loops: SIGINT to exit < 5 s; the journal stays, restore undoes it."""
    with ArduSubTwin() as twin:
        process = _bridge_process(twin, tmp_path)
        try:
            deadline = time.monotonic() + 30.0
            while not (twin.armed and functions(twin) == RCIN):
                assert process.poll() is None, process.communicate()[0]
                assert time.monotonic() < deadline, 'the bridge did not activate'
                time.sleep(0.05)
            original = twin._handle

            def deaf(msg: Any, now_s: float) -> None:
                if msg.get_type() not in ('PARAM_SET', 'COMMAND_LONG'):
                    original(msg, now_s)

            twin._handle = deaf  # type: ignore[method-assign]
            with busy_loops(2):
                start = time.monotonic()
                process.send_signal(signal.SIGINT)
                output, _ = process.communicate(timeout=SIGTERM_TIMEOUT_S + 10.0)
                stopped_s = time.monotonic() - start
        finally:
            if process.poll() is None:
                process.kill()
                process.communicate()
        print(f'SIGINT to exit with nothing answering: {stopped_s:.2f} s')
        assert process.returncode == 0, output
        assert stopped_s < SIGTERM_TIMEOUT_S, output
        assert 'not read back' in output and len(list(tmp_path.glob('*.json'))) == 1
        twin._handle = original  # type: ignore[method-assign]
        assert restore(twin.url, tmp_path) == 0, capsys.readouterr().out
        assert functions(twin) == MOTORS and not list(tmp_path.glob('*.json'))
