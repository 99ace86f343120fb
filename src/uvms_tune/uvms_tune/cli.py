"""``uvms tune``: the controller's gains by constrained Bayesian optimization over scenarios.

Exit status: 0 tuned (the gains file written), 1 Ray or the graph could not be started or
no trial was feasible, 2 bad usage or a bad tune file (one line naming the key), 130
interrupted (the journal keeps the finished trials: ``--resume`` continues).
"""

from __future__ import annotations

import argparse
import shutil
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from uvms_common.node_main import StopEvent
from uvms_common.ros_environment import ros_environment_defaults
from uvms_sweep.cli import add_ray_arguments, positive_int
from uvms_sweep.ideal_devices import add_ideal_devices_argument, with_ideal_devices

if TYPE_CHECKING:
    from uvms_tune.driver import Runner

EXIT_OK = 0
EXIT_FAILURE = 1
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130


def build_parser() -> argparse.ArgumentParser:
    """Argument parser of ``uvms tune``."""
    parser = argparse.ArgumentParser(
        prog='uvms tune',
        description='Tune the controller gains of a robot by constrained Bayesian optimization '
                    '(Optuna TPE, ask/tell) over the training scenarios of a tune file, each '
                    'trial run as Ray tasks through the sweep point runner; unstable gains are '
                    'refused before any simulation. Writes DIR/tuned_gains.yaml, report.md and '
                    'figures/ (docs/tuning.md).')
    parser.add_argument('tune', metavar='TUNE.yaml', help='tune file (docs/tuning.md)')
    parser.add_argument('--trials', '-n', type=positive_int, metavar='N',
                        help="trials to finish (default: the tune file's trials)")
    add_ray_arguments(parser, 'scenario runs')
    parser.add_argument('--resume', action='store_true',
                        help='continue the tune in --out from its journal')
    parser.add_argument('--out', '-o', metavar='DIR',
                        help='output folder (default: out/tune/NAME)')
    add_ideal_devices_argument(parser)
    parser.add_argument('--apply', action='store_true',
                        help='also write the gains as robots/NAME/controller_tuned.yaml, beside '
                             'the hand-tuned controller.yaml')
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``uvms tune`` with the arguments after the subcommand; returns the exit status."""
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as exc:
        return exc.code if isinstance(exc.code, int) else EXIT_USAGE
    ros_environment_defaults()
    stop = StopEvent()
    try:
        return _tune(args, stop)
    except KeyboardInterrupt:
        print('uvms tune: interrupted; add --resume to the same command to continue',
              file=sys.stderr)
        return EXIT_INTERRUPTED
    finally:
        stop.restore()


def _tune(args: argparse.Namespace, stop: StopEvent) -> int:
    """Check the tune file, run the trials, and write the gains and the report."""
    from uvms_sweep.batch import PointBatches
    from uvms_sweep.engine import SweepEngineError

    from uvms_tune.driver import Tuner
    from uvms_tune.errors import TuneError
    from uvms_tune.tune_file import load_tune_file

    try:
        tune = load_tune_file(args.tune)
    except TuneError as exc:
        return _error(str(exc), EXIT_USAGE)
    out_dir = Path(args.out) if args.out else Path('out') / 'tune' / tune.name
    trials = args.trials or tune.trials
    try:
        with PointBatches(args.address, args.workers, stop) as batches:
            try:
                runner = _ideal_devices_runner(batches.run) if args.ideal_devices else batches.run
                tuner = Tuner(tune, out_dir, runner, resume=args.resume)
            except TuneError as exc:
                return _error(str(exc), EXIT_USAGE)
            if tune.path.resolve() != (out_dir / 'tune.yaml').resolve():
                shutil.copyfile(tune.path, out_dir / 'tune.yaml')
            _run_trials(tuner, trials, stop, quiet=args.quiet)
            return _finish(tuner, trials, apply=args.apply)
    except SweepEngineError as exc:
        return _error(str(exc), EXIT_FAILURE)


def _ideal_devices_runner(run: Runner) -> Runner:
    """``run`` with ``--ideal-devices``' values over every point request's overrides."""
    def ideal(requests: Sequence[Mapping[str, Any]], timeout_s: float) -> list[dict[str, Any]]:
        return run([{**request, 'overrides': with_ideal_devices(request['overrides'])}
                    for request in requests], timeout_s)
    return ideal


def _run_trials(tuner: Any, trials: int, stop: StopEvent, *, quiet: bool) -> None:
    """Run the trials with a progress bar showing the best objective so far.

    A stop (Ctrl-C, SIGTERM) ends the running trial's points (``PointBatches``) or, between
    trials (an unstable one runs nothing), the loop: KeyboardInterrupt either way.
    """
    from tqdm import tqdm

    done = len(tuner.finished())
    bar = None if quiet else tqdm(total=trials, initial=min(done, trials), unit='trial',
                                  desc='uvms tune', file=sys.stderr, dynamic_ncols=True)

    def progress(finished: int, best: float | None) -> None:
        if bar is not None:
            bar.set_postfix_str('best ' + ('none feasible' if best is None else f'{best:.4g}'))
            bar.update(1)
        if stop.is_set():
            raise KeyboardInterrupt

    try:
        tuner.run(trials, progress)
    finally:
        if bar is not None:
            bar.close()


def _finish(tuner: Any, trials: int, *, apply: bool) -> int:
    """Write the tuned gains, the report and the figures; ``apply`` to the robot folder."""
    from uvms_description.robots import robot_files
    from uvms_tune.finish import write_results
    from uvms_tune.output import apply_to_robot

    best = tuner.best()
    if best is None:
        return _error(f'none of the {len(tuner.finished())} trials was feasible (see '
                      f'{tuner.out_dir / "journal.log"}); widen the ranges or check the '
                      'scenarios', EXIT_FAILURE)
    gains_file, report = write_results(tuner, best, trials)
    print(f'uvms tune: best trial {best.number} of {len(tuner.finished())}, objective '
          f'{best.value:.4g}; gains {gains_file}, report {report}', file=sys.stderr)
    if apply:
        target = apply_to_robot(gains_file, robot_files(tuner.tune.robot).directory)
        print(f'uvms tune: applied: {target} (beside controller.yaml; select it with '
              "`--params-file` on the controller or paste it into a scenario's "
              '`controller:` section)', file=sys.stderr)
    return EXIT_OK


def _error(message: str, status: int) -> int:
    """One-line error on stderr; returns ``status``."""
    print(f'uvms tune: error: {message}', file=sys.stderr)
    return status


if __name__ == '__main__':
    sys.exit(main())
