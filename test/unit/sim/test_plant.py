"""The plant: actuator mapping, wall contact, wrist sensor, exact time, divergence stop."""

import numpy as np
import pytest
from uvms_model.kinematics import rot_ned_from_body
from uvms_sim.errors import CommandError, DivergenceError, SimParameterError, SimulationError
from uvms_sim.plant import Plant, initial_coordinates

from uvms_model import UvmsModel, UvmsParameters

PARAMS = UvmsParameters()
MODEL = UvmsModel(PARAMS)
VEHICLE = np.zeros(6)
ARM_GUESS = np.array([0.0, 0.4, -0.8])


def plant_with_ee_at(
    x_ned: list[float], params: UvmsParameters = PARAMS, **kwargs: object
) -> Plant:
    """A plant at rest whose end effector starts at x_ned."""
    q0 = initial_coordinates(MODEL, VEHICLE, ARM_GUESS, x_ned)
    return Plant(params, q0, **kwargs)  # type: ignore[arg-type]


def zero_inputs(plant: Plant) -> tuple[np.ndarray, np.ndarray]:
    """Zero thrusts and joint torques."""
    return np.zeros(plant.n_thrusters), np.zeros(plant.n_joints)


#: 1/√2: the horizontal thrusters of config/robot.yaml are vectored at 45 degrees.
C45 = 0.5**0.5
#: Columns of E (eq. 9) written out from config/robot.yaml's layout: force = direction d,
#: moment = position r x d, in base_link_frd (not from the code under test).
HAND_COLUMNS = {
    # Thruster 0: r = (0.35, 0.25, 0), d = (c, -c, 0): r x d = (0, 0, -0.35 c - 0.25 c).
    0: [C45, -C45, 0.0, 0.0, 0.0, -0.6 * C45, 0.0, 0.0, 0.0],
    # Thruster 4: r = (0.25, 0.3, 0), d = (0, 0, 1): r x d = (0.3, -0.25, 0).
    4: [0.0, 0.0, 1.0, 0.3, -0.25, 0.0, 0.0, 0.0, 0.0],
}


@pytest.mark.parametrize('thruster', sorted(HAND_COLUMNS))
def test_one_thrust_gives_its_direction_as_force_and_position_cross_direction_as_moment(
    thruster: int,
) -> None:
    """tau_b of a unit thrust on one thruster is [d; r x d] (paper eq. 9), no joint torque."""
    plant = plant_with_ee_at([1.7, 0.0, -0.1])
    thrusts = np.zeros(plant.n_thrusters)
    thrusts[thruster] = 1.0
    tau = plant.tau_body(thrusts, np.zeros(3))
    np.testing.assert_allclose(tau, HAND_COLUMNS[thruster], atol=1e-12)


def test_joint_motor_torques_pass_straight_to_the_joints() -> None:
    """The arm block of E is the identity: joint torques appear unchanged, no vehicle wrench."""
    plant = plant_with_ee_at([1.7, 0.0, -0.1])
    tau = plant.tau_body(np.zeros(plant.n_thrusters), np.array([1.5, -2.0, 0.25]))
    np.testing.assert_allclose(tau, [0.0] * 6 + [1.5, -2.0, 0.25], atol=1e-12)


def test_actuator_map_is_linear() -> None:
    """tau_b(a u + b v) = a tau_b(u) + b tau_b(v): E is a matrix (eq. 9)."""
    plant = plant_with_ee_at([1.7, 0.0, -0.1])
    rng = np.random.default_rng(3)
    u, v = rng.normal(size=(2, plant.n_thrusters + 3))
    n = plant.n_thrusters
    combined = plant.tau_body(*np.split(2.0 * u - 3.0 * v, [n]))
    separate = 2.0 * plant.tau_body(*np.split(u, [n])) - 3.0 * plant.tau_body(*np.split(v, [n]))
    np.testing.assert_allclose(combined, separate, atol=1e-12)


def test_initial_ee_position_is_reached_by_inverse_kinematics() -> None:
    """initial.ee_position puts the end effector where asked."""
    plant = plant_with_ee_at([1.7, 0.0, -0.1])
    np.testing.assert_allclose(plant.model.ee_position(plant.q), [1.7, 0.0, -0.1], atol=1e-8)


def test_unreachable_initial_ee_position_names_the_parameter() -> None:
    """An end-effector start out of the arm's reach stops with the parameter's name."""
    with pytest.raises(SimParameterError, match=r'initial\.ee_position'):
        initial_coordinates(MODEL, VEHICLE, ARM_GUESS, [5.0, 0.0, 0.0])


def test_time_advances_by_whole_nanosecond_steps() -> None:
    """Simulated time after n steps is exactly n dt in integer nanoseconds."""
    plant = plant_with_ee_at([1.7, 0.0, -0.1])
    for _ in range(3):
        plant.step(*zero_inputs(plant))
    assert plant.t_ns == 3_000_000


def test_end_effector_inside_wall_exerts_stiffness_times_penetration() -> None:
    """F_e = K_e delta along +x of map_ned while the end effector is inside the wall."""
    plant = plant_with_ee_at([1.7871, 0.0, -0.1])
    contact = plant.contact()
    assert contact.in_contact
    np.testing.assert_allclose(contact.force_ned, [1.0e4 * 0.01, 0.0, 0.0], rtol=1e-6)


def test_wall_pushes_end_effector_back() -> None:
    """The wall's reaction -F_e accelerates the pressing end effector away from the wall."""
    free = plant_with_ee_at([1.7871, 0.0, -0.1], wall_enabled=False)
    touching = plant_with_ee_at([1.7871, 0.0, -0.1])
    for plant in (free, touching):
        for _ in range(5):
            plant.step(*zero_inputs(plant))
    x_free = free.model.ee_position(free.q)[0]
    x_touching = touching.model.ee_position(touching.q)[0]
    assert x_touching < x_free - 1e-6


def test_disabled_wall_gives_no_contact() -> None:
    """Without the wall there is no contact force even beyond the wall position."""
    plant = plant_with_ee_at([1.7871, 0.0, -0.1], wall_enabled=False)
    assert not plant.contact().in_contact
    np.testing.assert_array_equal(plant.contact().force_ned, np.zeros(3))


def test_wrist_sensor_reads_force_on_wall_in_sensor_frame() -> None:
    """Without noise the sensor reads rot_ned_from_sensor^T F_e."""
    plant = plant_with_ee_at([1.7871, 0.0, -0.1])
    force, torque = plant.read_wrench_sensor()
    rot = plant.model.ee_rotation(plant.q)
    np.testing.assert_allclose(force, rot.T @ plant.contact().force_ned, atol=1e-9)
    np.testing.assert_allclose(torque, np.zeros(3), atol=1e-12)


def test_same_sensor_seed_gives_same_noise_sequence() -> None:
    """Two plants with the same sensor.seed read identical noisy wrenches."""
    params = PARAMS.updated({'sensor.noise_fraction': 0.001, 'sensor.seed': 42})
    readings = []
    for _ in range(2):
        plant = plant_with_ee_at([1.7871, 0.0, -0.1], params=params)
        readings.append(np.concatenate([plant.read_wrench_sensor()[0] for _ in range(5)]))
    np.testing.assert_array_equal(readings[0], readings[1])
    assert not np.allclose(readings[0][:3], readings[0][3:6])  # noise differs per reading


@pytest.mark.parametrize('bad', [np.nan, np.inf])
def test_non_finite_actuator_output_is_rejected_before_integration(bad: float) -> None:
    """A NaN or Inf torque raises CommandError and leaves state and time untouched."""
    plant = plant_with_ee_at([1.7, 0.0, -0.1])
    q_before = plant.q
    with pytest.raises(CommandError, match='joint_torques'):
        plant.step(np.zeros(plant.n_thrusters), [0.0, bad, 0.0])
    assert plant.t_ns == 0
    np.testing.assert_array_equal(plant.q, q_before)


def test_wrongly_sized_thrusts_are_rejected() -> None:
    """A thrust vector of the wrong length raises CommandError naming the field."""
    plant = plant_with_ee_at([1.7, 0.0, -0.1])
    with pytest.raises(CommandError, match='thrusts must have 8 values'):
        plant.step(np.zeros(7), np.zeros(3))


def test_diverging_state_stops_with_error_naming_the_cause() -> None:
    """A state leaving its bounds raises DivergenceError and is not kept."""
    plant = plant_with_ee_at([1.7, 0.0, -0.1])
    with pytest.raises(DivergenceError, match='arm joint rate'):
        for _ in range(100):
            q_before, t_before = plant.q, plant.t_ns
            plant.step(np.zeros(plant.n_thrusters), [0.0, 0.0, 1.0e5])
    assert plant.t_ns == t_before
    np.testing.assert_array_equal(plant.q, q_before)


def test_plant_refuses_to_step_after_divergence() -> None:
    """After a divergence every further step raises SimulationError naming the first cause."""
    plant = plant_with_ee_at([1.7, 0.0, -0.1])
    with pytest.raises(DivergenceError):
        for _ in range(100):
            plant.step(np.zeros(plant.n_thrusters), [0.0, 0.0, 1.0e5])
    with pytest.raises(SimulationError, match=r'stopped.*arm joint rate'):
        plant.step(*zero_inputs(plant))


def test_frame_poses_start_at_vehicle_pose() -> None:
    """base_link_frd sits at the vehicle pose of q."""
    q0 = initial_coordinates(MODEL, [1.0, 2.0, 3.0, 0.1, -0.2, 0.3], ARM_GUESS)
    plant = Plant(PARAMS, q0)
    p, rot = plant.frame_poses()['base_link_frd']
    np.testing.assert_allclose(p, [1.0, 2.0, 3.0])
    np.testing.assert_allclose(rot, rot_ned_from_body(0.1, -0.2, 0.3), atol=1e-12)


@pytest.mark.parametrize(('start_force_n', 'moving'), [(0.0, True), (50.0, True), (200.0, False)])
def test_moving_wall_starts_once_the_contact_force_reaches_the_threshold(
    start_force_n: float, moving: bool
) -> None:
    """A 0.05 m/s wall pressed with 100 N moves only if its start force is at most 100 N."""
    params = PARAMS.updated({'contact.wall_speed_m_s': 0.05})
    plant = plant_with_ee_at([1.7871, 0.0, -0.1], params=params,
                             wall_motion_start_force_n=start_force_n)
    plant.step(*zero_inputs(plant))
    assert plant.contact().wall_velocity_m_s == (0.05 if moving else 0.0)
    assert plant.contact().wall_position_m == pytest.approx(1.7771 + (5e-5 if moving else 0.0))
