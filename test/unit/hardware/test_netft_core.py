"""The Net F/T bridge core: wrench in ft_sensor_link, bias, losses, staleness."""

from __future__ import annotations

import pytest
from uvms_hardware.netft_core import NetFtCore, check_rotation

from uvms_hardware import rdt_protocol as rdt

IDENTITY = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)


def datagram(sequence: int, counts: tuple[int, ...], status: int = 0) -> bytes:
    """A record's bytes."""
    return rdt.encode_record(rdt.Record(sequence, sequence, status, counts))  # type: ignore[arg-type]


def test_known_counts_give_the_known_wrench_with_identity_axes() -> None:
    """Counts (1e6, 2e6, -3e6, 5e5, 0, 1e5) are (1, 2, -3) N and (0.5, 0, 0.1) N m."""
    core = NetFtCore(rot_link_from_sensor=IDENTITY)
    force, torque = core.receive(datagram(1, (1_000_000, 2_000_000, -3_000_000, 500_000, 0,
                                              100_000)), 0.0) or ((), ())
    assert force == pytest.approx((1.0, 2.0, -3.0)) and torque == pytest.approx((0.5, 0.0, 0.1))


def test_default_axes_put_the_sensor_z_on_the_jaw_approach_x() -> None:
    """An axial push (sensor z) reads on ft_sensor_link x."""
    core = NetFtCore()
    force, _ = core.receive(datagram(1, (0, 0, 4_000_000, 0, 0, 0)), 0.0) or ((), ())
    assert force == pytest.approx((4.0, 0.0, 0.0))


def test_bias_zeroes_the_present_reading() -> None:
    """After bias the same counts read zero, and a change reads as the change."""
    core = NetFtCore(rot_link_from_sensor=IDENTITY)
    assert not core.bias()
    core.receive(datagram(1, (1_000_000, 0, 0, 0, 0, 0)), 0.0)
    assert core.bias()
    force, _ = core.receive(datagram(2, (1_500_000, 0, 0, 0, 0, 0)), 0.001) or ((), ())
    assert force == pytest.approx((0.5, 0.0, 0.0))


def test_lost_records_and_bad_datagrams_are_counted() -> None:
    """Sequences 1, 2, 6 lose 3; a 30-byte datagram is dropped and counted."""
    core = NetFtCore()
    for sequence in (1, 2, 6):
        core.receive(datagram(sequence, (0,) * 6), 0.0)
    assert core.receive(bytes(30), 0.0) is None
    assert (core.records, core.lost, core.bad_datagrams) == (3, 3, 1)
    assert core.report(0.0)[0] == 1


def test_stream_goes_stale_after_the_timeout() -> None:
    """No record for more than 0.1 s: stale, an ERROR report; a record ends it."""
    core = NetFtCore(timeout_s=0.1)
    core.receive(datagram(1, (0,) * 6), 1.0)
    assert not core.stale(1.05)
    assert core.stale(1.2) and core.report(1.2)[0] == 2
    core.receive(datagram(2, (0,) * 6), 1.3)
    assert not core.stale(1.31) and core.stale_episodes == 1


def test_status_word_set_is_an_error() -> None:
    """A record with a non-zero status makes the report an ERROR showing it."""
    core = NetFtCore()
    core.receive(datagram(1, (0,) * 6, status=0x80010000), 0.0)
    level, message, values = core.report(0.0)
    assert level == 2 and '0x80010000' in message and values['records_with_status_set'] == 1


@pytest.mark.parametrize('rot', [(1.0,) * 9, (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, -1.0),
                                 (1.0, 0.0)])
def test_improper_rotation_is_refused(rot: tuple[float, ...]) -> None:
    """Not orthonormal, a reflection, or not 9 values: ValueError."""
    with pytest.raises(ValueError, match='rot_link_from_sensor'):
        check_rotation(rot)


def test_an_infinite_calibration_is_refused_at_construction() -> None:
    """Counts per N of inf would silently read zero force: the core refuses it."""
    with pytest.raises(ValueError, match='finite'):
        NetFtCore(counts_per_force=float('inf'), counts_per_torque=1e6)
