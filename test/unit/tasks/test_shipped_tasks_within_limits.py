"""Every shipped task file and scenario mission passes its robot's goal checks and path limits."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml
from uvms_control.core.task.contact_task import (
    ContactTaskGoal,
    SafetyLimits,
    planned_goal,
    validate_goal,
)
from uvms_tasks.task_file import TaskSpec, load_task_file, parse_mission

from uvms_description.robots import robot_parameters, robot_start

CONFIG = Path(__file__).resolve().parents[3] / 'config'
SCENARIOS = sorted((CONFIG / 'scenarios').glob('*.yaml'))
#: The paper robot's task files (Case I's point A); the BlueROV2's pool tasks are relative.
POOL_TASK_FILES = sorted((CONFIG / 'tasks').glob('bluerov2_pool_*.yaml'))
TASK_FILES = sorted(set((CONFIG / 'tasks').glob('*.yaml')) - set(POOL_TASK_FILES))
BLUEROV2_CONTACT = CONFIG / 'scenarios' / 'bluerov2_alpha5_contact.yaml'

IDLE_WALL = CONFIG / 'scenarios' / 'idle_wall.yaml'  # the graph the task files are sent to
POINT_A = np.array([1.70, 0.0, -0.10])  # of the paper's Fig. 7 (m, map_ned)
#: Where the robot may hold when a task file is sent (m, map_ned): A, the half circle's end D,
#: where press_100n lets go of the wall, and somewhere else in reach.
HOLDS = {'A': POINT_A, 'D': np.array([1.70, 0.0, 0.10]),
         'press_end': np.array([1.775, 0.0, -0.06]), 'elsewhere': np.array([1.55, 0.1, 0.05])}


def robot_limits(robot: str) -> tuple[SafetyLimits, float]:
    """The robot folder's safety limits and contact threshold (N)."""
    values = {key: item.value for key, item in robot_parameters(robot, 'controller').items()}
    safety = {key.removeprefix('safety.'): float(value) for key, value in values.items()
              if key.startswith('safety.')}
    limits = SafetyLimits(**safety)  # as the controller node builds them
    return limits, float(values['force.contact_threshold_n'])


def as_goal(task: TaskSpec, start: np.ndarray) -> ContactTaskGoal:
    """The goal the controller gets from a task file's task (a half circle expanded at start)."""
    task = task.expanded(start.tolist())
    return ContactTaskGoal(path=task.path, times=task.time_from_start_s,
                           velocities=task.velocity, accelerations=task.acceleration,
                           normal=task.normal, force_n=task.force_n,
                           force_ramp_s=task.force_ramp_s, require_contact=task.require_contact,
                           start_time_s=task.start_time_s)


def scenario(path: Path) -> dict[str, object]:
    """A scenario file's mapping."""
    data = yaml.safe_load(path.read_text())
    assert isinstance(data, dict)
    return data


def start_of(data: dict[str, object]) -> np.ndarray:
    """The end effector's initial position of a scenario (m, map_ned): its own or its robot's."""
    simulator = data.get('simulator') or {}
    initial = simulator.get('initial', {}) if isinstance(simulator, dict) else {}
    if 'ee_position' in initial:
        return np.array(initial['ee_position'], dtype=np.float64)
    start = robot_start(str(data.get('robot', 'paper_uvms')))
    return np.array(start['initial.ee_position'], dtype=np.float64)


@pytest.mark.parametrize('path', [p for p in SCENARIOS if 'mission' in scenario(p)],
                         ids=lambda p: p.stem)
def test_scenario_missions_pass_the_goal_checks(path: Path) -> None:
    """Each mission task is accepted at the first step, from the scenario's start."""
    data = scenario(path)
    limits, threshold = robot_limits(str(data.get('robot', 'paper_uvms')))
    start = start_of(data)
    for task in parse_mission(data['mission'], str(path)):
        validate_goal(as_goal(task, start), start, limits, threshold, now_s=0.0)


@pytest.mark.parametrize('path', TASK_FILES, ids=lambda p: p.stem)
def test_task_files_pass_the_goal_checks_from_idle_wall(path: Path) -> None:
    """Each task file is accepted by the paper robot held at idle_wall's point A."""
    limits, threshold = robot_limits('paper_uvms')
    start = start_of(scenario(IDLE_WALL))
    for task in load_task_file(path):
        validate_goal(as_goal(task, start), start, limits, threshold, now_s=0.0)


@pytest.mark.parametrize('hold', sorted(HOLDS))
@pytest.mark.parametrize('path', TASK_FILES, ids=lambda p: p.stem)
def test_task_files_run_from_point_a_wherever_the_robot_holds(path: Path, hold: str) -> None:
    """Each task file's path starts at point A, the same from every hold, and is accepted.

    The controller reaches A by a transit first (none when it holds at A).
    """
    limits, threshold = robot_limits('paper_uvms')
    x = HOLDS[hold]
    for task in load_task_file(path):
        goal = as_goal(task, x)
        reference = as_goal(task, POINT_A)
        np.testing.assert_allclose(goal.path, reference.path, atol=1e-12)
        np.testing.assert_allclose(goal.path[0], POINT_A, atol=1e-12)
        validate_goal(goal, x, limits, threshold, now_s=0.0, start=x)
        planned, transit_s = planned_goal(goal, x, limits)
        assert (transit_s > 0.0) == (hold != 'A')
        np.testing.assert_allclose(planned.path[0], x, atol=1e-12)


@pytest.mark.parametrize('path', POOL_TASK_FILES, ids=lambda p: p.stem)
def test_pool_task_files_pass_the_bluerov2_checks_from_where_it_holds(path: Path) -> None:
    """Each pool task starts where the BlueROV2 holds (no start of its own) and is accepted.

    From the contact scenario's point A and from the robot's own start pose: no transit,
    the path's first point is the held one.
    """
    limits, threshold = robot_limits('bluerov2_alpha5')
    holds = (start_of(scenario(BLUEROV2_CONTACT)),
             np.array(robot_start('bluerov2_alpha5')['initial.ee_position'], dtype=np.float64))
    assert len(POOL_TASK_FILES) == 2
    for x in holds:
        for task in load_task_file(path):
            goal = as_goal(task, x)
            np.testing.assert_allclose(goal.path[0], x, atol=1e-12)
            validate_goal(goal, x, limits, threshold, now_s=0.0, start=x)
            assert planned_goal(goal, x, limits)[1] == 0.0
