"""Water Linked DVL A50/A125 JSON protocol over TCP: bytes in, velocity reports out. Pure.

Water Linked's "DVL protocol" (TCP, port 16171): newline-delimited JSON objects. A velocity
report has ``"type": "velocity"`` with ``vx, vy, vz`` (m/s, in the DVL's frame: x forward,
y right, z down as marked on the housing), ``fom`` (figure of merit, m/s: smaller is better),
``covariance`` (3x3, (m/s)^2), ``altitude`` (m), ``velocity_valid`` (bottom lock),
``time_of_validity`` (µs, Unix: the centre of the ping) and ``time_of_transmission`` (µs,
Unix: just before the report was sent), ``status`` (0 normal); waterlinked/docs
docs/dvl/dvl-json-protocol.md. Dead-reckoning reports (``"type": "position_local"``) and
command responses are counted and ignored. A line that is not a JSON object, a velocity report
missing a field, and any line holding a number that is not finite (the ``NaN``, ``Infinity``
and ``-Infinity`` literals Python's json reads by default, or ``1e999``) are counted as
malformed and skipped: no non-finite number ever leaves the parser::

    parser = DvlParser()
    for report in parser.feed(chunk):      # any split of the stream
        v_link = rot_link_from_dvl @ report.v_m_s
    parser.malformed, parser.ignored        # counters for /diagnostics
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from uvms_hardware.errors import ProtocolError

FloatArray = npt.NDArray[np.float64]
#: A line longer than this without a newline is dropped as malformed (bytes).
MAX_LINE_BYTES = 65536


@dataclass(frozen=True)
class VelocityReport:
    """One velocity report of the DVL.

    Attributes:
        v_m_s: (vx, vy, vz) in the DVL's frame (m/s).
        fom: Figure of merit (m/s).
        covariance: Row-major 3x3 ((m/s)^2), or None when the report has none usable.
        altitude_m: Distance to the bottom (m).
        valid: Bottom lock: the velocity is valid.
        time_of_validity_us: When it was measured (µs, the DVL's clock: Unix once it is
            synchronised, else from an arbitrary epoch), None when absent.
        status: 0 normal, else a fault flag.
        time_of_transmission_us: When the DVL sent it (µs, the same clock), None when absent.
    """

    v_m_s: tuple[float, float, float]
    fom: float
    covariance: tuple[float, ...] | None
    altitude_m: float
    valid: bool
    time_of_validity_us: int | None
    status: int
    time_of_transmission_us: int | None = None


def _refuse_constant(name: str) -> Any:
    raise ValueError(f'{name} is not a finite number')


def _finite_float(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f'{text} is not a finite number')
    return value


def loads_finite(line: bytes | str) -> Any:
    """JSON of one line, refusing NaN, Infinity, -Infinity and floats that overflow.

    Raises:
        ValueError: Not JSON, or a number that is not finite.
    """
    return json.loads(line, parse_constant=_refuse_constant, parse_float=_finite_float)


def _timestamp_us(obj: dict[str, Any], key: str) -> int | None:
    value = obj.get(key)
    if value is None:
        return None
    if (isinstance(value, bool) or not isinstance(value, (int, float))
            or (isinstance(value, float) and not math.isfinite(value))):
        raise ProtocolError(f'velocity report: {key!r} = {value!r} is not a finite number')
    return int(value)


def _number(obj: dict[str, Any], key: str) -> float:
    value = obj.get(key)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ProtocolError(f'velocity report: {key!r} = {value!r} is not a number')
    try:
        number = float(value)
    except OverflowError:
        number = math.inf
    if not math.isfinite(number):
        raise ProtocolError(f'velocity report: {key!r} = {value!r} is not a finite number')
    return number


def _covariance(value: Any) -> tuple[float, ...] | None:
    try:
        flat = tuple(float(x) for row in value for x in row)
    except (TypeError, ValueError):
        return None
    return flat if len(flat) == 9 and all(math.isfinite(x) for x in flat) else None


def velocity_report(obj: dict[str, Any]) -> VelocityReport:
    """The report of a decoded ``"type": "velocity"`` object.

    Raises:
        ProtocolError: a field missing or not of its type, named.
    """
    valid = obj.get('velocity_valid')
    if not isinstance(valid, bool):
        raise ProtocolError(f'velocity report: velocity_valid = {valid!r} is not a boolean')
    return VelocityReport(
        (_number(obj, 'vx'), _number(obj, 'vy'), _number(obj, 'vz')), _number(obj, 'fom'),
        _covariance(obj.get('covariance')), _number(obj, 'altitude'), valid,
        _timestamp_us(obj, 'time_of_validity'),
        int(obj.get('status', 0)) if isinstance(obj.get('status', 0), int) else -1,
        _timestamp_us(obj, 'time_of_transmission'))


class DvlParser:
    """Splits the TCP stream into lines and decodes them; keeps counters."""

    def __init__(self) -> None:
        self._buffer = b''
        self.reports = 0
        self.malformed = 0
        self.ignored = 0
        self.last_error = ''

    def feed(self, data: bytes) -> list[VelocityReport]:
        """Velocity reports completed by ``data`` (a chunk of the stream, any split)."""
        self._buffer += data
        *lines, self._buffer = self._buffer.split(b'\n')
        if len(self._buffer) > MAX_LINE_BYTES:
            self._bad(f'a line of more than {MAX_LINE_BYTES} bytes without a newline')
            self._buffer = b''
        out = []
        for line in lines:
            report = self.line(line)
            if report is not None:
                out.append(report)
        return out

    def line(self, line: bytes) -> VelocityReport | None:
        """The report of one line; None for an ignored, empty or malformed one."""
        if not line.strip():
            return None
        try:
            obj = loads_finite(line)
        except (UnicodeDecodeError, ValueError) as exc:
            self._bad(f'not JSON: {exc}')
            return None
        if not isinstance(obj, dict):
            self._bad(f'not a JSON object: {line[:40]!r}')
            return None
        if obj.get('type') != 'velocity':
            self.ignored += 1
            return None
        try:
            report = velocity_report(obj)
        except ProtocolError as exc:
            self._bad(str(exc))
            return None
        self.reports += 1
        return report

    def _bad(self, why: str) -> None:
        self.malformed += 1
        self.last_error = why


def rot_from_rpy(roll: float, pitch: float, yaw: float) -> FloatArray:
    """R = Rz(yaw) Ry(pitch) Rx(roll): a frame's axes in its parent (ZYX, as uvms_model)."""
    cr, sr, cp, sp = math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def rot_link_from_dvl(dvl_rpy_rad: Sequence[float], link_rpy_rad: Sequence[float]
                      ) -> FloatArray:
    """Rotation from the DVL's own frame to dvl_link, both mountings given in base_link_frd."""
    result: FloatArray = rot_from_rpy(*link_rpy_rad).T @ rot_from_rpy(*dvl_rpy_rad)
    return result


def report_in_link(report: VelocityReport, rot: FloatArray) -> tuple[FloatArray, FloatArray]:
    """(velocity m/s, covariance 3x3 (m/s)^2) in dvl_link; fom^2 on the diagonal without one."""
    v = rot @ np.asarray(report.v_m_s, dtype=float)
    if report.covariance is not None:
        cov = np.asarray(report.covariance, dtype=float).reshape(3, 3)
    else:
        cov = np.eye(3) * report.fom ** 2
    cov_link: FloatArray = rot @ cov @ rot.T
    return v, cov_link
