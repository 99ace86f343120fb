"""The controller names uvms_tune uses, imported in this one place.

``uvms_control.core.gain_stability`` and ``uvms_control.core.parameters`` are moving inside
``uvms_control.core`` on another branch; a move is a one-line fix here.
"""

from __future__ import annotations

from uvms_control.core.errors import ControlParameterError
from uvms_control.core.gain_stability import LoopRadius, loop_radii
from uvms_control.core.parameter_specs import (
    CONTROLLER_NODE_PARAMETER_SPECS,
    CONTROLLER_PARAMETER_SPECS,
)
from uvms_control.core.parameters import ControllerParameters

__all__ = ['CONTROLLER_NODE_PARAMETER_SPECS', 'CONTROLLER_PARAMETER_SPECS',
           'ControlParameterError', 'ControllerParameters', 'LoopRadius', 'loop_radii']
