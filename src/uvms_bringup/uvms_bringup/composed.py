"""A composed process: several nodes of the graph in one process, on one executor.

``uvms launch --compose control`` runs the controller, the thruster allocator and the
estimator (when the scenario has one) in one process, as a component container (or
ros2_control's controller manager) would: the same node names, topics, parameters and
lifecycle, each node built with its own ``--ros-args`` (its remaps and parameter files), on
one context and one EventsExecutor thread. Their messages to each other then stay in the
process (Fast DDS's intra-process delivery) instead of crossing loopback UDP, and one
executor's wake-ups serve the three. The price: a crash of one takes the others down with it,
and one slow callback delays the others' (docs/running.md, "A composed control process").

Usage (each group: a node name of ``COMPOSITIONS``, then its ``--ros-args ...`` as
``uvms launch`` gives them)::

    python -m uvms_bringup.composed controller --ros-args ... --and thruster_allocator ...

The module is light to import (rclpy and the nodes load in ``main``, after the stop handlers),
so a launcher stopping it during start-up gets status 0 and no traceback, as a node's console
script does (``uvms_common.node_entry``).
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING

from uvms_bringup.launch_helpers import (
    CONTROLLER,
    ESTIMATOR,
    HARDWARE_BRIDGES,
    THRUSTER_ALLOCATOR,
    NodeSpec,
)

if TYPE_CHECKING:
    from uvms_bringup.processes import NodeProcessSpec

#: Node sets that ``--compose`` may put in one process, by name. The allocator's module is
#: named once, in ``launch_helpers.THRUSTER_ALLOCATOR``.
COMPOSITIONS: dict[str, tuple[NodeSpec, ...]] = {
    'control': (ESTIMATOR, CONTROLLER, THRUSTER_ALLOCATOR),
    # What runs on the robot's computer: the control nodes and the device bridges in one
    # real-time loop (uvms_hardware.robot_loop): a device's reading reaches the controller,
    # and its command the device, by function calls in one period.
    'robot': (ESTIMATOR, CONTROLLER, THRUSTER_ALLOCATOR, *HARDWARE_BRIDGES.values()),
    # The same nodes on their own timers, talking through DDS (intra-process): the layout
    # before the robot loop, kept for comparison (bench/bench_robot_side.py).
    'robot-topics': (ESTIMATOR, CONTROLLER, THRUSTER_ALLOCATOR, *HARDWARE_BRIDGES.values()),
}
#: Compositions run by the robot loop instead of each node's own timers.
LOOPED = frozenset({'robot'})
#: The first argument of a composed process run by the robot loop.
LOOP_FLAG = '--loop'
#: The composed process as the launcher names it (``control``: the process of the group).
COMPOSED = NodeSpec('control', 'uvms_bringup', 'control_container', 'uvms_bringup.composed',
                    '', ())
#: Separates the node groups on the command line.
SEPARATOR = '--and'


def node_groups(argv: Sequence[str]) -> list[tuple[str, list[str]]]:
    """(node name, its arguments) per ``--and``-separated group of the command line."""
    out: list[tuple[str, list[str]]] = []
    current: list[str] = []
    for arg in [*argv, SEPARATOR]:
        if arg == SEPARATOR:
            if current:
                out.append((current[0], current[1:]))
            current = []
        else:
            current.append(arg)
    return out


def compose_plans(plans: Sequence[NodeProcessSpec], composition: str,
                  command_prefix: Sequence[str]) -> list[NodeProcessSpec]:
    """The plans with the nodes of ``composition`` replaced by one process, where the first was.

    Args:
        plans: The launch's node processes, one per node.
        composition: A key of ``COMPOSITIONS``.
        command_prefix: How the composed process starts (``python -m uvms_bringup.composed``).

    Raises:
        ValueError: An unknown composition; the message names the valid ones.
    """
    from uvms_bringup.processes import NodeProcessSpec

    if composition not in COMPOSITIONS:
        msg = f'--compose {composition!r}: valid: {", ".join(COMPOSITIONS)}'
        raise ValueError(msg)
    members = COMPOSITIONS[composition]
    grouped = [plan for plan in plans if plan.spec in members]
    if len(grouped) < 2:
        return list(plans)
    command = [*command_prefix, *([LOOP_FLAG] if composition in LOOPED else [])]
    start = list(command)
    for plan in grouped:
        args = list(plan.command)
        command += [*([SEPARATOR] if command != start else []), plan.spec.name,
                    *args[args.index('--ros-args'):]]
    out: list[NodeProcessSpec] = []
    for plan in plans:
        if plan is grouped[0]:
            out.append(NodeProcessSpec(COMPOSED, f'{COMPOSED.executable}-{len(out) + 1}',
                                       tuple(command), rt_priority=grouped[0].rt_priority))
        elif plan not in grouped:
            out.append(NodeProcessSpec(plan.spec, f'{plan.spec.executable}-{len(out) + 1}',
                                       plan.command, plan.parameters_file, plan.outcome_file,
                                       plan.rt_priority, plan.nice))
    return out


def main(argv: Sequence[str] | None = None) -> int:
    """Build every node of the command line on one context and executor; spin until a signal.

    Returns:
        0 after a signal or an external shutdown; 1 when a node could not be built or a
        callback raised (logged with the node's name and the error's type).
    """
    from uvms_common.stop_event import StopEvent, active_stop_event

    earlier = active_stop_event()
    stop = earlier if earlier is not None else StopEvent()
    try:
        args = list(sys.argv[1:] if argv is None else argv)
        loop = bool(args) and args[0] == LOOP_FLAG
        groups = node_groups(args[1:] if loop else args)
        by_name = {spec.name: spec for specs in COMPOSITIONS.values() for spec in specs}
        unknown = [name for name, _ in groups if name not in by_name]
        if not groups or unknown:
            print(f'composed: unknown node(s) {unknown}; valid: {sorted(by_name)}',
                  file=sys.stderr)
            return 2
        from uvms_bringup.composed_run import run_composed

        return run_composed([(by_name[name], args) for name, args in groups], stop, loop)
    finally:
        if stop is not earlier:
            stop.restore()


if __name__ == '__main__':
    from uvms_common.node_entry import end_process, mark_process_ends_after_main

    mark_process_ends_after_main()  # run_composed leaves the middleware teardown to the end
    end_process(main())
