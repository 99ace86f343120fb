"""Several of our nodes in one process, on one context and one executor (for bench_composed).

Usage (each group: the node class, then its ``--ros-args ...`` as ``uvms launch`` gives them)::

    python bench/composed_nodes.py MODULE:CLASS --ros-args ... --and MODULE:CLASS --ros-args ...

The nodes share the process's DDS participant, so a message between them is delivered inside
the process (Fast DDS's intra-process delivery) instead of over loopback UDP, and one
executor thread serves them all: what a component container (or ros2_control's controller
manager) does. SIGINT or SIGTERM ends it.
"""

from __future__ import annotations

import importlib
import signal
import sys
from typing import Any

import rclpy
from rclpy.context import Context
from rclpy.signals import SignalHandlerOptions
from uvms_common.node_main import make_executor


def groups(argv: list[str]) -> list[tuple[str, list[str]]]:
    """(``MODULE:CLASS``, its arguments) per ``--and``-separated group."""
    out: list[tuple[str, list[str]]] = []
    current: list[str] = []
    for arg in [*argv, '--and']:
        if arg == '--and':
            if current:
                out.append((current[0], current[1:]))
            current = []
        else:
            current.append(arg)
    return out


def main() -> None:
    """Build every node in one context and spin them on one executor until a signal."""
    stopping = []
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, lambda *_: stopping.append(True))
    context = Context()
    rclpy.init(args=[], context=context, signal_handler_options=SignalHandlerOptions.NO)
    nodes: list[Any] = []
    for target, args in groups(sys.argv[1:]):
        module, class_name = target.split(':')
        node_class = getattr(importlib.import_module(module), class_name)
        nodes.append(node_class(context=context, cli_args=args))
    executor = make_executor('events', context)
    for node in nodes:
        executor.add_node(node)
    while not stopping and rclpy.ok(context=context):
        executor.spin_once(timeout_sec=0.1)
    executor.shutdown()
    for node in nodes:
        node.destroy_node()
    rclpy.try_shutdown(context=context)


if __name__ == '__main__':
    main()
