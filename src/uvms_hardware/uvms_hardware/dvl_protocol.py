"""Water Linked DVL A50/A125 JSON protocol over TCP: bytes in, velocity reports out. Pure.

Water Linked's "DVL protocol" (TCP, port 16171): newline-delimited JSON objects. A velocity
report has ``"type": "velocity"`` with ``vx, vy, vz`` (m/s, in the DVL's frame: x forward,
y right, z down as marked on the housing), ``fom`` (figure of merit, m/s: smaller is better),
``covariance`` (3x3, (m/s)^2), ``altitude`` (m), ``velocity_valid`` (bottom lock),
``time_of_validity`` (µs, Unix), ``status`` (0 normal). Dead-reckoning reports
(``"type": "position_local"``) and command responses are counted and ignored. A line that is
not a JSON object, or a velocity report missing a field, is counted as malformed and skipped::

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
        time_of_validity_us: When it was measured (µs, Unix), None when absent.
        status: 0 normal, else a fault flag.
    """

    v_m_s: tuple[float, float, float]
    fom: float
    covariance: tuple[float, ...] | None
    altitude_m: float
    valid: bool
    time_of_validity_us: int | None
    status: int


def _number(obj: dict[str, Any], key: str) -> float:
    value = obj.get(key)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ProtocolError(f'velocity report: {key!r} = {value!r} is not a number')
    return float(value)


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
    tov = obj.get('time_of_validity')
    return VelocityReport(
        (_number(obj, 'vx'), _number(obj, 'vy'), _number(obj, 'vz')), _number(obj, 'fom'),
        _covariance(obj.get('covariance')), _number(obj, 'altitude'), valid,
        int(tov) if isinstance(tov, (int, float)) and not isinstance(tov, bool) else None,
        int(obj.get('status', 0)) if isinstance(obj.get('status', 0), int) else -1)


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
            obj = json.loads(line)
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
