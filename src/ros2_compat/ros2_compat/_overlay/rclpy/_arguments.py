"""Parsing of ``--ros-args ... [--]`` command-line arguments, as rcl_arguments does."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

from rclpy._params_yaml import (
    ParameterOverride,
    load_parameter_file,
    node_key_matches,
    parse_parameter_value,
)
from rclpy.impl.implementation_singleton import RCLError, UnknownROSArgsError

ROS_ARGS_FLAG = '--ros-args'
ROS_ARGS_END = '--'

_FLAGS_WITH_VALUE = {
    '-r': 'remap rule',
    '--remap': 'remap rule',
    '-p': 'parameter override rule',
    '--param': 'parameter override rule',
    '--params-file': 'parameter file path',
    '-e': 'enclave',
    '--enclave': 'enclave',
    '--log-level': 'log level',
    '--log-config-file': 'log configuration file',
    '--log-file-name': 'log file name',
}
_SWITCHES = {
    '--enable-rosout-logs': ('rosout_logs', True),
    '--disable-rosout-logs': ('rosout_logs', False),
    '--enable-stdout-logs': ('stdout_logs', True),
    '--disable-stdout-logs': ('stdout_logs', False),
    '--enable-external-lib-logs': ('external_lib_logs', True),
    '--disable-external-lib-logs': ('external_lib_logs', False),
}
_LOG_LEVELS = {'unset': 0, 'debug': 10, 'info': 20, 'warn': 30, 'warning': 30, 'error': 40,
               'fatal': 50}


@dataclass(frozen=True)
class RemapRule:
    """One ``-r [node:]from:=to`` rule.

    Attributes:
        node_name: Node the rule is limited to, or None for every node.
        kind: ``'topic'``, ``'node'`` (``__node``/``__name``) or ``'namespace'`` (``__ns``).
        match: Name to match (topic rules only).
        replacement: Name to use instead.
    """

    node_name: str | None
    kind: str
    match: str
    replacement: str


@dataclass
class RosArguments:
    """Everything found in the ``--ros-args`` sections of one argument list."""

    remap_rules: list[RemapRule] = field(default_factory=list)
    #: Parameter overrides by node key (``/**``, ``/ns/node``...) in command-line order.
    parameters: dict[str, dict[str, ParameterOverride]] = field(default_factory=dict)
    default_log_level: int | None = None
    logger_levels: dict[str, int] = field(default_factory=dict)
    enclave: str | None = None
    log_config_file: str | None = None
    log_file_name: str | None = None
    rosout_logs: bool = True
    stdout_logs: bool = True
    external_lib_logs: bool = True
    non_ros_args: list[str] = field(default_factory=list)

    def add_parameters(self, node_key: str, values: dict[str, ParameterOverride]) -> None:
        """Merge parameter overrides for a node key; later values replace earlier ones."""
        self.parameters.setdefault(node_key, {}).update(values)

    def parameters_for(self, node_fqn: str) -> dict[str, ParameterOverride]:
        """Return the overrides that apply to a node, later node keys winning, as rclpy does."""
        result: dict[str, ParameterOverride] = {}
        for node_key, values in self.parameters.items():
            if node_key_matches(node_key, node_fqn):
                result.update(values)
        return result


def parse_log_level(text: str, flag: str = '--log-level') -> int:
    """Return the severity for a level name (case-insensitive), or raise RCLError naming it."""
    level = _LOG_LEVELS.get(text.lower())
    if level is None:
        raise RCLError(
            f"{flag} {text}: unknown log level '{text}' "
            '(use one of debug, info, warn, error, fatal, unset)'
        )
    return level


def _split_rule(rule: str, flag: str) -> tuple[str | None, str, str]:
    """Split ``[node:]lhs:=rhs`` into its parts."""
    lhs, sep, rhs = rule.partition(':=')
    if not sep or not lhs:
        raise RCLError(f"{flag} {rule}: expected 'name:=value' (a rule needs ':=')")
    node_name: str | None = None
    if ':' in lhs:
        node_name, _, lhs = lhs.partition(':')
        if not node_name or not lhs:
            raise RCLError(f"{flag} {rule}: expected 'node_name:name:=value'")
    return node_name, lhs, rhs


def _parse_remap(rule: str, flag: str) -> RemapRule:
    node_name, lhs, rhs = _split_rule(rule, flag)
    if not rhs:
        raise RCLError(f"{flag} {rule}: the replacement after ':=' is empty")
    if lhs in ('__node', '__name'):
        return RemapRule(node_name, 'node', lhs, rhs)
    if lhs == '__ns':
        return RemapRule(node_name, 'namespace', lhs, rhs if rhs.startswith('/') else '/' + rhs)
    if lhs.startswith('__'):
        raise RCLError(f"{flag} {rule}: unknown special remap '{lhs}' (use __node or __ns)")
    return RemapRule(node_name, 'topic', lhs, rhs)


def _parse_param(args: RosArguments, rule: str, flag: str) -> None:
    node_name, name, text = _split_rule(rule, flag)
    value = parse_parameter_value(text, name)
    node_key = '/**' if node_name is None else node_name
    if not node_key.startswith('/'):
        node_key = '/' + node_key
    args.add_parameters(node_key, {name: ParameterOverride(value, f"-p '{rule}'")})


def _parse_log_level(args: RosArguments, text: str, flag: str) -> None:
    name, sep, level = text.partition(':=')
    if sep:
        args.logger_levels[name] = parse_log_level(level, flag)
    else:
        args.default_log_level = parse_log_level(text, flag)


def parse_ros_arguments(argv: Sequence[str] | None) -> RosArguments:
    """Parse the ROS-specific parts of an argument list.

    Arguments outside ``--ros-args ... [--]`` sections are kept in ``non_ros_args``.

    Raises:
        UnknownROSArgsError: If a ``--ros-args`` section holds unknown flags (all are named).
        RCLError: If a flag lacks its value or a rule, file or level is malformed.
    """
    args = RosArguments()
    unknown: list[str] = []
    in_ros_section = False
    items = list(argv or [])
    index = 0
    while index < len(items):
        arg = items[index]
        index += 1
        if not isinstance(arg, str):
            raise TypeError(f'arguments must be strings, got {arg!r} ({type(arg).__name__})')
        if not in_ros_section:
            if arg == ROS_ARGS_FLAG:
                in_ros_section = True
            else:
                args.non_ros_args.append(arg)
            continue
        if arg == ROS_ARGS_END:
            in_ros_section = False
            continue
        if arg == ROS_ARGS_FLAG:
            continue
        if arg in _SWITCHES:
            attribute, value = _SWITCHES[arg]
            setattr(args, attribute, value)
            continue
        if arg not in _FLAGS_WITH_VALUE:
            unknown.append(arg)
            continue
        if index >= len(items) or items[index] in (ROS_ARGS_END, ROS_ARGS_FLAG):
            raise RCLError(
                f"Couldn't parse trailing {arg} flag: no {_FLAGS_WITH_VALUE[arg]} follows it"
            )
        value = items[index]
        index += 1
        if arg in ('-r', '--remap'):
            args.remap_rules.append(_parse_remap(value, arg))
        elif arg in ('-p', '--param'):
            _parse_param(args, value, arg)
        elif arg == '--params-file':
            for node_key, values in load_parameter_file(value).items():
                args.add_parameters(node_key, values)
        elif arg in ('-e', '--enclave'):
            args.enclave = value
        elif arg == '--log-level':
            _parse_log_level(args, value, arg)
        elif arg == '--log-config-file':
            args.log_config_file = value
        else:
            args.log_file_name = value
    if unknown:
        raise UnknownROSArgsError(
            f'Found unknown ROS arguments: {unknown!r} (known flags: -r/--remap, -p/--param, '
            '--params-file, -e/--enclave, --log-level, --log-config-file, --log-file-name, '
            '--enable/--disable-rosout-logs, --enable/--disable-stdout-logs, '
            '--enable/--disable-external-lib-logs)'
        )
    return args


def remove_ros_args(argv: Sequence[str]) -> list[str]:
    """Return the arguments that are not ROS arguments (rclpy.utilities.remove_ros_args).

    Raises:
        UnknownROSArgsError: If a ``--ros-args`` section holds unknown flags.
        RCLError: If the ROS arguments are malformed, as rcl reports while removing them.
    """
    return parse_ros_arguments(argv).non_ros_args
