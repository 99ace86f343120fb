"""A UVMS recording as numpy time series per topic (a Run), from its messages or its MCAP file.

Time base: every series is indexed by its messages' header stamps (simulated time in lockstep
runs), in seconds since the earliest stamp among the loaded topics, so ``t = 0`` is the start
of the recording and all topics share one clock. ``load_run(..., time_source='log')`` uses the
MCAP log times instead (for recordings whose publishers left the stamps empty).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import numpy.typing as npt
from uvms_recording.errors import RecordingError
from uvms_recording.mcap_reader import RecordedMessage, open_recording
from uvms_recording.mcap_writer import RUN_METADATA_NAME
from uvms_recording.typestore import uvms_typestore

from uvms_analysis.tasks import TOPIC_TASK_RECORD, TaskRecord, task_records
from uvms_analysis.thruster_health import HealthSeries, health_series

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

TOPIC_CONTROLLER_STATE = '/uvms/controller/state'
TOPIC_CONTACT = '/uvms/contact'
TOPIC_ODOMETRY = '/uvms/odometry'
TOPIC_EE_POSE = '/uvms/ee_pose'
TOPIC_THRUSTERS = '/uvms/thrusters/state'
TOPIC_OCEAN_CURRENT = '/uvms/ocean/current'
TOPIC_HEALTH = '/uvms/thrusters/health'

#: The topics that ``load_run`` turns into series.
ANALYSIS_TOPICS = (
    TOPIC_CONTROLLER_STATE,
    TOPIC_CONTACT,
    TOPIC_ODOMETRY,
    TOPIC_EE_POSE,
    TOPIC_THRUSTERS,
    TOPIC_OCEAN_CURRENT,
    TOPIC_TASK_RECORD,
    TOPIC_HEALTH,
)


class AnalysisError(Exception):
    """A recording cannot be read or lacks what an analysis needs."""


# --------------------------------------------------------------------------------------------
# Time series
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ControllerSeries:
    """ControllerState samples: task-space vectors (n, 3) in map_ned, scalars (n,).

    Attributes:
        t: Time (s).
        W: Fuzzy switching weight in [0, 1] (eq. 2).
        phase: Task phase (ControllerState.PHASE_*).
        F_e: Measured contact force exerted by the end effector (N).
        F_d: Desired contact force (N).
        X: End-effector position (m).
        X_d: Desired end-effector position (m).
        X_dot: End-effector velocity (m/s).
        X_dot_d: Desired end-effector velocity (m/s).
        v_e: End-effector velocity along the wall normal (m/s).
        F_c: Blended control force (N, eq. 2).
        F_IP: Impedance controller output (N, eq. 31).
        F_H: Hybrid position/force controller output (N, eq. 35).
    """

    t: FloatArray
    W: FloatArray
    phase: npt.NDArray[np.uint8]
    F_e: FloatArray
    F_d: FloatArray
    X: FloatArray
    X_d: FloatArray
    X_dot: FloatArray
    X_dot_d: FloatArray
    v_e: FloatArray
    F_c: FloatArray
    F_IP: FloatArray
    F_H: FloatArray


@dataclass(frozen=True)
class ContactSeries:
    """Ground-truth contact samples from the simulator.

    Attributes:
        t: Time (s).
        in_contact: True while the end effector penetrates the wall.
        force: Force exerted by the end effector on the wall (N), (n, 3) in map_ned.
        penetration: Penetration depth (m).
        wall_position: Wall surface position along map_ned x (m).
        wall_velocity: Wall speed along map_ned x (m/s).
    """

    t: FloatArray
    in_contact: BoolArray
    force: FloatArray
    penetration: FloatArray
    wall_position: FloatArray
    wall_velocity: FloatArray


@dataclass(frozen=True)
class OdometrySeries:
    """Vehicle odometry samples: pose in map_ned, twist in base_link_frd.

    Attributes:
        t: Time (s).
        position: Vehicle origin in map_ned (m), (n, 3).
        quaternion: Orientation of base_link_frd in map_ned, (n, 4) as (x, y, z, w).
        rpy: Roll, pitch, yaw (rad), ZYX Euler angles, (n, 3).
        linear_velocity: Body linear velocity (m/s), (n, 3).
        angular_velocity: Body angular rates (rad/s), (n, 3).
    """

    t: FloatArray
    position: FloatArray
    quaternion: FloatArray
    rpy: FloatArray
    linear_velocity: FloatArray
    angular_velocity: FloatArray


@dataclass(frozen=True)
class PoseSeries:
    """End-effector pose samples in map_ned.

    Attributes:
        t: Time (s).
        position: End-effector position (m), (n, 3).
        quaternion: Orientation of ee_link, (n, 4) as (x, y, z, w).
    """

    t: FloatArray
    position: FloatArray
    quaternion: FloatArray


@dataclass(frozen=True)
class ThrusterSeries:
    """ThrusterState samples, arrays (n, p) indexed by thruster (NaN where a sample lacks one).

    Attributes:
        t: Time (s).
        desired_thrust: Allocated thrust F_td,v (N, eq. 10).
        actual_thrust: Thrust produced by the thruster model (N, eq. 15).
        propeller_speed: Propeller angular velocity Ω (rad/s).
        reference_speed: Reference angular velocity Ω_r (rad/s, eq. 11).
        motor_current: Motor current i_m (A, eq. 12).
        saturation_scale: Factor by which the wrench was scaled to respect limits, (n,).
    """

    t: FloatArray
    desired_thrust: FloatArray
    actual_thrust: FloatArray
    propeller_speed: FloatArray
    reference_speed: FloatArray
    motor_current: FloatArray
    saturation_scale: FloatArray


@dataclass(frozen=True)
class CurrentSeries:
    """Ocean current samples: t (s) and the water's velocity in map_ned (m/s), (n, 3)."""

    t: FloatArray
    velocity: FloatArray


@dataclass(frozen=True)
class Run:
    """One recording as time series; a topic absent from the recording is None.

    Attributes:
        name: Run name: the 'scenario' of the recording's 'uvms' metadata, else the file stem.
        path: The recording file, if it came from one.
        controller: /uvms/controller/state.
        contact: /uvms/contact (ground truth).
        odometry: /uvms/odometry.
        ee_pose: /uvms/ee_pose.
        thrusters: /uvms/thrusters/state.
        current: /uvms/ocean/current (None in still water: nothing is published).
        tasks: /uvms/controller/task_record: the contact tasks that ran, in order of their end.
        metadata: The recording's metadata records, by record name.
        time_origin_ns: Stamp (or log time) of t = 0 (ns).
        problem: What was lost if the recording was cut short, else None.
    """

    name: str
    path: Path | None = None
    controller: ControllerSeries | None = None
    contact: ContactSeries | None = None
    odometry: OdometrySeries | None = None
    ee_pose: PoseSeries | None = None
    thrusters: ThrusterSeries | None = None
    current: CurrentSeries | None = None
    tasks: tuple[TaskRecord, ...] = ()
    health: HealthSeries | None = None  # thrusters/health (uvms_analysis.thruster_health)
    metadata: dict[str, dict[str, str]] = field(default_factory=dict)
    time_origin_ns: int = 0
    problem: str | None = None


# --------------------------------------------------------------------------------------------
# From messages to series
# --------------------------------------------------------------------------------------------


def quaternion_to_rpy(quaternion: FloatArray) -> FloatArray:
    """Roll, pitch, yaw (rad, ZYX Euler as the paper's J1) from quaternions (x, y, z, w).

    Example: a quarter turn about z, ``(0, 0, sin(π/4), cos(π/4))``, gives ``(0, 0, π/2)``.
    """
    q = np.asarray(quaternion, dtype=np.float64).reshape(-1, 4)
    x, y, z, w = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    roll = np.arctan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    pitch = np.arcsin(np.clip(2.0 * (w * y - z * x), -1.0, 1.0))
    yaw = np.arctan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    return np.stack([roll, pitch, yaw], axis=1)


def _stamp_ns(msg: Any) -> int:
    """Header stamp of a message (ns)."""
    stamp = msg.header.stamp
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def _vec3(msgs: Sequence[Any], name: str) -> FloatArray:
    """Stack a Vector3/Point field of every message into (n, 3)."""
    return _xyz(getattr(msg, name) for msg in msgs)


def _quat(quaternions: Iterable[Any]) -> FloatArray:
    """Stack Quaternion messages into (n, 4) as (x, y, z, w)."""
    return np.array([(q.x, q.y, q.z, q.w) for q in quaternions], dtype=np.float64).reshape(-1, 4)


def _scalars(msgs: Sequence[Any], name: str, dtype: type = np.float64) -> npt.NDArray[Any]:
    """One scalar field of every message as (n,)."""
    return np.array([getattr(msg, name) for msg in msgs], dtype=dtype)


def _ragged(msgs: Sequence[Any], name: str) -> FloatArray:
    """A float64[] field of every message as (n, p), NaN-padded to the longest array."""
    rows = [np.asarray(getattr(msg, name), dtype=np.float64) for msg in msgs]
    width = max((row.size for row in rows), default=0)
    out = np.full((len(rows), width), np.nan)
    for i, row in enumerate(rows):
        out[i, : row.size] = row
    return out


def controller_series(t: FloatArray, msgs: Sequence[Any]) -> ControllerSeries:
    """ControllerState messages (uvms_msgs/msg/ControllerState) as a series."""
    return ControllerSeries(
        t=t,
        W=_scalars(msgs, 'weight'),
        phase=_scalars(msgs, 'phase', np.uint8),
        F_e=_vec3(msgs, 'contact_force'),
        F_d=_vec3(msgs, 'desired_force'),
        X=_vec3(msgs, 'position'),
        X_d=_vec3(msgs, 'desired_position'),
        X_dot=_vec3(msgs, 'velocity'),
        X_dot_d=_vec3(msgs, 'desired_velocity'),
        v_e=_scalars(msgs, 'normal_velocity'),
        F_c=_vec3(msgs, 'command_force'),
        F_IP=_vec3(msgs, 'impedance_force'),
        F_H=_vec3(msgs, 'hybrid_force'),
    )


def contact_series(t: FloatArray, msgs: Sequence[Any]) -> ContactSeries:
    """ContactState messages (uvms_msgs/msg/ContactState) as a series."""
    return ContactSeries(
        t=t,
        in_contact=_scalars(msgs, 'in_contact', np.bool_),
        force=_vec3(msgs, 'force'),
        penetration=_scalars(msgs, 'penetration'),
        wall_position=_scalars(msgs, 'wall_position'),
        wall_velocity=_scalars(msgs, 'wall_velocity'),
    )


def _xyz(vectors: Iterable[Any]) -> FloatArray:
    """Stack objects with x, y, z fields (Point, Vector3) into (n, 3)."""
    return np.array([(v.x, v.y, v.z) for v in vectors], dtype=np.float64).reshape(-1, 3)


def odometry_series(t: FloatArray, msgs: Sequence[Any]) -> OdometrySeries:
    """Odometry messages (nav_msgs/msg/Odometry) as a series."""
    quaternion = _quat(msg.pose.pose.orientation for msg in msgs)
    return OdometrySeries(
        t=t,
        position=_xyz(msg.pose.pose.position for msg in msgs),
        quaternion=quaternion,
        rpy=quaternion_to_rpy(quaternion),
        linear_velocity=_xyz(msg.twist.twist.linear for msg in msgs),
        angular_velocity=_xyz(msg.twist.twist.angular for msg in msgs),
    )


def pose_series(t: FloatArray, msgs: Sequence[Any]) -> PoseSeries:
    """PoseStamped messages (geometry_msgs/msg/PoseStamped) as a series."""
    return PoseSeries(
        t=t,
        position=_xyz(msg.pose.position for msg in msgs),
        quaternion=_quat(msg.pose.orientation for msg in msgs),
    )


def thruster_series(t: FloatArray, msgs: Sequence[Any]) -> ThrusterSeries:
    """ThrusterState messages (uvms_msgs/msg/ThrusterState) as a series."""
    return ThrusterSeries(
        t=t,
        desired_thrust=_ragged(msgs, 'desired_thrust'),
        actual_thrust=_ragged(msgs, 'actual_thrust'),
        propeller_speed=_ragged(msgs, 'propeller_speed'),
        reference_speed=_ragged(msgs, 'reference_speed'),
        motor_current=_ragged(msgs, 'motor_current'),
        saturation_scale=_scalars(msgs, 'saturation_scale'),
    )


def current_series(t: FloatArray, msgs: Sequence[Any]) -> CurrentSeries:
    """TwistStamped messages of the ocean current (linear part, map_ned) as a series."""
    return CurrentSeries(t=t, velocity=_xyz(msg.twist.linear for msg in msgs))


_SERIES_BUILDERS = {
    TOPIC_CONTROLLER_STATE: ('controller', controller_series),
    TOPIC_CONTACT: ('contact', contact_series),
    TOPIC_ODOMETRY: ('odometry', odometry_series),
    TOPIC_EE_POSE: ('ee_pose', pose_series),
    TOPIC_THRUSTERS: ('thrusters', thruster_series),
    TOPIC_OCEAN_CURRENT: ('current', current_series),
    TOPIC_TASK_RECORD: ('tasks', task_records),
    TOPIC_HEALTH: ('health', health_series),
}


def run_from_messages(
    name: str,
    messages: Iterable[tuple[str, int, Any]],
    time_source: Literal['header', 'log'] = 'header',
    path: Path | None = None,
    metadata: dict[str, dict[str, str]] | None = None,
    problem: str | None = None,
) -> Run:
    """Build a Run from decoded messages ``(topic, log_time_ns, msg)`` of the analysis topics.

    Messages of other topics are ignored. Each topic is sorted by its time; t = 0 is the
    earliest time among the analysis topics.
    """
    per_topic: dict[str, list[tuple[int, Any]]] = {}
    for topic, log_time_ns, msg in messages:
        if topic in _SERIES_BUILDERS:
            time_ns = _stamp_ns(msg) if time_source == 'header' else int(log_time_ns)
            per_topic.setdefault(topic, []).append((time_ns, msg))
    origin_ns = min((min(ns for ns, _ in items) for items in per_topic.values()), default=0)
    series: dict[str, Any] = {}
    for topic, items in per_topic.items():
        items.sort(key=lambda item: item[0])
        offsets_ns = np.array([ns for ns, _ in items], dtype=np.int64) - origin_ns
        t = offsets_ns.astype(np.float64) * 1e-9
        attribute, builder = _SERIES_BUILDERS[topic]
        series[attribute] = builder(t, [msg for _, msg in items])
    return Run(
        name=name,
        path=path,
        metadata=dict(metadata or {}),
        time_origin_ns=origin_ns,
        problem=problem,
        **series,
    )


# --------------------------------------------------------------------------------------------
# Reading a recording
# --------------------------------------------------------------------------------------------


def run_name(path: Path, metadata: dict[str, dict[str, str]]) -> str:
    """Run name: the 'scenario' entry of the 'uvms' metadata record, else the file stem."""
    scenario = metadata.get(RUN_METADATA_NAME, {}).get('scenario', '').strip()
    return scenario or path.stem


def load_run(path: str | Path, time_source: Literal['header', 'log'] = 'header') -> Run:
    """Read a recording (MCAP, ros2 profile) into a Run of numpy series.

    A file cut short by a crash is read up to its last complete chunk; ``Run.problem`` then
    says what was lost.

    Args:
        path: The recording.
        time_source: 'header' (message header stamps, default) or 'log' (MCAP log times).

    Raises:
        AnalysisError: The file is missing, not a ROS 2 MCAP recording, damaged, or holds
            none of the analysis topics.
    """
    path = Path(path)
    if not path.is_file():
        raise AnalysisError(f'{path}: no such file')
    try:
        recording = open_recording(path)
        typestore = uvms_typestore()
        messages = [
            (message.topic, message.log_time_ns, _decode(typestore, message))
            for message in recording.messages(ANALYSIS_TOPICS)
        ]
    except RecordingError as exc:
        raise AnalysisError(str(exc)) from exc
    if not messages:
        topics = ', '.join(ANALYSIS_TOPICS)
        raise AnalysisError(f'{path}: the recording holds none of the topics {topics}')
    return run_from_messages(
        run_name(path, recording.metadata),
        messages,
        time_source=time_source,
        path=path,
        metadata=recording.metadata,
        problem=recording.problem,
    )


def _decode(typestore: Typestore, message: RecordedMessage) -> Any:
    """Deserialize one recorded message, naming topic and type if its bytes do not fit."""
    try:
        return typestore.deserialize_cdr(message.data, message.type_name)
    # rosbags raises assorted errors (struct, index, key, its own) on bytes that do not fit.
    except Exception as exc:
        raise RecordingError(
            f'a message on {message.topic} cannot be decoded as {message.type_name} ({exc})'
        ) from exc
