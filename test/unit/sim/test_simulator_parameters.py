"""Simulator parameters: defaults are valid, bad values stop with name, value and range."""

import pytest
from uvms_sim.errors import SimParameterError
from uvms_sim.parameters import SIMULATOR_PARAMETERS, SPECS_BY_NAME, SimulatorSettings

DEFAULTS = {spec.name: spec.default for spec in SIMULATOR_PARAMETERS}


def test_defaults_give_1khz_physics_and_500hz_publication() -> None:
    """The default settings integrate at 1 kHz and publish every second step (500 Hz)."""
    settings = SimulatorSettings.from_values(DEFAULTS)
    assert settings.physics_dt_ns == 1_000_000
    assert settings.steps_per_publish == 2
    assert settings.mode == 'lockstep'


@pytest.mark.parametrize(
    ('name', 'value'),
    [
        ('physics_rate_hz', 0.0),
        ('publish_rate_hz', -5.0),
        ('watchdog_timeout_s', float('nan')),
        ('mode', 'fast'),
        ('initial.vehicle_pose', [0.0, 0.0, 0.0]),
        ('initial.joint_positions', [0.0, 10.0, 0.0]),
        ('wall_enabled', 1),
        ('real_time_factor', 0.0),
    ],
)
def test_invalid_value_error_names_parameter_value_and_range(name: str, value: object) -> None:
    """An invalid value raises SimParameterError naming the parameter, value and valid range."""
    with pytest.raises(SimParameterError) as info:
        SimulatorSettings.from_values({**DEFAULTS, name: value})
    message = str(info.value)
    assert repr(name) in message
    assert str(value)[:6] in message
    assert SPECS_BY_NAME[name].range_text() in message


def test_publish_rate_must_divide_physics_rate() -> None:
    """A publication rate that is no whole fraction of the physics rate is rejected."""
    with pytest.raises(SimParameterError, match='publish_rate_hz'):
        SimulatorSettings.from_values({**DEFAULTS, 'publish_rate_hz': 300.0})


def test_tf_rate_above_publish_rate_is_rejected() -> None:
    """/tf cannot be published more often than the state."""
    with pytest.raises(SimParameterError, match='tf_rate_hz'):
        SimulatorSettings.from_values({**DEFAULTS, 'tf_rate_hz': 1000.0})


def test_ground_truth_rate_above_publish_rate_is_every_state() -> None:
    """ee_pose and contact come at most with every state (the default at 250 Hz states)."""
    settings = SimulatorSettings.from_values({**DEFAULTS, 'publish_rate_hz': 250.0})
    assert settings.publishes_per_ground_truth == 1


def test_ground_truth_rate_in_whole_state_publications() -> None:
    """At 500 Hz states, 100 Hz ground truth is every 5th state; the default every state."""
    assert SimulatorSettings.from_values(DEFAULTS).publishes_per_ground_truth == 1
    settings = SimulatorSettings.from_values({**DEFAULTS, 'ground_truth_rate_hz': 100.0})
    assert settings.publishes_per_ground_truth == 5


def test_zero_tf_rate_disables_tf() -> None:
    """tf_rate_hz = 0 turns /tf off."""
    settings = SimulatorSettings.from_values({**DEFAULTS, 'tf_rate_hz': 0.0})
    assert settings.publishes_per_tf == 0


def test_half_real_time_ticks_every_other_millisecond_of_wall_time() -> None:
    """real_time_factor 0.5: a 1 ms step is due every 2 ms of wall time; 1 is the default."""
    assert SimulatorSettings.from_values(DEFAULTS).wall_period_s == pytest.approx(1e-3)
    half = SimulatorSettings.from_values({**DEFAULTS, 'real_time_factor': 0.5})
    assert half.wall_period_s == pytest.approx(2e-3)
    assert half.physics_dt_ns == 1_000_000


def test_joint_states_at_an_arm_bus_rate_only_in_real_time() -> None:
    """125 Hz of joint_states is every 4th state in real time; lockstep refuses it, named."""
    realtime = {**DEFAULTS, 'mode': 'realtime'}
    assert SimulatorSettings.from_values(realtime).publishes_per_joint_state == 1
    slow = SimulatorSettings.from_values({**realtime, 'joint_states_rate_hz': 125.0})
    assert slow.publishes_per_joint_state == 4
    with pytest.raises(SimParameterError, match=r"'joint_states_rate_hz' = 125.*real time"):
        SimulatorSettings.from_values({**DEFAULTS, 'joint_states_rate_hz': 125.0})
