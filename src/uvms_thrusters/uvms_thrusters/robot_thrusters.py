"""A robot's thrusters as its folder describes them: layout and thruster model (eq. 9, 11-15).

The allocator builds these from its declared parameters; a protocol twin, which stands for the
physical thrusters of a robot, builds the same from the robot folder alone::

    layout, model = robot_thrusters('bluerov2_alpha5')
    bank = ThrusterBank(model, layout.count)   # eq. 11-15, the propellers
"""

from __future__ import annotations

from uvms_model.thrusters import ThrusterLayout

from uvms_description.robots import robot_parameters, with_description_paths
from uvms_model import UvmsParameters
from uvms_thrusters.parameter_specs import ALLOCATOR_PARAMETER_SPECS
from uvms_thrusters.parameters import thruster_parameters_from_flat_dict
from uvms_thrusters.thruster_dynamics import ThrusterModelParameters

#: The node whose parameter files carry the thruster model (thrusters.yaml's section).
ALLOCATOR_NODE = 'thruster_allocator'
#: The model parameters a thruster model needs: layout, water density (uvms_model names).
MODEL_PREFIXES = ('thrusters.', 'hydrodynamics.')


def robot_thrusters(robot_name: str) -> tuple[ThrusterLayout, ThrusterModelParameters]:
    """The thruster layout and the Healey model constants of robot ``robot_name``.

    The model's values are the allocator's defaults overridden by the robot folder's
    (``thrusters.yaml``), in the water density of its ``hydrodynamics.yaml``.

    Raises:
        RobotFolderError, ModelError: The robot folder cannot be read.
    """
    robot = {key: item.value for key, item in robot_parameters(robot_name, ALLOCATOR_NODE).items()}
    simulator = {key: item.value for key, item in robot_parameters(robot_name, 'simulator').items()
                 if key.startswith(MODEL_PREFIXES)}
    uvms = UvmsParameters.from_flat_dict(with_description_paths(simulator, robot_name))
    thruster = {spec.name: spec.default for spec in ALLOCATOR_PARAMETER_SPECS
                if spec.name.startswith('thruster.')}
    thruster.update({k: v for k, v in robot.items() if k.startswith('thruster.')})
    model = thruster_parameters_from_flat_dict(thruster, uvms.hydrodynamics.water_density_kg_m3)
    return ThrusterLayout.from_parameters(uvms.thrusters), model
