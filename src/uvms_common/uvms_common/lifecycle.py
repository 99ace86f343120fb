"""Managed (lifecycle) nodes that bring themselves to active unless told not to.

A managed node starts unconfigured, as ROS 2 defines it; ours then configure and activate
themselves, so ``ros2 run``, ``uvms run``, ``uvms launch`` and the launch file start a working
graph. ``-p autostart:=false`` leaves the node unconfigured for a lifecycle manager or
``ros2 lifecycle set`` (the ``<node>/change_state`` service)::

    guard_change_state(self)  # an impossible transition is refused, not raised
    if declare_autostart(self) and not autostart(self):
        ...  # the failed transition is logged; stop, or stay in the state it left
"""

from __future__ import annotations

from collections.abc import Callable

from lifecycle_msgs.srv import ChangeState
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.lifecycle import LifecycleNode, TransitionCallbackReturn

__all__ = ['AUTOSTART_PARAMETER', 'autostart', 'declare_autostart', 'guard_change_state',
           'state_label']

#: The read-only bool parameter that decides whether the node activates itself.
AUTOSTART_PARAMETER = 'autostart'


def declare_autostart(node: LifecycleNode) -> bool:
    """Declare the read-only bool parameter ``autostart`` (default true); return its value."""
    descriptor = ParameterDescriptor(
        description='Configure and activate at start-up; false leaves the node unconfigured '
                    'for a lifecycle manager (<node>/change_state)', read_only=True)
    return bool(node.declare_parameter(AUTOSTART_PARAMETER, True, descriptor).value)


def state_label(node: LifecycleNode) -> str:
    """The node's lifecycle state: ``unconfigured``, ``inactive``, ``active``, ``finalized``.

    rclpy (Jazzy) has no public getter; its state machine holds (id, label).
    """
    return str(node._state_machine.current_state[1])  # private: no public getter


def autostart(node: LifecycleNode) -> bool:
    """Configure, then activate the node; log the transition that failed; True if active.

    A transition callback that raised counts as ERROR (rclpy swallows the exception), and
    the node is then back in unconfigured; a FAILURE leaves it in the state it started from.
    """
    steps: tuple[tuple[str, Callable[[], TransitionCallbackReturn]], ...] = (
        ('configure', node.trigger_configure), ('activate', node.trigger_activate))
    for name, trigger in steps:
        result = trigger()
        if result != TransitionCallbackReturn.SUCCESS:
            node.get_logger().error(
                f'autostart: {name} returned {result.to_label()}; the node is '
                f'{state_label(node)}')
            return False
    return True


def guard_change_state(node: LifecycleNode) -> None:
    """Answer a transition the current state has not with ``success: false``, as rclcpp does.

    rclpy 7.1.6's ``<node>/change_state`` service raises RCLError out of the executor for such
    a request (``ros2 lifecycle set <node> configure`` on an active node), which would stop
    the node process; guarded, the request is refused and logged.
    """
    service = node._service_change_state  # private: rclpy keeps the service there
    change_state = service.callback

    def guarded(request: ChangeState.Request,
                response: ChangeState.Response) -> ChangeState.Response:
        try:
            return change_state(request, response)
        except _rclpy.RCLError as error:
            transition = request.transition.label or request.transition.id
            node.get_logger().warning(
                f'change_state refused: transition {transition!r} is not available in state '
                f'{state_label(node)} ({error})')
            response.success = False
            return response

    service.callback = guarded
