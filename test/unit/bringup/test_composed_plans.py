"""--compose control: the control nodes' command lines joined into one process, unchanged."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from uvms_bringup.composed import COMPOSED, LOOP_FLAG, node_groups
from uvms_bringup.launch_helpers import resolve_scenario_path
from uvms_bringup.launcher import plan_launch
from uvms_common.process_costs import CostWatch, cpu_seconds
from uvms_common.scheduling import Scheduling
from uvms_scenarios.scenario import load_scenario

from uvms_common import process_stats


def test_the_composed_process_carries_each_nodes_own_ros_args(tmp_path: Path) -> None:
    """Estimator, controller and allocator: one process, each group its separate arguments."""
    scenario = load_scenario(resolve_scenario_path('case1_estimated'))
    (tmp_path / 'c').mkdir()
    (tmp_path / 's').mkdir()
    separate = plan_launch(scenario, 'realtime', tmp_path / 's', scheduling=Scheduling(50))
    composed = plan_launch(scenario, 'realtime', tmp_path / 'c', scheduling=Scheduling(50),
                           compose='control')
    [process] = [plan for plan in composed if plan.spec is COMPOSED]
    command = list(process.command)
    start = command.index('uvms_bringup.composed') + 1
    groups = dict(node_groups(command[start:]))
    assert list(groups) == ['estimator', 'controller', 'thruster_allocator']
    by_name = {plan.spec.name: plan for plan in separate}
    for name, args in groups.items():
        own = list(by_name[name].command)
        expected = own[own.index('--ros-args'):]
        assert [a.replace('/c/', '/s/') for a in args] == expected
    assert [plan.spec.name for plan in composed] == [
        'simulator', 'control', 'visualizer', 'mission']


def test_an_unknown_composition_names_the_valid_ones(tmp_path: Path) -> None:
    """--compose with another name is refused with the list."""
    with pytest.raises(ValueError, match='control'):
        plan_launch(None, 'realtime', tmp_path, compose='everything')


def test_cpu_of_a_process_comes_from_the_kernel() -> None:
    """The kernel's utime + stime of this process grow with work."""
    before = cpu_seconds(os.getpid())
    sum(range(3_000_000))
    after = cpu_seconds(os.getpid())
    assert before is not None and after is not None and after >= before


def test_the_cost_table_reads_the_processes_stats_files(tmp_path: Path,
                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    """First step and per-process periods come from UVMS_STATS_DIR's files."""
    monkeypatch.setenv(process_stats.ENV, str(tmp_path))
    watch = CostWatch(tmp_path)
    assert watch.poll([os.getpid()]) is None
    process_stats.mark_first_step()
    assert watch.poll([os.getpid()]).startswith('uvms launch: first simulated step')
    process_stats.write('controller', {'periods': 400, 'missed': 2, 'worst_late_ms': 4.0})
    watch.end([os.getpid()])
    table = watch.table([('controller', os.getpid()), ('visualizer', 1 << 30)])
    assert '2 of 400 (0.50 %)' in table[2] and '4.0 ms' in table[2]
    assert table[3].split()[:2] == ['visualizer', '-']


def test_the_robot_composition_holds_the_control_nodes_and_every_bridge(tmp_path: Path) -> None:
    """--compose robot with the twins: control and bridges in one loop; twins in the simulator."""
    from uvms_bringup.hardware_plan import hardware_file_path, load_hardware_plan

    scenario = load_scenario(resolve_scenario_path('bluerov2_alpha5_contact'))
    hardware = load_hardware_plan(hardware_file_path('twin', Path(__file__).resolve().parents[3]
                                                     / 'config'))
    composed = plan_launch(scenario, 'realtime', tmp_path, scheduling=Scheduling(50),
                           hardware=hardware, compose='robot')
    [process] = [plan for plan in composed if plan.spec is COMPOSED]
    command = list(process.command)
    args = command[command.index('uvms_bringup.composed') + 1:]
    assert args[0] == LOOP_FLAG  # one real-time loop, not each node on its own timer
    groups = dict(node_groups(args[1:]))
    assert set(groups) == {'controller', 'thruster_allocator', 'ardusub_bridge', 'dvl_bridge',
                           'alpha5_bridge', 'netft_bridge'}  # no estimator: state from truth
    assert {plan.spec.name for plan in composed} == {
        'simulator', 'control', 'visualizer', 'mission'}  # the twins in the simulator
