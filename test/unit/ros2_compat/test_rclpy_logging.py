"""Loggers of the compat rclpy: rcutils console format, levels, call-site filters, /rosout.

Each test states the behaviour of rclpy / rcutils (Jazzy) it mirrors.
"""

from __future__ import annotations

import re
from collections.abc import Iterator

import pytest
from rcl_interfaces.msg import Log
from rclpy.clock import ROSClock
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.logging import LoggingSeverity, clear_config, get_logger
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile
from rclpy.time import Time


@pytest.fixture(autouse=True)
def clean_levels(monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """Default console settings, and no logger levels left behind."""
    for name in ('RCUTILS_CONSOLE_OUTPUT_FORMAT', 'RCUTILS_COLORIZED_OUTPUT',
                 'RCUTILS_LOGGING_USE_STDOUT'):
        monkeypatch.delenv(name, raising=False)
    clear_config()
    yield
    clear_config()


def test_console_line_has_ros2_format_on_stderr(capfd: pytest.CaptureFixture[str]) -> None:
    """As rcutils: '[INFO] [<sec>.<nsec>] [name]: message' on stderr by default."""
    get_logger('format_check').info('hello world')
    out, err = capfd.readouterr()
    assert out == ''
    assert re.fullmatch(r'\[INFO\] \[\d+\.\d{9}\] \[format_check\]: hello world\n', err)


def test_node_logger_is_named_after_namespace_and_node(
    context: Context, capfd: pytest.CaptureFixture[str]
) -> None:
    """As rcl: a node's logger name is its namespace and name joined with dots."""
    node = Node('controller', namespace='/uvms', context=context)
    node.get_logger().warning('careful')
    node.destroy_node()
    err = capfd.readouterr().err
    assert node.get_logger().name == 'uvms.controller'
    assert '[WARN]' in err and '[uvms.controller]: careful' in err


def test_debug_is_hidden_until_the_level_allows_it(capfd: pytest.CaptureFixture[str]) -> None:
    """As rcutils: the default level is INFO; set_level(DEBUG) shows debug messages."""
    logger = get_logger('quiet')
    assert not logger.debug('hidden')
    logger.set_level(LoggingSeverity.DEBUG)
    assert logger.debug('shown')
    err = capfd.readouterr().err
    assert 'hidden' not in err and '[DEBUG]' in err and 'shown' in err


def test_child_logger_inherits_the_level_of_its_parent() -> None:
    """As rcutils: a logger without a level uses its nearest dotted ancestor's level."""
    get_logger('uvms').set_level(LoggingSeverity.ERROR)
    child = get_logger('uvms').get_child('controller')
    assert child.name == 'uvms.controller'
    assert child.get_effective_level() == LoggingSeverity.ERROR
    assert not child.is_enabled_for(LoggingSeverity.WARN)


def test_once_logs_only_the_first_call(capfd: pytest.CaptureFixture[str]) -> None:
    """As rclpy: once=True logs a call site's first message only."""
    logger = get_logger('filters')
    results = [logger.info(f'call {i}', once=True) for i in range(3)]
    assert results == [True, False, False]
    assert capfd.readouterr().err.count('call') == 1


def test_skip_first_drops_the_first_call(capfd: pytest.CaptureFixture[str]) -> None:
    """As rclpy: skip_first=True drops a call site's first message."""
    logger = get_logger('filters')
    results = [logger.info(f'call {i}', skip_first=True) for i in range(3)]
    assert results == [False, True, True]
    assert 'call 0' not in capfd.readouterr().err


def test_throttle_limits_messages_per_duration_of_the_given_clock(
    capfd: pytest.CaptureFixture[str],
) -> None:
    """As rclpy: throttle_duration_sec logs at most once per duration of the given clock."""
    clock = ROSClock()
    clock._set_ros_time_is_active(True)
    logger = get_logger('throttled')
    logged = []
    for step_ms in range(0, 2500, 100):
        clock.set_ros_time_override(Time(nanoseconds=(1000 + step_ms) * 1_000_000))
        logged.append(
            logger.warning('tick', throttle_duration_sec=1.0, throttle_time_source_type=clock)
        )
    capfd.readouterr()
    assert [i * 100 for i, was in enumerate(logged) if was] == [0, 1000, 2000]


def test_non_string_message_raises_type_error() -> None:
    """As rclpy: log messages must be str."""
    with pytest.raises(TypeError, match='must be a str'):
        get_logger('typed').info(42)  # type: ignore[arg-type]


def test_unknown_logging_keyword_raises_type_error() -> None:
    """As rclpy: a keyword that is not a logging filter raises TypeError."""
    with pytest.raises(TypeError, match='throttle'):
        get_logger('typed').info('x', throttle=1.0)


def test_output_format_follows_rcutils_environment_variable(
    capfd: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """As rcutils: RCUTILS_CONSOLE_OUTPUT_FORMAT chooses the line layout."""
    monkeypatch.setenv('RCUTILS_CONSOLE_OUTPUT_FORMAT', '{severity}|{name}|{message}')
    get_logger('custom').error('boom')
    assert capfd.readouterr().err == 'ERROR|custom|boom\n'


def test_node_log_messages_are_published_on_rosout(
    context: Context, capfd: pytest.CaptureFixture[str]
) -> None:
    """As rcl with rosout enabled: a node's log messages are rcl_interfaces/Log on /rosout."""
    node = Node('chatty', context=context)
    listener = Node('listener', context=context)
    received: list[Log] = []
    listener.create_subscription(
        Log, '/rosout', received.append,
        QoSProfile(depth=10, durability=DurabilityPolicy.TRANSIENT_LOCAL),
    )
    node.get_logger().info('to rosout')
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(listener)
    executor.spin_once(timeout_sec=0)
    executor.shutdown()
    node.destroy_node()
    listener.destroy_node()
    capfd.readouterr()
    assert [(m.name, m.msg, m.level) for m in received] == [('chatty', 'to rosout', Log.INFO)]
