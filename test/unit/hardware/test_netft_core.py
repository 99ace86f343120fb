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
    core = NetFtCore(1e6, 1e6, rot_link_from_sensor=IDENTITY)
    force, torque = core.receive(datagram(1, (1_000_000, 2_000_000, -3_000_000, 500_000, 0,
                                              100_000)), 0.0) or ((), ())
    assert force == pytest.approx((1.0, 2.0, -3.0)) and torque == pytest.approx((0.5, 0.0, 0.1))


def test_default_axes_put_the_sensor_z_on_the_jaw_approach_x() -> None:
    """An axial push (sensor z) reads on ft_sensor_link x."""
    core = NetFtCore(1e6, 1e6)
    force, _ = core.receive(datagram(1, (0, 0, 4_000_000, 0, 0, 0)), 0.0) or ((), ())
    assert force == pytest.approx((4.0, 0.0, 0.0))


def test_bias_zeroes_the_present_reading() -> None:
    """After bias the same counts read zero, and a change reads as the change."""
    core = NetFtCore(1e6, 1e6, rot_link_from_sensor=IDENTITY)
    assert not core.bias()
    core.receive(datagram(1, (1_000_000, 0, 0, 0, 0, 0)), 0.0)
    assert core.bias()
    force, _ = core.receive(datagram(2, (1_500_000, 0, 0, 0, 0, 0)), 0.001) or ((), ())
    assert force == pytest.approx((0.5, 0.0, 0.0))


def test_lost_records_and_bad_datagrams_are_counted() -> None:
    """Sequences 1, 2, 6 lose 3; a 30-byte datagram is dropped and counted."""
    core = NetFtCore(1e6, 1e6)
    for sequence in (1, 2, 6):
        core.receive(datagram(sequence, (0,) * 6), 0.0)
    assert core.receive(bytes(30), 0.0) is None
    assert (core.records, core.lost, core.bad_datagrams) == (3, 3, 1)
    assert core.report(0.0)[0] == 1


def test_stream_goes_stale_after_the_timeout() -> None:
    """No record for more than 0.1 s: stale, an ERROR report; a record ends it."""
    core = NetFtCore(1e6, 1e6, timeout_s=0.1)
    core.receive(datagram(1, (0,) * 6), 1.0)
    assert not core.stale(1.05)
    assert core.stale(1.2) and core.report(1.2)[0] == 2
    core.receive(datagram(2, (0,) * 6), 1.3)
    assert not core.stale(1.31) and core.stale_episodes == 1


def test_status_word_set_is_an_error() -> None:
    """A record with a non-zero status makes the report an ERROR showing it."""
    core = NetFtCore(1e6, 1e6)
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


def test_records_of_one_poll_are_stamped_one_period_apart() -> None:
    """Three records read at once at 500 Hz: 2 ms apart, the newest at the poll's time."""
    core = NetFtCore(1e6, 1e6, rot_link_from_sensor=IDENTITY, rdt_rate_hz=500.0)
    zero = (0, 0, 0, 0, 0, 0)
    samples = core.receive_all([datagram(s, zero) for s in (10, 11, 12)], 0.0, 100.0)
    stamps = [t for t, _ in samples]
    assert stamps[1] - stamps[0] == pytest.approx(0.002, abs=1e-9)
    assert stamps[2] - stamps[1] == pytest.approx(0.002, abs=1e-9)
    assert stamps[2] == pytest.approx(100.0, abs=1e-9)


def test_a_lost_record_advances_time_as_the_box_did() -> None:
    """Sequence 20 then 23 (21 and 22 lost): stamped 6 ms apart, two records counted lost."""
    core = NetFtCore(1e6, 1e6, rot_link_from_sensor=IDENTITY, rdt_rate_hz=500.0)
    zero = (0, 0, 0, 0, 0, 0)
    (first,) = core.receive_all([datagram(20, zero)], 0.0, 50.0)
    (second,) = core.receive_all([datagram(23, zero)], 0.006, 50.0061)
    assert second[0] - first[0] == pytest.approx(0.006, abs=1e-6) and core.lost == 2


def test_a_late_poll_keeps_the_records_stamps() -> None:
    """Records read 30 ms late are stamped when sampled, not when read."""
    core = NetFtCore(1e6, 1e6, rot_link_from_sensor=IDENTITY, rdt_rate_hz=1000.0)
    zero = (0, 0, 0, 0, 0, 0)
    for k in range(1, 200):  # timely polls: the offset is 10 s exactly
        core.receive_all([datagram(k, zero)], k * 0.001, 10.0 + k * 0.001)
    late = core.receive_all([datagram(k, zero) for k in range(200, 230)], 0.259, 10.259)
    assert [t for t, _ in late] == pytest.approx([10.0 + k * 0.001 for k in range(200, 230)],
                                                 abs=1e-6)


def test_a_new_stream_restarts_the_box_clock() -> None:
    """rdt_sequence back to 1 (a new start request): counted, the clock estimated again."""
    core = NetFtCore(1e6, 1e6, rot_link_from_sensor=IDENTITY, rdt_rate_hz=500.0)
    zero = (0, 0, 0, 0, 0, 0)
    core.receive_all([datagram(5000, zero)], 0.0, 100.0)
    ((stamp_s, _),) = core.receive_all([datagram(1, zero)], 1.0, 101.0)
    assert core.stream_restarts == 1 and core.lost == 0
    assert stamp_s == pytest.approx(101.0)


def test_without_a_rate_every_record_is_stamped_with_the_poll() -> None:
    """No rdt_rate_hz: the poll's time for each record (arrival stamps)."""
    core = NetFtCore(1e6, 1e6, rot_link_from_sensor=IDENTITY)
    zero = (0, 0, 0, 0, 0, 0)
    samples = core.receive_all([datagram(s, zero) for s in (1, 2)], 0.0, 7.0)
    assert [t for t, _ in samples] == [7.0, 7.0]


def test_a_wrong_rdt_rate_is_reported_and_stamps_fall_back_to_the_polls() -> None:
    """Records at 200 Hz taken for 500 Hz: WARN naming rdt_rate_hz, stamped at the poll."""
    core = NetFtCore(1e6, 1e6, rot_link_from_sensor=IDENTITY, rdt_rate_hz=500.0)
    zero = (0, 0, 0, 0, 0, 0)
    for k in range(1, 4000):  # 20 s at 200 Hz, 8 s of what it takes for the box's time
        samples = core.receive_all([datagram(k, zero)], k * 0.005, 3.0 + k * 0.005)
    level, message, values = core.report(3999 * 0.005)
    assert level == 1 and 'rdt_rate_hz 500' in message and values['clock_rates_agree'] is False
    assert samples[0][0] == pytest.approx(3.0 + 3999 * 0.005)


def test_arrival_stamps_take_out_the_phase_of_polls_in_step_with_the_box() -> None:
    """Polls at the box's 500 Hz, each 1.5 ms after a sample; records on the wire 0.05 ms.

    With each datagram's arrival (the kernel's stamp) the records are stamped 0.05 ms after
    they were sampled; with the polls' times alone, the phase stays in every stamp (1.5 ms),
    since no poll ever comes sooner after a record.
    """
    zero = (0, 0, 0, 0, 0, 0)
    period_s, phase_s, wire_s = 0.002, 0.0015, 0.00005
    errors: dict[str, float] = {}
    for kind in ('arrivals', 'polls'):
        core = NetFtCore(1e6, 1e6, rot_link_from_sensor=IDENTITY, rdt_rate_hz=500.0)
        for k in range(1, 3000):  # 6 s: the window full
            poll_s = 40.0 + k * period_s + phase_s
            ages = [phase_s - wire_s] if kind == 'arrivals' else None
            ((stamp_s, _),) = core.receive_all([datagram(k, zero)], poll_s, poll_s, ages)
        errors[kind] = stamp_s - (40.0 + k * period_s)
    assert errors['arrivals'] == pytest.approx(wire_s, abs=1e-6)
    assert errors['polls'] == pytest.approx(phase_s, abs=1e-6)


def test_the_earliest_arrival_of_a_poll_sets_the_box_clock() -> None:
    """A poll of three records, the middle one delayed least: its delay is the offset."""
    core = NetFtCore(1e6, 1e6, rot_link_from_sensor=IDENTITY, rdt_rate_hz=1000.0)
    zero = (0, 0, 0, 0, 0, 0)
    # Records 10, 11, 12 sampled at 0.010, 0.011, 0.012 on the box, arrived 3, 0.2, 1 ms later;
    # the poll at 20.02 (the box's 0 at 20.0 on ours).
    arrivals = [20.013, 20.0112, 20.013]
    ages = [20.02 - a for a in arrivals]
    stamps = [t for t, _ in core.receive_all([datagram(k, zero) for k in (10, 11, 12)],
                                             0.0, 20.02, ages)]
    assert stamps == pytest.approx([20.0102, 20.0112, 20.0122], abs=1e-9)
    with pytest.raises(ValueError, match='2 arrival ages for 3 datagrams'):
        core.receive_all([datagram(k, zero) for k in (13, 14, 15)], 0.0, 20.03, ages[:2])
