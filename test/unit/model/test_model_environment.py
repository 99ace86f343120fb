"""Wall contact, wrist force/torque sensor and thruster configuration matrix of uvms_model."""

from __future__ import annotations

import numpy as np
import pytest
from uvms_model.contact import WallContact
from uvms_model.parameters import ContactParameters, SensorParameters, ThrusterParameters
from uvms_model.sensors import ForceTorqueSensor, contact_wrench_in_sensor_frame
from uvms_model.thrusters import ThrusterLayout, configuration_matrix

from uvms_model import StateError


@pytest.mark.parametrize('stiffness', [1e4, 1e5])
@pytest.mark.parametrize('depth', [1e-4, 1.5e-3, 0.015])
def test_contact_force_is_stiffness_times_penetration(stiffness: float, depth: float) -> None:
    """F_e = K_e delta along +x of map_ned while the EE is delta beyond the wall."""
    wall = WallContact(ContactParameters(stiffness_n_m=stiffness))
    state = wall.evaluate(0.0, [1.7771 + depth, 0.3, -0.2])
    assert state.in_contact
    assert state.penetration_m == pytest.approx(depth, rel=1e-9)
    np.testing.assert_allclose(state.force_ned, [stiffness * depth, 0.0, 0.0], rtol=1e-9)


def test_wall_never_pulls() -> None:
    """In front of the wall, or receding fast with damping, the force is zero (unilateral)."""
    wall = WallContact(ContactParameters(stiffness_n_m=1e4, damping_n_s_m=1e4))
    assert not wall.evaluate(0.0, [1.70, 0.0, 0.0]).in_contact
    np.testing.assert_array_equal(wall.evaluate(0.0, [1.70, 0.0, 0.0]).force_ned, 0.0)
    receding = wall.evaluate(0.0, [1.7781, 0.0, 0.0], [-1.0, 0.0, 0.0])
    assert receding.penetration_m > 0.0
    np.testing.assert_array_equal(receding.force_ned, 0.0)


def test_contact_is_frictionless() -> None:
    """Sliding along the wall adds no tangential force."""
    wall = WallContact(ContactParameters(damping_n_s_m=100.0))
    state = wall.evaluate(0.0, [1.78, 0.0, 0.0], [0.0, 0.5, -0.3])
    assert state.force_ned[1] == 0.0 and state.force_ned[2] == 0.0


def test_moving_wall_starts_at_first_contact_and_moves_along_plus_x() -> None:
    """Case III: the wall stays until the first contact, then moves at 0.05 m/s along +x."""
    wall = WallContact(ContactParameters(wall_speed_m_s=0.05))
    wall.update(1.0, [1.70, 0.0, 0.0])
    assert wall.wall_position(2.0) == 1.7771
    wall.update(2.0, [1.78, 0.0, 0.0])
    assert wall.contact_time_s == 2.0
    assert wall.wall_position(4.0) == pytest.approx(1.7771 + 0.1)
    assert wall.wall_velocity(4.0) == 0.05
    wall.reset()
    assert wall.wall_position(4.0) == 1.7771


def test_sensor_frame_wrench_is_the_rotated_contact_force() -> None:
    """The sensor sees R^T F_e; the magnitude is preserved."""
    rot = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    force, torque = contact_wrench_in_sensor_frame(rot, [150.0, 0.0, 0.0])
    np.testing.assert_allclose(force, [0.0, -150.0, 0.0], atol=1e-12)
    np.testing.assert_array_equal(torque, 0.0)


def test_noise_free_sensor_reads_the_true_wrench() -> None:
    """With noise fraction 0 and no filter the reading is exact."""
    sensor = ForceTorqueSensor(SensorParameters())
    force, torque = sensor.measure([150.0, -3.0, 2.0], [0.1, 0.2, 0.3])
    np.testing.assert_array_equal(force, [150.0, -3.0, 2.0])
    np.testing.assert_array_equal(torque, [0.1, 0.2, 0.3])


def test_sensor_noise_has_the_set_standard_deviation() -> None:
    """Case II: std = 0.1 % of range per axis (20000 samples, within 3 %)."""
    params = SensorParameters(noise_fraction=0.001)
    sensor = ForceTorqueSensor(params, seed=11)
    samples = np.array(
        [np.concatenate(sensor.measure([150.0, 0, 0], [0, 0, 0])) for _ in range(20000)]
    )
    expected = 0.001 * np.array([400.0, 400.0, 400.0, 40.0, 40.0, 40.0])
    np.testing.assert_allclose(samples.std(axis=0), expected, rtol=0.03)
    np.testing.assert_allclose(
        samples.mean(axis=0), [150.0, 0, 0, 0, 0, 0], atol=3 * expected.max() / 100
    )


def test_seeded_sensor_runs_repeat_exactly() -> None:
    """Two sensors with the same seed give identical readings; another seed differs."""
    params = SensorParameters(noise_fraction=0.001, cutoff_hz=100.0)

    def run(seed: int) -> np.ndarray:
        sensor = ForceTorqueSensor(params, seed=seed)
        return np.array(
            [np.concatenate(sensor.measure([150.0, 0, 0], [0, 0, 0], 1e-3)) for _ in range(50)]
        )

    np.testing.assert_array_equal(run(3), run(3))
    assert not np.array_equal(run(3), run(4))


def test_sensor_saturates_at_its_range() -> None:
    """A force beyond full scale reads the full scale."""
    sensor = ForceTorqueSensor(SensorParameters())
    force, torque = sensor.measure([900.0, -500.0, 10.0], [0.0, 0.0, -99.0])
    np.testing.assert_array_equal(force, [400.0, -400.0, 10.0])
    assert torque[2] == -40.0


def test_low_pass_filter_has_the_set_time_constant() -> None:
    """A step through a 10 Hz first-order filter reaches 1 - 1/e after 1/(2 pi 10) s."""
    sensor = ForceTorqueSensor(SensorParameters(cutoff_hz=10.0))
    sensor.measure([0.0, 0, 0], [0, 0, 0], 1e-4)
    dt = 1e-4
    steps = round(1.0 / (2 * np.pi * 10.0) / dt)
    for _ in range(steps):
        force, _ = sensor.measure([100.0, 0, 0], [0, 0, 0], dt)
    assert force[0] == pytest.approx(100.0 * (1 - np.exp(-1.0)), rel=0.01)


def test_sensor_rejects_nan_input() -> None:
    """A NaN force raises StateError naming 'force'."""
    with pytest.raises(StateError, match='force'):
        ForceTorqueSensor().measure([np.nan, 0.0, 0.0], [0.0, 0.0, 0.0])


def test_configuration_matrix_has_full_row_rank_and_joint_identity() -> None:
    """E (eq. 9) is 9 x 11 of rank 9, the motor block is the identity."""
    e = configuration_matrix(ThrusterParameters(), 3)  # the paper robot's arm
    assert e.shape == (9, 11)
    assert np.linalg.matrix_rank(e) == 9
    np.testing.assert_array_equal(e[6:, 8:], np.eye(3))
    np.testing.assert_array_equal(e[:6, 8:], 0.0)


def test_thrust_column_is_force_and_moment_about_body_origin() -> None:
    """Column i of E is [d_i; r_i x d_i]; equal thrusts of the horizontal four give pure surge."""
    layout = ThrusterLayout.from_parameters()
    e = layout.configuration_matrix(3)
    thrust = np.zeros(11)
    thrust[:4] = 100.0
    tau_b = e @ thrust
    np.testing.assert_allclose(tau_b[:6], [4 * 100.0 * np.sqrt(0.5), 0, 0, 0, 0, 0], atol=1e-9)
    i = 5
    np.testing.assert_allclose(e[3:6, i], np.cross(layout.positions_m[i], layout.directions[i]))
