"""Tests of uvms_hardware.dvl_protocol: Water Linked JSON lines in, velocity reports out."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from uvms_hardware.dvl_protocol import (
    DvlParser,
    report_in_link,
    rot_from_rpy,
    rot_link_from_dvl,
    velocity_report,
)
from uvms_hardware.errors import ProtocolError

#: A velocity report as Water Linked's protocol documentation shows one (json_v3.1).
EXAMPLE = {
    'time': 106.3, 'vx': -3.5e-05, 'vy': 5.1e-05, 'vz': 2.4e-05, 'fom': 0.0028,
    'covariance': [[2.6e-06, -3.1e-06, -1.2e-07], [-3.1e-06, 5.1e-06, -1.1e-07],
                   [-1.2e-07, -1.1e-07, 2.6e-07]],
    'altitude': 0.41, 'transducers': [], 'velocity_valid': True, 'status': 0,
    'format': 'json_v3.1', 'type': 'velocity', 'time_of_validity': 1638191471563017,
    'time_of_transmission': 1638191471752336}


def line(obj: dict[str, object]) -> bytes:
    """One newline-terminated JSON line."""
    return (json.dumps(obj) + '\n').encode()


def test_a_locked_report_decodes_every_field() -> None:
    """Velocity, fom, covariance, altitude, lock and time of validity come through."""
    (report,) = DvlParser().feed(line(EXAMPLE))
    assert report.v_m_s == (-3.5e-05, 5.1e-05, 2.4e-05)
    assert report.fom == 0.0028 and report.altitude_m == 0.41 and report.valid
    assert report.covariance is not None and report.covariance[1] == -3.1e-06
    assert report.time_of_validity_us == 1638191471563017 and report.status == 0


def test_a_report_without_lock_is_decoded_as_invalid() -> None:
    """velocity_valid false: a report, marked invalid (the bridge drops it)."""
    (report,) = DvlParser().feed(line({**EXAMPLE, 'velocity_valid': False, 'altitude': -1.0}))
    assert not report.valid and report.altitude_m == -1.0


def test_a_stream_split_anywhere_gives_the_same_reports() -> None:
    """Reports cut across chunks are put together from the line buffer."""
    data = line(EXAMPLE) * 3
    parser = DvlParser()
    reports = [r for i in range(0, len(data), 7) for r in parser.feed(data[i:i + 7])]
    assert len(reports) == 3 and parser.reports == 3 and parser.malformed == 0


def test_malformed_lines_are_counted_and_survived() -> None:
    """Broken JSON, a non-object and a report missing vx: counted; the next one decodes."""
    parser = DvlParser()
    bad = b'{"vx": 0.1, "type": "veloc\n[1, 2]\n' + line({**EXAMPLE, 'vx': None}) + b'\xff\xfe\n'
    reports = parser.feed(bad + line(EXAMPLE))
    assert len(reports) == 1 and parser.malformed == 4 and parser.reports == 1
    parser.feed(line({**EXAMPLE, 'vx': None}))
    assert "'vx' = None" in parser.last_error


def test_dead_reckoning_reports_are_ignored() -> None:
    """position_local reports are counted as ignored, not as velocity."""
    parser = DvlParser()
    assert parser.feed(line({'type': 'position_local', 'x': 1.0, 'ts': 3.0})) == []
    assert (parser.ignored, parser.reports, parser.malformed) == (1, 0, 0)


def test_a_missing_lock_flag_is_a_protocol_error() -> None:
    """velocity_valid must be a boolean: the error names it."""
    with pytest.raises(ProtocolError, match='velocity_valid'):
        velocity_report({k: v for k, v in EXAMPLE.items() if k != 'velocity_valid'})


def test_without_covariance_the_fom_squared_is_used() -> None:
    """No usable covariance: fom^2 on the diagonal."""
    report = velocity_report({**EXAMPLE, 'covariance': 'n/a'})
    _, cov = report_in_link(report, np.eye(3))
    np.testing.assert_allclose(cov, np.eye(3) * 0.0028 ** 2)


def test_a_dvl_turned_180_deg_reports_forward_motion_as_backward() -> None:
    """DVL yawed pi in base_link_frd, dvl_link aligned: vx of the DVL flips sign in dvl_link."""
    rot = rot_link_from_dvl([0.0, 0.0, math.pi], [0.0, 0.0, 0.0])
    report = velocity_report({**EXAMPLE, 'vx': 0.5, 'vy': 0.1, 'vz': 0.0})
    v, cov = report_in_link(report, rot)
    np.testing.assert_allclose(v, [-0.5, -0.1, 0.0], atol=1e-12)
    np.testing.assert_allclose(cov, cov.T, atol=1e-18)


@pytest.mark.parametrize('rpy', [(0.0, 0.0, 0.0), (0.3, -0.2, 1.4), (-1.0, 0.5, -3.0)])
def test_rotation_is_orthonormal(rpy: tuple[float, float, float]) -> None:
    """R^T R = I and det R = +1."""
    rot = rot_from_rpy(*rpy)
    np.testing.assert_allclose(rot.T @ rot, np.eye(3), atol=1e-12)
    assert np.linalg.det(rot) == pytest.approx(1.0)


@pytest.mark.parametrize('literal', [b'NaN', b'Infinity', b'-Infinity', b'1e999', b'-1e999'])
@pytest.mark.parametrize('field', ['vx', 'fom', 'altitude', 'time_of_validity'])
def test_a_number_that_is_not_finite_makes_the_line_malformed(field: str,
                                                              literal: bytes) -> None:
    """NaN, Infinity (Python's json reads them by default) or an overflow: malformed, dropped."""
    text = line({**EXAMPLE, field: 12345})
    bad = text.replace(f'"{field}": 12345'.encode(), f'"{field}": '.encode() + literal)
    parser = DvlParser()
    assert parser.feed(bad + line(EXAMPLE)) != [] and parser.malformed == 1
    assert parser.reports == 1 and 'finite' in parser.last_error


def test_a_non_finite_covariance_entry_makes_the_line_malformed() -> None:
    """A NaN anywhere in the report (here the covariance) drops the whole line."""
    bad = line(EXAMPLE).replace(b'2.6e-06', b'NaN', 1)
    parser = DvlParser()
    assert parser.feed(bad) == [] and parser.malformed == 1


@pytest.mark.parametrize('value', [math.nan, math.inf, 10 ** 400])
def test_a_report_built_from_non_finite_numbers_is_refused(value: float) -> None:
    """velocity_report itself refuses a non-finite or overflowing number, naming the field."""
    with pytest.raises(ProtocolError, match="'vy'"):
        velocity_report({**EXAMPLE, 'vy': value})


def test_time_of_transmission_is_decoded() -> None:
    """The DVL's send time comes through beside the time of validity (µs)."""
    (report,) = DvlParser().feed(line(EXAMPLE))
    assert report.time_of_transmission_us == 1638191471752336
