"""How ``uvms launch`` lays its processes out: their scheduling and composition, on its line."""

from __future__ import annotations

import sys
from collections.abc import Iterable
from dataclasses import replace

from uvms_common.scheduling import Scheduling, fifo_refusal, may_lower_niceness

from uvms_bringup.launch_helpers import (
    HARDWARE_BRIDGES,
    LOOP_NODES,
    RECORDER,
    SENSOR_BRIDGES,
    NodeSpec,
)
from uvms_bringup.processes import NodeProcessSpec

#: SCHED_FIFO priority steps between the control loop and the sensor bridges.
SENSOR_BELOW_LOOP = 10
#: The recorder's niceness where the loops run SCHED_FIFO. It stays a normal process (a
#: recorder that spins must not take a loop's CPU) but takes what the loops leave before
#: other work: at 0, beside the twin stand at factor 1 and 2 busy loops, it got 13 % of a
#: core for the 16 % it needs and lost joint states in bursts of up to 0.84 s (2026-12-07);
#: the fit then biased the yaw added mass low (issue 50's twin stand test in CI).
RECORDER_NICE = -10


def launch_scheduling(priority: int, cpus: tuple[int, ...], lock_memory: bool) -> Scheduling:
    """What the loop processes ask for: the priority only where a child may have it.

    Tried once here (``fifo_refusal``): where it is refused, one warning line names what to
    change and the nodes do not ask (instead of each repeating the warning).
    """
    refusal = fifo_refusal(priority) if priority else ''
    if refusal:
        sys.stderr.write(f'uvms launch: warning: {refusal}\n')
        sys.stderr.flush()
        priority = 0
    return Scheduling(priority, cpus, lock_memory)


def sensor_priority(loop_priority: int) -> int:
    """SCHED_FIFO priority of the sensor bridges: ``SENSOR_BELOW_LOOP`` below the loop's.

    Below a loop priority of 11 they run one step below it; below the loop's 1, at normal
    priority (0): never at the loop's own.
    """
    if loop_priority > SENSOR_BELOW_LOOP:
        return loop_priority - SENSOR_BELOW_LOOP
    return max(loop_priority - 1, 0)


def node_scheduling(spec: NodeSpec, scheduling: Scheduling | None,
                    sensors_below_loop: bool = True) -> Scheduling | None:
    """What one node's process asks for: the loop's, lower for a sensor bridge; else None.

    Args:
        spec: The node.
        scheduling: What the loop processes (``LOOP_NODES``) ask for; None: nothing.
        sensors_below_loop: The sensor bridges ``SENSOR_BELOW_LOOP`` lower. False beside the
            twins (``--hardware twin``): there the sensors' own data comes from the twins'
            and the simulator's processes at the loop's priority, which on 2 cores starved a
            bridge below them (the Net F/T's wrench stalled, the controller stopped, the arm
            tripped: a suite run on 2026-12-06), what the robot's own computer never has.
    """
    if scheduling is None or spec not in LOOP_NODES:
        return None
    if spec in SENSOR_BRIDGES and sensors_below_loop:
        return replace(scheduling, priority=sensor_priority(scheduling.priority))
    return scheduling


def node_niceness(spec: NodeSpec, scheduling: Scheduling | None) -> int:
    """The niceness a node's process starts with, 0 but for the recorder's.

    ``RECORDER_NICE`` for the recorder beside loops at SCHED_FIFO, where this user may
    lower a niceness (CAP_SYS_NICE or RLIMIT_NICE); elsewhere 0, and the launch line does not
    name it.
    """
    if (spec is RECORDER and scheduling is not None and scheduling.priority > 0
            and may_lower_niceness(RECORDER_NICE)):
        return RECORDER_NICE
    return 0


def describe_scheduling(scheduling: Scheduling, plans: Iterable[NodeProcessSpec]) -> str:
    """The loop processes' scheduling on the launch line: ``; simulator, ...: SCHED_FIFO 50``.

    Processes at another priority (the sensor bridges) get a group of their own:
    ``; simulator, controller: SCHED_FIFO 50; dvl_bridge: SCHED_FIFO 40``.
    """
    extras = []
    if scheduling.cpus:
        extras.append('on CPUs ' + ','.join(map(str, scheduling.cpus)))
    if scheduling.lock_memory:
        extras.append('memory locked')
    groups: dict[int, list[str]] = {}
    nice: list[str] = []
    for plan in plans:
        if plan.spec in LOOP_NODES or composed_nodes(plan):
            groups.setdefault(plan.rt_priority, []).append(plan.spec.name)
        elif plan.nice:
            nice.append(f'; {plan.spec.name}: nice {plan.nice}')
    return ''.join(
        '; ' + ', '.join(names) + ': '
        + ', '.join([f'SCHED_FIFO {priority}' if priority else 'normal priority', *extras])
        for priority, names in groups.items()) + ''.join(nice)


def composed_nodes(plan: NodeProcessSpec) -> str:
    """The nodes a composed process runs (``controller+thruster_allocator``), else ''."""
    command = list(plan.command)
    names = [arg.split(':=', 1)[1] for arg in command if arg.startswith('__node:=')]
    return '+'.join(names) if len(names) > 1 else ''


def holds_bridge(plan: NodeProcessSpec) -> bool:
    """Whether the process runs a hardware bridge (alone, or composed: the robot process).

    Such a process stops before the others (``processes.Launcher.stop``): its devices, or
    their twins, must still answer while it puts them back.
    """
    return plan.spec in HARDWARE_BRIDGES.values() or any(
        name in HARDWARE_BRIDGES for name in composed_nodes(plan).split('+'))
