"""A hull given by published coefficients (added_mass: coefficients) against hand computations."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

import uvms_description
from uvms_model import DescriptionError, UvmsModel, UvmsParameters, load_description

PAPER = uvms_description.robots_directory() / 'paper_uvms'
ADDED = [6.0, 7.0, 18.0, 0.2, 0.1, 0.3]
LINEAR = [13.7, 2.0, 33.0, 0.5, 0.8, 0.4]
QUADRATIC = [141.0, 217.0, 190.0, 1.19, 0.47, 1.5]
#: The hull's body twist of the hand computations; the arm at rest relative to the hull.
NU = np.array([1.0, 0.5, 0.0, 0.0, 0.0, 0.0])


def _robot(tmp_path: Path, **hull: object) -> Path:
    """The paper's hydrodynamics with the hull replaced by a coefficient entry."""
    tree = yaml.safe_load((PAPER / 'hydrodynamics.yaml').read_text())
    tree['base_link_frd'] = {
        'added_mass': 'coefficients', 'added_mass_kg': ADDED, 'linear_damping': LINEAR,
        'quadratic_damping': QUADRATIC, 'displaced_volume_m3': 0.5,
        'center_of_buoyancy_m': [0.0, 0.0, 0.0], **hull}
    path = tmp_path / f'hydro_{len(list(tmp_path.iterdir()))}.yaml'
    path.write_text(yaml.safe_dump(tree))
    return path


def _model(path: Path, **switches: bool) -> UvmsModel:
    flat = {'description.hydrodynamics_path': str(path),
            **{f'hydrodynamics.{k}': v for k, v in switches.items()}}
    return UvmsModel(UvmsParameters().updated(flat))


def _state(nu: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    q = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.9273, -1.5708])
    return q, np.concatenate((nu, np.zeros(3)))


def test_added_mass_is_the_diagonal_block_of_the_mass_matrix(tmp_path: Path) -> None:
    """M_b with the coefficients minus M_b with zero coefficients = diag(added_mass_kg) at O."""
    model = _model(_robot(tmp_path))
    bare = _model(_robot(tmp_path, added_mass_kg=[0.0] * 6))
    q, _ = _state(NU)
    difference = model.mass_matrix_body(q) - bare.mass_matrix_body(q)
    expected = np.zeros((9, 9))
    expected[:6, :6] = np.diag(ADDED)
    np.testing.assert_allclose(difference, expected, atol=1e-12)


def test_munk_moment_by_hand(tmp_path: Path) -> None:
    """ν = (u, v) = (1, 0.5) m/s: C_A(ν) ν = [0; v × M_A v] = (0, 0, 0, 0, 0, (Y - X) u v).

    By hand: M_A v = (6, 3.5, 0), v × M_A v = (0, 0, 1 · 3.5 - 0.5 · 6) = (0, 0, 0.5) N m.
    """
    off = {'drag_enabled': False, 'buoyancy_enabled': False}
    model = _model(_robot(tmp_path), **off)
    bare = _model(_robot(tmp_path, added_mass_kg=[0.0] * 6), **off)
    q, w = _state(NU)
    difference = model.bias_body(q, w) - bare.bias_body(q, w)
    np.testing.assert_allclose(difference, [0, 0, 0, 0, 0, 0.5, 0, 0, 0], atol=1e-12)


def test_drag_by_hand(tmp_path: Path) -> None:
    """Hull drag D_l ν + D_q |ν| ν: surge 13.7 + 141 = 154.7 N, sway 2 · 0.5 + 217 · 0.25."""
    off = {'added_mass_enabled': False, 'buoyancy_enabled': False}
    model = _model(_robot(tmp_path), **off)
    bare = _model(_robot(tmp_path, linear_damping=[0.0] * 6, quadratic_damping=[0.0] * 6), **off)
    q, w = _state(NU)
    difference = model.bias_body(q, w) - bare.bias_body(q, w)
    np.testing.assert_allclose(difference, [154.7, 55.25, 0, 0, 0, 0, 0, 0, 0], atol=1e-10)


def test_buoyancy_from_the_displaced_volume(tmp_path: Path) -> None:
    """displaced_volume_m3 = 0.5 displaces rho V = 512.5 kg of sea water."""
    assert _model(_robot(tmp_path)).hull_displaced_mass_kg == pytest.approx(1025.0 * 0.5)


def test_forward_dynamics_solves_eq_8(tmp_path: Path) -> None:
    """w_dot = M_b⁻¹ (tau_b - bias) with the hull's M_A in M_b (no ABA shortcut)."""
    model = _model(_robot(tmp_path))
    rng = np.random.default_rng(3)
    q, w = _state(rng.normal(size=6) * 0.3)
    q[3:6] = rng.normal(size=3) * 0.2
    tau_b = rng.normal(size=9) * 10.0
    expected = np.linalg.solve(model.mass_matrix_body(q), tau_b - model.bias_body(q, w))
    np.testing.assert_allclose(model.forward_dynamics(q, w, tau_b), expected, rtol=1e-9,
                               atol=1e-9)


def test_kinetic_energy_is_conserved_without_drag_gravity_and_inputs(tmp_path: Path) -> None:
    """Kirchhoff's added-mass terms do no work: ½ wᵀ M_b w constant over 5 s of RK4."""
    model = _model(_robot(tmp_path), drag_enabled=False, buoyancy_enabled=False)
    model = UvmsModel(model.params.updated({'hydrodynamics.gravity_m_s2': 0.0}))
    q, w = _state(np.array([0.3, -0.2, 0.1, 0.2, -0.1, 0.3]))
    w[6:] = (0.2, -0.3, 0.1)
    energy = 0.5 * w @ model.mass_matrix_body(q) @ w
    for _ in range(1000):
        q, w = model.step(q, w, np.zeros(9), None, 5e-3)
    assert 0.5 * w @ model.mass_matrix_body(q) @ w == pytest.approx(energy, rel=1e-6)


def test_coefficient_hull_takes_exactly_one_buoyancy_key(tmp_path: Path) -> None:
    """Both displaced_volume_m3 and buoyancy_ratio: refused, naming the file and the keys."""
    path = _robot(tmp_path, buoyancy_ratio=1.0)
    with pytest.raises(DescriptionError, match=r'hydro_0\.yaml: base_link_frd: added_mass: '
                                               r'coefficients takes exactly one of'):
        load_description(None, path)


def test_coefficient_vectors_need_six_non_negative_values(tmp_path: Path) -> None:
    """Five values, or a negative magnitude, name the key."""
    with pytest.raises(DescriptionError, match=r'added_mass_kg = .* must be 6 numbers'):
        load_description(None, _robot(tmp_path, added_mass_kg=[1.0] * 5))
    with pytest.raises(DescriptionError, match=r'linear_damping = .* out of range'):
        load_description(None, _robot(tmp_path, linear_damping=[-1.0] + [0.0] * 5))


@pytest.mark.parametrize('seed', range(6))
def test_coefficient_hull_equals_the_independent_reference_model(
    tmp_path: Path, seed: int
) -> None:
    """M_b, bias and one RK4 step equal the pure-Python reference with the same coefficients."""
    from dataclasses import replace

    from model_oracles import random_state
    from reference_model import ReferenceModel, ReferenceRobot, ReferenceVehicle

    model = _model(_robot(tmp_path))
    vehicle = replace(ReferenceVehicle(), added_mass_kg=tuple(ADDED),
                      linear_damping=tuple(LINEAR), quadratic_damping=tuple(QUADRATIC),
                      displaced_volume_m3=0.5, center_of_buoyancy_m=(0.0, 0.0, 0.0))
    reference = ReferenceModel(model.params, ReferenceRobot(vehicle=vehicle))
    q, w = random_state(seed)
    np.testing.assert_allclose(model.mass_matrix_body(q), reference.mass_matrix_body(q),
                               rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(model.bias_body(q, w), reference.bias_body(q, w), rtol=1e-9,
                               atol=1e-9)
    tau_b = np.random.default_rng(seed).normal(0.0, 20.0, 9)
    for actual, expected in zip(model.step(q, w, tau_b, None, 1e-3),
                                reference.step(q, w, tau_b, None, 1e-3), strict=True):
        np.testing.assert_allclose(actual, expected, rtol=1e-9, atol=1e-12)
