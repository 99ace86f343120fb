"""docs/interfaces.md stays true: every runtime parameter and result code is documented."""

from __future__ import annotations

from pathlib import Path

import pytest
from uvms_control.core.parameter_specs import CONTROLLER_PARAMETER_SPECS, SAFETY_PARAMETER_SPECS
from uvms_control.core.task.contact_task import TaskCode

DOC = (Path(__file__).resolve().parents[3] / 'docs' / 'interfaces.md').read_text()
RUNTIME = [spec.name for spec in [*CONTROLLER_PARAMETER_SPECS, *SAFETY_PARAMETER_SPECS]
           if not spec.read_only]


def test_some_parameters_change_at_run_time_and_the_model_does_not() -> None:
    """Gains and limits are runtime parameters; the model scale and the mode are not."""
    assert 'hybrid.force_kp' in RUNTIME and 'safety.max_contact_force_n' in RUNTIME
    assert 'model.mass_scale' not in RUNTIME and 'mode' not in RUNTIME


@pytest.mark.parametrize('name', RUNTIME)
def test_runtime_parameter_is_documented(name: str) -> None:
    """A parameter a user may change while the node runs appears in docs/interfaces.md."""
    assert f'`{name}`' in DOC


@pytest.mark.parametrize('code', list(TaskCode), ids=lambda c: c.name)
def test_result_code_is_documented(code: TaskCode) -> None:
    """Each way a task can end is in the result table with its number."""
    assert f'`{code.name}` ({int(code)})' in DOC
