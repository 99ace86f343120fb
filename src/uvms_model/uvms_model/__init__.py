"""Pure numpy/scipy model of the UVMS: kinematics, dynamics, hydrodynamics (paper sec. 3, 5.1)."""

from uvms_model.errors import (
    ModelError,
    ParameterError,
    SingularAttitudeError,
    StateError,
    UnreachableError,
)
from uvms_model.model import FRAME_NAMES, UvmsModel
from uvms_model.parameters import PARAMETER_SPECS, ParameterSpec, UvmsParameters

__all__ = [
    'FRAME_NAMES',
    'PARAMETER_SPECS',
    'ModelError',
    'ParameterError',
    'ParameterSpec',
    'SingularAttitudeError',
    'StateError',
    'UnreachableError',
    'UvmsModel',
    'UvmsParameters',
]
