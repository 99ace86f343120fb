"""The worked examples in the core docstrings run and give the printed results."""

from __future__ import annotations

import doctest
import importlib

import pytest

MODULES = [
    'uvms_thrusters.allocation',
    'uvms_thrusters.fault_detection',
    'uvms_thrusters.thruster_faults',
    'uvms_control.core.law.filters',
    'uvms_control.core.task.force_figures',
    'uvms_control.core.fuzzy_sets',
    'uvms_control.core.law.fuzzy_switch',
    'uvms_control.core.law.hybrid',
    'uvms_control.core.law.impedance',
    'uvms_control.core.law.reference',
    'uvms_control.core.law.task_space',
    'uvms_thrusters.thruster_dynamics',
    'uvms_control.core.law.unified_controller',
]


@pytest.mark.parametrize('name', MODULES)
def test_docstring_examples_hold(name: str) -> None:
    """Every example of the module's docstrings reproduces its output."""
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0
    assert result.failed == 0
