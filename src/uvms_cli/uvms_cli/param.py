"""``uvms param list|get|set NODE [NAME] [VALUE]``: a running node's parameters from a shell.

What ``ros2 param`` does, without a ROS install (no ros2cli wheel exists): it calls the
node's own parameter services (rcl_interfaces ``ListParameters``, ``GetParameters`` and
``SetParameters``, ``/<ns>/<node>/list_parameters`` and so on)::

    uvms param list controller
    uvms param get controller hybrid.force_kp
    uvms param set controller hybrid.force_kp 0.12

A value is read as YAML, as ``ros2 param set`` reads it (``0.12`` a float, ``[1.0, 2.0]`` a
list, ``true`` a bool); a node refuses a value of another type or out of its range, and the
line says why. Exit status: 0 done, 1 the node did not answer within ``--timeout`` (the line
names the service it waited for), the parameter is not there, or the node refused the value,
2 bad usage, 130 interrupted.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import Any

import yaml
from uvms_common.ros_environment import ros_environment_defaults

from uvms_cli.service_call import call_service

EXIT_OK = 0
EXIT_FAILURE = 1
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130
ACTIONS = ('list', 'get', 'set')


class ParamCallError(RuntimeError):
    """A parameter service did not answer, or the node refused the request."""


def build_parser() -> argparse.ArgumentParser:
    """Argument parser of ``uvms param``."""
    parser = argparse.ArgumentParser(
        prog='uvms param',
        description="List, get or set a running node's parameters through its parameter "
                    'services (rcl_interfaces), as ros2 param does.',
        epilog='exit status: 0 done; 1 no answer within --timeout, no such parameter, or the '
               'node refused the value; 2 bad usage; 130 interrupted.')
    parser.add_argument('action', choices=ACTIONS, help='list names, get a value, set one')
    parser.add_argument('node', metavar='NODE',
                        help='node name in the namespace (controller, thruster_allocator, '
                             'simulator, ...) or a full name (/uvms/controller)')
    parser.add_argument('name', metavar='NAME', nargs='?',
                        help='parameter name (get, set), e.g. hybrid.force_kp; list: a '
                             'prefix to list under')
    parser.add_argument('value', metavar='VALUE', nargs='?',
                        help='set: the value, as YAML (0.12, [1.0, 2.0], true, text)')
    parser.add_argument('--namespace', default='/uvms', metavar='NS',
                        help="the graph's namespace (default /uvms)")
    parser.add_argument('--timeout', type=float, default=10.0, metavar='S',
                        help='seconds to wait for each service (default 10)')
    return parser


def parse_value(text: str) -> Any:
    """A command-line value as YAML reads it (as ``ros2 param set`` does)."""
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError:
        return text


def format_value(value: Any) -> str:
    """A parameter value as YAML writes it on one line."""
    if isinstance(value, list | tuple):
        return '[' + ', '.join(format_value(item) for item in value) + ']'
    if isinstance(value, bool):
        return 'true' if value else 'false'
    if value is None:
        return '(not set)'
    return str(value)


def as_type_of(current: Any, value: Any) -> Any:
    """An integer as a float where the parameter holds a float (``3`` for ``3.0``), lists too.

    ROS refuses an integer for a double parameter; YAML writes ``3`` for three.
    """
    def is_int(item: Any) -> bool:
        return isinstance(item, int) and not isinstance(item, bool)

    if isinstance(current, float) and is_int(value):
        return float(value)
    if (isinstance(current, list | tuple) and current and isinstance(current[0], float)
            and isinstance(value, list) and all(is_int(v) or isinstance(v, float)
                                                for v in value)):
        return [float(item) for item in value]
    return value


class ParamClient:
    """list_parameters, get_parameters and set_parameters of one node, called synchronously.

    Args:
        node: an rclpy node to create the clients on.
        target: the node's full name, e.g. ``/uvms/controller``.
        timeout_s: seconds to wait for a service and for each answer.
    """

    def __init__(self, node: Any, target: str, timeout_s: float) -> None:
        from rcl_interfaces.srv import GetParameters, ListParameters, SetParameters

        self._node = node
        self._target = target
        self._timeout_s = timeout_s
        self._list = node.create_client(ListParameters, f'{target}/list_parameters')
        self._get = node.create_client(GetParameters, f'{target}/get_parameters')
        self._set = node.create_client(SetParameters, f'{target}/set_parameters')

    def _call(self, client: Any, request: Any) -> Any:
        return call_service(self._node, client, request, self._timeout_s, ParamCallError,
                            f': no node {self._target} answers (is the graph running on this '
                            'ROS_DOMAIN_ID, in this namespace?)')

    def names(self, prefix: str = '') -> list[str]:
        """Every parameter name of the node (under ``prefix`` if given), sorted."""
        from rcl_interfaces.srv import ListParameters

        request = ListParameters.Request()
        if prefix:
            request.prefixes = [prefix]
        answer = self._call(self._list, request)
        return sorted(answer.result.names)

    def get(self, name: str) -> Any:
        """The value of parameter ``name``.

        Raises:
            ParamCallError: The node has no such parameter.
        """
        from rcl_interfaces.msg import ParameterType
        from rcl_interfaces.srv import GetParameters
        from rclpy.parameter import parameter_value_to_python

        answer = self._call(self._get, GetParameters.Request(names=[name]))
        # rclpy answers an unknown name with no value at all, rclcpp with one of type NOT_SET
        value = answer.values[0] if answer.values else None
        if value is None or value.type == ParameterType.PARAMETER_NOT_SET:
            msg = f'{self._target} has no parameter {name!r}'
            raise ParamCallError(msg)
        return parameter_value_to_python(value)

    def set(self, name: str, value: Any) -> None:
        """Set parameter ``name`` to ``value``.

        Raises:
            ParamCallError: The node refused it (its reason in the message).
        """
        from rcl_interfaces.srv import SetParameters
        from rclpy.parameter import Parameter

        try:
            message = Parameter(name, value=value).to_parameter_msg()
        except TypeError:
            msg = f'{value!r} is no parameter value (bool, int, float, str or a list of one)'
            raise ParamCallError(msg) from None
        answer = self._call(self._set, SetParameters.Request(parameters=[message]))
        (result,) = answer.results
        if not result.successful:
            msg = f'{self._target} refused {name} = {format_value(value)}: {result.reason}'
            raise ParamCallError(msg)


def _target(namespace: str, node: str) -> str:
    """The node's full name: as given when it starts with /, else in the namespace."""
    return node if node.startswith('/') else f'{namespace.rstrip("/")}/{node}'


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``uvms param``; returns the exit status."""
    parser = build_parser()
    try:
        args = parser.parse_args(list(sys.argv[1:] if argv is None else argv))
    except SystemExit as exc:
        return exc.code if isinstance(exc.code, int) else EXIT_USAGE
    if args.action in ('get', 'set') and args.name is None:
        print(f'uvms param: error: {args.action} needs NAME', file=sys.stderr)
        return EXIT_USAGE
    if (args.action == 'set') != (args.value is not None):
        print('uvms param: error: VALUE goes with set only', file=sys.stderr)
        return EXIT_USAGE
    ros_environment_defaults()
    import rclpy
    from rclpy.node import Node

    target = _target(args.namespace, args.node)
    rclpy.init(args=[])
    node = Node('uvms_param_cli', start_parameter_services=False)
    try:
        client = ParamClient(node, target, args.timeout)
        if args.action == 'list':
            for name in client.names(args.name or ''):
                print(name)
        elif args.action == 'get':
            print(format_value(client.get(args.name)))
        else:
            value = parse_value(args.value)
            client.set(args.name, as_type_of(client.get(args.name), value))
            print(f'{target}: {args.name} = {format_value(client.get(args.name))}')
        return EXIT_OK
    except ParamCallError as error:
        print(f'uvms param: error: {error}', file=sys.stderr)
        return EXIT_FAILURE
    except KeyboardInterrupt:
        return EXIT_INTERRUPTED
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
