"""The Node: entry point for publishers, subscriptions, timers, parameters, clock and logger."""

from __future__ import annotations

import math
import weakref
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING, Any, TypeVar

from rclpy._arguments import RosArguments, parse_ros_arguments
from rclpy._names import (
    expand_topic_name,
    fully_qualified_node_name,
    remap_name,
    remap_topic_name,
    validate_full_topic_name,
    validate_namespace,
    validate_node_name,
)
from rclpy.callback_groups import CallbackGroup, MutuallyExclusiveCallbackGroup
from rclpy.clock import Clock, ROSClock
from rclpy.constants import S_TO_NS
from rclpy.context import Context
from rclpy.exceptions import (
    InvalidHandle,
    InvalidParameterException,
    InvalidParameterTypeException,
    InvalidParameterValueException,
    NotInitializedException,
    ParameterAlreadyDeclaredException,
    ParameterImmutableException,
    ParameterNotDeclaredException,
    ParameterUninitializedException,
)
from rclpy.guard_condition import GuardCondition
from rclpy.logging import RcutilsLogger, _register_rosout, _unregister_rosout, get_logger
from rclpy.parameter import PARAMETER_SEPARATOR_STRING, Parameter
from rclpy.publisher import Publisher
from rclpy.qos import (
    QoSProfile,
    qos_profile_parameter_events,
    qos_profile_rosout_default,
)
from rclpy.subscription import Subscription
from rclpy.time_source import TimeSource
from rclpy.timer import Rate, Timer
from rclpy.topic_endpoint_info import TopicEndpointInfo, TopicEndpointTypeEnum
from rclpy.utilities import get_default_context

if TYPE_CHECKING:
    from rclpy.executors import Executor

MsgType = TypeVar('MsgType')

HIDDEN_NODE_PREFIX = '_'


class _NodeHandle:
    """Stand-in for the C node handle: usable in ``with``, invalid once destroyed."""

    def __init__(self, node: Node) -> None:
        self._node = weakref.ref(node)

    def __enter__(self) -> _NodeHandle:
        node = self._node()
        if node is None or node._destroyed:
            raise InvalidHandle('cannot use Destroyable because destruction was requested')
        return self

    def __exit__(self, *exc_info: object) -> None:
        return None


def _descriptor_class() -> Any:
    from rcl_interfaces.msg import ParameterDescriptor

    return ParameterDescriptor


def _result(successful: bool, reason: str = '') -> Any:
    from rcl_interfaces.msg import SetParametersResult

    return SetParametersResult(successful=successful, reason=reason)


class Node:
    """A node of the ROS graph: creates publishers, subscriptions, timers; holds parameters.

    Args:
        node_name: Name of the node (``-r __node:=NAME`` may replace it).
        context: Context of the node (the default context if None).
        cli_args: Arguments for this node only; their ``--ros-args`` sections are applied
            after the context's (remaps, ``-p``, ``--params-file``).
        namespace: Namespace for relative names (``-r __ns:=/NS`` may replace it).
        use_global_arguments: Whether the context's ``--ros-args`` apply to this node.
        enable_rosout: Whether log messages are also published on /rosout.
        start_parameter_services: Accepted for compatibility (no services in process).
        parameter_overrides: Initial values that win over every command-line override.
        allow_undeclared_parameters: Whether undeclared parameters may be set and read.
        automatically_declare_parameters_from_overrides: Declare every override at creation.
        enable_logger_service: Accepted for compatibility (no services in process).

    Raises:
        NotInitializedException: If the context is not initialized (or shut down).
        InvalidNodeNameException: If the node name is invalid.
        InvalidNamespaceException: If the namespace is invalid.
        UnknownROSArgsError: If ``cli_args`` hold unknown ROS flags.
        RCLError: If ``cli_args`` are malformed (e.g. a bad parameter file).
    """

    PARAM_REL_TOL = 1e-6

    def __init__(
        self,
        node_name: str,
        *,
        context: Context | None = None,
        cli_args: list[str] | None = None,
        namespace: str | None = None,
        use_global_arguments: bool = True,
        enable_rosout: bool = True,
        start_parameter_services: bool = True,
        parameter_overrides: list[Parameter] | None = None,
        allow_undeclared_parameters: bool = False,
        automatically_declare_parameters_from_overrides: bool = False,
        enable_logger_service: bool = False,
    ) -> None:
        self._destroyed = False
        self._executor: Executor | None = None
        self._context = get_default_context() if context is None else context
        self._parameters: dict[str, Parameter] = {}
        self._descriptors: dict[str, Any] = {}
        self._publishers: list[Publisher[Any]] = []
        self._subscriptions: list[Subscription[Any]] = []
        self._timers: list[Timer] = []
        self._guards: list[GuardCondition] = []
        self._default_callback_group = MutuallyExclusiveCallbackGroup()
        self._rate_group: CallbackGroup | None = None
        self._pre_set_parameters_callbacks: list[Callable[[list[Parameter]], list[Parameter]]] = []
        self._on_set_parameters_callbacks: list[Callable[[list[Parameter]], Any]] = []
        self._post_set_parameters_callbacks: list[Callable[[list[Parameter]], None]] = []
        self._allow_undeclared_parameters = allow_undeclared_parameters
        self._parameter_event_publisher: Publisher[Any] | None = None
        self._rosout_publisher: Publisher[Any] | None = None
        self._rosout_handler: Callable[..., None] | None = None

        if not self._context.ok():
            raise NotInitializedException('cannot create node')
        local_arguments = parse_ros_arguments(cli_args) if cli_args else RosArguments()
        self._remap_rules = list(local_arguments.remap_rules)
        global_arguments = self._context._arguments
        if use_global_arguments:
            self._remap_rules += global_arguments.remap_rules

        validate_node_name(node_name)
        namespace = namespace or '/'
        if not namespace.startswith('/'):
            namespace = '/' + namespace
        validate_namespace(namespace)
        name = remap_name(self._remap_rules, 'node', node_name, node_name)
        namespace = remap_name(self._remap_rules, 'namespace', node_name, namespace)
        validate_node_name(name)
        validate_namespace(namespace)
        self._name = name
        self._namespace = namespace
        self._fqn = fully_qualified_node_name(name, namespace)
        logger_name = name if namespace == '/' else (
            namespace[1:].replace('/', '.') + '.' + name
        )
        self._logger = get_logger(logger_name)
        self.__handle = _NodeHandle(self)

        overrides = {}
        if use_global_arguments:
            overrides.update(global_arguments.parameters_for(self._fqn))
        overrides.update(local_arguments.parameters_for(self._fqn))
        self._parameter_overrides: dict[str, Parameter] = {
            key: Parameter(key, value=override.value) for key, override in overrides.items()
        }
        self._override_sources: dict[str, str] = {
            key: override.source for key, override in overrides.items()
        }
        if parameter_overrides is not None:
            for parameter in parameter_overrides:
                self._parameter_overrides[parameter.name] = parameter
                self._override_sources[parameter.name] = 'parameter_overrides of the Node'
        if local_arguments.default_log_level is not None:
            self._logger.set_level(local_arguments.default_log_level)

        self._clock = ROSClock()
        self._context._graph.add_node(self)
        try:
            self._start(
                enable_rosout and global_arguments.rosout_logs and local_arguments.rosout_logs,
                automatically_declare_parameters_from_overrides,
            )
        except BaseException:
            self.destroy_node()
            raise

    def _start(self, enable_rosout: bool, declare_overrides: bool) -> None:
        """Create the parameter-event publisher, rosout, declared overrides and time source."""
        from rcl_interfaces.msg import ParameterEvent

        self._parameter_event_publisher = self.create_publisher(
            ParameterEvent, '/parameter_events', qos_profile_parameter_events
        )
        if enable_rosout:
            self._start_rosout(self._logger.name)
        if declare_overrides:
            self.declare_parameters(
                '',
                [
                    (name, parameter.value, _descriptor_class()())
                    for name, parameter in self._parameter_overrides.items()
                ],
                ignore_override=True,
            )
        self._time_source = TimeSource(node=self)
        self._time_source.attach_clock(self._clock)

    # -- identity, clock, logger -----------------------------------------------------------

    @property
    def publishers(self) -> Iterator[Publisher[Any]]:
        """Publishers created on this node."""
        yield from self._publishers

    @property
    def subscriptions(self) -> Iterator[Subscription[Any]]:
        """Subscriptions created on this node."""
        yield from self._subscriptions

    @property
    def clients(self) -> Iterator[Any]:
        """Service clients (none: services are not supported in process)."""
        yield from ()

    @property
    def services(self) -> Iterator[Any]:
        """Service servers (none: services are not supported in process)."""
        yield from ()

    @property
    def timers(self) -> Iterator[Timer]:
        """Timers created on this node."""
        yield from self._timers

    @property
    def guards(self) -> Iterator[GuardCondition]:
        """Guard conditions created on this node."""
        yield from self._guards

    @property
    def waitables(self) -> Iterator[Any]:
        """Waitables (none in process)."""
        yield from ()

    @property
    def executor(self) -> Executor | None:
        """Executor spinning this node, or None."""
        return self._executor

    @executor.setter
    def executor(self, new_executor: Executor | None) -> None:
        current = self._executor
        if current is new_executor:
            return
        if current is not None:
            current.remove_node(self)
        if new_executor is None:
            self._executor = None
        else:
            new_executor.add_node(self)
            self._executor = new_executor

    def _wake_executor(self) -> None:
        executor = self._executor
        if executor is not None:
            executor._wake()

    @property
    def context(self) -> Context:
        """Context of the node."""
        return self._context

    @property
    def default_callback_group(self) -> CallbackGroup:
        """Group of entities created without one (mutually exclusive)."""
        return self._default_callback_group

    @property
    def handle(self) -> _NodeHandle:
        """Handle of the node (usable in ``with``; raises InvalidHandle once destroyed)."""
        return self.__handle

    @handle.setter
    def handle(self, value: Any) -> None:
        raise AttributeError('handle cannot be modified after node creation')

    def _check(self) -> None:
        if self._destroyed:
            raise InvalidHandle('cannot use Destroyable because destruction was requested')

    def get_name(self) -> str:
        """Return the node name (after remapping)."""
        return self._name

    def get_namespace(self) -> str:
        """Return the node namespace (after remapping)."""
        return self._namespace

    def get_fully_qualified_name(self) -> str:
        """Return namespace and name, e.g. ``/uvms/controller``."""
        return self._fqn

    def get_clock(self) -> Clock:
        """Return the node's ROS clock (follows /clock while ``use_sim_time`` is true)."""
        return self._clock

    def get_logger(self) -> RcutilsLogger:
        """Return the node's logger (named after namespace and node, dot-separated)."""
        return self._logger

    # -- parameters ------------------------------------------------------------------------

    def declare_parameter(
        self,
        name: str,
        value: Any = None,
        descriptor: Any = None,
        ignore_override: bool = False,
    ) -> Parameter:
        """Declare a parameter and give it its initial value.

        The value is the override (``--params-file``, ``-p``, ``parameter_overrides``) if
        there is one, else ``value``. The type is that of ``value``, or ``value`` itself when it
        is a ``Parameter.Type`` (a typed parameter without a default).

        Args:
            name: Fully qualified parameter name.
            value: Default value, or a ``Parameter.Type``.
            descriptor: ``rcl_interfaces/msg/ParameterDescriptor`` (ranges, read-only, ...).
            ignore_override: Ignore overrides.

        Returns:
            The declared parameter.

        Raises:
            ParameterAlreadyDeclaredException: If the parameter was declared before.
            InvalidParameterException: If the name is invalid.
            InvalidParameterTypeException: If the initial value has another type than declared.
            InvalidParameterValueException: If the initial value is out of range or a callback
                rejects it.
        """
        if value is None and descriptor is None:
            args: tuple[Any, ...] = (name,)
        else:
            descriptor = _descriptor_class()() if descriptor is None else descriptor
            args = (name, value, descriptor)
        return self.declare_parameters('', [args], ignore_override)[0]

    def declare_parameters(
        self,
        namespace: str,
        parameters: list[tuple[Any, ...]],
        ignore_override: bool = False,
    ) -> list[Parameter]:
        """Declare several parameters ``namespace.name`` from ``(name[, value[, descriptor]])``.

        Raises:
            TypeError: If a tuple is malformed.
            ValueError: If a statically typed parameter would have no type.
            ParameterAlreadyDeclaredException, InvalidParameterException,
            InvalidParameterTypeException, InvalidParameterValueException: As
                :meth:`declare_parameter`.
        """
        from rcl_interfaces.msg import ParameterValue

        descriptor_cls = _descriptor_class()
        parameter_list: list[Parameter] = []
        descriptors: dict[str, Any] = {}
        overridden: set[str] = set()
        for index, parameter_tuple in enumerate(parameters):
            if len(parameter_tuple) < 1 or len(parameter_tuple) > 3:
                raise TypeError(
                    f'Invalid parameter tuple length at index {index} in parameters list: '
                    f'{parameter_tuple}; expecting length between 1 and 3'
                )
            name = parameter_tuple[0]
            if not isinstance(name, str):
                raise TypeError(
                    f'First element {name} at index {index} in parameters list is not a str.'
                )
            if namespace:
                name = f'{namespace}.{name}'
            _validate_parameter_name(name)
            second = parameter_tuple[1] if len(parameter_tuple) > 1 else None
            descriptor = parameter_tuple[2] if len(parameter_tuple) > 2 else descriptor_cls()
            if not isinstance(descriptor, descriptor_cls):
                raise TypeError(
                    f'Third element {descriptor} at index {index} in parameters list '
                    'is not a ParameterDescriptor.'
                )
            value = None
            if len(parameter_tuple) == 1:
                import warnings

                warnings.warn(
                    f"when declaring parameter named '{name}', declaring a parameter only "
                    'providing its name is deprecated. You have to either:\n'
                    '\t- Pass a name and a default value different to "PARAMETER NOT SET" '
                    '(and optionally a descriptor).\n'
                    '\t- Pass a name and a parameter type.\n'
                    '\t- Pass a name and a descriptor with `dynamic_typing=True',
                    stacklevel=3,
                )
                descriptor.dynamic_typing = True
            if isinstance(second, Parameter.Type):
                if second == Parameter.Type.NOT_SET:
                    raise ValueError(
                        f'Cannot declare parameter {{{name}}} as statically typed of type NOT_SET'
                    )
                if descriptor.dynamic_typing is True:
                    raise ValueError(
                        f'When declaring parameter {{{name}}} passing a descriptor with '
                        '`dynamic_typing=True` is not allowed when the parameter type is provided'
                    )
                descriptor.type = second.value
            else:
                value = second
                if isinstance(value, ParameterValue):
                    from rclpy.parameter import parameter_value_to_python

                    value = parameter_value_to_python(value)
                if not descriptor.dynamic_typing:
                    descriptor.type = Parameter.Type.from_parameter_value(value).value
                    if descriptor.type == Parameter.Type.NOT_SET.value:
                        raise ValueError(
                            'Cannot declare a statically typed parameter with default value '
                            'of type PARAMETER_NOT_SET'
                        )
            if not ignore_override and name in self._parameter_overrides:
                value = self._parameter_overrides[name].value
                overridden.add(name)
            parameter_list.append(Parameter(name, value=value))
            descriptors[name] = descriptor

        already = [p.name for p in parameter_list if p.name in self._parameters]
        if already:
            raise ParameterAlreadyDeclaredException(already)
        for parameter in parameter_list:
            result = self._set_parameters_atomically_common(
                [parameter], descriptors, allow_not_set_type=True
            )
            if not result.successful:
                error: Exception
                if result.reason.startswith('Wrong parameter type'):
                    error = InvalidParameterTypeException(
                        parameter, Parameter.Type(descriptors[parameter.name].type).name
                    )
                else:
                    error = InvalidParameterValueException(
                        parameter.name, parameter.value, result.reason
                    )
                if parameter.name in overridden:
                    source = self._override_sources.get(parameter.name)
                    if source:
                        error.args = (f'{error.args[0]} (value from {source})',)
                raise error
        return [self._parameters[p.name] for p in parameter_list]

    def undeclare_parameter(self, name: str) -> None:
        """Undeclare a parameter.

        Raises:
            ParameterNotDeclaredException: If it was not declared.
            ParameterImmutableException: If it is read-only.
        """
        if not self.has_parameter(name):
            raise ParameterNotDeclaredException(name)
        if self._descriptors[name].read_only:
            raise ParameterImmutableException(name)
        del self._parameters[name]
        del self._descriptors[name]

    def has_parameter(self, name: str) -> bool:
        """Tell whether a parameter is declared."""
        return name in self._parameters

    def get_parameter_types(self, names: list[str]) -> list[Parameter.Type]:
        """Return the types of parameters."""
        if not all(isinstance(name, str) for name in names):
            raise TypeError('All names must be instances of type str')
        return [self.get_parameter_type(name) for name in names]

    def get_parameter_type(self, name: str) -> Parameter.Type:
        """Return the type of a parameter (NOT_SET if undeclared and that is allowed).

        Raises:
            ParameterNotDeclaredException: If undeclared and undeclared parameters are not
                allowed.
        """
        if self.has_parameter(name):
            return self._parameters[name].type_
        if self._allow_undeclared_parameters:
            return Parameter.Type.NOT_SET
        raise ParameterNotDeclaredException(name)

    def get_parameters(self, names: list[str]) -> list[Parameter]:
        """Return parameters by name; see :meth:`get_parameter`."""
        if not all(isinstance(name, str) for name in names):
            raise TypeError('All names must be instances of type str')
        return [self.get_parameter(name) for name in names]

    def get_parameter(self, name: str) -> Parameter:
        """Return a parameter by name.

        Raises:
            ParameterNotDeclaredException: If undeclared and undeclared parameters are not
                allowed.
            ParameterUninitializedException: If statically typed and never given a value.
        """
        if self.has_parameter(name):
            parameter = self._parameters[name]
            if (
                parameter.type_ != Parameter.Type.NOT_SET
                or self._descriptors[name].dynamic_typing
            ):
                return parameter
            raise ParameterUninitializedException(name)
        if self._allow_undeclared_parameters:
            return Parameter(name, Parameter.Type.NOT_SET, None)
        raise ParameterNotDeclaredException(name)

    def get_parameter_or(
        self, name: str, alternative_value: Parameter | None = None
    ) -> Parameter:
        """Return a parameter, or ``alternative_value`` if undeclared or uninitialized."""
        if alternative_value is None:
            alternative_value = Parameter(name, Parameter.Type.NOT_SET)
        if not self.has_parameter(name):
            return alternative_value
        if self._parameters[name].type_ == Parameter.Type.NOT_SET:
            return alternative_value
        return self._parameters[name]

    def get_parameters_by_prefix(self, prefix: str) -> dict[str, Parameter]:
        """Return the parameters named ``prefix.<rest>`` keyed by ``<rest>``."""
        if prefix:
            prefix = prefix + PARAMETER_SEPARATOR_STRING
        length = len(prefix)
        return {
            name[length:]: parameter
            for name, parameter in self._parameters.items()
            if name.startswith(prefix)
        }

    def set_parameters(self, parameter_list: list[Parameter]) -> list[Any]:
        """Set parameters one by one.

        Returns:
            One ``rcl_interfaces/msg/SetParametersResult`` per parameter; a rejected value
            (wrong type, out of range, read-only, refused by a callback) gives
            ``successful=False`` with the reason.

        Raises:
            ParameterNotDeclaredException: If a parameter is undeclared and undeclared
                parameters are not allowed.
        """
        return [self._set_parameters_atomically([parameter]) for parameter in parameter_list]

    def set_parameters_atomically(self, parameter_list: list[Parameter]) -> Any:
        """Set parameters all at once or none.

        Returns:
            One ``SetParametersResult`` for all of them.

        Raises:
            ParameterNotDeclaredException: If a parameter is undeclared and undeclared
                parameters are not allowed.
        """
        return self._set_parameters_atomically(parameter_list)

    def _set_parameters_atomically(self, parameter_list: list[Parameter]) -> Any:
        modified = self._call_pre_set_parameters_callback(parameter_list)
        if modified is not None:
            parameter_list = modified
            if not parameter_list:
                return _result(
                    False,
                    'parameter list cannot be empty, this might be due to '
                    'pre_set_parameters_callback modifying the original parameters list.',
                )
        self._check_undeclared_parameters(parameter_list)
        return self._set_parameters_atomically_common(parameter_list)

    def _set_parameters_atomically_common(
        self,
        parameter_list: list[Parameter],
        descriptors: dict[str, Any] | None = None,
        allow_not_set_type: bool = False,
    ) -> Any:
        if descriptors is not None:
            result = self._apply_descriptors(parameter_list, descriptors, False)
        else:
            result = self._apply_descriptors(parameter_list, self._descriptors, True)
        if not result.successful:
            return result
        for callback in self._on_set_parameters_callbacks:
            result = callback(parameter_list)
            if not result.successful:
                return result
        new, changed, deleted = [], [], []
        for parameter in parameter_list:
            if not allow_not_set_type and parameter.type_ == Parameter.Type.NOT_SET:
                deleted.append(parameter)
                self._parameters.pop(parameter.name, None)
                self._descriptors.pop(parameter.name, None)
                continue
            if descriptors is not None:
                self._descriptors[parameter.name] = descriptors[parameter.name]
            elif parameter.name not in self._descriptors:
                descriptor = _descriptor_class()()
                descriptor.dynamic_typing = True
                self._descriptors[parameter.name] = descriptor
            if self.get_parameter_or(parameter.name).type_ == Parameter.Type.NOT_SET:
                new.append(parameter)
            else:
                changed.append(parameter)
            self._parameters[parameter.name] = parameter
        self._publish_parameter_event(new, changed, deleted)
        self._call_post_set_parameters_callback(parameter_list)
        return _result(True)

    def _publish_parameter_event(
        self, new: list[Parameter], changed: list[Parameter], deleted: list[Parameter]
    ) -> None:
        publisher = self._parameter_event_publisher
        if publisher is None or not publisher._matched:
            return
        event = publisher.msg_type()
        event.node = self._fqn
        event.new_parameters = [p.to_parameter_msg() for p in new]
        event.changed_parameters = [p.to_parameter_msg() for p in changed]
        event.deleted_parameters = [p.to_parameter_msg() for p in deleted]
        event.stamp = self._clock.now().to_msg()
        publisher.publish(event)

    def list_parameters(self, prefixes: list[str], depth: int) -> Any:
        """Return a ``ListParametersResult`` with names (and their prefixes) under ``prefixes``.

        Args:
            prefixes: Prefixes to list (all parameters if empty).
            depth: Levels of nesting to include (0: all).

        Raises:
            TypeError: If an argument has the wrong type.
            ValueError: If ``depth`` is negative.
        """
        from rcl_interfaces.msg import ListParametersResult

        if not isinstance(prefixes, list):
            raise TypeError('The prefixes argument must be a list')
        if not all(isinstance(prefix, str) for prefix in prefixes):
            raise TypeError('All prefixes must be instances of type str')
        if not isinstance(depth, int):
            raise TypeError('The depth must be instance of type int')
        if depth < 0:
            raise ValueError('The depth must be greater than or equal to zero')
        result = ListParametersResult()
        names: list[str] = []
        found_prefixes: list[str] = []

        def shallow(name: str) -> bool:
            return name.count(PARAMETER_SEPARATOR_STRING) < depth

        recursive = not prefixes and depth == 0
        for name in self._parameters:
            if not recursive:
                if not (not prefixes and shallow(name)) and not any(
                    name == prefix
                    or (
                        name.startswith(prefix + PARAMETER_SEPARATOR_STRING)
                        and (depth == 0 or shallow(name[len(prefix) + 1:]))
                    )
                    for prefix in prefixes
                ):
                    continue
            names.append(name)
            separator = name.rfind(PARAMETER_SEPARATOR_STRING)
            if separator != -1 and name[:separator] not in found_prefixes:
                found_prefixes.append(name[:separator])
        result.names = names
        result.prefixes = found_prefixes
        return result

    def _check_undeclared_parameters(self, parameter_list: list[Parameter]) -> None:
        if not all(isinstance(parameter, Parameter) for parameter in parameter_list):
            raise TypeError(f"parameter must be instance of type '{Parameter!r}'")
        undeclared = [p.name for p in parameter_list if p.name not in self._parameters]
        if not self._allow_undeclared_parameters and undeclared:
            raise ParameterNotDeclaredException(undeclared)

    def _call_pre_set_parameters_callback(
        self, parameter_list: list[Parameter]
    ) -> list[Parameter] | None:
        if not self._pre_set_parameters_callbacks:
            return None
        modified: list[Parameter] = []
        for callback in self._pre_set_parameters_callbacks:
            modified.extend(callback(parameter_list))
        return modified

    def _call_post_set_parameters_callback(self, parameter_list: list[Parameter]) -> None:
        for callback in self._post_set_parameters_callbacks:
            callback(parameter_list)

    def add_pre_set_parameters_callback(
        self, callback: Callable[[list[Parameter]], list[Parameter]]
    ) -> None:
        """Add a callback that may modify the parameters being set, before validation."""
        self._pre_set_parameters_callbacks.insert(0, callback)

    def add_on_set_parameters_callback(
        self, callback: Callable[[list[Parameter]], Any]
    ) -> None:
        """Add a callback that validates parameters before they are set (called first).

        The callback gets the list of parameters and returns a ``SetParametersResult``;
        ``successful=False`` rejects the change with ``reason``.
        """
        self._on_set_parameters_callbacks.insert(0, callback)

    def add_post_set_parameters_callback(
        self, callback: Callable[[list[Parameter]], None]
    ) -> None:
        """Add a callback called after parameters were set successfully."""
        self._post_set_parameters_callbacks.insert(0, callback)

    def remove_pre_set_parameters_callback(
        self, callback: Callable[[list[Parameter]], list[Parameter]]
    ) -> None:
        """Remove a pre-set callback (ValueError if absent)."""
        self._pre_set_parameters_callbacks.remove(callback)

    def remove_on_set_parameters_callback(
        self, callback: Callable[[list[Parameter]], Any]
    ) -> None:
        """Remove an on-set callback (ValueError if absent)."""
        self._on_set_parameters_callbacks.remove(callback)

    def remove_post_set_parameters_callback(
        self, callback: Callable[[list[Parameter]], None]
    ) -> None:
        """Remove a post-set callback (ValueError if absent)."""
        self._post_set_parameters_callbacks.remove(callback)

    def _apply_descriptors(
        self, parameter_list: list[Parameter], descriptors: dict[str, Any], check_read_only: bool
    ) -> Any:
        for parameter in parameter_list:
            if parameter.name in descriptors:
                result = self._apply_descriptor(
                    parameter, descriptors[parameter.name], check_read_only
                )
                if not result.successful:
                    return result
        return _result(True)

    def _apply_descriptor(
        self, parameter: Parameter, descriptor: Any = None, check_read_only: bool = True
    ) -> Any:
        if descriptor is None:
            descriptor = self.describe_parameter(parameter.name)
        else:
            descriptor.name = parameter.name
        if check_read_only and descriptor.read_only:
            return _result(False, f'Trying to set a read-only parameter: {parameter.name}.')
        if descriptor.dynamic_typing:
            descriptor.type = parameter.type_.value
        elif self.has_parameter(parameter.name) and parameter.type_ == Parameter.Type.NOT_SET:
            return _result(False, 'Static parameter cannot be undeclared')
        elif (
            parameter.type_ != Parameter.Type.NOT_SET
            and parameter.type_.value != descriptor.type
        ):
            return _result(
                False,
                f"Wrong parameter type, expected '{Parameter.Type(descriptor.type)}' "
                f"got '{parameter.type_}'",
            )
        if parameter.type_ == Parameter.Type.INTEGER and descriptor.integer_range:
            return self._apply_integer_range(parameter, descriptor.integer_range[0])
        if parameter.type_ == Parameter.Type.DOUBLE and descriptor.floating_point_range:
            return self._apply_floating_point_range(parameter, descriptor.floating_point_range[0])
        return _result(True)

    def _apply_integer_range(self, parameter: Parameter, integer_range: Any) -> Any:
        min_value = min(integer_range.from_value, integer_range.to_value)
        max_value = max(integer_range.from_value, integer_range.to_value)
        value = parameter.value
        if value in (min_value, max_value):
            return _result(True)
        if not min_value < value < max_value:
            return _result(
                False,
                f'Parameter {parameter.name} out of range. '
                f'Min: {min_value}, Max: {max_value}, value: {value}',
            )
        if integer_range.step != 0 and (value - min_value) % integer_range.step != 0:
            return _result(
                False,
                f'The parameter value for {parameter.name} is not a valid step. '
                f'Min: {min_value}, max: {max_value}, value: {value}, '
                f'step: {integer_range.step}',
            )
        return _result(True)

    def _apply_floating_point_range(self, parameter: Parameter, fp_range: Any) -> Any:
        min_value = min(fp_range.from_value, fp_range.to_value)
        max_value = max(fp_range.from_value, fp_range.to_value)
        value = parameter.value
        tol = self.PARAM_REL_TOL
        if math.isclose(value, min_value, rel_tol=tol) or math.isclose(
            value, max_value, rel_tol=tol
        ):
            return _result(True)
        if not min_value < value < max_value:
            return _result(
                False,
                f'Parameter {parameter.name} out of range '
                f'Min: {min_value}, Max: {max_value}, value: {value}',
            )
        if fp_range.step != 0.0:
            steps = round((value - min_value) / fp_range.step)
            if not math.isclose(min_value + steps * fp_range.step, value, rel_tol=tol):
                return _result(
                    False,
                    f'The parameter value for {parameter.name} is not close enough to a valid '
                    f'step. Min: {min_value}, max: {max_value}, value: {value}, '
                    f'step: {fp_range.step}',
                )
        return _result(True)

    def describe_parameter(self, name: str) -> Any:
        """Return the ``ParameterDescriptor`` of a parameter.

        Raises:
            ParameterNotDeclaredException: If undeclared and undeclared parameters are not
                allowed.
        """
        try:
            return self._descriptors[name]
        except KeyError:
            if self._allow_undeclared_parameters:
                return _descriptor_class()()
            raise ParameterNotDeclaredException(name) from None

    def describe_parameters(self, names: list[str]) -> list[Any]:
        """Return the descriptors of parameters; see :meth:`describe_parameter`."""
        return [self.describe_parameter(name) for name in names]

    def set_descriptor(
        self, name: str, descriptor: Any, alternative_value: Any = None
    ) -> Any:
        """Give a parameter a new descriptor (its value must comply, or the alternative's).

        Returns:
            The parameter's ``ParameterValue`` after the change.

        Raises:
            ParameterNotDeclaredException: If undeclared.
            ParameterImmutableException: If read-only.
            InvalidParameterValueException: If neither value complies.
        """
        if not self.has_parameter(name):
            if not self._allow_undeclared_parameters:
                raise ParameterNotDeclaredException(name)
            return self.get_parameter(name).get_parameter_value()
        if self.describe_parameter(name).read_only:
            raise ParameterImmutableException(name)
        current = self.get_parameter(name)
        if alternative_value is None:
            alternative = current
        else:
            from rcl_interfaces.msg import Parameter as ParameterMsg

            alternative = Parameter.from_parameter_msg(
                ParameterMsg(name=name, value=alternative_value)
            )
        if not self._apply_descriptor(current, descriptor, False).successful:
            result = self._apply_descriptor(alternative, descriptor, False)
            if not result.successful:
                raise InvalidParameterValueException(name, alternative.value, result.reason)
            self._parameters[name] = alternative
        self._descriptors[name] = descriptor
        return self.get_parameter(name).get_parameter_value()

    # -- topics ----------------------------------------------------------------------------

    def resolve_topic_name(self, topic: str, *, only_expand: bool = False) -> str:
        """Expand a topic name (relative, ``~``) and apply remap rules unless ``only_expand``.

        Raises:
            InvalidTopicNameException: If the name is invalid.
        """
        expanded = expand_topic_name(topic, self._name, self._namespace)
        if only_expand:
            return expanded
        return remap_topic_name(self._remap_rules, expanded, self._name, self._namespace)

    def resolve_service_name(self, service: str, *, only_expand: bool = False) -> str:
        """Expand (and remap) a service name like a topic name."""
        return self.resolve_topic_name(service, only_expand=only_expand)

    @staticmethod
    def _validate_qos_or_depth_parameter(qos_or_depth: QoSProfile | int) -> QoSProfile:
        if isinstance(qos_or_depth, QoSProfile):
            return qos_or_depth
        if isinstance(qos_or_depth, int) and not isinstance(qos_or_depth, bool):
            if qos_or_depth < 0:
                raise ValueError('history depth must be greater than or equal to zero')
            return QoSProfile(depth=qos_or_depth)
        raise TypeError(f'Expected QoSProfile or int, but received {type(qos_or_depth)!r}')

    @staticmethod
    def _check_msg_type(msg_type: Any) -> None:
        from rclpy._support import message_support

        if not message_support().is_message_class(msg_type):
            raise TypeError(
                f'{msg_type!r} is not a ROS message class (expected e.g. '
                'sensor_msgs.msg.JointState, the class rather than an instance)'
            )

    def create_publisher(
        self,
        msg_type: type[MsgType],
        topic: str,
        qos_profile: QoSProfile | int,
        *,
        callback_group: CallbackGroup | None = None,
        event_callbacks: Any = None,
        qos_overriding_options: Any = None,
        publisher_class: type[Publisher[Any]] = Publisher,
    ) -> Publisher[MsgType]:
        """Create a publisher.

        Args:
            msg_type: Message class.
            topic: Topic name (relative names get the namespace; remaps apply).
            qos_profile: A QoSProfile, or a history depth (KEEP_LAST, RELIABLE, VOLATILE).
            callback_group: Group for the publisher's event handlers.
            event_callbacks: Accepted for compatibility (no QoS events in process).
            qos_overriding_options: Accepted for compatibility.
            publisher_class: Publisher class to instantiate.

        Raises:
            TypeError: If ``msg_type`` is not a message class or ``qos_profile`` is invalid.
            InvalidTopicNameException: If the topic name is invalid.
        """
        self._check()
        qos = self._validate_qos_or_depth_parameter(qos_profile)
        callback_group = callback_group or self._default_callback_group
        self._check_msg_type(msg_type)
        topic_name = self.resolve_topic_name(topic)
        publisher = publisher_class(self, msg_type, topic, topic_name, qos, callback_group)
        self._publishers.append(publisher)
        self._context._graph.add_publisher(publisher)
        self._wake_executor()
        return publisher

    def create_subscription(
        self,
        msg_type: type[MsgType],
        topic: str,
        callback: Callable[[Any], Any],
        qos_profile: QoSProfile | int,
        *,
        callback_group: CallbackGroup | None = None,
        event_callbacks: Any = None,
        qos_overriding_options: Any = None,
        raw: bool = False,
    ) -> Subscription[MsgType]:
        """Create a subscription.

        Args:
            msg_type: Message class.
            topic: Topic name (relative names get the namespace; remaps apply).
            callback: Called with each message (bytes with ``raw=True``).
            qos_profile: A QoSProfile, or a history depth (KEEP_LAST, RELIABLE, VOLATILE).
            callback_group: Group of the callback (the node's default group if None).
            event_callbacks: Accepted for compatibility (no QoS events in process).
            qos_overriding_options: Accepted for compatibility.
            raw: Deliver serialized CDR bytes instead of message objects.

        Raises:
            TypeError: If ``msg_type`` is not a message class or ``qos_profile`` is invalid.
            InvalidTopicNameException: If the topic name is invalid.
        """
        self._check()
        qos = self._validate_qos_or_depth_parameter(qos_profile)
        callback_group = callback_group or self._default_callback_group
        self._check_msg_type(msg_type)
        topic_name = self.resolve_topic_name(topic)
        subscription = Subscription(
            self, msg_type, topic, topic_name, callback, callback_group, qos, raw
        )
        callback_group.add_entity(subscription)
        self._subscriptions.append(subscription)
        self._context._graph.add_subscription(subscription)
        self._wake_executor()
        return subscription

    def create_client(self, srv_type: Any, srv_name: str, **kwargs: Any) -> Any:
        """Services are not supported by the in-process runtime.

        Raises:
            NotImplementedError: Always.
        """
        raise NotImplementedError(
            f"create_client('{srv_name}'): services are not supported by the ros2_compat "
            'in-process runtime (use topics, or run with a real ROS 2)'
        )

    def create_service(self, srv_type: Any, srv_name: str, callback: Any, **kwargs: Any) -> Any:
        """Services are not supported by the in-process runtime.

        Raises:
            NotImplementedError: Always.
        """
        raise NotImplementedError(
            f"create_service('{srv_name}'): services are not supported by the ros2_compat "
            'in-process runtime (use topics, or run with a real ROS 2)'
        )

    def create_timer(
        self,
        timer_period_sec: float,
        callback: Callable[[], Any] | None,
        callback_group: CallbackGroup | None = None,
        clock: Clock | None = None,
        autostart: bool = True,
    ) -> Timer:
        """Create a timer calling ``callback`` every ``timer_period_sec`` s of ``clock``.

        Args:
            timer_period_sec: Period in seconds (non-negative).
            callback: Called with no argument.
            callback_group: Group of the callback (the node's default group if None).
            clock: Clock to run on (the node clock if None: wall time, or /clock time while
                ``use_sim_time`` is true).
            autostart: Start now; otherwise start with ``reset()``.

        Raises:
            ValueError: If the period is negative.
        """
        self._check()
        period_ns = int(float(timer_period_sec) * S_TO_NS)
        if period_ns < 0:
            raise ValueError(
                f'timer_period_sec must be non-negative, got {timer_period_sec}'
            )
        callback_group = callback_group or self._default_callback_group
        timer = Timer(
            callback,
            callback_group,
            period_ns,
            self._clock if clock is None else clock,
            context=self._context,
            autostart=autostart,
        )
        timer._node = self
        callback_group.add_entity(timer)
        self._timers.append(timer)
        self._wake_executor()
        return timer

    def create_guard_condition(
        self, callback: Callable[[], Any], callback_group: CallbackGroup | None = None
    ) -> GuardCondition:
        """Create a guard condition whose ``trigger()`` makes the executor call ``callback``."""
        self._check()
        callback_group = callback_group or self._default_callback_group
        guard = GuardCondition(callback, callback_group, context=self._context)
        guard._node = self
        callback_group.add_entity(guard)
        self._guards.append(guard)
        self._wake_executor()
        return guard

    def create_rate(self, frequency: float, clock: Clock | None = None) -> Rate:
        """Create a Rate ticking at ``frequency`` Hz (spin the node in another thread).

        Raises:
            ValueError: If ``frequency`` is not positive.
        """
        if frequency <= 0:
            raise ValueError(f'frequency must be > 0, got {frequency}')
        if self._rate_group is None:
            from rclpy.callback_groups import ReentrantCallbackGroup

            self._rate_group = ReentrantCallbackGroup()
        timer = self.create_timer(1.0 / frequency, None, self._rate_group, clock)
        return Rate(timer, context=self._context)

    def destroy_publisher(self, publisher: Publisher[Any]) -> bool:
        """Destroy a publisher of this node; return whether it was one."""
        if publisher in self._publishers:
            self._publishers.remove(publisher)
            publisher.destroy()
            self._wake_executor()
            return True
        return False

    def destroy_subscription(self, subscription: Subscription[Any]) -> bool:
        """Destroy a subscription of this node; return whether it was one."""
        if subscription in self._subscriptions:
            self._subscriptions.remove(subscription)
            subscription.destroy()
            self._wake_executor()
            return True
        return False

    def destroy_client(self, client: Any) -> bool:
        """Return False (no clients in process)."""
        return False

    def destroy_service(self, service: Any) -> bool:
        """Return False (no services in process)."""
        return False

    def destroy_timer(self, timer: Timer) -> bool:
        """Destroy a timer of this node; return whether it was one."""
        if timer in self._timers:
            self._timers.remove(timer)
            timer.destroy()
            self._wake_executor()
            return True
        return False

    def destroy_guard_condition(self, guard: GuardCondition) -> bool:
        """Destroy a guard condition of this node; return whether it was one."""
        if guard in self._guards:
            self._guards.remove(guard)
            guard.destroy()
            self._wake_executor()
            return True
        return False

    def destroy_rate(self, rate: Rate) -> bool:
        """Destroy a Rate created by this node."""
        success = self.destroy_timer(rate._timer)
        rate.destroy()
        return success

    def destroy_node(self) -> None:
        """Destroy the node and everything it created; it leaves the graph."""
        if self._destroyed:
            return
        self._parameter_event_publisher = None
        while self._publishers:
            self.destroy_publisher(self._publishers[0])
        while self._subscriptions:
            self.destroy_subscription(self._subscriptions[0])
        while self._timers:
            self.destroy_timer(self._timers[0])
        while self._guards:
            self.destroy_guard_condition(self._guards[0])
        self._stop_rosout()
        self._context._graph.remove_node(self)
        self._destroyed = True
        self._wake_executor()

    # -- rosout ------------------------------------------------------------------------------

    def _start_rosout(self, logger_name: str) -> None:
        from rcl_interfaces.msg import Log

        publisher = Publisher(
            self, Log, '/rosout', '/rosout', qos_profile_rosout_default,
            self._default_callback_group,
        )
        self._context._graph.add_publisher(publisher)
        self._rosout_publisher = publisher

        def handler(
            severity: int, name: str, message: str, function: str, file: str, line: int,
            stamp_ns: int,
        ) -> None:
            if publisher._destroyed or not self._context.ok():
                return
            seconds, nanoseconds = divmod(stamp_ns, S_TO_NS)
            msg = Log(level=severity, name=name, msg=message, file=file, function=function,
                      line=line)
            msg.stamp.sec = seconds
            msg.stamp.nanosec = nanoseconds
            publisher.publish(msg)

        self._rosout_handler = handler
        self._rosout_logger_name = logger_name
        _register_rosout(logger_name, handler)

    def _stop_rosout(self) -> None:
        if self._rosout_handler is not None:
            _unregister_rosout(self._rosout_logger_name, self._rosout_handler)
            self._rosout_handler = None
        if self._rosout_publisher is not None:
            self._rosout_publisher.destroy()
            self._rosout_publisher = None

    # -- graph -------------------------------------------------------------------------------

    def get_topic_names_and_types(self, no_demangle: bool = False) -> list[tuple[str, list[str]]]:
        """Return every topic of the context with its message types, sorted by name."""
        self._check()
        return self._context._graph.topic_names_and_types()

    def get_service_names_and_types(self) -> list[tuple[str, list[str]]]:
        """Return the services (none in process)."""
        return []

    def get_node_names(self) -> list[str]:
        """Return the names of the nodes of the context."""
        return [node._name for node in self._context._graph.nodes()]

    def get_node_names_and_namespaces(self) -> list[tuple[str, str]]:
        """Return (name, namespace) of the nodes of the context."""
        return [(node._name, node._namespace) for node in self._context._graph.nodes()]

    def get_node_names_and_namespaces_with_enclaves(self) -> list[tuple[str, str, str]]:
        """Return (name, namespace, enclave) of the nodes of the context."""
        enclave = self._context._arguments.enclave or '/'
        return [
            (node._name, node._namespace, enclave) for node in self._context._graph.nodes()
        ]

    def get_fully_qualified_node_names(self) -> list[str]:
        """Return the fully qualified names of the nodes of the context."""
        return [node._fqn for node in self._context._graph.nodes()]

    def _find_node(self, node_name: str, node_namespace: str) -> Node:
        from rclpy.impl.implementation_singleton import NodeNameNonExistentError

        for node in self._context._graph.nodes():
            if node._name == node_name and node._namespace == node_namespace:
                return node
        raise NodeNameNonExistentError(
            f'cannot get information of nodes: node {node_namespace}/{node_name} not found'
        )

    def get_publisher_names_and_types_by_node(
        self, node_name: str, node_namespace: str, no_demangle: bool = False
    ) -> list[tuple[str, list[str]]]:
        """Return the topics a node publishes, with types."""
        node = self._find_node(node_name, node_namespace)
        return self._context._graph.endpoints_of_node(node, publishers=True)

    def get_subscriber_names_and_types_by_node(
        self, node_name: str, node_namespace: str, no_demangle: bool = False
    ) -> list[tuple[str, list[str]]]:
        """Return the topics a node subscribes to, with types."""
        node = self._find_node(node_name, node_namespace)
        return self._context._graph.endpoints_of_node(node, publishers=False)

    def _expand_for_count(self, topic_name: str) -> str:
        name = expand_topic_name(topic_name, self._name, self._namespace)
        validate_full_topic_name(name)
        return name

    def count_publishers(self, topic_name: str) -> int:
        """Return the number of publishers on a topic (expanded, not remapped)."""
        self._check()
        return len(self._context._graph.publishers(self._expand_for_count(topic_name)))

    def count_subscribers(self, topic_name: str) -> int:
        """Return the number of subscriptions on a topic (expanded, not remapped)."""
        self._check()
        return len(self._context._graph.subscriptions(self._expand_for_count(topic_name)))

    def count_clients(self, service_name: str) -> int:
        """Return 0 (no services in process)."""
        return 0

    def count_services(self, service_name: str) -> int:
        """Return 0 (no services in process)."""
        return 0

    def _endpoint_infos(
        self, topic_name: str, no_mangle: bool, publishers: bool
    ) -> list[TopicEndpointInfo]:
        if no_mangle:
            name = topic_name
        else:
            name = self.resolve_topic_name(topic_name)
        graph = self._context._graph
        endpoints: list[Any] = graph.publishers(name) if publishers else graph.subscriptions(name)
        kind = (
            TopicEndpointTypeEnum.PUBLISHER if publishers
            else TopicEndpointTypeEnum.SUBSCRIPTION
        )
        return [
            TopicEndpointInfo(
                node_name=e._node._name,
                node_namespace=e._node._namespace,
                topic_type=e._type_name,
                endpoint_type=kind,
                endpoint_gid=list(id(e).to_bytes(16, 'little')),
                qos_profile=e.qos_profile,
            )
            for e in endpoints
        ]

    def get_publishers_info_by_topic(
        self, topic_name: str, no_mangle: bool = False
    ) -> list[TopicEndpointInfo]:
        """Return node, type and QoS of each publisher of a topic (expanded and remapped)."""
        return self._endpoint_infos(topic_name, no_mangle, publishers=True)

    def get_subscriptions_info_by_topic(
        self, topic_name: str, no_mangle: bool = False
    ) -> list[TopicEndpointInfo]:
        """Return node, type and QoS of each subscription of a topic (expanded and remapped)."""
        return self._endpoint_infos(topic_name, no_mangle, publishers=False)

    def __repr__(self) -> str:
        return f'<rclpy.node.Node {self._fqn}>'


def _validate_parameter_name(name: str) -> None:
    if not name or name.startswith('.') or name.endswith('.') or '..' in name:
        raise InvalidParameterException(name)


