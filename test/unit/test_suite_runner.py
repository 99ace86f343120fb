"""tools/run_suite.py: which pytest process runs which tests, and the closing line it prints."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

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


def test_unit_tests_run_in_one_process() -> None:
    """Every unit module is run, all by one process."""
    groups = run_suite.groups_for([ROOT / 'test' / 'unit'], 900.0, 1500.0)
    assert len(groups) == 1
    assert sorted(groups[0].paths) == sorted((ROOT / 'test' / 'unit').rglob('test_*.py'))


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
