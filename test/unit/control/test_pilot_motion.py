"""Pilot velocities to references: rate-limited, zero after the deadman, the arm riding along."""

from __future__ import annotations

import math

import numpy as np
import pytest
from uvms_control.core.pilot.inputs import PilotTwist
from uvms_control.core.pilot.limits import PilotLimits
from uvms_control.core.pilot.motion import PilotMotion
from uvms_model.kinematics import rot_ned_from_body

DT = 0.002
LIMITS = PilotLimits(vehicle_speed_m_s=(0.5, 0.5, 0.3), vehicle_rate_rad_s=(0.0, 0.0, 0.5),
                     vehicle_acceleration_m_s2=0.25, vehicle_angular_acceleration_rad_s2=0.5,
                     ee_speed_m_s=(0.1, 0.1, 0.1), ee_acceleration_m_s2=0.2)


def started(yaw: float = 0.0) -> PilotMotion:
    """A motion started at the origin facing yaw, the end effector 1.7 m ahead, 0.1 m up."""
    motion = PilotMotion(LIMITS)
    eta = np.array([0.0, 0.0, 0.0, 0.0, 0.0, yaw])
    motion.start(eta, rot_ned_from_body(0.0, 0.0, yaw) @ np.array([1.7, 0.0, -0.1]))
    return motion


def run(motion: PilotMotion, t0: float, duration_s: float, twist: PilotTwist | None = None,
        ee: PilotTwist | None = None) -> list:
    """Step for duration_s, sending the twist every step (None: silence)."""
    out = []
    for k in range(round(duration_s / DT)):
        t = t0 + k * DT
        if twist is not None:
            motion.command_vehicle(t, twist)
        if ee is not None:
            motion.command_ee(t, ee)
        out.append(motion.step(t, DT))
    return out


def test_a_step_command_ramps_at_the_acceleration_limit() -> None:
    """Full speed asked at once: the reference velocity rises 0.25 m/s^2, X_d never jumps."""
    motion = started()
    refs = run(motion, 0.0, 3.0, PilotTwist((0.5, 0.0, 0.0)))
    speeds = np.array([r.eta_dot[0] for r in refs])
    assert np.max(np.diff(speeds)) <= 0.25 * DT + 1e-12
    assert speeds[-1] == pytest.approx(0.5)
    steps = np.linalg.norm(np.diff([r.X_d for r in refs], axis=0), axis=1)
    assert np.max(steps) <= 0.5 * DT + 1e-9


def test_silence_longer_than_the_deadman_stops_the_motion_and_holds() -> None:
    """After the last message, 0.3 s at speed, then a ramp down; the pose then stays."""
    motion = started()
    run(motion, 0.0, 2.0, PilotTwist((0.5, 0.0, 0.0)))
    last_message = 2.0 - DT
    refs = run(motion, 2.0, 3.0)
    times = 2.0 + DT * np.arange(len(refs))
    speeds = np.array([r.eta_dot[0] for r in refs])
    assert np.all(speeds[times <= last_message + 0.3 - DT] > 0.49)
    stopped = times[np.argmax(speeds == 0.0)]
    assert stopped - last_message == pytest.approx(0.3 + 0.5 / 0.25, abs=0.01)
    assert not motion.moving and not motion.driving(times[-1])
    held = refs[-1].eta.copy()
    run(motion, 5.0, 1.0)
    np.testing.assert_array_equal(motion.eta, held)


def test_driving_forward_facing_east_moves_east_and_the_arm_rides_along() -> None:
    """Forward is the body x axis: at yaw 90 deg the vehicle moves +y (east) in map_ned."""
    motion = started(math.pi / 2)
    refs = run(motion, 0.0, 4.0, PilotTwist((0.25, 0.0, 0.0)))
    refs += run(motion, 4.0, 3.0)
    eta, X_d = refs[-1].eta, refs[-1].X_d
    assert eta[0] == pytest.approx(0.0, abs=1e-9)
    assert eta[1] > 0.5
    np.testing.assert_allclose(X_d - eta[:3], [0.0, 1.7, -0.1], atol=1e-9)


def test_a_yaw_command_swings_the_end_effector_about_the_vehicle() -> None:
    """Yawing 90 degrees keeps the arm's offset in the body: X_d turns with the vehicle."""
    motion = started()
    rate = PilotTwist((0.0, 0.0, 0.0), (0.0, 0.0, 0.5))
    t, refs = 0.0, []
    while motion.eta[5] < math.pi / 2 - 0.2:  # 0.25 s of deadman plus the ramp down: short
        refs += run(motion, t, 0.1, rate)
        t += 0.1
    refs += run(motion, t, 2.0)
    yaw = refs[-1].eta[5]
    np.testing.assert_allclose(refs[-1].X_d, rot_ned_from_body(0.0, 0.0, yaw) @ [1.7, 0, -0.1],
                               atol=1e-9)
    finite_difference = np.diff([r.X_d for r in refs], axis=0) / DT
    velocities = np.array([r.X_dot_d for r in refs])[1:]
    np.testing.assert_allclose(finite_difference, velocities, atol=2e-3)


def test_an_end_effector_command_in_the_map_frame_keeps_its_map_direction() -> None:
    """Facing east, 2 cm/s north in map_ned moves X_d north relative to the vehicle."""
    motion = started(math.pi / 2)
    refs = run(motion, 0.0, 2.0, ee=PilotTwist((0.02, 0.0, 0.0), in_body=False))
    refs += run(motion, 2.0, 1.0)
    moved = refs[-1].X_d - refs[0].X_d
    assert moved[0] > 0.03
    assert abs(moved[1]) < 1e-9
