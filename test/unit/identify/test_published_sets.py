"""The published alternative hull (Wu 2018) loads as a hydrodynamics file, with its top speed."""

from __future__ import annotations

import math
import re

from uvms_model.description import load_description

from uvms_description.robots import robot_files

SURGE_N = 4 * math.sqrt(0.5) * 39.9  # the four horizontals at the allocator's limit


def _top_speed(linear: float, quadratic: float) -> float:
    """Steady surge speed of linear u + quadratic u^2 = SURGE_N (m/s)."""
    return (-linear + math.sqrt(linear**2 + 4.0 * quadratic * SURGE_N)) / (2.0 * quadratic)


def test_the_wu_2018_hull_loads_and_states_its_top_surge_speed() -> None:
    """The file is a valid hull for the robot's URDF; the speeds in its header are its own."""
    files = robot_files('bluerov2_alpha5')
    path = files.directory / 'hydrodynamics_wu2018.yaml'
    hull = load_description(files.urdf, path).hull_hydrodynamics
    assert hull.quadratic_damping is not None and hull.linear_damping is not None
    assert hull.quadratic_damping[0] == 18.18 and hull.linear_damping[0] == 4.03
    text = path.read_text(encoding='utf-8')
    wu = _top_speed(hull.linear_damping[0], hull.quadratic_damping[0])
    assert f'Wu 2018 {wu:.2f} m/s' in re.sub(r'\s+', ' ', text)
    assert 'von Benzon 2022 (shipped) 0.85 m/s' in re.sub(r'\s+', ' ', text.replace('# ', ''))
    assert abs(_top_speed(13.7, 141.0) - 0.85) < 0.005
