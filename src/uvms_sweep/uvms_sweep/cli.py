"""``uvms sweep``: run a parameter sweep of a scenario on Ray, tabulate and map its metrics.

Exit status: 0 every point has its row (points that failed are results too: the table says
why), 1 the graph or Ray could not be started, 2 bad usage or a bad sweep file (one line
naming the key), 130 interrupted (what is done is kept; the same command resumes).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

from uvms_common.node_main import StopEvent
from uvms_common.ros_environment import ros_environment_defaults

from uvms_sweep.ideal_devices import add_ideal_devices_argument, with_ideal_devices

EXIT_OK = 0
EXIT_FAILURE = 1
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130


def positive_int(text: str) -> int:
    """Argparse type: an integer >= 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'expected an integer, got {text!r}') from None
    if value < 1:
        raise argparse.ArgumentTypeError(f'expected an integer >= 1, got {value}')
    return value


def add_ray_arguments(parser: argparse.ArgumentParser, runs: str) -> None:
    """The Ray options of a command that runs graphs as Ray tasks (``uvms sweep``, ``uvms tune``).

    ``--address`` (join a cluster instead of a local Ray), ``--workers``/``-j`` (runs at once)
    and ``--quiet``/``-q`` (no progress bar).

    Args:
        parser: The command's parser.
        runs: What runs at once, for ``--workers``' help (``points``, ``scenario runs``).
    """
    parser.add_argument('--address', metavar='RAY_ADDRESS',
                        help='join this Ray cluster (e.g. HOST:6379 or auto) instead of '
                             'starting a local Ray')
    parser.add_argument('--workers', '-j', type=positive_int, metavar='N',
                        help=f"{runs} at once (default: this machine's CPUs, or the "
                             "cluster's)")
    parser.add_argument('--quiet', '-q', action='store_true', help='no progress bar')


def build_parser() -> argparse.ArgumentParser:
    """Argument parser of ``uvms sweep``."""
    parser = argparse.ArgumentParser(
        prog='uvms sweep',
        description='Run every point of a sweep file (base scenario x parameter axes x seeds) '
                    'as a full lockstep graph run in its own process and DDS domain, on a '
                    'local Ray (127.0.0.1 only) or an existing Ray cluster; write '
                    'DIR/points.csv and DIR/figures/METRIC.png. Re-running resumes: points '
                    'already done are skipped.')
    parser.add_argument('sweep', metavar='SWEEP.yaml', help='sweep file (docs/sweeps.md)')
    parser.add_argument('--out', '-o', required=True, metavar='DIR',
                        help='output directory: points.csv, figures/, mcap/, logs/')
    parser.add_argument(
        '--params-file', action='append', default=[], metavar='FILE',
        help='a ROS 2 parameter file (node_name: ros__parameters: ..., /** and /**/node '
             "wildcards) applied to every point over the scenario and the sweep file's "
             'params_files, under the axes; repeatable, later files win; every name is '
             'checked against what the nodes declare before any point runs (as uvms run '
             '--params-file; docs/sweeps.md)')
    add_ray_arguments(parser, 'points')
    add_ideal_devices_argument(parser)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``uvms sweep`` with the arguments after the subcommand; returns the exit status."""
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as exc:
        return exc.code if isinstance(exc.code, int) else EXIT_USAGE
    ros_environment_defaults()
    stop = StopEvent()
    try:
        return _sweep(args, stop)
    except KeyboardInterrupt:
        print('uvms sweep: interrupted', file=sys.stderr)
        return EXIT_INTERRUPTED
    finally:
        stop.restore()


def _sweep(args: argparse.Namespace, stop: StopEvent) -> int:
    """Check the sweep, run it, and report."""
    import rclpy.logging
    from uvms_run.graph import GraphError
    from uvms_scenarios.scenario import ScenarioError

    from uvms_sweep.engine import SweepEngineError, run_sweep
    from uvms_sweep.sweep_file import SweepError, load_sweep
    from uvms_sweep.table import TableError
    from uvms_sweep.validate import check_sweep, duration_warning

    # The nodes built to check the axes would log their start-up lines: only warnings.
    rclpy.logging.set_logger_level('uvms', rclpy.logging.LoggingSeverity.WARN)
    try:
        sweep, scenario = check_sweep(load_sweep(args.sweep), args.params_file)
    except (SweepError, ScenarioError) as exc:
        _error(str(exc))
        return EXIT_USAGE
    except GraphError as exc:
        _error(str(exc))
        return EXIT_FAILURE
    if args.ideal_devices:  # every point's request carries the base scenario's overrides
        scenario = replace(scenario, overrides=with_ideal_devices(scenario.overrides))
    if warning := duration_warning(sweep, scenario):
        print(f'uvms sweep: warning: {warning}', file=sys.stderr)
    if stop.is_set():
        return EXIT_INTERRUPTED
    try:
        summary = run_sweep(sweep, scenario, Path(args.out), address=args.address,
                            workers=args.workers, progress=not args.quiet, stop=stop)
    except TableError as exc:
        _error(str(exc))
        return EXIT_USAGE
    except SweepEngineError as exc:
        _error(str(exc))
        return EXIT_FAILURE
    print(f'uvms sweep: {summary.total} points: {summary.skipped} already done, '
          f'{summary.ran} run ({summary.failed} failed); table {summary.table}'
          + (f', {len(summary.figures)} figures in {Path(args.out) / "figures"}'
             if summary.figures else ''), file=sys.stderr)
    if summary.interrupted:
        print('uvms sweep: interrupted; re-run the same command to resume', file=sys.stderr)
        return EXIT_INTERRUPTED
    return EXIT_OK


def _error(message: str) -> None:
    """One-line error on stderr."""
    print(f'uvms sweep: error: {message}', file=sys.stderr)


if __name__ == '__main__':
    sys.exit(main())
