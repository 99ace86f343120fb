"""Exceptions of uvms_model; every one is a ValueError that names the offending input."""


class ModelError(ValueError):
    """Invalid input to the UVMS model: a wrong shape, a non-finite value, a bad parameter."""


class ParameterError(ModelError):
    """A model parameter is unknown, of the wrong type or length, or out of its valid range."""


class StateError(ModelError):
    """A state, input or result is not finite or has the wrong shape."""


class SingularAttitudeError(ModelError):
    """Pitch is too close to +-90 deg, where the Euler-angle rate matrix J2 is singular."""


class UnreachableError(ModelError):
    """The inverse kinematics found no arm configuration that reaches the requested point.

    Attributes:
        residual_m: Distance (m) left between the end effector and the point after the last
            iteration (NaN where unknown).
    """

    def __init__(self, message: str, residual_m: float = float('nan')) -> None:
        super().__init__(message)
        self.residual_m = residual_m


class DescriptionError(ModelError):
    """The robot description (URDF or hydrodynamics file) is missing, malformed or incomplete."""
