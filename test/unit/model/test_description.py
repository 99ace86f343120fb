"""The robot description: the URDF read by an independent parser, its files, and bad input."""

from __future__ import annotations

import dataclasses
import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
import yaml

import uvms_description
from uvms_model import (
    DescriptionError,
    UvmsModel,
    UvmsParameters,
    load_description,
)

URDF = uvms_description.urdf_path()
HYDRODYNAMICS = uvms_description.hydrodynamics_path()
PAPER_LINKS = {  # paper sec. 5.1: length (m), radius (m), mass (kg)
    'link_1': (0.5, 0.05, 10.0),
    'link_2': (0.5, 0.04, 8.0),
    'link_3': (0.5, 0.035, 5.0),
}


def _robot() -> ET.Element:
    return ET.parse(URDF).getroot()


def _link(name: str) -> ET.Element:
    link = _robot().find(f"link[@name='{name}']")
    assert link is not None, name
    return link


def _floats(text: str | None) -> list[float]:
    assert text is not None
    return [float(v) for v in text.split()]


def test_urdf_is_a_tree_with_one_root_and_every_joint_between_existing_links() -> None:
    """check_urdf's rules: links named once, parents and children exist, one root, no loops."""
    robot = _robot()
    links = [link.get('name') for link in robot.findall('link')]
    assert len(links) == len(set(links))
    children = []
    for joint in robot.findall('joint'):
        parent = joint.find('parent').get('link')  # type: ignore[union-attr]
        child = joint.find('child').get('link')  # type: ignore[union-attr]
        assert parent in links and child in links, joint.get('name')
        children.append(child)
    assert len(children) == len(set(children))
    assert [name for name in links if name not in children] == ['base_link_frd']
    assert set(load_description().frame_names) <= set(links)


def test_urdf_holds_the_papers_vehicle() -> None:
    """Sec. 5.1: an ellipsoid 1.0 m long, 0.5 m high and wide, 530 kg (a scaled unit sphere)."""
    hull = _link('base_link_frd')
    assert float(hull.find('inertial/mass').get('value')) == 530.0  # type: ignore[union-attr]
    for element in ('visual', 'collision'):
        mesh = hull.find(f'{element}/geometry/mesh')
        assert mesh is not None
        assert mesh.get('filename') == 'package://uvms_description/meshes/unit_sphere.stl'
        assert _floats(mesh.get('scale')) == [1.0, 0.5, 0.5]


def test_hull_mesh_is_a_sphere_of_unit_diameter() -> None:
    """Every vertex of meshes/unit_sphere.stl lies 0.5 m from the origin, extent +-0.5 m."""
    text = (uvms_description.share_directory() / uvms_description.HULL_MESH_FILE).read_text()
    vertices = np.array(
        [[float(v) for v in line.split()[1:]] for line in text.splitlines() if 'vertex' in line]
    )
    np.testing.assert_allclose(np.linalg.norm(vertices, axis=1), 0.5, atol=1e-9)
    np.testing.assert_allclose(vertices.max(axis=0), 0.5, atol=1e-9)
    np.testing.assert_allclose(vertices.min(axis=0), -0.5, atol=1e-9)


@pytest.mark.parametrize('name', list(PAPER_LINKS))
def test_urdf_holds_the_papers_links(name: str) -> None:
    """Cylinders of 0.5 m, radii 5/4/3.5 cm, 10/8/5 kg, along x from their joint."""
    length, radius, mass = PAPER_LINKS[name]
    link = _link(name)
    assert float(link.find('inertial/mass').get('value')) == mass  # type: ignore[union-attr]
    for element in ('visual', 'collision'):
        cylinder = link.find(f'{element}/geometry/cylinder')
        assert cylinder is not None
        assert float(cylinder.get('radius')) == radius  # type: ignore[arg-type]
        assert float(cylinder.get('length')) == length  # type: ignore[arg-type]
        origin = link.find(f'{element}/origin')
        assert _floats(origin.get('xyz')) == [0.5 * length, 0.0, 0.0]  # type: ignore[union-attr]
        assert _floats(origin.get('rpy')) == [0.0, math.pi / 2, 0.0]  # type: ignore[union-attr]


@pytest.mark.parametrize('name', list(PAPER_LINKS))
def test_link_inertia_is_a_uniform_solid_cylinder_about_its_centre(name: str) -> None:
    """M r^2 / 2 axially, m (3 r^2 + L^2) / 12 across, at (L/2, 0, 0)."""
    length, radius, mass = PAPER_LINKS[name]
    inertial = _link(name).find('inertial')
    assert inertial is not None
    origin = inertial.find('origin')
    assert origin is not None
    assert _floats(origin.get('xyz')) == [0.5 * length, 0.0, 0.0]
    inertia = inertial.find('inertia')
    assert inertia is not None
    transverse = mass * (3 * radius**2 + length**2) / 12
    assert float(inertia.get('ixx')) == pytest.approx(0.5 * mass * radius**2, rel=1e-15)  # type: ignore[arg-type]
    assert float(inertia.get('iyy')) == pytest.approx(transverse, rel=1e-15)  # type: ignore[arg-type]
    assert float(inertia.get('izz')) == pytest.approx(transverse, rel=1e-15)  # type: ignore[arg-type]


def test_joints_mount_the_arm_at_the_nose_yaw_then_pitch_pitch() -> None:
    """joint_1 at (0.5, 0, 0) about z, joints 2 and 3 at 0.5 m along the links about y."""
    robot = _robot()
    expected = {
        'joint_1': ([0.5, 0.0, 0.0], [0.0, 0.0, 1.0]),
        'joint_2': ([0.5, 0.0, 0.0], [0.0, 1.0, 0.0]),
        'joint_3': ([0.5, 0.0, 0.0], [0.0, 1.0, 0.0]),
    }
    for name, (xyz, axis) in expected.items():
        joint = robot.find(f"joint[@name='{name}']")
        assert joint is not None and joint.get('type') == 'revolute'
        assert _floats(joint.find('origin').get('xyz')) == xyz  # type: ignore[union-attr]
        assert _floats(joint.find('axis').get('xyz')) == axis  # type: ignore[union-attr]
    ee = robot.find("joint[@name='ee_joint']")
    assert ee is not None and ee.get('type') == 'fixed'
    assert _floats(ee.find('origin').get('xyz')) == [0.5, 0.0, 0.0]  # type: ignore[union-attr]


def test_hydrodynamics_file_holds_the_papers_coefficients_by_link() -> None:
    """Sec. 5.1: linear 0 and 0.81, quadratic 1.05 and 1.0, manipulator 1.1; neutral UVMS."""
    tree = yaml.safe_load(HYDRODYNAMICS.read_text())
    assert set(tree) == {'base_link_frd', 'link_1', 'link_2', 'link_3'}
    hull = tree['base_link_frd']
    assert hull['linear_drag_translation_n_s_m'] == 0.0
    assert hull['linear_drag_rotation_n_m_s'] == 0.81
    assert (hull['drag_coefficient_translation'], hull['drag_coefficient_rotation']) == (1.05, 1.0)
    assert hull['buoyancy_ratio'] == 1.0
    for link in PAPER_LINKS:
        assert tree[link]['cross_flow_drag_coefficient'] == 1.1


def test_description_is_found_beside_the_package_in_a_source_checkout() -> None:
    """From src/uvms_description: robots/paper_uvms/robot.urdf and its hydrodynamics.yaml."""
    share = uvms_description.share_directory()
    assert share == Path(uvms_description.__file__).resolve().parents[1]
    assert URDF == share / 'robots' / 'paper_uvms' / 'robot.urdf'
    assert HYDRODYNAMICS == share / 'robots' / 'paper_uvms' / 'hydrodynamics.yaml'


def test_description_is_found_through_the_ament_index_of_a_colcon_install(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """With the module installed elsewhere, share/uvms_description comes from the index."""
    prefix = tmp_path / 'install'
    share = prefix / 'share' / 'uvms_description'
    (share / 'robots' / 'paper_uvms').mkdir(parents=True)
    (share / 'robots' / 'paper_uvms' / 'robot.urdf').write_text(URDF.read_text())
    index = prefix / 'share' / 'ament_index' / 'resource_index' / 'packages'
    index.mkdir(parents=True)
    (index / 'uvms_description').write_text('')
    module = prefix / 'lib' / 'python3' / 'site-packages' / 'uvms_description' / '__init__.py'
    monkeypatch.setattr(uvms_description, '__file__', str(module))
    monkeypatch.setenv('AMENT_PREFIX_PATH', str(prefix))
    assert uvms_description.share_directory() == share


def test_model_reads_a_missing_description_as_a_one_line_error_naming_the_file(
    tmp_path: Path,
) -> None:
    """A URDF that does not exist stops the model with its path in one line."""
    missing = tmp_path / 'nowhere.urdf'
    params = UvmsParameters().updated({'description.urdf_path': str(missing)})
    with pytest.raises(DescriptionError, match=r'nowhere\.urdf: cannot read the URDF') as error:
        UvmsModel(params)
    assert '\n' not in str(error.value)


def _edited(tmp_path: Path, old: str, new: str, count: int = -1) -> Path:
    text = URDF.read_text()
    assert old in text
    path = tmp_path / 'edited.urdf'
    path.write_text(text.replace(old, new, count))
    return path


@pytest.mark.parametrize(
    ('old', 'new', 'pattern'),
    [
        ('</robot>', '', r'edited\.urdf: malformed URDF \(XML\)'),
        (
            '<link name="ft_sensor_link"/>',
            '',
            r"edited\.urdf: joint 'ft_sensor_joint': child link 'ft_sensor_link' is not defined",
        ),
        (
            '<parent link="link_1"/>',
            '<parent link="link_9"/>',
            r"edited\.urdf: joint 'joint_2': parent link 'link_9' is not defined",
        ),
        (
            '<link name="ee_link"/>',
            '<link name="ee_link"/><link name="stray"/>',
            r"edited\.urdf: expected one root link, found \['base_link_frd', 'stray'\]",
        ),
        (
            '<cylinder radius="0.04" length="0.5"/>',
            '<cylinder radius="wide" length="0.5"/>',
            r"edited\.urdf: link 'link_2' <collision><geometry><cylinder>: attribute 'radius'",
        ),
        (
            'type="revolute">\n    <parent link="link_2"/>',
            'type="prismatic">\n    <parent link="link_2"/>',
            r"edited\.urdf: joint 'joint_3' on the arm \(base_link_frd to ee_link\) is of type "
            r"'prismatic'",
        ),
        (
            'type="revolute">\n    <parent link="link_2"/>',
            'type="fixed">\n    <parent link="link_2"/>',
            r"edited\.urdf: the arm from base_link_frd to ee_link has 2 revolute joints "
            r"\['joint_1', 'joint_2'\]; at least 3",
        ),
        (
            '<link name="ee_link"/>',
            '<link name="ee_link"/><link name="fin"><inertial><mass value="1.0"/><inertia '
            'ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link><joint '
            'name="fin_joint" type="revolute"><parent link="base_link_frd"/><child '
            'link="fin"/><axis xyz="0 0 1"/><limit effort="1" velocity="1" lower="-1" '
            'upper="1"/></joint>',
            r"edited\.urdf: joint 'fin_joint' \(revolute\) is not on the arm from base_link_frd "
            r'to ee_link: a branched chain',
        ),
        (
            '<mass value="8.0"/>',
            '<mass value="0.0"/>',
            r"edited\.urdf: link 'link_2' <inertial><mass value='0.0'>: the mass must be "
            'positive',
        ),
        (
            '<mass value="530.0"/>',
            '<mass value="-530.0"/>',
            r"edited\.urdf: link 'base_link_frd' <inertial><mass value='-530.0'>: the mass "
            'must be positive',
        ),
    ],
    ids=['malformed', 'missing frame', 'missing parent', 'two roots', 'bad number', 'prismatic',
         'two joints', 'branched', 'zero mass', 'negative mass'],
)
def test_broken_urdf_stops_start_up_naming_the_file_and_the_element(
    tmp_path: Path, old: str, new: str, pattern: str
) -> None:
    """Malformed XML, a missing frame or link, a bad attribute: one line, file and element."""
    with pytest.raises(DescriptionError, match=pattern) as error:
        load_description(_edited(tmp_path, old, new))
    assert '\n' not in str(error.value)


def test_renamed_frame_is_reported_as_missing(tmp_path: Path) -> None:
    """A URDF without the link ee_link (renamed) names the missing frame."""
    path = _edited(tmp_path, 'ee_link', 'tool0', count=-1)
    with pytest.raises(DescriptionError, match=r"link 'ee_link' is missing"):
        load_description(path)


@pytest.mark.parametrize(
    ('edit', 'pattern'),
    [
        ({'link_2': {'drag': 1.1}}, r"link_2: unknown keys \['drag'\]"),
        ({'link_4': {}}, r"links \['link_4'\] are not the hull or arm links of the URDF"),
        ({'base_link_frd': {'buoyancy_ratio': 'neutral'}}, r'base_link_frd\.buoyancy_ratio'),
        ({'link_1': {'added_mass': 'sphere'}}, r'must be one of'),
    ],
)
def test_bad_hydrodynamics_file_names_the_file_link_and_key(
    tmp_path: Path, edit: dict[str, dict[str, object]], pattern: str
) -> None:
    """Unknown keys, unknown links and bad values are rejected with file, link and key."""
    tree = yaml.safe_load(HYDRODYNAMICS.read_text())
    for link, entry in edit.items():
        tree[link] = {**tree.get(link, {}), **entry} if link in tree else entry
    path = tmp_path / 'hydro.yaml'
    path.write_text(yaml.safe_dump(tree))
    with pytest.raises(DescriptionError, match=rf'hydro\.yaml: .*{pattern}'):
        load_description(URDF, path)


def test_a_longer_link_in_the_urdf_changes_the_kinematics_and_the_dynamics(
    tmp_path: Path,
) -> None:
    """link_3 of 0.6 m (joint, geometry, inertia edited): the EE reaches 2.1 m, M_b changes."""
    text = URDF.read_text()
    link_3 = text.index('<link name="link_3">')
    ee_joint = text.index('<joint name="ee_joint"')
    end = text.index('</joint>', ee_joint)
    section = text[link_3:end]
    section = section.replace('xyz="0.25 0.0 0.0"', 'xyz="0.3 0.0 0.0"')
    section = section.replace('length="0.5"', 'length="0.6"')
    tip = '<origin xyz="0.5 0.0 0.0" rpy="0 0 0"/>'
    section = section.replace(tip, tip.replace('0.5', '0.6'))
    path = tmp_path / 'longer.urdf'
    path.write_text(text[:link_3] + section + text[end:])
    longer = UvmsModel(UvmsParameters().updated({'description.urdf_path': str(path)}))
    paper = UvmsModel()
    q = np.zeros(9)
    np.testing.assert_allclose(longer.ee_position(q), [2.1, 0.0, 0.0], atol=1e-12)
    assert longer.description.links[2].length_m == 0.6
    assert not np.allclose(longer.mass_matrix_body(q), paper.mass_matrix_body(q))


@pytest.mark.parametrize('ratio', [1.0, 1.02])
def test_buoyancy_ratio_sets_total_buoyancy_over_weight(ratio: float) -> None:
    """Hull displacement + link displacement = ratio x total mass (553 kg)."""
    description = load_description()
    hull = dataclasses.replace(description.hull_hydrodynamics, buoyancy_ratio=ratio)
    model = UvmsModel(description=dataclasses.replace(description, hull_hydrodynamics=hull))
    links = 1025.0 * np.pi * (0.05**2 + 0.04**2 + 0.035**2) * 0.5
    assert model.hull_displaced_mass_kg + links == pytest.approx(ratio * 553.0, rel=1e-12)


def test_buoyancy_ratio_below_the_links_displacement_is_rejected() -> None:
    """A ratio the links alone exceed would need a negative hull volume: DescriptionError."""
    description = load_description()
    hull = dataclasses.replace(description.hull_hydrodynamics, buoyancy_ratio=0.01)
    with pytest.raises(DescriptionError, match=r'base_link_frd\.buoyancy_ratio = 0\.01 is below'):
        UvmsModel(description=dataclasses.replace(description, hull_hydrodynamics=hull))


def test_neutral_hull_with_zero_net_weight_keeps_its_restoring_moment() -> None:
    """Hull weight = hull buoyancy (net weight 0): G_b still holds m g (CB - CG) x g."""
    description = load_description()
    links = 1025.0 * np.pi * (0.05**2 + 0.04**2 + 0.035**2) * 0.5
    ratio = (530.0 + links) / 553.0  # hull displaces exactly its own 530 kg
    hull = dataclasses.replace(description.hull_hydrodynamics, buoyancy_ratio=ratio)
    model = UvmsModel(description=dataclasses.replace(description, hull_hydrodynamics=hull))
    assert model.hull_displaced_mass_kg == pytest.approx(530.0, rel=1e-12)
    q = np.zeros(9)
    q[3] = 0.2  # roll; arm straight ahead along the roll axis
    g_b = model.gravity_body(q)
    # Roll moment of the hull alone: m g (z_CG - z_CB) sin(roll), CB at z = 0 (0.028 m ahead).
    assert g_b[3] == pytest.approx(530.0 * 9.81 * 0.05 * np.sin(0.2), rel=1e-9)
