"""The plant in an ocean current, and the simulator's ``ocean.current.*`` parameters."""

import math

import numpy as np
import pytest
from uvms_model.ocean_current import CurrentParameters
from uvms_sim.conversions import current_message
from uvms_sim.errors import SimParameterError
from uvms_sim.ocean import OCEAN_PARAMETERS, current_parameters
from uvms_sim.plant import Plant, initial_coordinates

from uvms_model import UvmsModel, UvmsParameters

PARAMS = UvmsParameters()
MODEL = UvmsModel(PARAMS)
Q0 = initial_coordinates(MODEL, np.zeros(6), np.array([0.0, 0.4, -0.8]), [1.6, 0.0, -0.1])


def _run(current: CurrentParameters | None, steps: int = 200, seed: int = 1) -> Plant:
    """A plant without a wall stepped with thrusters and motors off."""
    params = PARAMS.updated({'sensor.seed': seed})
    plant = Plant(params, Q0, 1_000_000, wall_enabled=False, current=current)
    for _ in range(steps):
        plant.step(np.zeros(plant.n_thrusters), np.zeros(plant.n_joints))
    return plant


def test_still_water_is_bit_identical_to_the_model_without_a_current() -> None:
    """Current off (the default, or set all zero): the states are the model's own, bit for bit."""
    q, w = Q0.copy(), np.zeros(MODEL.n_dof)
    for _ in range(200):
        q, w = MODEL.step(q, w, np.zeros(MODEL.n_dof), None, 1e-3)
    for current in (None, CurrentParameters(), CurrentParameters(direction_rad=1.0)):
        plant = _run(current)
        assert plant.q.tobytes() == q.tobytes() and plant.w.tobytes() == w.tobytes()
        assert plant.current_ned.tolist() == [0.0, 0.0, 0.0]


def test_a_current_pushes_the_free_robot_along_the_flow() -> None:
    """0.3 m/s toward east: after 0.2 s the vehicle moves east, not in still water's way."""
    still = _run(None)
    east = _run(CurrentParameters(mean_speed_m_s=0.3, direction_rad=0.5 * math.pi))
    np.testing.assert_allclose(east.current_ned, [0.0, 0.3, 0.0], atol=1e-15)
    assert east.w[1] - still.w[1] > 1e-4  # sway (east at zero yaw) gains speed downstream


def test_same_seed_same_noisy_current_run() -> None:
    """The current's noise comes from the scenario's seed (sensor.seed): same seed, same run."""
    noisy = CurrentParameters(mean_speed_m_s=0.2, sigma_m_s=0.05, time_constant_s=0.05)
    first, again, other = _run(noisy, 50, 4), _run(noisy, 50, 4), _run(noisy, 50, 5)
    assert first.q.tobytes() == again.q.tobytes()
    assert first.current_ned.tolist() == again.current_ned.tolist()
    assert first.current_ned.tolist() != other.current_ned.tolist()


def test_set_current_at_run_time_takes_the_new_mean_at_once() -> None:
    """Plant.set_current restarts the process at the new mean: the next step applies it."""
    plant = _run(None, 1)
    plant.set_current(CurrentParameters(mean_speed_m_s=0.4))
    np.testing.assert_allclose(plant.current_ned, [0.4, 0.0, 0.0])


def test_parameters_cover_every_field_with_its_range() -> None:
    """ocean.current.<field> for each field of CurrentParameters, defaults giving still water."""
    names = {spec.name for spec in OCEAN_PARAMETERS}
    assert {'ocean.current.mean_speed_m_s', 'ocean.current.direction_rad',
            'ocean.current.vertical_angle_rad', 'ocean.current.sigma_m_s',
            'ocean.current.time_constant_s', 'ocean.current.max_speed_m_s'} <= names
    assert not current_parameters({}).enabled


@pytest.mark.parametrize('name, value', [('ocean.current.mean_speed_m_s', -0.5),
                                         ('ocean.current.time_constant_s', 0.0),
                                         ('ocean.current.sigma_m_s', 'fast'),
                                         ('ocean.current.mean_speed_m_s', 3.0)])
def test_invalid_value_names_the_parameter(name: str, value: object) -> None:
    """Out of range (or above max_speed_m_s), or not a number: refused naming the parameter."""
    with pytest.raises(SimParameterError, match=name):
        current_parameters({name: value})


def test_current_message_is_a_twist_in_map_ned() -> None:
    """geometry_msgs/TwistStamped: linear = v_c (m/s) in map_ned, angular zero, the stamp."""
    msg = current_message(1_500_000_000, np.array([0.1, -0.2, 0.05]))
    assert msg.header.frame_id == 'map_ned'
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == (1, 500_000_000)
    assert (msg.twist.linear.x, msg.twist.linear.y, msg.twist.linear.z) == (0.1, -0.2, 0.05)
    assert (msg.twist.angular.x, msg.twist.angular.y, msg.twist.angular.z) == (0.0, 0.0, 0.0)
