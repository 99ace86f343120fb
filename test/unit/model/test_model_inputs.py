"""Bad input to uvms_model: wrong shapes and non-finite states raise ValueErrors naming them."""

from __future__ import annotations

import numpy as np
import pytest

from uvms_model import ModelError, StateError, UvmsModel

MODEL = UvmsModel()
GOOD = np.zeros(9)


@pytest.mark.parametrize(
    ('call', 'name'),
    [
        (lambda: MODEL.mass_matrix(np.zeros(8)), 'q'),
        (lambda: MODEL.mass_matrix_body(np.zeros((9, 1))), 'q'),
        (lambda: MODEL.bias(GOOD, np.zeros(10)), 'q_dot'),
        (lambda: MODEL.bias_body(GOOD, np.zeros(3)), 'w'),
        (lambda: MODEL.forward_dynamics(GOOD, GOOD, np.zeros(6)), 'tau_b'),
        (lambda: MODEL.forward_dynamics(GOOD, GOOD, GOOD, np.zeros(2)), 'f_ee_ned'),
        (lambda: MODEL.ee_jacobian(np.zeros(6)), 'q'),
        (lambda: MODEL.step(GOOD, GOOD, GOOD, None, 0.0), 'dt'),
        (
            lambda: MODEL.joint_positions_for_ee_position(np.zeros(5), np.zeros(3), np.zeros(3)),
            'q_vehicle',
        ),
    ],
)
def test_wrong_shape_raises_value_error_naming_the_argument(call: object, name: str) -> None:
    """Shapes are checked and the message starts with the argument's name."""
    with pytest.raises(ValueError, match=rf'^{name}\b'):
        call()  # type: ignore[operator]


@pytest.mark.parametrize('bad', [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize('argument', ['q', 'w', 'tau_b', 'f_ee_ned'])
def test_non_finite_state_or_input_raises_state_error(bad: float, argument: str) -> None:
    """NaN or Inf in q, w, tau_b or the EE force makes step raise StateError naming it."""
    values = {'q': np.zeros(9), 'w': np.zeros(9), 'tau_b': np.zeros(9), 'f_ee_ned': np.zeros(3)}
    values[argument][1] = bad
    with pytest.raises(StateError, match=rf'^{argument} must be finite'):
        MODEL.step(values['q'], values['w'], values['tau_b'], values['f_ee_ned'], 1e-3)


@pytest.mark.filterwarnings('ignore::RuntimeWarning')
def test_diverging_step_raises_instead_of_returning_nan() -> None:
    """A step whose result overflows raises StateError rather than returning Inf/NaN."""
    w = np.zeros(9)
    w[6] = 1e160
    with pytest.raises(StateError):
        MODEL.step(np.zeros(9), w, np.zeros(9), None, 1.0)


def test_errors_are_value_errors() -> None:
    """ModelError and its subclasses are ValueErrors."""
    assert issubclass(ModelError, ValueError)
    assert issubclass(StateError, ModelError)


def test_unknown_integration_method_is_rejected() -> None:
    """step(method='euler') raises ModelError naming the method."""
    with pytest.raises(ModelError, match='method'):
        MODEL.step(GOOD, GOOD, GOOD, None, 1e-3, method='euler')
