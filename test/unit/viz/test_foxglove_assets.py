"""What the live view hands to the Foxglove app: the URDF's mesh, nothing outside its package."""

from __future__ import annotations

from uvms_viz.foxglove_server_node import asset

import uvms_description


def test_the_hull_mesh_the_urdf_names_is_served() -> None:
    """package://uvms_description/meshes/unit_sphere.stl is the file of the share directory."""
    data = asset('package://uvms_description/meshes/unit_sphere.stl')
    expected = (uvms_description.share_directory() / uvms_description.HULL_MESH_FILE)
    assert data == expected.read_bytes()


def test_paths_leaving_the_package_and_other_packages_are_refused() -> None:
    """No file outside uvms_description's share directory is served."""
    assert asset('package://uvms_description/../../../etc/passwd') is None
    assert asset('package://other/meshes/unit_sphere.stl') is None
    assert asset('file:///etc/passwd') is None
    assert asset('package://uvms_description/meshes/missing.stl') is None
