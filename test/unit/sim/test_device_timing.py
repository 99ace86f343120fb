"""Device timing in the simulator: sensors at their rate and latency, commands at the devices'."""

from __future__ import annotations

import itertools

import pytest
from uvms_sim.device_timing import CommandHold, DeviceTiming, SampleHold, SignalTiming
from uvms_sim.errors import SimParameterError
from uvms_sim.parameters import SIMULATOR_PARAMETERS, SPECS_BY_NAME, SimulatorSettings

from uvms_description.robots import robot_parameters

DEFAULTS = {spec.name: spec.default for spec in SIMULATOR_PARAMETERS}
STATE_NS = 2_000_000  # the 500 Hz state grid


def _deliveries(timing: SignalTiming, seconds: float = 1.0, seed: int = 0
                ) -> list[tuple[int, int]]:
    """(state time, time of the sample it delivers) for every state of ``seconds``."""
    hold: SampleHold[int] = SampleHold(timing, seed)
    return [(t, hold.at(t, lambda t=t: t))
            for t in range(0, round(seconds * 1e9) + 1, STATE_NS)]


def test_joint_states_at_77_hz_arrive_77_times_a_second_at_least_their_latency_old() -> None:
    """Alpha 5 feedback on the bus: 77 fresh samples a second, each at least 6.5 ms old."""
    deliveries = _deliveries(SignalTiming(rate_hz=77.0, latency_s=0.0065))
    fresh = {sample for _, sample in deliveries}
    assert 76 <= len(fresh) <= 78
    ages = [t - sample for t, sample in deliveries if t > 20_000_000]
    assert min(ages) >= 6_500_000
    # Never older than latency + one sample period + one state (the grid's rounding).
    assert max(ages) <= 6_500_000 + round(1e9 / 77) + STATE_NS


def test_an_ideal_signal_delivers_every_state_its_own_sample() -> None:
    """Ideal devices: every state carries its own sample (today's graph)."""
    assert all(t == sample for t, sample in _deliveries(SignalTiming()))


def test_jittered_latency_is_deterministic_per_seed_and_within_its_band() -> None:
    """The jitter draws repeat per seed (lockstep stays deterministic) and stay in +-jitter."""
    timing = SignalTiming(rate_hz=100.0, latency_s=0.004, jitter_s=0.0035)
    assert _deliveries(timing, seed=3) == _deliveries(timing, seed=3)
    assert _deliveries(timing, seed=3) != _deliveries(timing, seed=4)
    ages = [t - s for t, s in _deliveries(timing, seed=3) if t > 20_000_000]
    assert min(ages) >= 500_000


def test_thrusts_change_only_in_ardusubs_50_hz_rc_loop() -> None:
    """A command each plant step reaches the thrusters 50 times a second, in RC loop slots."""
    hold: CommandHold[int] = CommandHold(50.0)
    applied = [hold.at(t, t) for t in range(0, 1_000_000_001, 1_000_000)]  # 1 kHz plant
    changes = [t for t, (before, after) in zip(range(1_000_000, 1_000_000_001, 1_000_000),
                                               itertools.pairwise(applied), strict=True)
               if before != after]
    assert len(changes) == 50
    assert all(t % 20_000_000 == 0 for t in changes)


def test_ideal_devices_override_the_robots_timing() -> None:
    """devices.ideal true gives ideal devices whatever the robot declares."""
    values = {**DEFAULTS, 'devices.thrusts.rate_hz': 50.0,
              'devices.joint_states.rate_hz': 77.0}
    assert not DeviceTiming.from_values(values).ideal
    assert DeviceTiming.from_values({**values, 'devices.ideal': True}).ideal


def test_a_jitter_above_its_latency_is_refused_by_name() -> None:
    """A delivery before its sample is refused, naming the parameter."""
    with pytest.raises(SimParameterError, match=r'devices\.dvl\.jitter_s'):
        SimulatorSettings.from_values({**DEFAULTS, 'devices.dvl.latency_s': 0.001,
                                       'devices.dvl.jitter_s': 0.002})


def test_the_simulator_defaults_are_ideal_devices() -> None:
    """A robot that declares no device timing has ideal devices."""
    assert SimulatorSettings.from_values(DEFAULTS).devices.ideal


def test_bluerov2_alpha5_declares_device_timing_and_the_paper_robot_none() -> None:
    """The BlueROV2 + Alpha 5 folder declares its timing; the paper robot none."""
    bluerov = robot_parameters('bluerov2_alpha5', 'simulator')
    assert bluerov['devices.thrusts.rate_hz'].value == 50.0
    assert bluerov['devices.ideal'].value is True  # until the controller holds at its rates
    assert bluerov['devices.joint_states.rate_hz'].value < 500.0
    assert bluerov['devices.thrusts.rate_hz'].source.name == 'device_timing.yaml'
    for name, item in bluerov.items():
        if name.startswith('devices.'):
            assert name in SPECS_BY_NAME, name
            assert item.source.name == 'device_timing.yaml'
    paper = robot_parameters('paper_uvms', 'simulator')
    assert not [name for name in paper if name.startswith('devices.')]
    timing = DeviceTiming.from_values(
        {**DEFAULTS, **{n: i.value for n, i in bluerov.items() if n.startswith('devices.')},
         'devices.ideal': False})  # what a scenario's devices.ideal false applies
    assert not timing.ideal
    assert timing['wrench'].latency_s == pytest.approx(288e-6)
