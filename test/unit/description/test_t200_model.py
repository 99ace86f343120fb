"""The T200 thruster constants of bluerov2_alpha5 against the data sheet and von Benzon's K(s)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

TOOL = Path(__file__).resolve().parents[3] / 'tools' / 't200_step_response.py'
#: Largest ratio of the model's rise time (10-90 %) to K(s)'s at a 25 N step, either way.
RISE_TIME_FACTOR = 2.0
#: Largest ratio of the times to 63 % at a 25 N step.
T63_FACTOR = 1.5


def _load_tool() -> ModuleType:
    spec = importlib.util.spec_from_file_location('t200_step_response', TOOL)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


t200 = _load_tool()


@pytest.fixture(scope='module')
def params() -> object:
    """The thruster constants of robots/bluerov2_alpha5/thrusters.yaml in sea water."""
    return t200.load_thruster_parameters()


@pytest.mark.parametrize(('command', 'expected'), [(1000.0, 51.4), (-1000.0, -39.9)])
def test_static_thrust_at_full_command_is_the_16v_data(
    params: object, command: float, expected: float
) -> None:
    """A command beyond the current limit settles within 5 % of 51.4 N forward, 39.9 N reverse."""
    _, thrust = t200.model_step_response(params, command, duration_s=1.0, dt=1e-3)
    assert thrust[-1] == pytest.approx(expected, rel=0.05)
    assert np.abs(np.diff(thrust[-100:])).max() < 1e-3  # steady


def test_current_limit_thrusts_are_the_16v_data(params: object) -> None:
    """The bollard limits the calibration reports are the data sheet's extremes."""
    forward, reverse = t200.static_thrust_limits(params)
    assert forward == pytest.approx(t200.DATASHEET_FORWARD_N, rel=0.05)
    assert reverse == pytest.approx(t200.DATASHEET_REVERSE_N, rel=0.05)


def test_von_benzon_reference_is_the_identified_transfer_function() -> None:
    """K(s) has unit DC gain and its step reaches 63 % at about 20 ms, without overshoot."""
    t = np.linspace(0.0, 1.0, 10001)
    metrics = t200.step_metrics(t, t200.reference_step_response(t))
    assert t200.reference_step_response(np.array([0.0, 5.0]))[-1] == pytest.approx(1.0, 1e-4)
    assert metrics.time_to_63_s == pytest.approx(0.020, abs=0.002)
    assert metrics.overshoot < 1e-3


@pytest.mark.parametrize('command', [25.0, -25.0])
def test_step_response_rise_time_is_close_to_von_benzon(params: object, command: float) -> None:
    """At a 25 N step either way, rise time within a factor 2 and t63 within 1.5 of K(s)."""
    comparison = t200.compare(params, command, duration_s=0.4)
    model, reference = comparison.model_metrics, comparison.reference_metrics
    ratio = model.rise_time_s / reference.rise_time_s
    assert 1.0 / RISE_TIME_FACTOR < ratio < RISE_TIME_FACTOR
    ratio_63 = model.time_to_63_s / reference.time_to_63_s
    assert 1.0 / T63_FACTOR < ratio_63 < T63_FACTOR
    assert model.overshoot < 0.05
    assert comparison.rms_difference < 0.1
