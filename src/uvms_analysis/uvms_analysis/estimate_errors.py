"""The estimator's errors against the truth in a recording: position, velocity, yaw (pure)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from uvms_recording.errors import RecordingError
from uvms_recording.mcap_reader import open_recording
from uvms_recording.typestore import uvms_typestore

TRUTH, ESTIMATE = '/uvms/odometry', '/uvms/odometry/filtered'


@dataclass(frozen=True)
class EstimateErrors:
    """Errors of /uvms/odometry/filtered against /uvms/odometry at the same stamps.

    Attributes:
        samples: Stamps present in both.
        position_rms_m, position_max_m: Norm of the position error in map_ned (m).
        horizontal_rms_m, horizontal_max_m: Its north-east part (m).
        vertical_rms_m, vertical_max_m: Its down part (m): without a position fix, the depth
            sensor's per-run bias.
        velocity_rms_m_s, velocity_max_m_s: Norm of the linear velocity error in
            base_link_frd (m/s).
        yaw_rms_deg, yaw_max_deg: Yaw error (deg).
        true_e_contact_max_m: Largest |e_y|, |e_z| in contact of the true end effector,
            X_d of controller/state against /uvms/ee_pose (m); the report's own e columns
            are the controller's view (X from the estimate). None without contact.
    """

    samples: int
    position_rms_m: float
    position_max_m: float
    horizontal_rms_m: float
    horizontal_max_m: float
    vertical_rms_m: float
    vertical_max_m: float
    velocity_rms_m_s: float
    velocity_max_m_s: float
    yaw_rms_deg: float
    yaw_max_deg: float
    true_e_contact_max_m: tuple[float, float] | None = None


def _yaw(q: object) -> float:
    x, y, z, w = (float(getattr(q, k)) for k in 'xyzw')
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def _by_stamp(path: Path) -> dict[str, dict[int, tuple[np.ndarray, np.ndarray, float]]]:
    typestore = uvms_typestore()
    out: dict[str, dict[int, tuple[np.ndarray, np.ndarray, float]]] = {TRUTH: {}, ESTIMATE: {}}
    for message in open_recording(path).messages([TRUTH, ESTIMATE]):
        msg = typestore.deserialize_cdr(message.data, 'nav_msgs/msg/Odometry')
        stamp = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
        p, v = msg.pose.pose.position, msg.twist.twist.linear
        out[message.topic][stamp] = (np.array([p.x, p.y, p.z]), np.array([v.x, v.y, v.z]),
                                     _yaw(msg.pose.pose.orientation))
    return out


def _true_errors_in_contact(path: Path) -> tuple[float, float] | None:
    """Largest |e_y|, |e_z| of X_d against the true end effector while in contact (m)."""
    typestore = uvms_typestore()
    wanted = ('/uvms/controller/state', '/uvms/ee_pose', '/uvms/contact')
    seen: dict[str, dict[int, object]] = {topic: {} for topic in wanted}
    for message in open_recording(path).messages(wanted):
        msg = typestore.deserialize_cdr(message.data, message.type_name)
        seen[message.topic][msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec] = msg
    state, ee, contact = (seen[t] for t in wanted)
    rows = [(np.array([state[t].desired_position.y, state[t].desired_position.z])
             - np.array([ee[t].pose.position.y, ee[t].pose.position.z]))
            for t in sorted(set(state) & set(ee) & set(contact)) if contact[t].penetration > 0]
    if not rows:
        return None
    worst = np.abs(np.array(rows)).max(axis=0)
    return float(worst[0]), float(worst[1])


def estimate_errors(path: str | Path) -> EstimateErrors | None:
    """The estimate's errors in a recording; None if it holds no estimate.

    Raises:
        RecordingError: The file cannot be read.
    """
    series = _by_stamp(Path(path))
    stamps = sorted(set(series[TRUTH]) & set(series[ESTIMATE]))
    if not stamps:
        return None
    truth = [series[TRUTH][t] for t in stamps]
    est = [series[ESTIMATE][t] for t in stamps]
    delta = np.array([a[0] - b[0] for a, b in zip(truth, est, strict=True)])
    dp = np.linalg.norm(delta, axis=1)
    dh = np.linalg.norm(delta[:, :2], axis=1)
    dz = np.abs(delta[:, 2])
    dv = np.array([np.linalg.norm(a[1] - b[1]) for a, b in zip(truth, est, strict=True)])
    dyaw = np.degrees([abs(math.remainder(a[2] - b[2], 2 * math.pi))
                       for a, b in zip(truth, est, strict=True)])
    return EstimateErrors(len(stamps), _rms(dp), float(dp.max()), _rms(dh), float(dh.max()),
                          _rms(dz), float(dz.max()), _rms(dv), float(dv.max()),
                          _rms(dyaw), float(dyaw.max()), _true_errors_in_contact(Path(path)))


def _pair_mm(pair: tuple[float, float] | None) -> str:
    return 'n/a' if pair is None else f'{pair[0] * 1e3:.1f}/{pair[1] * 1e3:.1f}'


def _rms(values: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(values))))


def format_estimate_errors(rows: list[tuple[str, EstimateErrors]]) -> str:
    """A text table, one row per recording with an estimate."""
    head = ('run', 'samples', 'pos RMS (mm)', 'pos max (mm)', 'horiz RMS/max (mm)',
            'down RMS/max (mm)', 'vel RMS (mm/s)', 'vel max (mm/s)', 'yaw RMS (deg)',
            'yaw max (deg)', 'true e_y/e_z contact max (mm)')
    lines = [' | '.join(head)]
    for name, e in rows:
        lines.append(' | '.join((name, str(e.samples), f'{e.position_rms_m * 1e3:.1f}',
                                 f'{e.position_max_m * 1e3:.1f}',
                                 f'{e.horizontal_rms_m * 1e3:.1f}/{e.horizontal_max_m * 1e3:.1f}',
                                 f'{e.vertical_rms_m * 1e3:.1f}/{e.vertical_max_m * 1e3:.1f}',
                                 f'{e.velocity_rms_m_s * 1e3:.1f}',
                                 f'{e.velocity_max_m_s * 1e3:.1f}', f'{e.yaw_rms_deg:.2f}',
                                 f'{e.yaw_max_deg:.2f}', _pair_mm(e.true_e_contact_max_m))))
    return '\n'.join(lines) + '\n'


__all__ = ['EstimateErrors', 'RecordingError', 'estimate_errors', 'format_estimate_errors']
