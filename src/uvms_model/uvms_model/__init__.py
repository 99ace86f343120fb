"""Model of the UVMS from its URDF: kinematics, Pinocchio dynamics, hydrodynamics (sec. 3, 5.1)."""

from uvms_model.description import RobotDescription, load_description
from uvms_model.errors import (
    DescriptionError,
    ModelError,
    ParameterError,
    SingularAttitudeError,
    StateError,
    UnreachableError,
)
from uvms_model.model import TaskSpaceTerms, UvmsModel
from uvms_model.parameters import PARAMETER_SPECS, ParameterSpec, UvmsParameters

__all__ = [
    'PARAMETER_SPECS',
    'DescriptionError',
    'ModelError',
    'ParameterError',
    'ParameterSpec',
    'RobotDescription',
    'SingularAttitudeError',
    'StateError',
    'TaskSpaceTerms',
    'UnreachableError',
    'UvmsModel',
    'UvmsParameters',
    'load_description',
]
