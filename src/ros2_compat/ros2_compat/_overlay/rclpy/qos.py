"""Quality of service profiles and policies (rclpy.qos), with rmw's preset values."""

from __future__ import annotations

import warnings
from enum import Enum, IntEnum
from typing import Any

from rclpy.duration import Duration

__all__ = [
    'DeadlineBestAvailable',
    'DurabilityPolicy',
    'HistoryPolicy',
    'InvalidQoSProfileException',
    'LivelinessLeaseDurationeBestAvailable',
    'LivelinessPolicy',
    'QoSCompatibility',
    'QoSDurabilityPolicy',
    'QoSHistoryPolicy',
    'QoSLivelinessPolicy',
    'QoSPolicyKind',
    'QoSPresetProfiles',
    'QoSProfile',
    'QoSReliabilityPolicy',
    'ReliabilityPolicy',
    'qos_check_compatible',
    'qos_policy_name_from_kind',
    'qos_profile_action_status_default',
    'qos_profile_best_available',
    'qos_profile_parameter_events',
    'qos_profile_parameters',
    'qos_profile_rosout_default',
    'qos_profile_sensor_data',
    'qos_profile_services_default',
    'qos_profile_system_default',
    'qos_profile_unknown',
]


class QoSPolicyKind(IntEnum):
    """Kinds of QoS policies (``rmw_qos_policy_kind_t``)."""

    INVALID = 1 << 0
    DURABILITY = 1 << 1
    DEADLINE = 1 << 2
    LIVELINESS = 1 << 3
    RELIABILITY = 1 << 4
    HISTORY = 1 << 5
    LIFESPAN = 1 << 6
    DEPTH = 1 << 7
    LIVELINESS_LEASE_DURATION = 1 << 8
    AVOID_ROS_NAMESPACE_CONVENTIONS = 1 << 9


def qos_policy_name_from_kind(policy_kind: QoSPolicyKind | int) -> str:
    """Return the name of a QoS policy kind."""
    return QoSPolicyKind(policy_kind).name


class InvalidQoSProfileException(Exception):  # noqa: N818 (rclpy's name)
    """Raised when constructing a QoSProfile with invalid arguments."""

    def __init__(self, *args: object) -> None:
        super().__init__('Invalid QoSProfile', *args)


class QoSPolicyEnum(IntEnum):
    """Base of the QoS policy enumerations, with short-key helpers."""

    @classmethod
    def short_keys(cls) -> list[str]:
        """Return the lower-case names of the policy values."""
        return [k.lower() for k in cls.__members__]

    @classmethod
    def get_from_short_key(cls, name: str) -> int:
        """Return the value named ``name`` (case-insensitive)."""
        return cls[name.upper()].value

    @property
    def short_key(self) -> str:
        """Lower-case name of this value."""
        return self.name.lower()


class HistoryPolicy(QoSPolicyEnum):
    """History: keep the last ``depth`` samples, or all of them."""

    SYSTEM_DEFAULT = 0
    KEEP_LAST = 1
    KEEP_ALL = 2
    UNKNOWN = 3


class ReliabilityPolicy(QoSPolicyEnum):
    """Reliability: guaranteed delivery (RELIABLE) or best effort."""

    SYSTEM_DEFAULT = 0
    RELIABLE = 1
    BEST_EFFORT = 2
    UNKNOWN = 3
    BEST_AVAILABLE = 4


class DurabilityPolicy(QoSPolicyEnum):
    """Durability: whether late-joining subscriptions get samples published before they joined."""

    SYSTEM_DEFAULT = 0
    TRANSIENT_LOCAL = 1
    VOLATILE = 2
    UNKNOWN = 3
    BEST_AVAILABLE = 4


class LivelinessPolicy(QoSPolicyEnum):
    """Liveliness: how a publisher asserts that it is alive."""

    SYSTEM_DEFAULT = 0
    AUTOMATIC = 1
    MANUAL_BY_TOPIC = 3
    UNKNOWN = 4
    BEST_AVAILABLE = 5


QoSHistoryPolicy = HistoryPolicy
QoSReliabilityPolicy = ReliabilityPolicy
QoSDurabilityPolicy = DurabilityPolicy
QoSLivelinessPolicy = LivelinessPolicy

#: Deadline that matches the majority of endpoints (``RMW_QOS_DEADLINE_BEST_AVAILABLE``).
DeadlineBestAvailable = Duration(nanoseconds=2**63 - 2)
#: Lease duration matching most endpoints (``RMW_QOS_LIVELINESS_LEASE_DURATION_BEST_AVAILABLE``).
LivelinessLeaseDurationeBestAvailable = Duration(nanoseconds=2**63 - 2)

_DEFAULTS: dict[str, Any] = {
    'depth': 10,
    'reliability': ReliabilityPolicy.RELIABLE,
    'durability': DurabilityPolicy.VOLATILE,
    'lifespan': Duration(),
    'deadline': Duration(),
    'liveliness': LivelinessPolicy.SYSTEM_DEFAULT,
    'liveliness_lease_duration': Duration(),
    'avoid_ros_namespace_conventions': False,
}


class QoSProfile:
    """A set of QoS policies for a publisher or subscription.

    ``QoSProfile(depth=10)`` means KEEP_LAST with depth 10; unspecified policies take rmw's
    default profile (RELIABLE, VOLATILE).

    Raises:
        InvalidQoSProfileException: If neither history nor depth is given, or KEEP_LAST lacks a
            depth.
    """

    __slots__ = [
        '_avoid_ros_namespace_conventions',
        '_deadline',
        '_depth',
        '_durability',
        '_history',
        '_lifespan',
        '_liveliness',
        '_liveliness_lease_duration',
        '_reliability',
    ]

    def __init__(self, **kwargs: Any) -> None:
        unknown = [key for key in kwargs if '_' + key not in self.__slots__]
        if unknown:
            raise AssertionError(f'Invalid arguments passed to constructor: {unknown!r}')
        if 'history' not in kwargs:
            if 'depth' not in kwargs:
                raise InvalidQoSProfileException('History and/or depth settings are required.')
            kwargs['history'] = HistoryPolicy.KEEP_LAST
        self.history = kwargs['history']
        if self.history == HistoryPolicy.KEEP_LAST and 'depth' not in kwargs:
            raise InvalidQoSProfileException('History set to KEEP_LAST without a depth setting.')
        for key, default in _DEFAULTS.items():
            setattr(self, key, kwargs.get(key, default))

    @property
    def history(self) -> HistoryPolicy:
        """History policy."""
        return self._history

    @history.setter
    def history(self, value: HistoryPolicy | int) -> None:
        assert isinstance(value, int), f'history must be a HistoryPolicy, got {value!r}'
        self._history = HistoryPolicy(value)

    @property
    def reliability(self) -> ReliabilityPolicy:
        """Reliability policy."""
        return self._reliability

    @reliability.setter
    def reliability(self, value: ReliabilityPolicy | int) -> None:
        assert isinstance(value, int), f'reliability must be a ReliabilityPolicy, got {value!r}'
        self._reliability = ReliabilityPolicy(value)

    @property
    def durability(self) -> DurabilityPolicy:
        """Durability policy."""
        return self._durability

    @durability.setter
    def durability(self, value: DurabilityPolicy | int) -> None:
        assert isinstance(value, int), f'durability must be a DurabilityPolicy, got {value!r}'
        self._durability = DurabilityPolicy(value)

    @property
    def depth(self) -> int:
        """History depth (samples kept with KEEP_LAST)."""
        return self._depth

    @depth.setter
    def depth(self, value: int) -> None:
        assert isinstance(value, int), f'depth must be an int, got {value!r}'
        if self.history == HistoryPolicy.KEEP_LAST and value == 0:
            warnings.warn(
                "A zero depth with KEEP_LAST doesn't make sense; no data could be stored. "
                'This will be interpreted as SYSTEM_DEFAULT',
                stacklevel=2,
            )
        self._depth = value

    @property
    def lifespan(self) -> Duration:
        """Lifespan of samples (zero: default)."""
        return self._lifespan

    @lifespan.setter
    def lifespan(self, value: Duration) -> None:
        assert isinstance(value, Duration), f'lifespan must be a Duration, got {value!r}'
        self._lifespan = value

    @property
    def deadline(self) -> Duration:
        """Deadline period (zero: default)."""
        return self._deadline

    @deadline.setter
    def deadline(self, value: Duration) -> None:
        assert isinstance(value, Duration), f'deadline must be a Duration, got {value!r}'
        self._deadline = value

    @property
    def liveliness(self) -> LivelinessPolicy:
        """Liveliness policy."""
        return self._liveliness

    @liveliness.setter
    def liveliness(self, value: LivelinessPolicy | int) -> None:
        assert isinstance(value, int), f'liveliness must be a LivelinessPolicy, got {value!r}'
        self._liveliness = LivelinessPolicy(value)

    @property
    def liveliness_lease_duration(self) -> Duration:
        """Liveliness lease duration (zero: default)."""
        return self._liveliness_lease_duration

    @liveliness_lease_duration.setter
    def liveliness_lease_duration(self, value: Duration) -> None:
        assert isinstance(value, Duration), f'lease duration must be a Duration, got {value!r}'
        self._liveliness_lease_duration = value

    @property
    def avoid_ros_namespace_conventions(self) -> bool:
        """Whether topic names skip the ROS namespace conventions."""
        return self._avoid_ros_namespace_conventions

    @avoid_ros_namespace_conventions.setter
    def avoid_ros_namespace_conventions(self, value: bool) -> None:
        assert isinstance(value, bool), f'avoid_ros_namespace_conventions must be bool: {value!r}'
        self._avoid_ros_namespace_conventions = value

    def get_c_qos_profile(self) -> QoSProfile:
        """Return the profile (rclpy returns its C struct here)."""
        return self

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, QoSProfile):
            return False
        return all(getattr(self, slot) == getattr(other, slot) for slot in self.__slots__)

    __hash__ = None  # type: ignore[assignment]

    def __str__(self) -> str:
        fields = ', '.join(f'{slot[1:]}={getattr(self, slot)}' for slot in self.__slots__)
        return f'{type(self).__name__}({fields})'

    __repr__ = __str__

    def _keep(self) -> int | None:
        """Samples a queue of this profile keeps (None: unbounded)."""
        if self._history == HistoryPolicy.KEEP_ALL:
            return None
        if self._history == HistoryPolicy.KEEP_LAST:
            return max(self._depth, 1)
        return max(self._depth, 1) if self._depth else 1


def _profile(**kwargs: Any) -> QoSProfile:
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')
        return QoSProfile(**kwargs)


#: Used for initialization; not to be used as an actual profile.
qos_profile_unknown = _profile(
    history=HistoryPolicy.UNKNOWN, depth=0, reliability=ReliabilityPolicy.UNKNOWN,
    durability=DurabilityPolicy.UNKNOWN, liveliness=LivelinessPolicy.UNKNOWN)
#: The settings of the middleware (DDS vendor defaults).
qos_profile_system_default = _profile(
    history=HistoryPolicy.SYSTEM_DEFAULT, depth=0,
    reliability=ReliabilityPolicy.SYSTEM_DEFAULT, durability=DurabilityPolicy.SYSTEM_DEFAULT)
#: For sensor data: best effort and a small queue.
qos_profile_sensor_data = _profile(
    history=HistoryPolicy.KEEP_LAST, depth=5, reliability=ReliabilityPolicy.BEST_EFFORT,
    durability=DurabilityPolicy.VOLATILE)
#: For services: reliable and volatile.
qos_profile_services_default = _profile(
    history=HistoryPolicy.KEEP_LAST, depth=10, reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE)
#: For parameter services: like services, with a deeper queue.
qos_profile_parameters = _profile(
    history=HistoryPolicy.KEEP_LAST, depth=1000, reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE)
#: For parameter events.
qos_profile_parameter_events = _profile(
    history=HistoryPolicy.KEEP_LAST, depth=1000, reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE)
#: Matches the majority of endpoints while keeping the highest level of service.
qos_profile_best_available = _profile(
    history=HistoryPolicy.KEEP_LAST, depth=10, reliability=ReliabilityPolicy.BEST_AVAILABLE,
    durability=DurabilityPolicy.BEST_AVAILABLE, deadline=DeadlineBestAvailable,
    liveliness=LivelinessPolicy.BEST_AVAILABLE,
    liveliness_lease_duration=LivelinessLeaseDurationeBestAvailable)
#: For action status: reliable and transient-local.
qos_profile_action_status_default = _profile(
    history=HistoryPolicy.KEEP_LAST, depth=1, reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL)
#: For /rosout (``rcl_qos_profile_rosout_default``).
qos_profile_rosout_default = _profile(
    history=HistoryPolicy.KEEP_LAST, depth=1000, reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL, lifespan=Duration(seconds=10))
_qos_profile_default = _profile(depth=10)


class QoSPresetProfiles(Enum):
    """The preset profiles by name."""

    UNKNOWN = qos_profile_unknown
    DEFAULT = _qos_profile_default
    SYSTEM_DEFAULT = qos_profile_system_default
    SENSOR_DATA = qos_profile_sensor_data
    SERVICES_DEFAULT = qos_profile_services_default
    PARAMETERS = qos_profile_parameters
    PARAMETER_EVENTS = qos_profile_parameter_events
    ACTION_STATUS_DEFAULT = qos_profile_action_status_default
    BEST_AVAILABLE = qos_profile_best_available

    @classmethod
    def short_keys(cls) -> list[str]:
        """Return the lower-case names of the presets."""
        return [k.lower() for k in cls.__members__]

    @classmethod
    def get_from_short_key(cls, name: str) -> QoSProfile:
        """Return the preset named ``name`` (case-insensitive)."""
        return cls[name.upper()].value


class QoSCompatibility(IntEnum):
    """Result of a QoS compatibility check."""

    OK = 0
    WARNING = 1
    ERROR = 2


def _reliable(policy: ReliabilityPolicy) -> bool:
    return policy in (ReliabilityPolicy.RELIABLE, ReliabilityPolicy.SYSTEM_DEFAULT)


def _transient_local(policy: DurabilityPolicy) -> bool:
    return policy == DurabilityPolicy.TRANSIENT_LOCAL


def qos_check_compatible(
    publisher_qos: QoSProfile, subscription_qos: QoSProfile
) -> tuple[QoSCompatibility, str]:
    """Check whether a publisher and a subscription with these profiles can communicate.

    As in DDS: a BEST_EFFORT publisher cannot serve a RELIABLE subscription, and a VOLATILE
    publisher cannot serve a TRANSIENT_LOCAL subscription.

    Returns:
        The compatibility and, when not OK, the reason naming the policy.
    """
    if (
        subscription_qos.reliability != ReliabilityPolicy.BEST_AVAILABLE
        and _reliable(subscription_qos.reliability)
        and publisher_qos.reliability == ReliabilityPolicy.BEST_EFFORT
    ):
        return (
            QoSCompatibility.ERROR,
            'ERROR: Best effort publisher and reliable subscription;',
        )
    if (
        _transient_local(subscription_qos.durability)
        and not _transient_local(publisher_qos.durability)
        and publisher_qos.durability != DurabilityPolicy.BEST_AVAILABLE
    ):
        return (
            QoSCompatibility.ERROR,
            'ERROR: Volatile publisher and transient local subscription;',
        )
    return QoSCompatibility.OK, ''
