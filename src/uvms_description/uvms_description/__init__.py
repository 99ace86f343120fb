"""Where the UVMS robot descriptions are: robots/<name>/ folders, the hull mesh, the layout.

A robot is a folder ``robots/<name>/`` (format: docs/robots.md, "Adding a robot"): its URDF
(``robot.urdf`` or ``robot.urdf.xacro``), ``hydrodynamics.yaml``, and the ROS 2 parameter
files ``thrusters.yaml``, ``sensor.yaml`` and ``controller.yaml``. ``uvms_description.robots``
finds, checks and reads them.

Three layouts are searched for the share directory, in this order:

1. a source checkout or an editable install: the package folder ``src/uvms_description``
   beside this module (``robots/``, ``meshes/``, ``foxglove/``);
2. the pip wheel: the same folders under ``uvms_description/share`` inside the package;
3. a colcon install: ``share/uvms_description`` found through the ament index.

Only the last needs ROS (``ament_index_python``), and it is imported only when the first
two find nothing.
"""

from __future__ import annotations

from pathlib import Path

PACKAGE = 'uvms_description'
ROBOTS_DIR = 'robots'
"""Folder of the robot folders, relative to the share directory."""
DEFAULT_ROBOT = 'paper_uvms'
"""The robot of Cui & Sarkar (sec. 5.1), the default of every node's ``robot_name``."""
HULL_MESH_FILE = 'meshes/unit_sphere.stl'
"""Sphere of diameter 1 m that the paper robot's URDF scales into the ellipsoidal hull."""
FOXGLOVE_LAYOUT_FILE = 'foxglove/uvms_layout.json'
"""Foxglove layout: 3-D view, F_e with F_d, W, position errors (relative to the share dir)."""


def share_directory() -> Path:
    """The directory holding ``robots/``, ``meshes/`` and ``foxglove/`` of uvms_description.

    Raises:
        FileNotFoundError: If none of the three layouts holds ``robots/``.
    """
    here = Path(__file__).resolve().parent
    tried = [here.parent, here / 'share']
    for candidate in tried:
        if (candidate / ROBOTS_DIR).is_dir():
            return candidate
    try:
        from ament_index_python.packages import (
            PackageNotFoundError,
            get_package_share_directory,
        )
    except ImportError:
        pass
    else:
        try:
            share = Path(get_package_share_directory(PACKAGE))
        except PackageNotFoundError:
            pass
        else:
            if (share / ROBOTS_DIR).is_dir():
                return share
            tried.append(share)
    places = ', '.join(str(path) for path in tried)
    raise FileNotFoundError(
        f'{ROBOTS_DIR}/ of {PACKAGE} not found in {places} nor in the ament index'
    )


def robots_directory() -> Path:
    """The folder of the robot folders (``share/uvms_description/robots``)."""
    return share_directory() / ROBOTS_DIR


def urdf_path(robot: str = DEFAULT_ROBOT) -> Path:
    """Path of a robot's URDF (``robot.urdf`` or ``robot.urdf.xacro`` of its folder)."""
    from uvms_description.robots import robot_files

    return robot_files(robot).urdf


def hydrodynamics_path(robot: str = DEFAULT_ROBOT) -> Path:
    """Path of a robot's hydrodynamic parameters (``hydrodynamics.yaml`` of its folder)."""
    from uvms_description.robots import robot_files

    return robot_files(robot).hydrodynamics


def foxglove_layout_path() -> Path:
    """Path of the Foxglove layout (``share/uvms_description/foxglove/uvms_layout.json``)."""
    return share_directory() / FOXGLOVE_LAYOUT_FILE
