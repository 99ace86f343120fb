"""DiagnosticsPublisher reports a real rclpy node's checks on /diagnostics."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator

import pytest
import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from rclpy.context import Context
from rclpy.executors import Executor
from rclpy.node import Node
from uvms_common.diagnostics import (
    ERROR,
    OK,
    STALE,
    WARN,
    DiagnosticsPublisher,
    RateMeter,
    Report,
    format_value,
    robot_name,
)
from uvms_common.node_main import make_executor


class Graph:
    """A context, an EventsExecutor, the node under test in /uvms and a listener node."""

    def __init__(self) -> None:
        self.context = Context()
        rclpy.init(args=[], context=self.context)
        self.executor: Executor = make_executor('events', self.context)
        self.node = Node('reporter', namespace='uvms', context=self.context)
        self.listener = Node('listener', context=self.context)
        self.arrays: list[DiagnosticArray] = []
        # Absolute topic: a node in another namespace hears it.
        self.listener.create_subscription(DiagnosticArray, '/diagnostics', self.arrays.append,
                                          10)
        for node in (self.node, self.listener):
            self.executor.add_node(node)

    def spin_until(self, done: Callable[[], bool], timeout_s: float = 5.0) -> bool:
        """Spin until done() or the wall-clock timeout."""
        deadline = time.monotonic() + timeout_s
        while not done():
            if time.monotonic() > deadline:
                return False
            self.executor.spin_once(timeout_sec=0.01)
        return True

    def close(self) -> None:
        """Destroy the nodes and shut the context down."""
        self.executor.shutdown()
        for node in (self.node, self.listener):
            node.destroy_node()
        rclpy.try_shutdown(context=self.context)


@pytest.fixture
def graph() -> Iterator[Graph]:
    """A fresh in-process graph."""
    g = Graph()
    yield g
    g.close()


def statuses(array: DiagnosticArray) -> dict[str, DiagnosticStatus]:
    """Status name -> status."""
    return {status.name: status for status in array.status}


def test_each_check_is_a_status_named_after_node_and_task(graph: Graph) -> None:
    """Names '<node>: <task>', the hardware_id, the level as bytes, values as strings."""
    diagnostics = DiagnosticsPublisher(graph.node, hardware_id='bluerov_alpha', period_s=0.1)
    diagnostics.add('stepping', lambda: Report(OK, 'running', {'rate_hz': 499.8123, 'n': 3}))
    diagnostics.add('input', lambda: Report(WARN, 'stale input', {'age_s': None}))
    assert graph.spin_until(lambda: len(graph.arrays) >= 1)
    found = statuses(graph.arrays[0])
    assert sorted(found) == ['reporter: input', 'reporter: process', 'reporter: stepping']
    stepping, stale = found['reporter: stepping'], found['reporter: input']
    assert (stepping.level, stepping.message, stepping.hardware_id) == (
        DiagnosticStatus.OK, 'running', 'bluerov_alpha')
    assert [(kv.key, kv.value) for kv in stepping.values] == [('rate_hz', '499.8'), ('n', '3')]
    assert stale.level == DiagnosticStatus.WARN == b'\x01'
    assert [(kv.key, kv.value) for kv in stale.values] == [('age_s', 'none')]


def test_publications_follow_the_period_of_the_node_clock(graph: Graph) -> None:
    """Ten periods of 0.05 s take about 0.5 s of the node's (system) clock."""
    DiagnosticsPublisher(graph.node, period_s=0.05).add('t', lambda: Report(OK, 'ok'))
    assert graph.spin_until(lambda: len(graph.arrays) >= 11)
    stamps = [a.header.stamp.sec + a.header.stamp.nanosec * 1e-9 for a in graph.arrays[:11]]
    assert stamps[-1] - stamps[0] == pytest.approx(0.5, abs=0.15)


def test_a_check_that_raises_is_an_error_status_and_the_node_goes_on(graph: Graph) -> None:
    """The exception is named in an ERROR status; the other checks and later periods go on."""
    def broken() -> Report:
        raise ZeroDivisionError('division by zero')

    diagnostics = DiagnosticsPublisher(graph.node, period_s=0.05)
    diagnostics.add('broken', broken)
    diagnostics.add('level', lambda: Report(3, 'int level'))  # type: ignore[arg-type]
    diagnostics.add('fine', lambda: Report(STALE, 'no data yet'))
    assert graph.spin_until(lambda: len(graph.arrays) >= 3)
    found = statuses(graph.arrays[-1])
    assert found['reporter: broken'].level == ERROR
    assert found['reporter: broken'].message == 'check failed: ZeroDivisionError: division by zero'
    assert found['reporter: level'].level == ERROR
    assert 'level 3' in found['reporter: level'].message
    assert found['reporter: fine'].level == STALE


def test_update_publishes_at_once_and_destroy_stops_the_publications(graph: Graph) -> None:
    """update() returns what it publishes; after destroy() nothing more comes."""
    diagnostics = DiagnosticsPublisher(graph.node, period_s=3600.0)
    diagnostics.add('t', lambda: Report(OK, 'ok'))
    array = diagnostics.update()
    assert graph.spin_until(lambda: len(graph.arrays) == 1)
    assert graph.arrays[0].status[0].name == array.status[0].name == 'reporter: t'
    diagnostics.destroy()
    diagnostics.destroy()
    periodic = DiagnosticsPublisher(graph.node, period_s=0.02)
    assert graph.spin_until(lambda: len(graph.arrays) >= 3)
    periodic.destroy()
    graph.spin_until(lambda: False, timeout_s=0.1)  # deliver what was on its way
    count = len(graph.arrays)
    graph.spin_until(lambda: False, timeout_s=0.2)
    assert len(graph.arrays) == count


@pytest.mark.parametrize('period_s', [0.0, -1.0, float('nan')])
def test_a_period_that_is_not_positive_is_refused(graph: Graph, period_s: float) -> None:
    """The message names the argument and what is valid."""
    with pytest.raises(ValueError, match='period_s'):
        DiagnosticsPublisher(graph.node, period_s=period_s)


def test_rate_meter_gives_the_growth_per_second_between_reads() -> None:
    """None at the first read or without elapsed time, then delta count / delta time."""
    meter = RateMeter()
    assert meter.rate_hz(5, 1_000_000_000) is None
    assert meter.rate_hz(5, 1_000_000_000) is None
    assert meter.rate_hz(105, 1_500_000_000) == pytest.approx(200.0)
    assert meter.rate_hz(105, 2_500_000_000) == 0.0


@pytest.mark.parametrize(('value', 'text'), [
    (0.5, '0.5'), (1234567.0, '1.235e+06'), (float('nan'), 'nan'), (False, 'false'),
    (None, 'none'), (7, '7'), ('active', 'active')])
def test_values_are_formatted_for_people(value: object, text: str) -> None:
    """Floats to 4 significant digits, bools and None in lower case."""
    assert format_value(value) == text


def test_robot_name_comes_from_the_urdf_of_the_project() -> None:
    """The project's URDF names its robot 'uvms'; text without a robot gives the default."""
    import uvms_description

    assert robot_name(uvms_description.urdf_path().read_text()) == 'uvms'
    assert robot_name("<robot version='1.0' name='alpha_5'/>") == 'alpha_5'
    assert robot_name('<link name="x"/>') == 'uvms'


def test_levels_are_the_message_constants() -> None:
    """OK/WARN/ERROR/STALE are diagnostic_msgs' byte constants, 0..3."""
    assert (OK, WARN, ERROR, STALE) == (b'\x00', b'\x01', b'\x02', b'\x03')


def test_every_node_reports_what_its_process_costs(graph: Graph) -> None:
    """'<node>: process' comes last, with CPU % of a core, missed periods, worst lateness."""
    diagnostics = DiagnosticsPublisher(graph.node, period_s=3600.0)
    diagnostics.add('t', lambda: Report(OK, 'ok'))
    array = diagnostics.update()
    process = array.status[-1]
    assert process.name == 'reporter: process'
    keys = [value.key for value in process.values]
    assert keys == ['cpu_percent', 'periods', 'missed', 'missed_share', 'worst_late_ms']
