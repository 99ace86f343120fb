"""The sensor bridges run SCHED_FIFO below the control loop; the actuator bridges at its level.

Beside loops at SCHED_FIFO the recorder starts at a lower niceness: a normal process that takes
what the loops leave before other work.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest
from uvms_bringup.hardware_plan import (
    hardware_file_path,
    hardware_scenario,
    load_hardware_plan,
)
from uvms_bringup.launch_helpers import resolve_scenario_path
from uvms_bringup.launch_layout import RECORDER_NICE, describe_scheduling, sensor_priority
from uvms_bringup.launcher import plan_launch
from uvms_bringup.processes import NodeProcessSpec
from uvms_common.scheduling import Scheduling
from uvms_scenarios.scenario import load_scenario

from uvms_bringup import launch_layout

CONFIG = Path(__file__).resolve().parents[3] / 'config'


def twin_plans(tmp_path: Path, scheduling: Scheduling,
               twins: bool = False) -> dict[str, NodeProcessSpec]:
    """The processes of ``uvms launch bluerov2_alpha5_contact --hardware FILE``, by node.

    The twin file's bridges; ``twins`` False as a robot's own hardware file (no twins beside).
    """
    hardware = replace(load_hardware_plan(hardware_file_path('twin', CONFIG)), twins=twins,
                       twins_in_simulator=False)
    scenario = hardware_scenario(
        load_scenario(resolve_scenario_path('bluerov2_alpha5_contact')), hardware)
    plans = plan_launch(scenario, 'realtime', tmp_path, output_path=tmp_path / 'r.mcap',
                        hardware=hardware, scheduling=scheduling)
    return {plan.spec.name: plan for plan in plans}


def asked_priority(plan: NodeProcessSpec) -> int | None:
    """The ``rt_priority`` a process is given on its command line, None if none."""
    values = [arg.split(':=', 1)[1] for arg in plan.command if arg.startswith('rt_priority:=')]
    return int(values[0]) if values else None


def test_sensor_bridges_start_and_ask_10_below_the_control_loop(tmp_path: Path) -> None:
    """DVL and Net F/T at FIFO 40 beside a loop at 50; ArduSub and Alpha 5 at the loop's 50."""
    plans = twin_plans(tmp_path, Scheduling(50, (1,)))
    for name in ('dvl_bridge', 'netft_bridge'):
        assert (plans[name].rt_priority, asked_priority(plans[name])) == (40, 40)
        assert "rt_cpus:='1'" in plans[name].command
    for name in ('ardusub_bridge', 'alpha5_bridge', 'controller', 'thruster_allocator',
                 'estimator'):
        assert (plans[name].rt_priority, asked_priority(plans[name])) == (50, 50)
    assert 'simulator' not in plans and 'hardware_twins' not in plans  # the robot's own
    for name in ('recorder', 'mission', 'visualizer'):
        assert (plans[name].rt_priority, asked_priority(plans[name])) == (0, None)


def test_the_launch_line_names_the_sensor_bridges_priority(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """One group per priority on the launch line, the loop's first; the recorder's niceness."""
    monkeypatch.setattr(launch_layout, 'may_lower_niceness', lambda nice: True)
    scheduling = Scheduling(50)
    line = describe_scheduling(scheduling, twin_plans(tmp_path, scheduling).values())
    assert line.endswith('; dvl_bridge, netft_bridge: SCHED_FIFO 40; recorder: nice -10')
    assert line.startswith('; ardusub_bridge, alpha5_bridge')
    assert ': SCHED_FIFO 50; ' in line


def test_beside_the_twins_the_sensor_bridges_keep_the_loops_priority(tmp_path: Path) -> None:
    """--hardware twin: the sensors' data comes from processes at 50: the bridges at 50 too."""
    plans = twin_plans(tmp_path, Scheduling(50), twins=True)
    for name in ('dvl_bridge', 'netft_bridge', 'hardware_twins', 'simulator', 'controller'):
        assert (plans[name].rt_priority, asked_priority(plans[name])) == (50, 50)


def test_without_priorities_the_sensor_bridges_ask_for_nothing_either(tmp_path: Path) -> None:
    """--no-rt: every process at normal priority, one group on the launch line."""
    plans = twin_plans(tmp_path, Scheduling())
    assert all(plan.rt_priority == 0 and asked_priority(plan) is None
               for plan in plans.values())
    assert describe_scheduling(Scheduling(), plans.values()).endswith(': normal priority')


@pytest.mark.parametrize(('loop', 'sensor'), [(99, 89), (50, 40), (11, 1), (10, 9), (2, 1),
                                              (1, 0)])
def test_a_sensor_bridge_is_never_at_or_above_the_loop(loop: int, sensor: int) -> None:
    """10 below; one below a low loop priority; normal scheduling below the loop's 1."""
    assert sensor_priority(loop) == sensor


def test_beside_fifo_loops_the_recorder_starts_nicer(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The recorder at nice -10, every other process at 0; with --no-rt the recorder at 0 too."""
    monkeypatch.setattr(launch_layout, 'may_lower_niceness', lambda nice: True)
    plans = twin_plans(tmp_path, Scheduling(50), twins=True)
    assert plans['recorder'].nice == RECORDER_NICE < 0
    assert plans['recorder'].rt_priority == 0  # a normal process still
    assert all(plan.nice == 0 for name, plan in plans.items() if name != 'recorder')
    assert twin_plans(tmp_path, Scheduling())['recorder'].nice == 0


def test_where_niceness_is_refused_the_recorder_starts_at_0_and_the_line_is_silent(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """SCHED_FIFO allowed (RLIMIT_RTPRIO) but not a lower niceness (RLIMIT_NICE): no claim."""
    monkeypatch.setattr(launch_layout, 'may_lower_niceness', lambda nice: False)
    scheduling = Scheduling(50)
    plans = twin_plans(tmp_path, scheduling)
    assert plans['recorder'].nice == 0
    assert 'nice' not in describe_scheduling(scheduling, plans.values())
