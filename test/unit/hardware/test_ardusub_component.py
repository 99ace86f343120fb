"""ArduSubComponent without ROS, against the ArduSub twin on 127.0.0.1: its contract."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from uvms_hardware.ardusub_component import SPECS, ArduSubComponent
from uvms_hardware.component import ERROR
from uvms_hardware.errors import DeviceCheckError
from uvms_hardware.t200_curve import robot_curve
from uvms_twins.ardusub_twin import ArduSubTwin

from uvms_hardware import bridge_messages as bm

NOISE = bm.ImuNoise(1e-4, 1e-3, (1e-3, 1e-3, 1e-2))


def settings(url: str, **changes: object) -> dict[str, object]:
    """The node's defaults on ``url`` (passthrough, no listening for the script)."""
    values: dict[str, object] = {spec.name: spec.default for spec in SPECS}
    values.update(mavlink_url=url, reply_timeout_s=0.3,
                  script_wait_s=0.0, autopilot_watchdog='passthrough')
    values.update(changes)
    return values


def run_until(sub: ArduSubComponent, done: Callable[[], bool], timeout_s: float = 3.0,
              thrusts_n: list[float] | None = None) -> int:
    """read() and write() every 10 ms until done(); the IMU samples given meanwhile."""
    samples = 0
    end = time.monotonic() + timeout_s
    while not done():
        assert time.monotonic() < end, 'timed out'
        now_s = time.monotonic()
        sub.read(now_s)
        samples += len(sub.state().imu)
        sub.write(now_s, thrusts_n)
        time.sleep(0.01)
    return samples


@pytest.fixture(autouse=True)
def journal_dir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """Journals of original values go to the test's folder, never the user's."""
    monkeypatch.setenv('UVMS_JOURNAL_DIR', str(tmp_path))
    return tmp_path


@pytest.fixture
def twin() -> Iterator[ArduSubTwin]:
    """An ArduSub twin on a free loopback port."""
    with ArduSubTwin() as running:
        yield running


@pytest.fixture
def sub(twin: ArduSubTwin) -> Iterator[ArduSubComponent]:
    """A configured, active component on the twin (passthrough); put back and released after."""
    made = ArduSubComponent(settings(twin.url), robot_curve(), NOISE, 1e-4,
                            log=lambda level, text: None)
    made.configure()
    made.activate()
    yield made
    made.put_back()
    made.release()


def test_telemetry_as_plain_data_each_sample_once(twin: ArduSubTwin,
                                                  sub: ArduSubComponent) -> None:
    """imu, depth and battery come out of read()/state() as numbers, fresh."""
    twin.set_plant_state(depth_m=2.0, voltage_v=15.5)
    depths: list[float] = []

    def seen() -> bool:
        depths.extend(d for _, d in sub.state().depth)
        return len(depths) >= 3 and sub.state().imu != ()

    run_until(sub, seen)
    assert depths[-1] == pytest.approx(2.0, abs=0.01)
    state = sub.state()
    assert state.fresh and twin.armed
    imu = state.imu[-1]
    assert len(imu.quaternion_wxyz) == 4 and len(imu.w_rad_s) == 3


def test_commands_drive_the_thrusters_and_the_watchdog_returns_them_to_neutral(
        twin: ArduSubTwin, sub: ArduSubComponent) -> None:
    """A command's PWM on the outputs; no new command for 0.1 s: 1500 on every thruster."""
    run_until(sub, lambda: twin.servo_outputs_us()[0] > 1550, thrusts_n=[20.0] * 8)
    run_until(sub, lambda: twin.servo_outputs_us()[:8] == [1500] * 8)
    assert sub.core.watchdog.trips >= 1
    assert sub.report(time.monotonic()).message == 'no command: thrusters neutral'


def test_a_silent_vehicle_returns_at_once_and_is_stale(twin: ArduSubTwin,
                                                      sub: ArduSubComponent,
                                                      no_waiting: Any) -> None:
    """The vehicle stops answering: read() and write() never wait; not fresh, ERROR."""
    run_until(sub, lambda: sub.state().fresh)
    twin.silent = True
    time.sleep(1.1)  # longer than link_timeout_s 1.0
    with no_waiting.check():  # no sleep, select or blocking receive (conftest.py)
        for _ in range(20):
            now_s = time.monotonic()
            sub.read(now_s)
            sub.write(now_s, [1.0] * 8)
    assert not sub.state().fresh
    report = sub.report(time.monotonic())
    assert report.level == ERROR and 'vehicle silent' in report.message


def test_a_bad_command_is_counted(sub: ArduSubComponent) -> None:
    """Seven thrusts for eight thrusters: refused, named, counted in the report."""
    assert sub.command([1.0] * 7, time.monotonic()) == '7 thrusts (expected 8 finite)'
    assert sub.report(time.monotonic()).values['rejected_commands'] == 1


def test_put_back_restores_the_outputs_and_disarms(twin: ArduSubTwin,
                                                  sub: ArduSubComponent) -> None:
    """Passthrough had changed SERVOn_FUNCTION: put_back sets them back, disarmed."""
    assert twin.param('SERVO1_FUNCTION') == 51.0  # RCIN1 while active
    assert sub.put_back() == []
    assert not twin.armed
    assert [twin.param(f'SERVO{n}_FUNCTION') for n in range(1, 9)] == [
        33.0 + n for n in range(8)]


def test_gcs_id_mismatch_is_refused(twin: ArduSubTwin) -> None:
    """Our system id is not the vehicle's GCS id: configure refused naming both."""
    sub = ArduSubComponent(settings(twin.url, gcs_system_id=200), robot_curve(), NOISE, 1e-4,
                           log=lambda level, text: None)
    with pytest.raises(DeviceCheckError, match='GCS system id 255'):
        sub.configure()
    sub.release()
    assert sub.link is None
