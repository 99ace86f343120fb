"""Where the UVMS robot description is: its URDF, hydrodynamic parameters and hull mesh.

Three layouts are searched, in this order:

1. a source checkout or an editable install: the package folder ``src/uvms_description``
   beside this module (``urdf/``, ``config/``, ``meshes/``);
2. the pip wheel: the same folders under ``uvms_description/share`` inside the package;
3. a colcon install: ``share/uvms_description`` found through the ament index.

Only the last needs ROS (``ament_index_python``), and it is imported only when the first
two find nothing.
"""

from __future__ import annotations

from pathlib import Path

PACKAGE = 'uvms_description'
URDF_FILE = 'urdf/uvms.urdf'
"""The URDF of the paper's UVMS, relative to the share directory."""
HYDRODYNAMICS_FILE = 'config/hydrodynamics.yaml'
"""Hydrodynamic parameters keyed by link name, relative to the share directory."""
HULL_MESH_FILE = 'meshes/unit_sphere.stl'
"""Sphere of diameter 1 m that the URDF scales into the ellipsoidal hull."""
FOXGLOVE_LAYOUT_FILE = 'foxglove/uvms_layout.json'
"""Foxglove layout: 3-D view, F_e with F_d, W, position errors (relative to the share dir)."""


def share_directory() -> Path:
    """The directory holding ``urdf/``, ``config/`` and ``meshes/`` of uvms_description.

    Raises:
        FileNotFoundError: If none of the three layouts holds ``urdf/uvms.urdf``.
    """
    here = Path(__file__).resolve().parent
    tried = [here.parent, here / 'share']
    for candidate in tried:
        if (candidate / URDF_FILE).is_file():
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
            if (share / URDF_FILE).is_file():
                return share
            tried.append(share)
    places = ', '.join(str(path) for path in tried)
    raise FileNotFoundError(
        f'{URDF_FILE} of {PACKAGE} not found in {places} nor in the ament index'
    )


def urdf_path() -> Path:
    """Path of the UVMS URDF (``share/uvms_description/urdf/uvms.urdf``)."""
    return share_directory() / URDF_FILE


def hydrodynamics_path() -> Path:
    """Path of the hydrodynamic parameters beside the URDF (``config/hydrodynamics.yaml``)."""
    return share_directory() / HYDRODYNAMICS_FILE


def foxglove_layout_path() -> Path:
    """Path of the Foxglove layout (``share/uvms_description/foxglove/uvms_layout.json``)."""
    return share_directory() / FOXGLOVE_LAYOUT_FILE
