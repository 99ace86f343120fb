"""`uvms doctor` reports the active runtime and checks every message type of the stack."""

from __future__ import annotations

import importlib.metadata
import io
import os
from pathlib import Path

import pytest

from uvms_cli import doctor


def test_doctor_reports_genuine_rclpy_rmw_and_profile(capsys: pytest.CaptureFixture[str]) -> None:
    """The report names the imported rclpy (path, version), the rmw and the DDS profile."""
    import rclpy

    assert doctor.main([]) == 0
    out = capsys.readouterr().out
    assert f'at {Path(rclpy.__file__).resolve().parent}' in out
    assert '  rclpy       7.1.6 at ' in out
    assert '  rmw         rmw_fastrtps_cpp' in out
    assert f'DDS profile {os.environ["FASTRTPS_DEFAULT_PROFILES_FILE"]}' in out
    assert f'rosbags     {importlib.metadata.version("rosbags")}' in out
    for typename in doctor.USED_MESSAGE_TYPES:
        assert f'ok   {typename}: ok (' in out
    assert out.rstrip().endswith('all good')


def test_doctor_reports_foxglove_sdk_and_ray_when_installed(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """foxglove-sdk (the live view) always, Ray (uvms sweep) only where it is installed."""
    doctor.main([])
    out = capsys.readouterr().out
    assert f'  foxglove-sdk {importlib.metadata.version("foxglove-sdk")}\n' in out
    try:
        ray_version = importlib.metadata.version('ray')
    except importlib.metadata.PackageNotFoundError:
        assert '  ray ' not in out
    else:
        assert f'  ray         {ray_version}\n' in out


def test_doctor_leaves_out_ray_when_it_is_not_installed(monkeypatch: pytest.MonkeyPatch) -> None:
    """Without Ray the report has no ray line and is still all good (Ray is optional)."""
    real_version = importlib.metadata.version

    def version(name: str) -> str:
        if name == 'ray':
            raise importlib.metadata.PackageNotFoundError(name)
        return real_version(name)

    monkeypatch.setattr(importlib.metadata, 'version', version)
    out = io.StringIO()
    ok = doctor.report(out, types=('sensor_msgs/msg/JointState',))
    assert ok
    assert '  ray ' not in out.getvalue()


def test_doctor_fails_when_a_message_type_does_not_load() -> None:
    """An unknown type is reported as FAIL and the report is not all good."""
    out = io.StringIO()
    ok = doctor.report(out, types=('sensor_msgs/msg/JointState', 'uvms_msgs/msg/Missing'))
    text = out.getvalue()
    assert not ok
    assert 'FAIL uvms_msgs/msg/Missing: AttributeError' in text
    assert text.rstrip().endswith('PROBLEMS FOUND (see above)')


def test_doctor_fails_when_a_round_trip_changes_the_message(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A serializer that loses data is caught by the round-trip comparison."""
    import rclpy.serialization

    def lossy_deserialize(data: bytes, cls: type) -> object:
        return cls()

    monkeypatch.setattr(rclpy.serialization, 'deserialize_message', lossy_deserialize)
    results, ok = doctor.check_messages(['sensor_msgs/msg/JointState'])
    assert not ok
    assert results == [('sensor_msgs/msg/JointState', 'round trip changed the message')]


def test_doctor_help_exits_cleanly() -> None:
    """`uvms doctor --help` prints usage and exits 0 (argparse)."""
    with pytest.raises(SystemExit) as exit_info:
        doctor.main(['--help'])
    assert exit_info.value.code == 0


def test_doctor_says_whether_real_time_scheduling_is_available() -> None:
    """A line from a child's try (granted, or the refusal) and one on the rt throttling."""
    from uvms_cli.doctor import realtime_lines
    from uvms_common.scheduling import fifo_refusal

    available, throttle = realtime_lines()
    if fifo_refusal(50):
        assert available.startswith('real time   NOT available: real-time scheduling refused')
    else:
        assert available.startswith('real time   available (SCHED_FIFO 50 granted')
    assert throttle.startswith('rt throttle ')
