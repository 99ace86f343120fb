"""Steady surge speed of a robot with every horizontal thruster at full forward thrust.

Run: ``.venv/bin/python bench/bench_surge_speed.py [--robot bluerov2_alpha5] [--duration S]``.
The robot's model (its URDF, hydrodynamics and thruster layout) starts level at rest; each
thruster whose direction lies in the body x-y plane pushes with its ``thrusters.max_thrust_n``
in the sense that drives the vehicle forward (+x of base_link_frd), the vertical ones are
used only to hold depth, roll and pitch (a PD through their least-squares allocation, as
ArduSub's stabilize and depth-hold modes do: the horizontal thrusters act below the centre of
gravity and would pitch the vehicle over), and a PD on the arm joints holds the arm at its
start posture (a stowed arm). The thrust is held constant: a bollard figure, so the speed
is an upper bound (a real propeller's thrust drops with the inflow). With von Benzon's
damping (141 N s^2/m^2 in surge, the robot's hydrodynamics.yaml) the hull alone reaches
about 0.85 m/s on 4 x 39.9 N x cos 45 deg; the published 1.5 m/s would need about a third
of that quadratic damping (Wu 2018's 18.18 gives 2.4 m/s). It prints the speed reached
beside the published figure of the BlueROV2 Heavy: Blue Robotics' product page, "max forward speed
1.5 m/s (3 knots)", as quoted in issue 21 (not re-checked here: the stored copies of public
pages hold no copy of that page). A benchmark prints figures; it never asserts.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
for folder in ('src/uvms_description', 'src/uvms_model'):
    sys.path.insert(0, str(ROOT / folder))

from uvms_model.thrusters import ThrusterLayout  # noqa: E402

from uvms_description.robots import (  # noqa: E402
    robot_files,
    robot_parameters,
    with_description_paths,
)
from uvms_model import UvmsModel, UvmsParameters  # noqa: E402

PUBLISHED_M_S = 1.5
"""Blue Robotics, BlueROV2 product page (as quoted in issue 21): 1.5 m/s (3 knots)."""


def surge_speed(robot: str, duration_s: float,
                dt: float = 1e-3) -> tuple[float, float, float]:
    """(surge speed u (m/s), forward thrust (N), pitch (rad)) after ``duration_s``."""
    values = {k: item.value for k, item in robot_parameters(robot, 'simulator').items()
              if k.split('.')[0] in ('thrusters', 'sensor')}
    params = UvmsParameters.from_flat_dict(with_description_paths(values, robot))
    model = UvmsModel(params)
    layout = ThrusterLayout.from_parameters(params.thrusters)
    directions = np.asarray(layout.directions)
    horizontal = np.abs(directions[:, 2]) < 1e-9
    thrust = np.where(horizontal, np.sign(directions[:, 0]) * np.asarray(layout.max_thrust_n),
                      0.0)
    matrix = layout.thrust_matrix()
    wrench = matrix @ thrust  # (6,) in base_link_frd
    vertical = np.linalg.pinv(matrix[np.ix_([2, 3, 4], np.flatnonzero(~horizontal))])
    q = np.zeros(model.n_dof)
    q[6:] = model.joint_positions_for_ee_position(
        np.zeros(6), model.ee_position(q), np.zeros(model.n_joints))
    w = np.zeros(model.n_dof)
    arm0 = q[6:].copy()
    for _ in range(round(duration_s / dt)):
        hold = -np.array([400.0, 400.0, 400.0]) * q[[2, 3, 4]] - np.array(
            [80.0, 20.0, 20.0]) * w[[2, 3, 4]]  # heave, roll, pitch
        stabilize = np.zeros(len(thrust))
        stabilize[~horizontal] = vertical @ hold
        tau_b = np.concatenate((matrix @ (thrust + stabilize),
                                1.0 * (arm0 - q[6:]) - 0.05 * w[6:]))
        q, w = model.step(q, w, tau_b, None, dt)
    return float(w[0]), float(wrench[0]), float(q[4])


def main() -> None:
    """Print the steady surge speed beside the published figure."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument('--robot', default='bluerov2_alpha5', help='robot folder name')
    parser.add_argument('--duration', type=float, default=20.0, help='simulated seconds')
    args = parser.parse_args()
    robot_files(args.robot)
    speed, forward, pitch = surge_speed(args.robot, args.duration)
    print(f'{args.robot}: horizontal thrusters at full forward thrust ({forward:.1f} N along x)')
    print(f'  steady surge speed after {args.duration:g} s: {speed:.3f} m/s '
          f'(pitch {np.degrees(pitch):.2f} deg, held by the vertical thrusters)')
    print(f'  published (BlueROV2 Heavy, Blue Robotics): {PUBLISHED_M_S:.1f} m/s (3 knots); '
          f'ratio {speed / PUBLISHED_M_S:.2f}')


if __name__ == '__main__':
    main()
