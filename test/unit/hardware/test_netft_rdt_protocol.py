"""ATI Net F/T RDT codec: requests, records, counts to wrench, lost records."""

from __future__ import annotations

import math
import struct

import pytest
from uvms_hardware.errors import ProtocolError

from uvms_hardware import rdt_protocol as rdt


def test_start_request_is_the_documented_eight_bytes() -> None:
    """Start real-time streaming, infinite samples: 12 34 00 02 00 00 00 00."""
    assert rdt.encode_request(rdt.COMMAND_START_REALTIME) == bytes.fromhex('1234000200000000')
    assert rdt.encode_request(rdt.COMMAND_STOP) == bytes.fromhex('1234000000000000')


def test_request_decodes_back() -> None:
    """A request with a sample count of 100 decodes to command and count."""
    assert rdt.decode_request(bytes.fromhex('1234000200000064')) == rdt.Request(2, 100)


def test_request_with_another_header_is_refused() -> None:
    """A header other than 0x1234 is a ProtocolError."""
    with pytest.raises(ProtocolError, match='header'):
        rdt.decode_request(bytes.fromhex('4321000200000000'))


def test_record_with_known_counts_gives_the_known_wrench() -> None:
    """Counts 1.5e6, -2e6, 0.25e6, 1e5, -3e5, 7 at 1e6 per unit are 1.5 N ... 7e-6 N m."""
    datagram = struct.pack('>III6i', 10, 20, 0, 1_500_000, -2_000_000, 250_000, 100_000,
                           -300_000, 7)
    record = rdt.decode_record(datagram)
    assert (record.rdt_sequence, record.ft_sequence, record.status) == (10, 20, 0)
    force, torque = rdt.wrench_from_counts(record.counts)
    assert force == pytest.approx((1.5, -2.0, 0.25))
    assert torque == pytest.approx((0.1, -0.3, 7e-6))


def test_calibration_divides_the_counts() -> None:
    """At 1e5 counts per N and 2e5 per N m the same counts give 10x and 5x."""
    force, torque = rdt.wrench_from_counts((1_000_000, 0, 0, 1_000_000, 0, 0), 1e5, 2e5)
    assert force[0] == pytest.approx(10.0) and torque[0] == pytest.approx(5.0)


@pytest.mark.parametrize('size', [0, 8, 35, 37, 72])
def test_short_or_long_datagram_is_a_protocol_error(size: int) -> None:
    """Only a 36-byte datagram is a record."""
    with pytest.raises(ProtocolError, match='36'):
        rdt.decode_record(bytes(size))


def test_record_round_trips() -> None:
    """encode_record then decode_record gives the record back."""
    record = rdt.Record(2**32 - 1, 5, 0x80000000, (1, -2, 3, -4, 5, -2**31))
    assert rdt.decode_record(rdt.encode_record(record)) == record


@pytest.mark.parametrize(('previous', 'current', 'lost'), [
    (None, 5, 0), (5, 6, 0), (5, 9, 3), (5, 5, 0), (9, 5, 0), (2**32 - 2, 1, 2)])
def test_lost_records_count_the_sequence_gaps(previous: int | None, current: int,
                                              lost: int) -> None:
    """A gap of n in rdt_sequence is n - 1 lost records; repeats and reorders lose none."""
    assert rdt.lost_records(previous, current) == lost


def test_extreme_int32_counts_decode_to_finite_wrenches() -> None:
    """Counts are int32 on the wire: the largest and smallest give finite forces and torques."""
    extreme = (2 ** 31 - 1, -2 ** 31, 2 ** 31 - 1, -2 ** 31, 0, 1)
    record = rdt.decode_record(rdt.encode_record(rdt.Record(1, 1, 0, extreme)))
    force, torque = rdt.wrench_from_counts(record.counts, 1e6, 1e6)
    assert all(math.isfinite(x) for x in (*force, *torque))
    assert force[0] == pytest.approx(2147.483647)


def test_counts_beyond_int32_cannot_be_encoded() -> None:
    """A count outside int32 is no record (the twin cannot send one by mistake)."""
    with pytest.raises(struct.error):
        rdt.encode_record(rdt.Record(1, 1, 0, (2 ** 31, 0, 0, 0, 0, 0)))


@pytest.mark.parametrize('calibration', [(math.inf, 1e6), (1e6, math.nan), (0.0, 1e6),
                                         (1e6, -1.0)])
def test_a_calibration_that_is_not_finite_and_positive_is_refused(
        calibration: tuple[float, float]) -> None:
    """Infinite counts per N would read every force as 0: refused like a negative one."""
    with pytest.raises(ProtocolError, match='finite and > 0'):
        rdt.wrench_from_counts((1, 2, 3, 4, 5, 6), *calibration)


def page(cpf: str = '1000000', cpt: str = '1000000', force_unit: str = 'N',
         torque_unit: str = 'N-m', extra: str = '<comrdtrate>500</comrdtrate>') -> str:
    """A netftapi2.xml page with the fields ATI's demo code reads."""
    return (f'<netft><setcfgsel>2</setcfgsel><cfgcpf>{cpf}</cfgcpf><cfgcpt>{cpt}</cfgcpt>'
            f'<scfgfu>{force_unit}</scfgfu><scfgtu>{torque_unit}</scfgtu>{extra}</netft>')


def test_the_boxs_page_gives_counts_per_n_and_per_n_m_and_its_rate() -> None:
    """cfgcpf, cfgcpt in N and N-m, comrdtrate: taken as they are; setcfgsel names the config."""
    calibration = rdt.calibration_from_netftapi2(page())
    assert calibration == rdt.BoxCalibration(1e6, 1e6, 500.0)
    assert rdt.active_configuration(page()) == 2


def test_other_units_are_converted_to_n_and_n_m() -> None:
    """A box set to lbf and lbf-in: counts per lbf / 4.448 N = counts per N (and per N m)."""
    calibration = rdt.calibration_from_netftapi2(page('4448', '1130', 'lbf', 'lbf-in'))
    assert calibration.counts_per_force == pytest.approx(4448 / 4.4482216152605)
    assert calibration.counts_per_torque == pytest.approx(1130 / 0.1129848290276167)
    n_mm = rdt.calibration_from_netftapi2(page(torque_unit='N-mm'))
    assert n_mm.counts_per_torque == pytest.approx(1e9)  # 1e6 per N mm is 1e9 per N m


@pytest.mark.parametrize(('text', 'named'), [
    (page(force_unit='stone'), 'scfgfu'), (page(cpf='0'), 'cfgcpf'),
    (page(cpt='NaN'), 'cfgcpt'), ('<netft><cfgcpf>1</cfgcpf></netft>', 'scfgfu'),
    ('<html>not a page', 'not XML')])
def test_a_page_that_does_not_give_the_calibration_is_refused(text: str, named: str) -> None:
    """A unit not known, a count not positive, a field missing, not XML: refused, named."""
    with pytest.raises(ProtocolError, match=named):
        rdt.calibration_from_netftapi2(text)


def test_a_page_without_a_rate_gives_none_for_it() -> None:
    """No comrdtrate on the page: the rate is not given (the hardware file must say it)."""
    assert rdt.calibration_from_netftapi2(page(extra='')).rdt_rate_hz is None
