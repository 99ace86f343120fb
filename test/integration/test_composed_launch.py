"""``uvms launch --compose control``: the control nodes in one process, the same graph.

Both layouts run a few simulated seconds, the paper's case and its estimated variant (whose
estimator joins the composed process); the graph seen from this process holds the same node
names in each, and the composed one has the control nodes in one child.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest
import rclpy
from rclpy.context import Context
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions

BIN = Path(sys.executable).parent
#: Every node of ``case1_ke1e4``, as ``uvms launch`` names them.
NODES = {'simulator', 'controller', 'thruster_allocator', 'visualizer', 'mission'}
#: The nodes of the control composition, per scenario.
COMPOSED_NODES = {'case1_ke1e4': {'controller', 'thruster_allocator'},
                  'case1_estimated': {'estimator', 'controller', 'thruster_allocator'}}
#: Nodes whose names the graph must show (discovery of the others' names can lag the run on
#: a loaded machine; their command lines name them).
SEEN_IN_GRAPH = {'simulator', 'controller', 'thruster_allocator'}
#: Half of real time. The layout is under test here, not the machine's speed: at 1.0 the
#: separate graph of case1_estimated takes 186-193 % of one core of this 2-core machine (its
#: cost table, quiet machine), so on a slower one it cannot keep its periods at all. In the
#: landing CI of 2026-12-07 its SCHED_FIFO processes got 125 % of a core, missed 11-16 % of
#: their periods (worst 104-112 ms late) and the stale commands tripped the controller's
#: position limit: 3 of the 4 runs failed. The claims at 1.0 are the benches' (bench/).
REAL_TIME_FACTOR = 0.5


def child_env() -> dict[str, str]:
    """This test's sources first on the children's path (they import this tree)."""
    return {**os.environ, 'PYTHONUNBUFFERED': '1',
            'PYTHONPATH': os.pathsep.join(p for p in sys.path if p)}


def graph_nodes(process: subprocess.Popen[str], timeout_s: float,
                children_seen: dict[int, list[str]], expected_processes: int) -> set[str]:
    """Names of the nodes in /uvms once ``SEEN_IN_GRAPH`` and the processes are seen.

    The launcher's children seen meanwhile are collected into ``children_seen``.
    """
    context = Context()
    rclpy.init(args=[], context=context, domain_id=int(os.environ['ROS_DOMAIN_ID']),
               signal_handler_options=SignalHandlerOptions.NO)
    node = Node('composed_observer', context=context)
    seen: set[str] = set()
    try:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline and process.poll() is None:
            children_seen.update(children(process.pid))
            seen |= {name for name, ns in node.get_node_names_and_namespaces() if ns == '/uvms'}
            if SEEN_IN_GRAPH <= seen and len(children_seen) >= expected_processes:
                break
            time.sleep(0.2)
    finally:
        node.destroy_node()
        rclpy.try_shutdown(context=context)
    return seen


def children(pid: int) -> dict[int, list[str]]:
    """Command lines of the node processes among the children of ``pid``, by pid."""
    out = {}
    for entry in Path('/proc').iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / 'stat').read_text()
                cmdline = (entry / 'cmdline').read_bytes().decode().split('\0')
            except OSError:
                continue
            # Node processes only: not the launcher's probe of SCHED_FIFO (a short child).
            if int(stat.rsplit(')', 1)[1].split()[1]) == pid and '--ros-args' in cmdline:
                out[int(entry.name)] = cmdline
    return out


@pytest.mark.parametrize('scenario', sorted(COMPOSED_NODES))
@pytest.mark.parametrize('compose', [None, 'control'])
def test_the_graph_runs_with_the_same_node_names_composed_or_not(compose: str | None,
                                                                  scenario: str) -> None:
    """A short run ends with status 0; the node names do not depend on the layout."""
    nodes = NODES | COMPOSED_NODES[scenario]
    command = [str(BIN / 'uvms'), 'launch', scenario, '--duration', '6',
               '--real-time-factor', str(REAL_TIME_FACTOR)]
    if compose is not None:
        command += ['--compose', compose]
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                               text=True, env=child_env(), stdin=subprocess.DEVNULL)
    try:
        seen_children: dict[int, list[str]] = {}
        expected = len(nodes) - (len(COMPOSED_NODES[scenario]) - 1 if compose else 0)
        names = graph_nodes(process, 90.0, seen_children, expected)
        processes = list(seen_children.values())
        _, err = process.communicate(timeout=120)
    finally:
        if process.poll() is None:
            process.kill()
            process.communicate()
    assert process.returncode == 0, err
    assert names >= SEEN_IN_GRAPH, (names, err)
    named = {a.split(':=')[1] for cmd in processes for a in cmd if a.startswith('__node:=')}
    assert named == nodes
    composed = [cmd for cmd in processes if sum(a.startswith('__node:=') for a in cmd) > 1]
    if compose is None:
        assert composed == [] and len(processes) == len(nodes)
    else:
        [command_line] = composed
        in_one = [a.split(':=')[1] for a in command_line if a.startswith('__node:=')]
        assert set(in_one) == COMPOSED_NODES[scenario]
        assert len(processes) == expected
        assert f'{"+".join(in_one)} in one process' in err
