"""tools/run_suite.py: which pytest process runs which tests, and the closing line it prints."""

from __future__ import annotations

import importlib.util
import os
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
_spec = importlib.util.spec_from_file_location('run_suite', ROOT / 'tools' / 'run_suite.py')
assert _spec is not None and _spec.loader is not None
run_suite = importlib.util.module_from_spec(_spec)
sys.modules['run_suite'] = run_suite
_spec.loader.exec_module(run_suite)


def test_every_integration_module_gets_a_process_of_its_own() -> None:
    """A hang in one integration module can end that module only."""
    groups = run_suite.groups_for([ROOT / 'test' / 'integration'], 900.0, 1500.0)
    modules = sorted((ROOT / 'test' / 'integration').glob('test_*.py'))
    assert [g.paths for g in groups] == [[m] for m in modules]


def test_scenario_modules_share_one_process_with_the_longer_limit() -> None:
    """The scenario runs are session fixtures shared across modules: one process."""
    groups = run_suite.groups_for([ROOT / 'test' / 'scenarios'], 900.0, 1500.0)
    assert len(groups) == 1
    assert groups[0].limit_s == 1500.0
    assert len(groups[0].paths) == len(list((ROOT / 'test' / 'scenarios').glob('test_*.py')))


def test_unit_sub_folders_are_groups_of_one_pool() -> None:
    """Every unit module runs once, in its sub-folder's group, pooled (timed ones alone)."""
    groups = run_suite.groups_for([ROOT / 'test' / 'unit'], 900.0, 1500.0)
    unit = ROOT / 'test' / 'unit'
    assert {g.name for g in groups} == {'test/unit', *(f'test/unit/{d.name}' for d in
                                                        unit.iterdir() if d.is_dir() and
                                                        any(d.rglob('test_*.py')))}
    assert {g.name for g in groups if g.batch != 'unit'} == {
        f'test/unit/{d}' for d in run_suite.TIMED_UNIT_FOLDERS}
    dealt = [p for g in groups for p in g.paths]
    assert sorted(dealt) == sorted(unit.rglob('test_*.py'))
    assert run_suite.CONCURRENT['unit'] == 2


def test_a_batch_runs_its_groups_at_once_and_prints_each_output_whole(
        tmp_path: Path, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    """Two groups of one batch both run; each one's output is printed as one block."""
    monkeypatch.setitem(run_suite.CONCURRENT, 'x', 2)
    for name in ('a', 'b'):
        (tmp_path / f'test_{name}.py').write_text(
            f'def test_{name}():\n    print("from {name}")\n')
    groups = [run_suite.Group(f'g{name}', [tmp_path / f'test_{name}.py'], 60.0, batch='x')
              for name in ('a', 'b')]
    run_suite.run_batch(groups, 0, 2, ['-s', '-q', '--rootdir', str(tmp_path)], tmp_path)
    out = capsys.readouterr().out
    assert [g.status for g in groups] == [0, 0]
    assert [g.counts['tests'] for g in groups] == [1, 1]
    for name in ('a', 'b'):
        block = out[out.index(f'== run_suite: g{name}'):]
        assert f'from {name}' in block.split('== run_suite:', 2)[1]


def test_a_timed_out_group_counts_as_a_failure_and_is_named() -> None:
    """The summary names the module that hung and the test it was in; the closing line fails."""
    ok = run_suite.Group('test/unit/common', [], 900.0, counts={'tests': 5}, status=0)
    hung = run_suite.Group('test/integration/test_graph.py', [], 900.0, status=-1,
                           timed_out=True, last_test='test_graph.py::test_x')
    lines = run_suite.summary([ok, hung], 10.0)
    assert 'TIMED OUT test/integration/test_graph.py after 900 s, in test ' \
           'test_graph.py::test_x' in lines
    assert lines[-1] == '5 passed, 1 failed'


def test_failures_from_the_junit_report_are_listed(tmp_path: Path) -> None:
    """A failed test of a group is listed by id and counted in the closing line."""
    report = tmp_path / 'r.xml'
    report.write_text(
        '<testsuites><testsuite tests="3" failures="1" errors="0" skipped="1">'
        '<testcase classname="test.unit.x" name="test_a"><failure/></testcase>'
        '<testcase classname="test.unit.x" name="test_b"/>'
        '<testcase classname="test.unit.x" name="test_c"><skipped/></testcase>'
        '</testsuite></testsuites>')
    group = run_suite.Group('test/unit', [], 900.0, status=1)
    run_suite.read_junit(group, report)
    assert group.failed == ['test.unit.x::test_a']
    assert run_suite.closing_line([group]) == '1 passed, 1 failed, 1 skipped'


def test_hypothesis_plugin_is_loaded_only_where_a_module_uses_hypothesis() -> None:
    """The supervisor's property tests keep the plugin; an integration module goes without."""
    unit = run_suite.Group('u', [ROOT / 'test/unit/control/test_supervisor_properties.py'], 9.0)
    graph = run_suite.Group('g', [ROOT / 'test/integration/test_graph.py'], 9.0)
    assert run_suite.uses_hypothesis(unit) and not run_suite.uses_hypothesis(graph)


def test_unit_groups_run_in_the_idle_lane_the_others_in_the_main_one() -> None:
    """The unit groups are marked for the idle lane, with a longer limit; nothing else is."""
    groups = run_suite.groups_for([ROOT / 'test'], 900.0, 1500.0)
    idle = {g.name for g in groups if g.idle}
    assert 'test/unit/control' in idle
    assert all(name.startswith('test/unit') for name in idle)
    assert 'test/unit/hardware' not in idle  # its twins serve on wall time
    control = next(g for g in groups if g.name == 'test/unit/control')
    assert control.wall_limit_s == 900.0 * run_suite.IDLE_LIMIT_FACTOR


def test_an_idle_lane_group_runs_at_sched_idle_beside_the_main_lane(
        tmp_path: Path, capfd: pytest.CaptureFixture[str]) -> None:
    """The idle group's pytest is SCHED_IDLE with longer test limits; the other's is not."""
    for name in ('idle', 'main'):
        (tmp_path / f'test_{name}.py').write_text(
            'import os\n'
            f'def test_{name}(request):\n'
            f'    print("{name} policy", os.sched_getscheduler(0),\n'
            f'          "timeout", request.config.getoption("timeout"),\n'
            f'          "domains", os.environ["UVMS_TEST_DOMAINS"])\n')
    groups = [run_suite.Group(f'g{name}', [tmp_path / f'test_{name}.py'], 60.0,
                              idle=name == 'idle') for name in ('idle', 'main')]
    run_suite.run_lanes(groups, ['-s', '-q', '--rootdir', str(tmp_path)], tmp_path,
                        one_lane=False)
    out = capfd.readouterr().out  # the main lane streams: its pytest writes to fd 1
    assert [g.status for g in groups] == [0, 0]
    # Its per-test hang limit scaled as its group's: a test waiting for the CPU is no hang.
    assert f'idle policy {os.SCHED_IDLE} timeout 600.0 domains 71-100' in out
    assert 'domains 1-70' in out  # the lanes' tests never share a ROS domain
    # The main lane's pytest keeps the runner's own policy (this test's: SCHED_IDLE when the
    # suite runs it in its idle lane).
    assert f'main policy {os.sched_getscheduler(0)} ' in out
    assert '== run_suite: gidle' in out  # its output printed whole at its end


def test_no_group_starts_once_the_suite_is_stopping(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """After Ctrl-C the idle lane starts nothing more: the group is left not run."""
    (tmp_path / 'test_a.py').write_text('def test_a():\n    pass\n')
    monkeypatch.setattr(run_suite, 'STOPPING', run_suite.threading.Event())
    run_suite.STOPPING.set()
    group = run_suite.Group('ga', [tmp_path / 'test_a.py'], 60.0, idle=True)
    run_suite.run_group(group, 0, ['-q', '--rootdir', str(tmp_path)], tmp_path)
    assert group.status is None and group.process is None


def test_a_second_interpreter_runs_every_group_again_but_the_colcon_workspace() -> None:
    """--also-python: the same groups, named after the interpreter, in the same lanes."""
    groups = run_suite.groups_for([ROOT / 'test'], 900.0, 1500.0)
    again = run_suite.groups_again(groups, sys.executable)
    label = run_suite.python_label(sys.executable)
    assert label == f'py{sys.version_info[0]}.{sys.version_info[1]}'
    kept = [g for g in groups if not g.name.startswith('test/ros2_way')]
    assert [g.name for g in again] == [f'{label} {g.name}' for g in kept]
    assert [(g.paths, g.idle, g.limit_s) for g in again] == [(g.paths, g.idle, g.limit_s)
                                                              for g in kept]
    assert {g.batch for g in again if g.batch} == {f'{label} unit'}
