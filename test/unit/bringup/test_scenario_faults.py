"""Tests of the scenario key ``faults``: parsed into the allocator's injected faults."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from uvms_scenarios.scenario import ScenarioError, parse_scenario
from uvms_thrusters.thruster_faults import ThrusterFault, parse_faults

PATH = Path('x.yaml')


def scenario(**extra: Any) -> dict[str, Any]:
    """A minimal scenario document plus ``extra`` keys."""
    return {'name': 'x', 'description': 'x', 'duration_s': 1.0, **extra}


def test_faults_become_the_allocator_parameter() -> None:
    """Two faults arrive as fault_injection.thrusters, in onset order, values intact."""
    parsed = parse_scenario(scenario(faults={'thrusters': [
        {'index': 5, 'kind': 'efficiency', 'value': 0.3, 'at_s': 8.0},
        {'index': 2, 'kind': 'off', 'at_s': 3}]}), PATH)
    text = parsed.node_overrides('thruster_allocator')['fault_injection.thrusters']
    assert isinstance(text, str)
    assert parse_faults(text) == (ThrusterFault(2, 'off', 0.0, 3.0),
                                  ThrusterFault(5, 'efficiency', 0.3, 8.0))


@pytest.mark.parametrize(('faults', 'match'), [
    ({'thrusters': [{'index': 1, 'kind': 'efficiency', 'value': 2.0, 'at_s': 1.0}]},
     r'faults\.thrusters\[0\].*\[0, 1\]'),
    ({'thrusters': [{'index': -1, 'kind': 'off', 'at_s': 1.0}]}, r'index -1'),
    ({'thrusters': [{'index': 1, 'kind': 'broken', 'at_s': 1.0}]}, r'kind .broken.'),
    ({'thrusters': [{'index': 1, 'kind': 'off'}]}, r'at_s None'),
    ({'thrusters': [{'index': 1, 'kind': 'off', 'at_s': 1, 'when': 2}]}, r'unknown keys'),
    ({'vehicle': []}, r'key .faults.'),
    ({'thrusters': {'index': 1}}, r'faults\.thrusters'),
])
def test_bad_fault_is_refused_naming_the_key(faults: Any, match: str) -> None:
    """A wrong fault names the file, the key and what is valid."""
    with pytest.raises(ScenarioError, match=match) as info:
        parse_scenario(scenario(faults=faults), PATH)
    assert str(info.value).startswith('x.yaml: ')


def test_faults_key_and_allocator_parameter_together_are_refused() -> None:
    """The faults key and thruster_allocator.fault_injection.thrusters: one source only."""
    with pytest.raises(ScenarioError, match='keep one'):
        parse_scenario(scenario(
            faults={'thrusters': [{'index': 1, 'kind': 'off', 'at_s': 1.0}]},
            thruster_allocator={'fault_injection': {'thrusters': 'index=2 kind=off at_s=1'}}),
            PATH)
