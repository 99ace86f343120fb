"""The controller's names that uvms_tune uses: its gains, their specs and the stability check."""

from __future__ import annotations

from uvms_control.core.errors import ControlParameterError
from uvms_control.core.law.gain_stability import LoopRadius, loop_radii
from uvms_control.core.parameter_specs import (
    CONTROLLER_NODE_PARAMETER_SPECS,
    CONTROLLER_PARAMETER_SPECS,
)
from uvms_control.core.parameters import ControllerParameters

__all__ = ['CONTROLLER_NODE_PARAMETER_SPECS', 'CONTROLLER_PARAMETER_SPECS',
           'ControlParameterError', 'ControllerParameters', 'LoopRadius', 'loop_radii']
