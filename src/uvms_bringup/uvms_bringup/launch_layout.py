"""How ``uvms launch`` lays its processes out: their scheduling and composition, on its line."""

from __future__ import annotations

import sys
from collections.abc import Iterable

from uvms_common.scheduling import Scheduling, fifo_refusal

from uvms_bringup.launch_helpers import LOOP_NODES
from uvms_bringup.processes import NodeProcessSpec


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


def describe_scheduling(scheduling: Scheduling, plans: Iterable[NodeProcessSpec]) -> str:
    """The loop processes' scheduling on the launch line: ``; simulator, ...: SCHED_FIFO 50``."""
    asked = [f'SCHED_FIFO {scheduling.priority}' if scheduling.priority else 'normal priority']
    if scheduling.cpus:
        asked.append('on CPUs ' + ','.join(map(str, scheduling.cpus)))
    if scheduling.lock_memory:
        asked.append('memory locked')
    loop = [plan.spec.name for plan in plans
            if plan.spec in LOOP_NODES or composed_nodes(plan)]
    return '; ' + ', '.join(loop) + ': ' + ', '.join(asked)


def composed_nodes(plan: NodeProcessSpec) -> str:
    """The nodes a composed process runs (``controller+thruster_allocator``), else ''."""
    command = list(plan.command)
    names = [arg.split(':=', 1)[1] for arg in command if arg.startswith('__node:=')]
    return '+'.join(names) if len(names) > 1 else ''
