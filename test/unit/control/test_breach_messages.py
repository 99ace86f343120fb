"""A breach message shows why it is one: the measured value reads apart from its limit."""

from __future__ import annotations

import pytest
from uvms_control.core.task.safety_checks import beyond


@pytest.mark.parametrize(('value', 'limit', 'decimals', 'text'), [
    (0.0031, 0.003, 3, '0.0031'),
    (0.1036, 0.1, 3, '0.104'),
    (150.04, 150.0, 1, '150.04'),
    (151.0, 150.0, 1, '151.0'),
])
def test_the_value_is_printed_with_the_digits_that_show_it_exceeds(
        value: float, limit: float, decimals: int, text: str) -> None:
    """As many decimals as needed (at least the usual ones) for value and limit to differ."""
    assert beyond(value, limit, decimals) == text
    digits = len(text.split('.')[1])
    assert text != f'{limit:.{digits}f}'


def test_digits_are_bounded_when_the_value_is_the_limit() -> None:
    """At most 9 decimals: a value equal to the limit does not loop."""
    assert beyond(0.003, 0.003, 3) == '0.003000000'
