"""``uvms lifecycle NODE ACTION``: a managed node's state, and its transitions, from a shell.

The managed (lifecycle) nodes are ``MANAGED_NODES``: the controller, the thruster
allocator, the estimator and the four hardware bridges. This command calls their real
lifecycle services, ``/<ns>/<node>/get_state`` (lifecycle_msgs/srv/GetState) and
``/<ns>/<node>/change_state`` (lifecycle_msgs/srv/ChangeState), as ``ros2 lifecycle`` would
without a ROS install. ``reset`` is deactivate then activate: it clears the controller's
safe hold (docs/interfaces.md, "Safety")::

    uvms lifecycle controller get       # active
    uvms lifecycle controller reset     # active -> inactive -> active

Exit status: 0 done, 1 the node did not answer or refused the transition (the line says its
state), 2 bad usage, 130 interrupted.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import Any

from uvms_common.ros_environment import ros_environment_defaults

from uvms_cli.service_call import call_service

EXIT_OK = 0
EXIT_FAILURE = 1
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130
#: Transitions by name, in the order ``reset`` and the help list them.
TRANSITIONS = ('configure', 'activate', 'deactivate', 'cleanup')
ACTIONS = ('get', *TRANSITIONS, 'reset')
#: Every managed (lifecycle) node of the graph: the loop nodes, the estimator
#: (``state_source: estimate``) and the hardware bridges (``--hardware``).
MANAGED_NODES = ('controller', 'thruster_allocator', 'estimator', 'ardusub_bridge',
                 'dvl_bridge', 'alpha5_bridge', 'netft_bridge')
#: The command that clears a latched safe hold (named by the controller's refusal and log).
RESET_COMMAND = 'uvms lifecycle controller reset'


class LifecycleCallError(RuntimeError):
    """A lifecycle service did not answer, or refused the transition."""


def build_parser() -> argparse.ArgumentParser:
    """Argument parser of ``uvms lifecycle``."""
    parser = argparse.ArgumentParser(
        prog='uvms lifecycle',
        description="Get or change a managed node's lifecycle state through its "
                    'get_state and change_state services (lifecycle_msgs). reset is '
                    "deactivate then activate: it clears the controller's safe hold.",
        epilog='exit status: 0 done; 1 no answer within --timeout, or the node refused the '
               'transition; 2 bad usage; 130 interrupted.')
    parser.add_argument('node', metavar='NODE',
                        help='node name in the namespace, a managed node: '
                             f'{", ".join(MANAGED_NODES)} (the last four with --hardware)')
    parser.add_argument('action', choices=ACTIONS,
                        help='get the state, make one transition, or reset (deactivate, '
                             'activate)')
    parser.add_argument('--namespace', default='/uvms', metavar='NS',
                        help="the graph's namespace (default /uvms)")
    parser.add_argument('--timeout', type=float, default=10.0, metavar='S',
                        help='seconds to wait for each service (default 10)')
    return parser


class LifecycleClient:
    """get_state and change_state of one managed node, called synchronously.

    Args:
        node: an rclpy node to create the clients on.
        target: the managed node's full name, e.g. ``/uvms/controller``.
        timeout_s: seconds to wait for a service and for each answer.
    """

    def __init__(self, node: Any, target: str, timeout_s: float) -> None:
        from lifecycle_msgs.srv import ChangeState, GetState

        self._node = node
        self._target = target
        self._timeout_s = timeout_s
        self._get = node.create_client(GetState, f'{target}/get_state')
        self._change = node.create_client(ChangeState, f'{target}/change_state')

    def _call(self, client: Any, request: Any) -> Any:
        return call_service(self._node, client, request, self._timeout_s, LifecycleCallError,
                            ' (is the graph running on this ROS_DOMAIN_ID, and is the node '
                            'managed?)')

    def state(self) -> str:
        """The node's current state label (``unconfigured``, ``inactive``, ``active``, ...)."""
        from lifecycle_msgs.srv import GetState

        return str(self._call(self._get, GetState.Request()).current_state.label)

    def transition(self, name: str) -> str:
        """Make the transition ``name``; the state it led to. Raises if refused."""
        from lifecycle_msgs.msg import Transition
        from lifecycle_msgs.srv import ChangeState

        request = ChangeState.Request()
        request.transition.id = getattr(Transition, f'TRANSITION_{name.upper()}')
        answer = self._call(self._change, request)
        state = self.state()
        if not answer.success:
            msg = f'{self._target} refused {name} (it is {state})'
            raise LifecycleCallError(msg)
        return state


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``uvms lifecycle``; returns the exit status."""
    parser = build_parser()
    try:
        args = parser.parse_args(list(sys.argv[1:] if argv is None else argv))
    except SystemExit as exc:
        return exc.code if isinstance(exc.code, int) else EXIT_USAGE
    ros_environment_defaults()
    import rclpy
    from rclpy.node import Node

    target = f'{args.namespace.rstrip("/")}/{args.node}'
    rclpy.init(args=[])
    node = Node('uvms_lifecycle_cli')
    try:
        client = LifecycleClient(node, target, args.timeout)
        steps = (('deactivate', 'activate') if args.action == 'reset'
                 else () if args.action == 'get' else (args.action,))
        states = [client.state()]
        for step in steps:
            states.append(client.transition(step))
        print(f'{target}: {" -> ".join(states)}')
        return EXIT_OK
    except LifecycleCallError as error:
        print(f'uvms lifecycle: error: {error}', file=sys.stderr)
        return EXIT_FAILURE
    except KeyboardInterrupt:
        return EXIT_INTERRUPTED
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
