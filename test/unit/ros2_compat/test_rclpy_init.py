"""Init, shutdown, contexts and ``--ros-args`` parsing (remaps, unknown flags) of the compat rclpy.

Each test states the behaviour of rclpy (Jazzy) or rcl it mirrors.
"""

from __future__ import annotations

from collections.abc import Iterator

import pytest
import rclpy
from rclpy.context import Context
from rclpy.exceptions import InvalidNodeNameException, NotInitializedException
from rclpy.impl.implementation_singleton import RCLError, UnknownROSArgsError
from rclpy.logging import LoggingSeverity, get_logger_effective_level
from rclpy.node import Node
from rclpy.utilities import remove_ros_args
from std_msgs.msg import String


@pytest.fixture
def fresh_context() -> Iterator[Context]:
    """A context not yet initialized, shut down after the test if it was."""
    ctx = Context()
    yield ctx
    ctx.try_shutdown()


def test_init_returns_none_and_context_is_ok(fresh_context: Context) -> None:
    """As in Jazzy, rclpy.init returns None and ok() is true until shutdown."""
    assert rclpy.init(args=[], context=fresh_context) is None
    assert rclpy.ok(context=fresh_context)
    rclpy.shutdown(context=fresh_context)
    assert not rclpy.ok(context=fresh_context)


def test_init_twice_on_a_context_raises(fresh_context: Context) -> None:
    """As in rclpy, a second init of a context raises 'Context.init() must only be called once'."""
    rclpy.init(args=[], context=fresh_context)
    with pytest.raises(RuntimeError, match=r'Context\.init\(\) must only be called once'):
        rclpy.init(args=[], context=fresh_context)


def test_shutdown_twice_raises_but_try_shutdown_does_not(fresh_context: Context) -> None:
    """As in rclpy, shutdown of a shut-down context raises RCLError; try_shutdown is silent."""
    rclpy.init(args=[], context=fresh_context)
    rclpy.shutdown(context=fresh_context)
    with pytest.raises(RCLError, match='already called'):
        rclpy.shutdown(context=fresh_context)
    rclpy.try_shutdown(context=fresh_context)


def test_default_context_can_be_initialized_again_after_shutdown() -> None:
    """As in rclpy, rclpy.shutdown() retires the default context; init() then makes a new one."""
    rclpy.init(args=[])
    first = rclpy.get_default_context()
    rclpy.shutdown()
    rclpy.init(args=[])
    try:
        assert rclpy.get_default_context() is not first
        assert rclpy.ok()
    finally:
        rclpy.try_shutdown()
    assert not rclpy.ok()


def test_on_shutdown_callbacks_run_once_at_shutdown(fresh_context: Context) -> None:
    """As in rclpy, Context.on_shutdown callbacks run when the context shuts down."""
    rclpy.init(args=[], context=fresh_context)
    calls: list[str] = []
    fresh_context.on_shutdown(lambda: calls.append('down'))
    fresh_context.shutdown()
    fresh_context.try_shutdown()
    assert calls == ['down']


def test_node_before_init_raises_not_initialized(fresh_context: Context) -> None:
    """As in rclpy, creating a node on an uninitialized context raises NotInitializedException."""
    with pytest.raises(NotInitializedException, match=r'rclpy\.init'):
        Node('early', context=fresh_context)


def test_invalid_node_name_raises(fresh_context: Context) -> None:
    """As in rclpy, an invalid node name raises InvalidNodeNameException."""
    rclpy.init(args=[], context=fresh_context)
    with pytest.raises(InvalidNodeNameException, match='node name'):
        Node('bad-name', context=fresh_context)


def test_remove_ros_args_keeps_only_user_arguments() -> None:
    """As in rclpy, remove_ros_args drops every --ros-args ... [--] section."""
    args = ['prog', '--user', '--ros-args', '-p', 'a:=1', '--', 'x', '--ros-args', '-r', 'a:=b']
    assert remove_ros_args(args) == ['prog', '--user', 'x']


def test_unknown_ros_flag_raises_naming_the_flag(fresh_context: Context) -> None:
    """As in rclpy, an unknown flag inside --ros-args raises UnknownROSArgsError naming it."""
    with pytest.raises(UnknownROSArgsError, match=r"Found unknown ROS arguments: \['--bogus'\]"):
        rclpy.init(args=['prog', '--ros-args', '--bogus', '-p', 'a:=1'], context=fresh_context)
    assert not fresh_context.ok()


def test_unknown_ros_flag_in_node_cli_args_raises(fresh_context: Context) -> None:
    """As in rclpy, unknown flags in Node(cli_args=...) raise at node creation."""
    rclpy.init(args=[], context=fresh_context)
    with pytest.raises(UnknownROSArgsError, match='--params'):
        Node('n', context=fresh_context, cli_args=['--ros-args', '--params', 'f.yaml'])


def test_flag_without_its_value_raises_naming_the_flag(fresh_context: Context) -> None:
    """As rcl: a trailing -p with no rule fails ("Couldn't parse trailing -p flag")."""
    with pytest.raises(RCLError, match="Couldn't parse trailing -p flag"):
        rclpy.init(args=['--ros-args', '-p'], context=fresh_context)


def test_malformed_parameter_rule_raises(fresh_context: Context) -> None:
    """As rcl: a -p rule needs 'name:=value'."""
    with pytest.raises(RCLError, match="-p gain=1: expected 'name:=value'"):
        rclpy.init(args=['--ros-args', '-p', 'gain=1'], context=fresh_context)


def test_arguments_outside_ros_args_are_ignored(fresh_context: Context) -> None:
    """As in rclpy, arguments outside --ros-args belong to the program and are not parsed."""
    rclpy.init(args=['prog', '-p', 'not:=ros', '--whatever'], context=fresh_context)
    node = Node('plain', context=fresh_context)
    assert not node.has_parameter('not')
    node.destroy_node()


def test_node_name_and_namespace_remaps(fresh_context: Context) -> None:
    """As rcl: -r __node:=NAME and -r __ns:=/NS rename the node and move it."""
    rclpy.init(args=['--ros-args', '-r', '__node:=renamed', '-r', '__ns:=/robot2'],
               context=fresh_context)
    node = Node('original', namespace='/uvms', context=fresh_context)
    assert node.get_name() == 'renamed'
    assert node.get_namespace() == '/robot2'
    assert node.get_fully_qualified_name() == '/robot2/renamed'
    node.destroy_node()


def test_node_specific_remap_applies_only_to_that_node(fresh_context: Context) -> None:
    """As rcl: -r old:__node:=new renames only the node called 'old'."""
    rclpy.init(args=['--ros-args', '-r', 'controller:__node:=ctl'], context=fresh_context)
    controller = Node('controller', context=fresh_context)
    other = Node('allocator', context=fresh_context)
    assert (controller.get_name(), other.get_name()) == ('ctl', 'allocator')
    controller.destroy_node()
    other.destroy_node()


def test_topic_remap_moves_publisher_and_subscription(fresh_context: Context) -> None:
    """As rcl: -r from:=to applies to expanded names of topics the node creates."""
    rclpy.init(args=['--ros-args', '-r', 'joint_states:=/sim/joints'], context=fresh_context)
    node = Node('controller', namespace='/uvms', context=fresh_context)
    publisher = node.create_publisher(String, 'joint_states', 10)
    subscription = node.create_subscription(String, '/uvms/joint_states', lambda m: None, 10)
    untouched = node.create_publisher(String, 'odometry', 10)
    assert publisher.topic_name == '/sim/joints'
    assert subscription.topic_name == '/sim/joints'
    assert untouched.topic_name == '/uvms/odometry'
    assert node.resolve_topic_name('joint_states', only_expand=True) == '/uvms/joint_states'
    node.destroy_node()


def test_node_cli_remaps_take_precedence_over_global_ones(fresh_context: Context) -> None:
    """As rcl: node-local remap rules are matched before the global ones."""
    rclpy.init(args=['--ros-args', '-r', '__node:=global_name'], context=fresh_context)
    node = Node('n', context=fresh_context, cli_args=['--ros-args', '-r', '__node:=local_name'])
    assert node.get_name() == 'local_name'
    node.destroy_node()


def test_log_level_argument_sets_default_and_named_levels(fresh_context: Context) -> None:
    """As rcl logging: --log-level LEVEL sets the default, --log-level name:=LEVEL one logger."""
    try:
        rclpy.init(
            args=['--ros-args', '--log-level', 'warn', '--log-level', 'noisy:=debug'],
            context=fresh_context,
        )
        assert get_logger_effective_level('anything') == LoggingSeverity.WARN
        assert get_logger_effective_level('noisy.child') == LoggingSeverity.DEBUG
    finally:
        from rclpy.logging import clear_config

        clear_config()


def test_unknown_log_level_raises_naming_it(fresh_context: Context) -> None:
    """As rcl: an unknown --log-level value is an error naming the value."""
    with pytest.raises(RCLError, match="unknown log level 'loud'"):
        rclpy.init(args=['--ros-args', '--log-level', 'loud'], context=fresh_context)


def test_context_manager_initializes_and_shuts_down() -> None:
    """As in rclpy, ``with Context() as ctx`` initializes the context and shuts it down."""
    with Context() as context:
        assert context.ok()
    assert not context.ok()


def test_sigterm_shuts_down_initialized_contexts(fresh_context: Context) -> None:
    """As rclpy's signal handler: SIGTERM shuts every context down (spin then stops)."""
    import os
    import signal

    from rclpy.signals import (
        SignalHandlerOptions,
        install_signal_handlers,
        uninstall_signal_handlers,
    )

    previous = signal.getsignal(signal.SIGTERM)
    rclpy.init(args=[], context=fresh_context, signal_handler_options=SignalHandlerOptions.NO)
    install_signal_handlers(SignalHandlerOptions.SIGTERM)
    try:
        os.kill(os.getpid(), signal.SIGTERM)
        assert not fresh_context.ok()
    finally:
        uninstall_signal_handlers()
    assert signal.getsignal(signal.SIGTERM) is previous


def test_node_failing_at_creation_leaves_no_trace_in_the_graph(fresh_context: Context) -> None:
    """As in rclpy, a wrong-typed use_sim_time override fails Node creation with its type error."""
    from rclpy.exceptions import InvalidParameterTypeException

    rclpy.init(args=['--ros-args', '-p', 'use_sim_time:=1'], context=fresh_context)
    with pytest.raises(InvalidParameterTypeException, match=r"'use_sim_time'.*type 'BOOL'"):
        Node('broken', context=fresh_context)
    local_fix = ['--ros-args', '-p', 'use_sim_time:=false']
    witness = Node('witness', context=fresh_context, cli_args=local_fix)
    names = witness.get_node_names()
    witness.destroy_node()
    assert names == ['witness']
