"""``uvms launch --compose control``: the control nodes in one process, the same graph.

Both layouts run the estimated case for a few simulated seconds; the graph seen from this
process holds the same node names in each, and the composed one has them in one child.
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
#: Every node of ``case1_estimated``, as ``uvms launch`` names them.
NODES = {'simulator', 'estimator', 'controller', 'thruster_allocator', 'visualizer', 'mission'}


def child_env() -> dict[str, str]:
    """This test's sources first on the children's path (they import this tree)."""
    return {**os.environ, 'PYTHONUNBUFFERED': '1',
            'PYTHONPATH': os.pathsep.join(p for p in sys.path if p)}


def graph_nodes(process: subprocess.Popen[str], timeout_s: float) -> set[str]:
    """Names of the nodes in /uvms once all of ``NODES`` are seen (or the timeout passed)."""
    context = Context()
    rclpy.init(args=[], context=context, domain_id=int(os.environ['ROS_DOMAIN_ID']),
               signal_handler_options=SignalHandlerOptions.NO)
    node = Node('composed_observer', context=context)
    seen: set[str] = set()
    try:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline and process.poll() is None:
            seen = {name for name, ns in node.get_node_names_and_namespaces() if ns == '/uvms'}
            if NODES <= seen:
                break
            time.sleep(0.2)
    finally:
        node.destroy_node()
        rclpy.try_shutdown(context=context)
    return seen


def children(pid: int) -> list[list[str]]:
    """Command lines of the direct children of ``pid``."""
    out = []
    for entry in Path('/proc').iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / 'stat').read_text()
                cmdline = (entry / 'cmdline').read_bytes().decode().split('\0')
            except OSError:
                continue
            if int(stat.rsplit(')', 1)[1].split()[1]) == pid:
                out.append(cmdline)
    return out


@pytest.mark.parametrize('compose', [None, 'control'])
def test_the_graph_runs_with_the_same_node_names_composed_or_not(compose: str | None) -> None:
    """A short estimated run ends with status 0; the node names do not depend on the layout."""
    command = [str(BIN / 'uvms'), 'launch', 'case1_estimated', '--duration', '3']
    if compose is not None:
        command += ['--compose', compose]
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                               text=True, env=child_env(), stdin=subprocess.DEVNULL)
    try:
        names = graph_nodes(process, 90.0)
        processes = children(process.pid)
        _, err = process.communicate(timeout=120)
    finally:
        if process.poll() is None:
            process.kill()
            process.communicate()
    assert process.returncode == 0, err
    assert names >= NODES, (names, err)
    composed = [cmd for cmd in processes if sum(a.startswith('__node:=') for a in cmd) > 1]
    if compose is None:
        assert composed == [] and len(processes) == len(NODES)
    else:
        [command_line] = composed
        assert {a.split(':=')[1] for a in command_line if a.startswith('__node:=')} == {
            'estimator', 'controller', 'thruster_allocator'}
        assert len(processes) == len(NODES) - 2
        assert 'estimator+controller+thruster_allocator in one process' in err
