"""Real time on the estimate: ``uvms launch`` beside ``uvms run`` of a scenario with the estimator.

Runs ``uvms launch SCENARIO --duration S --output A.mcap`` (one process per node, real time)
and ``uvms run config/scenarios/SCENARIO.yaml --duration S --output B.mcap`` (lockstep), then
prints, per recording, how the estimate and the control loop kept pace with the states:

- per topic, messages and the lag of each message behind its stamp as the recorder saw it
  (its log time, on ``/clock``, minus the header stamp; a resolution of one state period,
  2 ms), mean, p99 and max;
- the share of states (``/clock`` stamps) without an estimate stamped alike
  (``odometry/filtered``), without a command (``command/generalized_force``) and without an
  actuator command stamped alike: the periods the estimator, controller or allocator missed;

then ``uvms report`` of both (RMS force error, contacts, thrust scale, e_z, ...) and the load
average before and after. Figures taken on a shared machine are marked by that load.

Usage::

    .venv/bin/python bench/bench_realtime_estimate.py [SCENARIO] [--duration S] [--out DIR]
        [--no-lockstep]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(p) for p in sorted((REPO / 'src').glob('uvms_*')) if p.name != 'uvms_msgs']

from uvms_common.cdr_codecs import read_stamp_ns  # noqa: E402
from uvms_recording.mcap_reader import open_recording  # noqa: E402

UVMS = Path(sys.executable).parent / 'uvms'
TOPICS = ('/clock', '/uvms/imu', '/uvms/odometry/filtered', '/uvms/command/generalized_force',
          '/uvms/command/actuators', '/uvms/joint_states')


def stamps_and_lags(path: Path) -> dict[str, tuple[list[int], list[int]]]:
    """Per topic: header stamps (ns) and log time minus stamp (ns), in log order."""
    out: dict[str, tuple[list[int], list[int]]] = defaultdict(lambda: ([], []))
    for msg in open_recording(path).messages(TOPICS):
        stamp = read_stamp_ns(msg.data)
        stamps, lags = out[msg.topic]
        stamps.append(stamp)
        lags.append(msg.log_time_ns - stamp)
    return out


def describe(path: Path) -> None:
    """Print the lag table and the missed states of one recording."""
    series = stamps_and_lags(path)
    print(f'  {path.name}')
    print(f'    {"topic":<34}{"msgs":>7}{"lag mean":>10}{"p99":>8}{"max":>8}  (ms)')
    for topic in TOPICS:
        stamps, lags = series.get(topic, ([], []))
        if not stamps:
            continue
        lag = np.array(lags) * 1e-6
        print(f'    {topic:<34}{len(stamps):>7}{lag.mean():>10.2f}'
              f'{np.percentile(lag, 99):>8.1f}{lag.max():>8.1f}')
    states = set(series['/clock'][0])
    states.discard(0)  # the held initial state is re-published during start-up
    for topic in ('/uvms/odometry/filtered', '/uvms/command/generalized_force',
                  '/uvms/command/actuators'):
        got = set(series.get(topic, ([], []))[0])
        if states:
            missed = len(states - got) / len(states)
            print(f'    states without {topic.rsplit("/uvms/", 1)[-1]} stamped alike: '
                  f'{missed:.1%} of {len(states)}')


def main() -> None:
    """Run the launch (and the lockstep run), describe both, report both."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('scenario', nargs='?', default='case1_estimated')
    parser.add_argument('--duration', type=float, default=14.0)
    parser.add_argument('--out', type=Path, default=Path('out/bench_realtime_estimate'))
    parser.add_argument('--no-lockstep', action='store_true')
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    launched = args.out / f'{args.scenario}_launch.mcap'
    lockstep = args.out / f'{args.scenario}_run.mcap'
    print(f'load average before: {os.getloadavg()}', flush=True)
    runs = [[str(UVMS), 'launch', args.scenario, '--duration', str(args.duration),
             '--output', str(launched)]]
    if not args.no_lockstep:
        runs.append([str(UVMS), 'run', str(REPO / 'config' / 'scenarios' /
                                           f'{args.scenario}.yaml'),
                     '--duration', str(args.duration), '--output', str(lockstep)])
    for command in runs:
        done = subprocess.run(command, capture_output=True, text=True, check=False)
        print(f'{" ".join(command[1:3])}: exit {done.returncode}; load average '
              f'{os.getloadavg()[0]:.2f}', flush=True)
        if done.returncode:
            print(done.stdout[-2000:] + done.stderr[-2000:])
    recordings = [p for p in (launched, lockstep) if p.exists()]
    for path in recordings:
        describe(path)
    subprocess.run([str(UVMS), 'report', *map(str, recordings)], check=False)
    print(f'load average after: {os.getloadavg()}')


if __name__ == '__main__':
    main()
