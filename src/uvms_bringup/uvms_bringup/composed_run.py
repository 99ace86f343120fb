"""The composed process's main loop: ``uvms_common.node_main.run_node`` for several nodes.

The same steps as a node process (rclpy without its signal handlers, a stop event checked
between short executor turns, the nodes off the executor before it shuts down, a bounded
teardown), with every node of the group built on one context and added to one executor.
The process asks for real-time scheduling once, with the first node's ``rt_*`` parameters.
Started as ``python -m uvms_bringup.composed`` (the launcher's way), it leaves the
middleware's teardown to the process's end, as a node process does (issue 48).
"""

from __future__ import annotations

import contextlib
import importlib
import threading
from collections.abc import Sequence
from typing import Any

import rclpy
from rclpy.executors import Executor, ExternalShutdownException
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions
from uvms_common.node_entry import end_unbuilt, process_ends_after_main
from uvms_common.node_main import (
    ACK_WAIT_S,
    TeardownDeadline,
    make_executor,
    middleware_teardown_skipped,
    profiled,
    schedule_process,
    spin_until_stopped,
    wait_for_acks,
)
from uvms_common.realtime import process_periods
from uvms_common.ros_environment import ros_environment_defaults
from uvms_common.stop_event import StopEvent
from uvms_hardware.robot_loop import RobotLoop

from uvms_bringup.launch_helpers import NodeSpec
from uvms_common import direct_topics, process_stats

#: Logger of the process's own lines (errors that are no one node's).
LOGGER = 'composed'
#: Name of the process's stats file for its launcher (``uvms_common.process_stats``): the
#: name the launcher gives the process (``composed.COMPOSED``).
COMPOSED_STATS = 'control'


def start_loop(nodes: Sequence[Node]) -> RobotLoop:
    """The robot loop over the built nodes, its timer on the controller at its rate."""
    bus = direct_topics.active_bus()
    assert bus is not None
    controller = next((n for n in nodes if n.get_name() == 'controller'), nodes[0])
    rate_hz = float(controller.get_parameter('control_rate_hz').value
                    if controller.has_parameter('control_rate_hz') else 100.0)
    robot_loop = RobotLoop(bus, nodes, rate_hz)
    robot_loop.start(controller)
    rclpy.logging.get_logger(LOGGER).info(
        f'robot loop at {rate_hz:g} Hz: {len(bus.timers)} device timers, direct topics '
        + ', '.join(sorted(t for t, subs in bus.subscriptions.items() if subs))
        + (f'; on DDS (no publisher in the process): {", ".join(robot_loop.fallbacks)}'
           if robot_loop.fallbacks else ''))
    return robot_loop


def put_back_all(nodes: Sequence[Node], logger: Any) -> None:
    """Every bridge's ``put_back_now``, each in its own thread; wait for all of them."""
    def put_back(node: Node) -> None:
        try:
            node.put_back_now()  # type: ignore[attr-defined]
        except Exception as exc:
            logger.error(f'{node.get_name()}: putting the device back: '
                         f'{type(exc).__name__}: {exc}')

    threads = [threading.Thread(target=put_back, args=(node,), name=node.get_name())
               for node in nodes if hasattr(node, 'put_back_now')]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()


def build_node(spec: NodeSpec, args: Sequence[str]) -> Node:
    """One node of the group, from its module and class, with its own ``--ros-args``."""
    node_class = getattr(importlib.import_module(spec.module), spec.class_name)
    node: Node = node_class(cli_args=list(args))
    return node


def run_composed(groups: Sequence[tuple[NodeSpec, Sequence[str]]], stop: StopEvent,
                 loop: bool = False) -> int:
    """Build the nodes in order, spin them on one executor until a stop; the exit status.

    ``loop``: the nodes' direct topics and device timers are served by one robot loop at the
    controller's rate (``uvms_hardware.robot_loop``) instead of DDS and their own timers.
    """
    ros_environment_defaults()
    rclpy.init(args=[], signal_handler_options=SignalHandlerOptions.NO)
    logger = rclpy.logging.get_logger(LOGGER)
    nodes: list[Node] = []
    executor: Executor | None = None
    status = 0
    current = ''
    robot_loop: RobotLoop | None = None
    if loop:
        direct_topics.install(direct_topics.Bus())
    try:
        # A stop ends the process at once, as it ends a node process's build
        # (node_entry.end_unbuilt), until a bridge's activate starts changing its device
        # (defer_stop_end, for the rest of the builds): then it waits and puts back.
        with (stop.ending(end_unbuilt) if process_ends_after_main()
              else contextlib.nullcontext()):
            for spec, args in groups:
                current = spec.name
                nodes.append(build_node(spec, args))
                if stop.is_set():
                    break
        current = ''
        if loop:
            robot_loop = start_loop(nodes)
        schedule_process(nodes[0])
        executor = make_executor()
        for node in nodes:
            executor.add_node(node)
        with profiled(LOGGER):
            spin_until_stopped(executor, stop)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except Exception as exc:
        where = f'{current}: ' if current else ''
        logger.fatal(f'{where}{type(exc).__name__}: {exc}')
        status = 1
    finally:
        process_stats.write(COMPOSED_STATS, process_periods())
        if robot_loop is not None:
            logger.info(robot_loop.summary())
        # Devices first, before the teardown's deadline is armed: a bridge's restore (the
        # vehicle disarmed, its outputs' functions back) must not be cut short by it.
        # All at once, as separate bridge processes do: one device's bounded restore (the
        # vehicle's disarm) must not wait for another's, or for a device side that is
        # stopping meanwhile.
        put_back_all(nodes, logger)
        deadline = TeardownDeadline(LOGGER, status)
        if process_ends_after_main():
            # As a node process (uvms_common.node_main): the nodes' own end, not the
            # middleware's, which the process's end makes needless (issue 48).
            with middleware_teardown_skipped():
                for node in reversed(nodes):
                    node.destroy_node()
            for node in nodes:
                wait_for_acks(node, ACK_WAIT_S / len(nodes))
        else:
            if executor is not None:
                for node in nodes:
                    if node in executor.get_nodes():
                        executor.remove_node(node)
                executor.shutdown()
            for node in reversed(nodes):
                node.destroy_node()
            rclpy.try_shutdown()
        deadline.cancel()
    return status
