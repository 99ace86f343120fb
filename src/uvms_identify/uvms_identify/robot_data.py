"""What the identification takes from a robot folder: thrusters, DVL mounting, hull prior."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml
from numpy.typing import NDArray

from uvms_description.robots import RobotFiles, parameter_file_values, robot_files
from uvms_identify.errors import IdentifyError
from uvms_identify.regressor import theta_from_hull
from uvms_identify.signals import rpy_matrix

FloatArray = NDArray[np.float64]
ROOT_LINK = 'base_link_frd'


@dataclass(frozen=True)
class RobotData:
    """A robot folder as the identification reads it.

    Attributes:
        files: The folder's files.
        thrust_matrix: T (6, p): vehicle wrench in base_link_frd of the p thrusts (N -> N, N m).
        max_thrust_n: Per thruster limit (p,) (N).
        dvl_position_m: DVL position in base_link_frd (3,) (m).
        dvl_rotation: Rotation of dvl_link in base_link_frd (3, 3).
        hull: The hull's entry of hydrodynamics.yaml (a mapping, as in the file).
        water_density_kg_m3: The environment's rho (config/robot.yaml).
        gravity_m_s2: The environment's g.
    """

    files: RobotFiles
    thrust_matrix: FloatArray
    max_thrust_n: FloatArray
    dvl_position_m: FloatArray
    dvl_rotation: FloatArray
    hull: dict[str, object]
    water_density_kg_m3: float
    gravity_m_s2: float

    @property
    def name(self) -> str:
        """The robot's name."""
        return self.files.name

    def prior_theta(self) -> FloatArray:
        """The robot folder's hull terms as theta (``uvms_identify.regressor``)."""
        hull = self.hull
        if hull.get('added_mass') != 'coefficients':
            raise IdentifyError(
                f'{self.files.hydrodynamics}: {ROOT_LINK} has added_mass: '
                f'{hull.get("added_mass")}; uvms identify fits the coefficients form '
                '(added_mass: coefficients, docs/robots.md)')
        return theta_from_hull(np.array(hull['added_mass_kg'], float),  # type: ignore[arg-type]
                               np.array(hull['linear_damping'], float),  # type: ignore[arg-type]
                               np.array(hull['quadratic_damping'], float),  # type: ignore[arg-type]
                               self.hull_buoyancy_n(),
                               np.array(hull['center_of_buoyancy_m'], float))  # type: ignore[arg-type]

    def hull_buoyancy_n(self) -> float:
        """The hull's buoyancy (N) of the file (displaced volume, or the ratio's share)."""
        from uvms_identify.known_terms import hull_buoyancy_n
        return hull_buoyancy_n(self)


def _environment() -> tuple[float, float]:
    """Water density and gravity of the simulator's config/robot.yaml."""
    from uvms_bringup.launch_helpers import config_dir
    values = parameter_file_values(Path(config_dir()) / 'robot.yaml', 'simulator')
    rho = values.get('hydrodynamics.water_density_kg_m3')
    g = values.get('hydrodynamics.gravity_m_s2')
    return (float(rho.value) if rho else 1025.0, float(g.value) if g else 9.81)


def load_robot(name: str) -> RobotData:
    """Read robot ``name`` (a folder name or a path with a ``/``).

    Raises:
        IdentifyError: An unknown robot or a folder without what the identification needs.
    """
    from uvms_description.robots import RobotFolderError
    try:
        files = robot_files(name)
    except RobotFolderError as exc:
        raise IdentifyError(str(exc)) from exc
    folder = files.directory
    thrusters = parameter_file_values(folder / 'thrusters.yaml', 'thruster_allocator')
    try:
        positions = np.array(thrusters['thrusters.positions_m'].value, float).reshape(-1, 3)
        directions = np.array(thrusters['thrusters.directions'].value, float).reshape(-1, 3)
        limits = np.array(thrusters['thrusters.max_thrust_n'].value, float)
    except (KeyError, ValueError) as exc:
        raise IdentifyError(f'{folder / "thrusters.yaml"}: no thrusters.positions_m, '
                            f'directions and max_thrust_n of one length ({exc})') from exc
    matrix = np.vstack([directions.T, np.cross(positions, directions).T])
    navigation = parameter_file_values(folder / 'navigation.yaml', 'simulator')
    dvl_position = np.array(navigation['navigation.dvl.position_m'].value, float) \
        if 'navigation.dvl.position_m' in navigation else np.zeros(3)
    rpy = navigation['navigation.dvl.orientation_rpy'].value \
        if 'navigation.dvl.orientation_rpy' in navigation else [0.0, 0.0, 0.0]
    tree = yaml.safe_load(files.hydrodynamics.read_text(encoding='utf-8'))
    hull = dict(tree.get(ROOT_LINK, {}))
    rho, g = _environment()
    return RobotData(files, matrix, limits, dvl_position, rpy_matrix(*map(float, rpy)), hull,
                     rho, g)
