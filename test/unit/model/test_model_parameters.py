"""Parameters of uvms_model: defaults, flat names, validation and config/robot.yaml."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml
from uvms_model.thrusters import ThrusterLayout

from uvms_description.robots import robot_parameters
from uvms_model import PARAMETER_SPECS, ParameterError, UvmsParameters

ROBOT_YAML = Path(__file__).resolve().parents[3] / 'config' / 'robot.yaml'


def _flatten(tree: dict[str, object], prefix: str = '') -> dict[str, object]:
    flat: dict[str, object] = {}
    for key, value in tree.items():
        name = f'{prefix}{key}'
        if isinstance(value, dict):
            flat.update(_flatten(value, f'{name}.'))
        else:
            flat[name] = value
    return flat


def test_defaults_are_the_papers_environment_and_wall() -> None:
    """Sec. 5.1: wall at x = 1.7771 m, K_e = 1e4 N/m; sea water; the description's defaults."""
    p = UvmsParameters()
    assert p.contact.wall_position_m == 1.7771
    assert p.contact.stiffness_n_m == 1e4
    assert p.hydrodynamics.water_density_kg_m3 == 1025.0
    assert (p.description.urdf_path, p.description.hydrodynamics_path) == ('', '')


def test_no_parameter_repeats_what_the_urdf_holds() -> None:
    """Masses, dimensions, mount point and joint axes are no ROS parameters (the URDF's)."""
    names = {spec.name for spec in PARAMETER_SPECS}
    assert not {name for name in names if name.split('.')[0] in ('vehicle', 'arm')}


def test_flat_dict_round_trips() -> None:
    """from_flat_dict(to_flat_dict()) rebuilds the same parameters."""
    p = UvmsParameters().updated({'contact.stiffness_n_m': 1e5, 'sensor.noise_fraction': 0.001})
    assert UvmsParameters.from_flat_dict(p.to_flat_dict()) == p


def test_specs_list_every_parameter_with_ros_types_and_units() -> None:
    """PARAMETER_SPECS names equal the flat names; defaults ROS-typed; numbers carry a unit."""
    flat = UvmsParameters().to_flat_dict()
    assert [spec.name for spec in PARAMETER_SPECS] == list(flat)
    for name, default, description, lo, hi in PARAMETER_SPECS:
        assert default == flat[name]
        assert isinstance(default, (bool, int, float, str, list))
        if isinstance(default, list):
            assert all(isinstance(x, float) for x in default) or all(
                isinstance(x, str) for x in default
            )
        assert description.strip(), name
        if isinstance(default, (int, float)) and not isinstance(default, bool):
            assert '(' in description, f'{name}: unit missing'
        if lo is not None and hi is not None:
            assert lo <= hi


def test_integers_are_accepted_for_float_parameters() -> None:
    """A YAML integer (10000) is a valid float parameter."""
    params = UvmsParameters.from_flat_dict({'contact.stiffness_n_m': 10000})
    assert params.contact.stiffness_n_m == 10000.0


def test_unknown_parameter_is_rejected_by_name() -> None:
    """An unknown dotted name (one the URDF now holds, too) raises ParameterError naming it."""
    with pytest.raises(ParameterError, match=r'vehicle\.mass_kg'):
        UvmsParameters.from_flat_dict({'vehicle.mass_kg': 530.0})


@pytest.mark.parametrize(
    ('name', 'value', 'pattern'),
    [
        ('contact.wall_position_m', -2e4, r'contact\.wall_position_m = -20000\.0 is out'),
        ('contact.stiffness_n_m', 0.0, r'contact\.stiffness_n_m = 0\.0 is out of range'),
        ('contact.stiffness_n_m', -1e4, r'contact\.stiffness_n_m'),
        ('sensor.force_range_n', [400.0, -8.0, 5.0], r'sensor\.force_range_n'),
        ('sensor.force_range_n', [1.0, 2.0], r'sensor\.force_range_n has 2 elements, expected 3'),
        ('thrusters.max_thrust_n', [200.0] * 7, r'thrusters\.max_thrust_n has 7 elements'),
        ('thrusters.positions_m', [0.0] * 10, r'thrusters\.positions_m has 10 elements'),
        ('contact.stiffness_n_m', float('nan'), r'contact\.stiffness_n_m = nan must be finite'),
        ('contact.stiffness_n_m', 'stiff', r'contact\.stiffness_n_m'),
        ('description.urdf_path', 3, r'description\.urdf_path = 3 must be a string'),
        ('hydrodynamics.drag_enabled', 1, r'hydrodynamics\.drag_enabled = 1 must be a bool'),
        ('integration.method', 'euler', r'integration\.method'),
    ],
)
def test_invalid_parameter_raises_a_value_error_naming_it(
    name: str, value: object, pattern: str
) -> None:
    """Bad values raise ParameterError (a ValueError) naming the parameter and the problem."""
    with pytest.raises(ValueError, match=pattern):
        UvmsParameters.from_flat_dict({name: value})


def test_thrusters_that_cannot_roll_are_rejected() -> None:
    """All thrusters in one plane and direction give E rank < 9: ParameterError."""
    positions = [float(v) for i in range(8) for v in (0.1 * i, 0.0, 0.0)]
    directions = [1.0, 0.0, 0.0] * 8
    with pytest.raises(ParameterError, match='rank'):
        UvmsParameters.from_flat_dict(
            {'thrusters.positions_m': positions, 'thrusters.directions': directions}
        )


def test_robot_yaml_and_the_paper_robot_hold_every_parameter_at_its_default() -> None:
    """config/robot.yaml (the world) and robots/paper_uvms (the robot) give every default.

    No name is in both: the world file would override every robot's values.
    """
    tree = yaml.safe_load(ROBOT_YAML.read_text())
    world = _flatten(tree['/**']['ros__parameters'])
    robot = {name: item.value for name, item in robot_parameters('paper_uvms', 'simulator').items()
             if not name.startswith(('description.', 'initial.', 'navigation.'))}
    assert not set(world) & set(robot)
    flat = {**world, **robot}
    assert set(flat) == {spec.name for spec in PARAMETER_SPECS} - {
        'description.urdf_path', 'description.hydrodynamics_path'}
    loaded = UvmsParameters.from_flat_dict(flat)
    assert loaded == UvmsParameters()


def test_robot_yaml_documents_every_parameter_in_a_comment() -> None:
    """Each parameter line of config/robot.yaml carries a '#' comment (source or reason)."""
    for line in ROBOT_YAML.read_text().splitlines():
        stripped = line.strip()
        if stripped and not stripped.startswith('#') and not stripped.endswith(':'):
            assert '#' in stripped, line


def test_default_thruster_layout_has_eight_thrusters_within_limits() -> None:
    """Default: 8 thrusters, 200 N each, unit directions."""
    layout = ThrusterLayout.from_parameters(UvmsParameters().thrusters)
    assert layout.count == 8
    np.testing.assert_allclose(np.linalg.norm(layout.directions, axis=1), 1.0)
