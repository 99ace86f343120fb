"""uvms hardware check: every device of a hardware file found and described, nothing changed."""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import yaml
from uvms_cli.hardware import main
from uvms_hardware.hardware_config import load_alpha5
from uvms_twins.alpha5_twin import Alpha5Twin
from uvms_twins.ardusub_twin import ArduSubTwin
from uvms_twins.dvl_twin import DvlTwin
from uvms_twins.netft_twin import NetFtTwin

ROBOT = 'bluerov2_alpha5'


class Twins:
    """The four twins on ephemeral loopback ports and a hardware file naming them."""

    def __init__(self, directory: Path, gcs_id: int = 255,
                 ardusub_parameters: dict[str, float] | None = None) -> None:
        self.ardusub = ArduSubTwin(parameters={'MAV_GCS_SYSID': gcs_id,
                                               **(ardusub_parameters or {})}).start()
        self.dvl = DvlTwin(rate_hz=20.0).start()
        self.arm = Alpha5Twin(load_alpha5(ROBOT), port=0)
        self.arm.start()
        self.netft = NetFtTwin(port=0, rate_hz=100.0)
        self.netft.start()
        self.path = directory / 'pool.yaml'
        host, port = self.ardusub.address
        self.path.write_text(yaml.safe_dump({'twins': False, 'bridges': {
            'ardusub_bridge': {'mavlink_url': f'udpout:{host}:{port}'},
            'dvl_bridge': {'address': f'{self.dvl.address[0]}:{self.dvl.address[1]}'},
            'alpha5_bridge': {'connection': f'udp:127.0.0.1:{self.arm.port}'},
            'netft_bridge': {'address': f'127.0.0.1:{self.netft.port}'}}}))

    def stop(self) -> None:
        """Every twin stopped."""
        for twin in (self.ardusub, self.dvl, self.arm, self.netft):
            twin.stop()


@pytest.fixture
def twins(tmp_path: Path) -> Iterator[Twins]:
    """Twins of a healthy robot."""
    t = Twins(tmp_path)
    yield t
    t.stop()


def test_a_healthy_robot_checks_clean_and_nothing_is_changed(
        twins: Twins, capsys: pytest.CaptureFixture[str]) -> None:
    """Each device described; the vehicle as it was, and the Net F/T stream stopped again."""
    before = {name: twins.ardusub.param(name) for name in twins.ardusub.params}
    assert main(['check', str(twins.path)]) == 0
    out = capsys.readouterr().out
    assert 'ardusub: MAV_GCS_SYSID = 255: our RC overrides will be obeyed' in out
    assert 'ardusub: thruster outputs SERVOn_FUNCTION: 1=33, 2=34' in out
    assert 'dvl: 127.0.0.1' in out and 'bottom lock' in out
    assert out.count('limits as the URDF') == 4
    assert 'netft: 127.0.0.1' in out
    assert out.rstrip().endswith('0 problem(s); nothing was changed on any device')
    assert not twins.ardusub.armed and not twins.ardusub.overrides()
    assert {name: twins.ardusub.param(name) for name in before} == before
    deadline = time.monotonic() + 2.0  # the twin's thread takes the stop request in its turn
    while twins.netft.streaming and time.monotonic() < deadline:
        time.sleep(0.01)
    assert not twins.netft.streaming


def test_a_gcs_id_mismatch_and_a_silent_joint_are_named(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """What would stop the bridges is said, each with what to change; status 1."""
    twins = Twins(tmp_path, gcs_id=254)
    twins.arm.set_silent(0x02)
    try:
        assert main(['check', str(twins.path)]) == 1
    finally:
        twins.stop()
    out = capsys.readouterr().out
    assert 'GCS system id 254 (MAV_GCS_SYSID), ours is 255' in out
    assert 'alpha5: PROBLEM: joint_4 (device 0x02, B): silent' in out
    assert '2 problem(s)' in out


def test_thruster_outputs_left_in_passthrough_are_a_problem(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    """RCIN on outputs 1-8 (a bridge killed in passthrough): a PROBLEM naming the restore."""
    monkeypatch.setenv('UVMS_JOURNAL_DIR', str(tmp_path))
    twins = Twins(tmp_path, ardusub_parameters={f'SERVO{n}_FUNCTION': 50.0 + n
                                                for n in range(1, 9)})
    try:
        assert main(['check', str(twins.path)]) == 1
    finally:
        twins.stop()
    out = capsys.readouterr().out
    assert 'ardusub: PROBLEM: thruster outputs left in RC passthrough' in out
    assert 'SERVO1_FUNCTION = 51 (restore 33)' in out
    assert 'uvms hardware restore ardusub --url udpout:127.0.0.1:' in out
    assert '1 problem(s)' in out


def test_an_unknown_hardware_file_is_bad_usage(capsys: pytest.CaptureFixture[str]) -> None:
    """A typo in the file name: status 2 and the shipped files listed."""
    assert main(['check', 'pool']) == 2
    assert 'shipped: bluerov2_pool, twin, twin_alpha5_bus' in capsys.readouterr().err
