"""Task and mission files: the schema, and one named line for every way a file can be wrong."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml
from uvms_tasks.errors import TaskFileError
from uvms_tasks.task_file import (
    DEFAULT_FORCE_RAMP_S,
    HalfCircle,
    load_task_file,
    parse_mission,
    parse_task_document,
)

MISSION = """\
mission:
  - name: approach
    path: [[1.6, 0, 0.2], [1.7, 0.0, 0.2]]
    time_from_start_s: [0, 5]
    velocity: [[0, 0, 0], [0, 0, 0]]
    acceleration: [[0, 0, 0], [0, 0, 0]]
    normal: [1, 0, 0]
    start_time_s: 2
  - half_circle: {duration_s: 20, radius_m: 0.1, sweep: [0, 0, 1], points: 41}
    normal: [1, 0, 0]
    force_n: 1.5e2
    force_ramp_s: 1
    require_contact: true
"""

PATH_TASK = {'path': [[0, 0, 0], [1, 0, 0]], 'time_from_start_s': [0, 1], 'normal': [1, 0, 0]}
CIRCLE_TASK = {'half_circle': {'duration_s': 10}, 'normal': [1, 0, 0]}


def write(tmp_path: Path, text: str) -> Path:
    """A task file holding text."""
    path = tmp_path / 'task.yaml'
    path.write_text(text)
    return path


def test_mission_file_gives_its_tasks_in_order(tmp_path: Path) -> None:
    """Both kinds of task are read, ints as floats, 1.5e2 as a number (YAML 1.2)."""
    tasks = load_task_file(write(tmp_path, MISSION))
    assert [task.name for task in tasks] == ['approach', 'mission[1]']
    approach, circle = tasks
    np.testing.assert_array_equal(approach.path, [[1.6, 0.0, 0.2], [1.7, 0.0, 0.2]])
    np.testing.assert_array_equal(approach.time_from_start_s, [0.0, 5.0])
    assert approach.velocity is not None and approach.velocity.shape == (2, 3)
    assert approach.start_time_s == 2.0 and approach.force_n == 0.0
    assert approach.force_ramp_s == DEFAULT_FORCE_RAMP_S and not approach.require_contact
    assert not approach.needs_start
    assert circle.needs_start and circle.path.shape == (0, 3)
    assert circle.half_circle == HalfCircle(duration_s=20.0, points=41)
    assert circle.force_n == 150.0 and isinstance(circle.force_n, float)
    assert circle.require_contact and circle.start_time_s is None


def test_task_file_holds_one_task(tmp_path: Path) -> None:
    """A mapping of task keys is a mission of one task named ``task``."""
    (task,) = load_task_file(write(tmp_path, yaml.safe_dump(PATH_TASK)))
    assert task.name == 'task' and task.velocity is None and task.acceleration is None
    np.testing.assert_array_equal(task.normal, [1.0, 0.0, 0.0])


def test_scenario_mission_key_uses_the_same_parser() -> None:
    """A scenario file's ``mission:`` list parses with keys named in that file."""
    tasks = parse_mission([PATH_TASK, CIRCLE_TASK], 'case1.yaml')
    assert [task.needs_start for task in tasks] == [False, True]
    with pytest.raises(TaskFileError, match=r"^case1\.yaml: key 'mission\[1\]\.force_n'"):
        parse_mission([PATH_TASK, {**CIRCLE_TASK, 'force_n': -1}], 'case1.yaml')


def task(**changes: object) -> dict[str, object]:
    """The path task with keys changed (None removes a key)."""
    data = {**PATH_TASK, **changes}
    return {key: value for key, value in data.items() if value is not None}


def circle(**changes: object) -> dict[str, object]:
    """The half-circle task with half_circle keys changed."""
    return {**CIRCLE_TASK, 'half_circle': {'duration_s': 10, **changes}}


BAD = [
    # (document, key named, what is expected)
    ([1, 2], 'the document', 'a mapping'),
    ({'mission': {'a': 1}}, "'mission'", 'a non-empty list of tasks'),
    ({'mission': []}, "'mission'", 'a non-empty list of tasks'),
    ({'mission': [PATH_TASK], 'name': 'x'}, "'name'", 'only the key mission'),
    ({'mission': [PATH_TASK, 3]}, "'mission[1]'", 'a mapping of task keys'),
    ({'mission': [task(forse_n=1)]}, "'mission[0].forse_n'", 'expected one of'),
    (task(normal=None), "'normal' is missing", 'a list of 3 finite numbers'),
    (task(normal=[0, 0, 0]), "'normal'", 'not all zero'),
    (task(normal=[1, 0]), "'normal'", 'a list of 3 finite numbers'),
    (task(normal=[1, 0, float('nan')]), "'normal'", 'a list of 3 finite numbers'),
    (task(normal=[True, 0, 0]), "'normal'", 'a list of 3 finite numbers'),
    (task(path=None), "'path' is missing", 'or half_circle'),
    (task(path=[[0, 0, 0]], time_from_start_s=[0]), "'path'", 'at least 2'),
    (task(path='a line'), "'path'", 'at least 2'),
    (task(path=[[0, 0, 0], [1, 0]]), "'path[1]'", 'a list of 3 finite numbers'),
    (task(path=[[0, 0, 0], [1, 0, '1']]), "'path[1]'", 'a list of 3 finite numbers'),
    (task(time_from_start_s=None), "'time_from_start_s'", '2 times (s), one per waypoint'),
    (task(time_from_start_s=[0, 1, 2]), "'time_from_start_s'", 'one per waypoint'),
    (task(time_from_start_s=[0, 'x']), "'time_from_start_s[1]'", 'a finite number of seconds'),
    (task(time_from_start_s=[-1, 1]), "'time_from_start_s[0]'", 'a time >= 0 s'),
    (task(time_from_start_s=[1, 1]), "'time_from_start_s[1]'", 'strictly increasing'),
    (task(velocity=[[0, 0, 0]]), "'velocity'", 'a list of 2 [x, y, z] points'),
    (task(acceleration=[[0, 0, 0], [0, 0]]), "'acceleration[1]'", 'a list of 3'),
    (task(half_circle={'duration_s': 1}), "'path'", 'either half_circle or path'),
    (task(force_n=-5), "'force_n'", 'a finite number >= 0 (N)'),
    (task(force_n=True), "'force_n'", 'a finite number >= 0 (N)'),
    (task(force_n=float('inf')), "'force_n'", 'a finite number >= 0 (N)'),
    (task(force_ramp_s=0), "'force_ramp_s'", 'a finite number > 0 (s)'),
    (task(require_contact='yes'), "'require_contact'", 'true or false'),
    (task(start_time_s=-0.5), "'start_time_s'", 'a finite number >= 0 (s)'),
    (task(name=''), "'name'", 'a non-empty string'),
    ({**CIRCLE_TASK, 'half_circle': [10]}, "'half_circle'", 'a mapping of duration_s'),
    (circle(speed=1), "'half_circle.speed'", 'expected one of'),
    ({**CIRCLE_TASK, 'half_circle': {}}, "'half_circle.duration_s' is missing", '> 0 (s)'),
    (circle(duration_s=0), "'half_circle.duration_s'", 'a finite number > 0 (s)'),
    (circle(radius_m=-0.1), "'half_circle.radius_m'", 'a finite number > 0 (m)'),
    (circle(toward=[0, 0, 0]), "'half_circle.toward'", 'not all zero'),
    (circle(sweep=[2, 0, 0]), "'half_circle.sweep'", 'not parallel'),
    (circle(toward=[0, 0, 1]), "'half_circle.sweep'", 'not parallel'),
    (circle(points=2), "'half_circle.points'", 'an int in [3, 10000]'),
    (circle(points=81.0), "'half_circle.points'", 'an int in [3, 10000]'),
    (circle(points=True), "'half_circle.points'", 'an int in [3, 10000]'),
]


@pytest.mark.parametrize(('document', 'key', 'expected'), BAD,
                         ids=[f'{i}-{case[1]}' for i, case in enumerate(BAD)])
def test_bad_input_is_refused_in_one_line_naming_file_and_key(
        document: object, key: str, expected: str) -> None:
    """Each error names the file, the key and what was expected, on one line."""
    with pytest.raises(TaskFileError) as error:
        parse_task_document(document, 'tasks/press.yaml')
    message = str(error.value)
    assert message.startswith('tasks/press.yaml: ')
    assert key in message and expected in message, message
    assert '\n' not in message


def test_unreadable_file_is_named(tmp_path: Path) -> None:
    """A missing file is one line naming it."""
    with pytest.raises(TaskFileError, match=r'missing\.yaml: cannot read the task file'):
        load_task_file(tmp_path / 'missing.yaml')


def test_invalid_yaml_is_one_line(tmp_path: Path) -> None:
    """A YAML syntax error is one line with the file's name and the position."""
    with pytest.raises(TaskFileError) as error:
        load_task_file(write(tmp_path, 'path: [[0, 0, 0]\nnormal: 1\n'))
    assert str(error.value).startswith(f'{tmp_path / "task.yaml"}: not valid YAML: ')
    assert '\n' not in str(error.value) and 'line' in str(error.value)
