"""uvms launch gives SCHED_FIFO to the loop processes only, on their command lines."""

from __future__ import annotations

from pathlib import Path

from uvms_bringup.launch_helpers import LOOP_NODES, resolve_scenario_path
from uvms_bringup.launcher import plan_launch
from uvms_common.scheduling import Scheduling
from uvms_scenarios.scenario import load_scenario


def _arguments(command: tuple[str, ...]) -> list[str]:
    return [command[i + 1] for i, arg in enumerate(command) if arg == '-p']


def test_loop_processes_ask_for_the_priority_and_the_others_do_not(tmp_path: Path) -> None:
    """Simulator, controller and allocator get rt_priority 50 and CPUs; the others nothing."""
    scenario = load_scenario(resolve_scenario_path('case1_ke1e4'))
    plans = plan_launch(scenario, 'realtime', tmp_path, output_path=tmp_path / 'r.mcap',
                        scheduling=Scheduling(50, (1,)))
    asked = {plan.spec.name: _arguments(plan.command) for plan in plans}
    loop = {spec.name for spec in LOOP_NODES}
    assert {name for name, args in asked.items() if args} == loop & set(asked)
    assert asked['controller'] == ['rt_priority:=50', "rt_cpus:='1'"]
    for name in ('recorder', 'visualizer', 'mission'):
        assert asked[name] == []


def test_no_scheduling_leaves_every_command_line_as_before(tmp_path: Path) -> None:
    """--no-rt: no node is given rt_priority."""
    plans = plan_launch(None, 'realtime', tmp_path, scheduling=Scheduling())
    assert all(not _arguments(plan.command) for plan in plans)


def test_scheduling_stays_out_of_the_recorded_run_parameters(tmp_path: Path) -> None:
    """run.parameters (what replay rebuilds from) holds no rt_priority."""
    plans = plan_launch(None, 'realtime', tmp_path, output_path=tmp_path / 'r.mcap',
                        scheduling=Scheduling(50))
    recorder = next(plan for plan in plans if plan.spec.name == 'recorder')
    assert recorder.parameters_file is not None
    assert 'rt_priority' not in recorder.parameters_file.read_text()


def test_loop_processes_start_at_their_priority(tmp_path: Path) -> None:
    """The launcher sets SCHED_FIFO between fork and exec for the loop processes only."""
    plans = plan_launch(None, 'realtime', tmp_path, output_path=tmp_path / 'r.mcap',
                        scheduling=Scheduling(50))
    starts = {plan.spec.name: plan.rt_priority for plan in plans}
    assert starts == {'simulator': 50, 'controller': 50, 'thruster_allocator': 50,
                      'visualizer': 0, 'recorder': 0}
