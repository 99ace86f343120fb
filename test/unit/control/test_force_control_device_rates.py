"""Force control at the Alpha 5's device rates (issue 49 item 5; docs/hardware.md "Device timing").

A closed loop in the style of ``closed_loop_plant``: the BlueROV2 Heavy + Alpha 5 (the
controller's own model, exact, with the robot folder's gains) presses a 1e4 N/m wall with
20 N and slides 2 cm down it. At the devices' rates the arm's torques are latched in 77 Hz
slots from t = 0 and held (the bus, ``devices.arm_commands.rate_hz``) and the wrist force
reaches the controller one 2 ms state late (``devices.wrench``), as the simulator with
``devices.ideal: false`` does. Today's controller (arm.command_rate_hz 0) loses its force
there; cancelling the force predicted for the held slot's middle (``held_command``) holds it.
With the wrist sensor's 0.1 % noise (sensor.yaml: 0.58 N axial, 0.29 N across, 1 sd) a
quadratic through the last three samples amplifies the noise about 33 times and the arm
diverges; the prediction weighed by the samples' own noise holds there too.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
import yaml
from uvms_control.core.law.held_command import (
    HeldCommandForce,
    held_slot_horizon_s,
    quadratic_extrapolation,
)
from uvms_control.core.law.unified_controller import UnifiedForceController
from uvms_control.core.parameters import ControllerParameters
from uvms_control.core.task.contact_task import ContactTaskGoal, SafetyLimits
from uvms_control.core.task.task_supervisor import TaskSupervisor

from uvms_description import robots_directory
from uvms_description.robots import with_description_paths
from uvms_model import UvmsModel, UvmsParameters

ROBOT = 'bluerov2_alpha5'
#: Control period (s): the simulator's state rate.
DT = 0.002
#: The Alpha 5's command slot (ns): 77 Hz (device_timing.yaml arm_commands.rate_hz).
SLOT_NS = round(1e9 / 77.0)
K_E = 1e4
F_D = 20.0
#: Joint positions of point A (start.yaml's inverse-kinematics guess: the arm forward and down).
Q0 = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0])
#: The middle of the contact (s): after the force ramp, before the path ends.
MID_CONTACT_S = (2.5, 4.5)
#: The wrist sensor's noise, 1 sd per sensor axis (N): 0.1 % of the Mini45's ranges
#: (sensor.yaml noise_fraction 0.001, force_range_n [580, 290, 290]).
NOISE_SD_N = np.array([0.58, 0.29, 0.29])
#: An arm joint faster than this (rad/s) has run away: the loop stops there.
RUNAWAY_RAD_S = 50.0


def flat(tree: dict[str, object], prefix: str = '') -> dict[str, object]:
    """Nested parameter YAML to dotted names."""
    out: dict[str, object] = {}
    for key, value in tree.items():
        if isinstance(value, dict):
            out.update(flat(value, f'{prefix}{key}.'))
        else:
            out[f'{prefix}{key}'] = value
    return out


@functools.cache
def robot_gains() -> ControllerParameters:
    """The controller gains of the robot folder (safety and pilot limits aside)."""
    text = (robots_directory() / ROBOT / 'controller.yaml').read_text()
    values = flat(yaml.safe_load(text)['/**/controller']['ros__parameters'])
    return ControllerParameters.from_flat_dict(
        {k: v for k, v in values.items() if not k.startswith(('safety.', 'pilot.'))})


def model() -> UvmsModel:
    """The robot's model (plant and controller alike)."""
    return UvmsModel(UvmsParameters().updated(with_description_paths({}, ROBOT)))


@functools.cache
def press(command_rate_hz: float, force_latency_s: float, devices: bool,
          noise_seed: int | None = None,
          with_wall: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Times (s), wall force, F_d (N) and position error (m) of the press.

    ``devices``: 77 Hz slots, 2 ms late force. ``noise_seed``: the wrist sensor's 0.1 % noise
    (``NOISE_SD_N``) drawn with this seed; None noise-free. ``with_wall`` False: the same path
    in free water (``with_wall`` False). The controller is told the devices' timing through
    ``held_slot_horizon_s`` (the node's arm.command_rate_hz and arm.force_latency_s). A run
    away arm ends the series there.
    """
    plant = model()
    controller = UnifiedForceController(robot_gains(), model(), DT,
                                        held_slot_horizon_s(command_rate_hz, force_latency_s))
    supervisor = TaskSupervisor(controller, SafetyLimits(
        max_contact_force_n=60.0, sensor_range_n=290.0, max_path_distance_m=0.5))
    x_a = plant.ee_position(Q0)
    wall_x = float(x_a[0]) + (0.003 if with_wall else 1.0)
    rng = None if noise_seed is None else np.random.default_rng(noise_seed)
    goal = ContactTaskGoal(
        path=x_a + np.array([[0.0, 0.0, 0.0], [0.0115, 0.0, 0.0], [0.0115, 0.0, 0.02]]),
        times=np.array([0.0, 1.5, 4.5]), velocities=None, accelerations=None,
        normal=np.array([1.0, 0.0, 0.0]), force_n=F_D, force_ramp_s=1.0,
        require_contact=with_wall, start_time_s=0.5)
    q, w = Q0.copy(), np.zeros(10)
    late_sensor = np.zeros(3)
    held = np.zeros(4)
    next_slot_ns = 0
    times, force, f_d, x_error = [], [], [], []
    for k in range(round(5.0 / DT)):
        t, t_ns = k * DT, k * round(DT * 1e9)
        wall = np.array([K_E * max(float(plant.ee_position(q)[0]) - wall_x, 0.0), 0.0, 0.0])
        sensor = plant.ee_rotation(q).T @ wall
        if rng is not None:
            sensor = sensor + NOISE_SD_N * rng.standard_normal(3)
        if k == 1:
            supervisor.submit('press', goal, t)
        result, _ = supervisor.step(t, q, w, late_sensor if devices else sensor)
        late_sensor = sensor
        tau_b = result.tau_b.copy()
        if devices:
            if t_ns >= next_slot_ns:  # the bus latches the newest command at each slot
                held = tau_b[6:].copy()
                next_slot_ns = (t_ns // SLOT_NS + 1) * SLOT_NS
            tau_b[6:] = held
        q, w = plant.step(q, w, tau_b, -wall, DT)
        times.append(t)
        force.append(wall[0])
        f_d.append(result.F_d[0])
        x_error.append(float(np.linalg.norm(result.X - result.X_d)))
        if not np.isfinite(w).all() or float(np.abs(w[6:]).max()) > RUNAWAY_RAD_S:
            break
    return np.array(times), np.array(force), np.array(f_d), np.array(x_error)


def mid_contact_rms(command_rate_hz: float, force_latency_s: float, devices: bool,
                    noise_seed: int | None = None) -> float:
    """RMS of F - F_d (N) over the middle of the contact; inf when the run ended before it."""
    t, force, f_d, _ = press(command_rate_hz, force_latency_s, devices, noise_seed)
    if t[-1] < MID_CONTACT_S[1]:
        return math.inf
    middle = (t > MID_CONTACT_S[0]) & (t < MID_CONTACT_S[1])
    return float(np.sqrt(np.mean((force[middle] - f_d[middle]) ** 2)))


def test_controller_holds_its_force_at_the_device_rates() -> None:
    """77 Hz held arm commands and a 2 ms late force: at most 1.3x the ideal RMS, peak 15 %.

    Today's controller (rate 0) misses the bound by far: measured 0.40 N against 0.007 N.
    """
    ideal = mid_contact_rms(0.0, 0.0, devices=False)
    held = mid_contact_rms(77.0, 0.002, devices=True)
    assert ideal < 0.02
    assert held <= 1.3 * ideal
    peak_ideal = press(0.0, 0.0, False)[1].max()
    assert abs(press(77.0, 0.002, True)[1].max() - peak_ideal) <= 0.15 * peak_ideal


def test_todays_controller_does_not_hold_at_the_device_rates() -> None:
    """The same press with the controller told nothing (ideal devices): far over 1.3x."""
    assert mid_contact_rms(0.0, 0.0, devices=True) > 10.0 * mid_contact_rms(0.0, 0.0, False)


def test_horizon_is_the_force_age_plus_half_a_slot() -> None:
    """The horizon is latency + 1 / (2 rate); rate 0 is the ideal device (no prediction)."""
    assert held_slot_horizon_s(77.0, 0.002) == pytest.approx(0.002 + 0.5 / 77.0)
    assert held_slot_horizon_s(0.0, 0.002) == 0.0
    with pytest.raises(ValueError, match=r'arm\.command_rate_hz'):
        held_slot_horizon_s(-1.0, 0.0)


def test_prediction_is_exact_for_a_parabola_and_skips_repeated_samples() -> None:
    """A quadratic force is predicted exactly; a re-published sample is not taken twice."""
    force = HeldCommandForce(0.0085)
    for k in range(5):
        t = DT * k
        predicted = force.update(t, (3.0 * t * t + t, 0.0, -t))
    t_next = DT * 4 + 0.0085
    assert predicted[0] == pytest.approx(3.0 * t_next**2 + t_next)
    assert predicted[2] == pytest.approx(-t_next)
    assert force.update(DT * 4, (99.0, 0.0, 0.0)) == pytest.approx(predicted)
    assert quadratic_extrapolation([(0.0, (1.0, 2.0, 3.0))], 0.01) == (1.0, 2.0, 3.0)


def test_a_gap_restarts_the_prediction() -> None:
    """After a gap of more than five sample periods the old slope is forgotten."""
    force = HeldCommandForce(0.01)
    for k in range(3):
        force.update(DT * k, (100.0 * k, 0.0, 0.0))
    assert force.update(1.0, (7.0, 0.0, 0.0)) == (7.0, 0.0, 0.0)


def test_zero_horizon_is_the_measured_force() -> None:
    """The ideal device: the controller cancels the measured F_e, as eq. 29."""
    force = HeldCommandForce(0.0)
    assert force.update(0.0, (1.0, 2.0, 3.0)) == (1.0, 2.0, 3.0)
    assert force.update(DT, (5.0, 2.0, 3.0)) == (5.0, 2.0, 3.0)


#: Seeds of the noisy presses: one draw of the noise can favour either loop (measured mid-contact
#: RMS 1.83 / 1.60 / 1.73 N at the devices' rates against 1.59 / 1.26 / 1.68 N ideal).
NOISE_SEEDS = (1, 2, 3)


def test_controller_holds_its_force_with_the_wrist_sensors_noise() -> None:
    """0.1 % wrist noise at the device rates: the press holds, 1.3x the ideal loop, peak 15 %.

    Over three noise draws the mean mid-contact RMS is at most 1.3x the ideal loop's with the
    same draws (measured 1.72 N against 1.51 N) and every peak within 15 % of its ideal run's
    (+6 to +10 %). The quadratic alone through the last three samples (held_command before
    the noise weighting) amplifies the noise about 33 times: every draw ran away within 1.3 s.
    """
    held, ideal = [], []
    for seed in NOISE_SEEDS:
        held.append(mid_contact_rms(77.0, 0.002, True, seed))
        ideal.append(mid_contact_rms(0.0, 0.0, False, seed))
        peak_ideal = press(0.0, 0.0, False, seed)[1].max()
        peak = press(77.0, 0.002, True, seed)[1].max()
        assert abs(peak - peak_ideal) <= 0.15 * peak_ideal, f'seed {seed}: peak {peak:.1f} N'
    assert all(math.isfinite(rms) for rms in held), f'ran away: {held}'
    assert np.mean(held) <= 1.3 * np.mean(ideal), f'{held} against {ideal}'


def test_free_motion_with_the_wrist_sensors_noise_keeps_its_path_as_at_ideal_devices() -> None:
    """The same path in free water with the 0.1 % noise: within 1.3x the ideal loop's error.

    Measured 3.1 mm against 3.5 mm at ideal devices. Cancelling each noisy sample as eq. 29
    does, held over a 77 Hz slot, costs 6.0 mm (the controller told nothing of the devices);
    the quadratic alone ran away (0.2 m).
    """
    t, _, _, x_error = press(77.0, 0.002, True, NOISE_SEEDS[0], False)
    t_ideal, _, _, x_error_ideal = press(0.0, 0.0, False, NOISE_SEEDS[0], False)
    assert t[-1] == t_ideal[-1] > MID_CONTACT_S[1]
    assert x_error.max() <= 1.3 * x_error_ideal.max()
