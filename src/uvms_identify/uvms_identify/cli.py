"""``uvms identify``: plan the identification experiments, and fit a robot to their recordings.

``uvms identify plan --robot NAME|PATH --out DIR`` writes one scenario per vehicle axis
(``uvms_identify.plan``); ``uvms identify fit MCAP... --robot NAME|PATH --out DIR`` writes
DIR/hydrodynamics.yaml, DIR/report.md and the figures (docs/identification.md).

Exit status: 0 done; 1 the fit failed (no term excited); 2 bad usage, an unknown robot, or a
recording refused (one line naming the file and what is missing).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

EXIT_OK = 0
EXIT_FAILURE = 1
EXIT_USAGE = 2

ROBOT_HELP = ('a robot folder of uvms_description by name or a path to a robot folder of your '
              'own (any name with a /: ./my_robot)')


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add ``identify`` with its ``plan`` and ``fit`` subcommands to ``uvms``'s subparsers."""
    parser: argparse.ArgumentParser = subparsers.add_parser(
        'identify', help="identify the vehicle's hydrodynamics from its own recordings",
        description="Plan the identification experiments of a robot (scenario files), and fit "
                    "the robot's hull hydrodynamics (added mass, damping, buoyancy) to their "
                    'recordings. docs/identification.md')
    sub = parser.add_subparsers(dest='identify_command', metavar='plan|fit')
    plan = sub.add_parser('plan', help='write the experiments as scenario files',
                          description='Write one scenario per vehicle axis (thrust steps '
                                      'and a chirp about a static offset, free decays; heave '
                                      'by doublets, trimmed, the arm held; --level: surge and '
                                      'sway too; at most 60 s each), runnable with `uvms run` '
                                      'and `uvms launch`.')
    plan.add_argument('--robot', required=True, metavar='NAME|PATH', help=ROBOT_HELP)
    plan.add_argument('--out', required=True, type=Path, metavar='DIR',
                      help='directory of the scenario files (created)')
    plan.add_argument('--level', action='store_true',
                      help='trim weight and buoyancy in every experiment, hold the arm in '
                           'joint space, surge and sway by doublets below the Munk speed '
                           '(docs/identification.md: the vehicle still tilts while the '
                           'controller reaches with the arm)')
    fit = sub.add_parser('fit', help='fit the hull to recordings of the experiments',
                         description='Fit the hull terms to recordings (IMU, DVL, joint states, '
                                     'thrusts; never the ground truth) and write '
                                     'hydrodynamics.yaml, report.md and figures to DIR.')
    fit.add_argument('recordings', nargs='+', type=Path, metavar='MCAP')
    fit.add_argument('--robot', required=True, metavar='NAME|PATH',
                     help=ROBOT_HELP + '; its hydrodynamics.yaml is the prior and the comparison')
    fit.add_argument('--out', required=True, type=Path, metavar='DIR',
                     help='directory of hydrodynamics.yaml, report.md and the figures (created)')
    fit.add_argument('--velocity', choices=('dvl', 'estimate'), default='dvl',
                     help='body velocity from the DVL with the IMU rates (default), or from '
                          'the estimator (odometry/filtered)')
    return parser


def _plan(args: argparse.Namespace) -> int:
    from uvms_identify.known_terms import rigid_and_restoring, start_joints, trim_wrench
    from uvms_identify.plan import plan, write_plan
    from uvms_identify.robot_data import load_robot

    robot = load_robot(args.robot)
    inertia, restoring = rigid_and_restoring(robot)
    experiments = plan(robot, inertia, restoring, trim_wrench(robot), level=args.level)
    joints = start_joints(robot, _joint_count(robot))
    reference = str(robot.files.directory) if '/' in args.robot else robot.name
    paths = write_plan(robot, experiments, args.out, reference, joints)
    for path, experiment in zip(paths, experiments, strict=True):
        unit = 'm' if experiment.axis < 3 else 'rad'
        print(f'{path}: expected excursion {experiment.excursion:.2f} {unit}, top speed '
              f'{experiment.top_speed:.2f} {unit}/s')
    return EXIT_OK


def _joint_count(robot: Any) -> int:
    from uvms_identify.known_terms import ZERO_HULL, model_with_hull
    return int(model_with_hull(robot, ZERO_HULL).n_joints)


def _fit(args: argparse.Namespace) -> int:
    from uvms_identify.actuator_output import write_thrusters, write_urdf
    from uvms_identify.identify import identify
    from uvms_identify.output import (
        provenance,
        write_figures,
        write_hydrodynamics,
        write_report,
    )
    from uvms_identify.robot_data import load_robot

    robot = load_robot(args.robot)
    result = identify(list(args.recordings), robot, velocity=args.velocity)
    args.out.mkdir(parents=True, exist_ok=True)
    figures = write_figures(result, args.out)
    hydrodynamics = write_hydrodynamics(result, args.out, figures)
    report = write_report(result, args.out, figures)
    header = provenance(result, figures)
    written = [hydrodynamics, write_thrusters(result, args.out, header)]
    urdf = write_urdf(result, args.out, header)
    if urdf is not None:
        written.append(urdf)
    well = sum(result.fit.well_determined(j) for j in range(len(result.fit.theta)))
    fitted = sum(result.fit.identified(j) for j in range(len(result.fit.theta)))
    print(f'uvms identify: {fitted} of {len(result.fit.theta)} terms identified ({well} within '
          f'10 %); wrote {", ".join(str(p) for p in written)}, {report} and {len(figures)} '
          'figures')
    return EXIT_OK


def run(args: argparse.Namespace) -> int:
    """Run ``uvms identify plan|fit`` on parsed arguments; the exit status."""
    from uvms_identify.errors import IdentifyError

    command = getattr(args, 'identify_command', None)
    if command not in ('plan', 'fit'):
        print('uvms identify: error: give a subcommand, plan or fit (uvms identify --help)',
              file=sys.stderr)
        return EXIT_USAGE
    try:
        return _plan(args) if command == 'plan' else _fit(args)
    except IdentifyError as exc:
        message = str(exc)
        status = EXIT_FAILURE if 'no hull term is excited' in message else EXIT_USAGE
        print(f'uvms identify: error: {message}', file=sys.stderr)
        return status


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m uvms_identify.cli``: the subcommand alone, as ``uvms identify`` runs it."""
    parser = argparse.ArgumentParser(prog='uvms')
    add_parser(parser.add_subparsers(dest='command'))
    args = parser.parse_args(['identify', *(sys.argv[1:] if argv is None else argv)])
    return run(args)


if __name__ == '__main__':
    sys.exit(main())
