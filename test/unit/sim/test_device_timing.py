"""Device timing in the simulator: sensors at their rate and latency, commands at the devices'."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from uvms_model.contact import ContactState
from uvms_sim.device_delivery import DeviceDelivery
from uvms_sim.device_timing import (
    CommandHold,
    DeviceTiming,
    SampleHold,
    SignalTiming,
    StaggeredHold,
)
from uvms_sim.errors import SimParameterError
from uvms_sim.parameters import SIMULATOR_PARAMETERS, SPECS_BY_NAME, SimulatorSettings
from uvms_sim.plant import Observation

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


def test_staggered_joints_are_each_sampled_at_their_turn_and_delivered_as_a_round() -> None:
    """A polled bus: joint j answers j/n of a round after joint 0; the round arrives whole.

    Four joints at 43.5 Hz (23 ms rounds), 2 ms after the round's last answer: every
    delivered round holds four sampling instants 5.75 ms apart (on the 2 ms state grid), and
    no value is delivered before its round's last joint was sampled plus the latency.
    """
    timing = SignalTiming(rate_hz=43.5, latency_s=0.002, staggered=True)
    hold = StaggeredHold(timing, 4)
    rounds = []
    for t in range(0, 1_000_000_001, STATE_NS):
        times = hold.at(t, [t] * 4, [0.0] * 4, [0.0] * 4)[0]
        if not rounds or times != rounds[-1][1]:
            rounds.append((t, times))
    assert 42 <= len(rounds) - 1 <= 44  # 43.5 rounds a second (the first: the start-up value)
    for arrived, times in rounds[1:]:
        spread = [b - a for a, b in itertools.pairwise(times)]
        assert all(4_000_000 <= d <= 8_000_000 for d in spread), spread
        assert arrived - times[-1] >= 2_000_000
        assert times[-1] - times[0] < round(1e9 / 43.5)


def test_staggered_joint_states_through_the_simulators_parameters() -> None:
    """devices.joint_states.staggered: declared false, read into the joint states' timing."""
    assert SPECS_BY_NAME['devices.joint_states.staggered'].default is False
    values = {**DEFAULTS, 'devices.joint_states.rate_hz': 43.5,
              'devices.joint_states.staggered': True}
    timing = DeviceTiming.from_values(values)
    assert timing['joint_states'].staggered
    assert 'one joint at a time' in timing.summary()


def test_thrusts_change_only_in_ardusubs_50_hz_rc_loop() -> None:
    """A command each plant step reaches the thrusters 50 times a second, in RC loop slots."""
    hold: CommandHold[int] = CommandHold(50.0)
    applied = [hold.at(t, t) for t in range(0, 1_000_000_001, 1_000_000)]  # 1 kHz plant
    changes = [t for t, (before, after) in zip(range(1_000_000, 1_000_000_001, 1_000_000),
                                               itertools.pairwise(applied), strict=True)
               if before != after]
    assert len(changes) == 50
    assert all(t % 20_000_000 == 0 for t in changes)


def test_arm_commands_act_their_latency_after_each_slot() -> None:
    """devices.arm_commands.latency_s: each slot's command acts that late, held until the next.

    The Alpha 5 bus sends a slot's four CURRENT frames one after another (0.87 ms each) from
    the robot loop's next 2 ms turn: the stand's joints get them 1-5.5 ms after the slot.
    """
    values = {**DEFAULTS, 'devices.arm_commands.rate_hz': 77.0,
              'devices.arm_commands.latency_s': 0.0035}
    timing = DeviceTiming.from_values(values)['arm_commands']
    assert '77 Hz +3.5 ms' in DeviceTiming.from_values(values).summary()
    hold: CommandHold[int] = CommandHold(timing.rate_hz, timing.latency_s)
    plant_ns = range(0, 1_000_000_001, 1_000_000)  # 1 kHz plant, the command is its time
    applied = [hold.at(t, t) for t in plant_ns]
    changes = [(t, now) for t, (before, now) in zip(plant_ns[1:], itertools.pairwise(applied),
                                                    strict=True) if before != now]
    assert len(changes) in (76, 77)
    slot_ns = 1e9 / 77.0
    for t, latched in changes:
        assert 3_500_000 <= t - latched < 4_500_000  # the latency, on the plant's grid
        assert latched % slot_ns < 1_000_000  # latched at the slot's first plant step
    with pytest.raises(SimParameterError, match=r'devices\.arm_commands\.latency_s'):
        DeviceTiming.from_values({**values, 'devices.arm_commands.latency_s': 0.013})


def test_each_joints_command_acts_when_its_frame_has_crossed_the_line() -> None:
    """devices.arm_commands.frame_s: joint j's torque acts j frames after joint 0's, in order.

    The bus sends a slot's CURRENT frames one after another (0.87 ms each at 115200 baud).
    """
    values = {**DEFAULTS, 'devices.arm_commands.rate_hz': 77.0,
              'devices.arm_commands.latency_s': 0.002, 'devices.arm_commands.frame_s': 0.001}
    timing = DeviceTiming.from_values(values)
    assert '77 Hz +2 ms +1 ms a joint' in timing.summary()
    arm = timing['arm_commands']
    hold: CommandHold[np.ndarray] = CommandHold(arm.rate_hz, arm.latency_s, arm.frame_s)
    first_acting = {}
    for t in range(0, 30_000_001, 500_000):  # 2 kHz plant, every command its time (ms)
        applied = hold.at(t, np.full(4, t / 1e6))
        for joint, value in enumerate(applied):
            first_acting.setdefault((joint, float(value)), t / 1e6)
    slot_ms = 1e3 / 77.0  # the second slot's latch is the plant step at or after it
    latched = min(v for (_, v) in first_acting if v >= slot_ms)
    assert [first_acting[(j, latched)] - latched for j in range(4)] == [2.0, 3.0, 4.0, 5.0]
    too_late = DeviceTiming.from_values({**values, 'devices.arm_commands.frame_s': 0.004})
    with pytest.raises(SimParameterError, match=r"devices\.arm_commands\.latency_s' = 0\.014"):
        DeviceDelivery(too_late, 0, 4)  # the fourth joint 2 + 3 x 4 ms after the slot
    DeviceDelivery(too_late, 0, 3)  # three joints: 10 ms, within the 13 ms slot


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


def test_the_simulators_observation_carries_each_joint_from_its_own_turn() -> None:
    """DeviceDelivery, staggered: the arm's values of a state come from four instants.

    The vehicle's coordinates and the wrist sensor stay those of the state.
    """
    values = {**DEFAULTS, 'devices.joint_states.rate_hz': 43.5,
              'devices.joint_states.staggered': True}
    delivery = DeviceDelivery(DeviceTiming.from_values(values), seed=0, n_joints=4)
    contact = ContactState(False, np.zeros(3), 0.0, 1.0, 0.0)
    seen = None
    for t in range(0, 100_000_001, STATE_NS):
        now = np.full(10, float(t))
        seen = delivery.observation(Observation(
            t, now.copy(), now.copy(), np.full(4, float(t)), {}, contact,
            np.full(3, float(t)), np.zeros(3)))
    assert seen is not None
    assert seen.q[:6].tolist() == [100_000_000.0] * 6  # the vehicle: the state's own
    assert seen.sensor_force.tolist() == [100_000_000.0] * 3
    arm = seen.q[6:].tolist()
    assert arm == seen.w[6:].tolist() == seen.joint_torques.tolist()
    assert len(set(arm)) == 4 and max(arm) < 100_000_000.0
