"""The latency from a device's reply to the command it causes, measured through the twins.

Runs ``uvms launch SCENARIO --hardware twin`` (the robot loop and the twins in the
simulator's process, the defaults) with ``UVMS_LATENCY_PROBE`` set
(``uvms_hardware.latency_probe``): the Alpha 5 twin and the Net F/T twin note when each
datagram leaves them, the bridges when they read datagrams and when a command leaves them
(the arm's CURRENT frames, the vehicle's RC overrides), all on CLOCK_MONOTONIC.

Reply i of a device is the i-th datagram its bridge read (loopback UDP neither loses nor
reorders; the bridge reads only its twin's port; the Net F/T's records by their RDT
sequence); the command it causes is the first one of
its kind that leaves the bridge after that read. The latency is the command's time minus the
reply's: the wait for the bridge's next read (the loop's period), the read, the estimator,
the controller, the allocator and the write. Replies count from 1 s after the first command
to the last command (before, the bridges read what queued while they were activated).
Printed per path: p50 / p99 / max (ms) and the number of replies, with the part from the
read to the command on its own:

- ``alpha5 reply -> CURRENT``: a joint's answer (POSITION + VELOCITY) to the next CURRENT
  frames. A joint's answer enters the controller with its round (``joint_states`` is
  published once every joint answered afresh), so the round's last answer is the one that
  causes the command; every answer's figure is printed too;
- ``netft record -> CURRENT`` and ``netft record -> RC override``: a wrench record to the next
  arm command, and to the next RC override (written at the ArduSub bridge's own
  ``override_rate_hz``, so that wait is in it).

It asserts nothing; the load average is printed. Usage::

    .venv/bin/python bench/bench_twin_latency.py [--scenario NAME] [--real-time-factor F]
"""

from __future__ import annotations

import argparse
import bisect
import os
import random
import subprocess
import sys
import tempfile
from collections import defaultdict
from pathlib import Path

import numpy as np
from bench_realtime_load import MISSION_FAILED, source_path

SCENARIO = 'bluerov2_alpha5_contact'
#: Joints the Alpha 5 bridge polls in one round (one answer datagram each).
ROUND = 4
#: The Net F/T twin's port (``rdt_protocol.RDT_PORT``); the other twin is the Alpha 5.
RDT_PORT = 49152
#: Replies counted from this long after the first command (ns).
SETTLE_NS = 1_000_000_000


def read_notes(directory: Path) -> dict[str, list[tuple[int, int, int]]]:
    """Every note of every process, by kind: (t_ns, value, extra), in time order."""
    notes: dict[str, list[tuple[int, int, int]]] = defaultdict(list)
    for path in directory.glob('probe-*.txt'):
        for line in path.read_text().splitlines():
            kind, t_ns, value, extra = line.split()
            notes[kind].append((int(t_ns), int(value), int(extra)))
    for events in notes.values():
        events.sort()
    return notes


def replies_read(notes: dict[str, list[tuple[int, int, int]]], port: int
                 ) -> tuple[np.ndarray, np.ndarray]:
    """(sent ns, read ns) of each reply from the twin at ``port`` that its bridge read.

    The Net F/T's records by their RDT sequence (the latest sending of it before the read:
    a new stream starts its sequence again); the Alpha 5's answers in order.
    """
    if port == RDT_PORT:
        sends: dict[int, list[int]] = defaultdict(list)
        for t, p, sequence in notes['reply']:
            if p == port:
                sends[sequence].append(t)
        pairs = []
        for r, _, sequence in notes['ftrx']:
            times = sends.get(sequence, [])
            k = bisect.bisect_right(times, r)
            if k:
                pairs.append((times[k - 1], r))
        both = np.array(pairs, dtype=np.int64).reshape(-1, 2)
        return both[:, 0], both[:, 1]
    sent = np.array([t for t, p, _ in notes['reply'] if p == port], dtype=np.int64)
    read = np.array([t for t, p, n in notes['rx'] if p == port for _ in range(n)],
                    dtype=np.int64)
    count = min(sent.size, read.size)
    return sent[:count], read[:count]


def latencies(sent: np.ndarray, read: np.ndarray, commands: list[int]
              ) -> tuple[np.ndarray, np.ndarray]:
    """(reply -> command, read -> command) in ms for each reply followed by a command."""
    total, after_read = [], []
    for s, r in zip(sent.tolist(), read.tolist(), strict=True):
        k = bisect.bisect_right(commands, r)
        if k < len(commands):
            total.append((commands[k] - s) * 1e-6)
            after_read.append((commands[k] - r) * 1e-6)
    return np.array(total), np.array(after_read)


def figure(name: str, total: np.ndarray, after_read: np.ndarray) -> str:
    """One path's line."""
    if not total.size:
        return f'{name}: no reply followed by a command'
    p = np.percentile
    return (f'{name}: p50 {p(total, 50):.2f} ms, p99 {p(total, 99):.2f} ms, max '
            f"{total.max():.2f} ms ({total.size} replies); of which from the bridge's read: "
            f'p50 {p(after_read, 50):.2f}, p99 {p(after_read, 99):.2f}, max '
            f'{after_read.max():.2f} ms')


def main() -> None:
    """One launch with the probe on, then the figures per path."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--scenario', default=SCENARIO)
    parser.add_argument('--real-time-factor', type=float, default=1.0)
    args = parser.parse_args()
    print(f'load before: {" ".join(f"{v:.2f}" for v in os.getloadavg())} '
          f'({os.cpu_count()} CPUs); {args.scenario} --hardware twin, factor '
          f'{args.real_time_factor:g}')
    with tempfile.TemporaryDirectory(prefix='uvms_twin_latency_') as directory:
        probe = Path(directory) / 'probe'
        env = dict(os.environ, PYTHONPATH=source_path(), UVMS_LATENCY_PROBE=str(probe),
                   ROS_DOMAIN_ID=str(random.randint(1, 100)))
        command = [str(Path(sys.executable).parent / 'uvms'), 'launch', args.scenario,
                   '--hardware', 'twin', '--real-time-factor', str(args.real_time_factor),
                   '--output', str(Path(directory) / 'run.mcap')]
        result = subprocess.run(command, env=env, capture_output=True, text=True,
                                timeout=1200, check=False, stdin=subprocess.DEVNULL)
        outcome = 'SUCCEEDED' if result.returncode == 0 else f'exit {result.returncode}'
        for line in result.stderr.splitlines():
            failed = MISSION_FAILED.match(line)
            if failed:
                outcome = failed.group(1)
        loop = next((line for line in result.stderr.splitlines() if 'robot loop: ' in line),
                    '')
        notes = read_notes(probe)
    print(f'outcome {outcome}; load after: {" ".join(f"{v:.2f}" for v in os.getloadavg())}')
    if loop:
        print(loop.split('; direct:')[0].split('composed]: ')[-1])
    ports = sorted({p for _, p, _ in notes['reply']})
    currents = [t for t, _, _ in notes['current']]
    overrides = [t for t, _, _ in notes['rc']]
    if not currents:
        print('no CURRENT frame left the bridge: nothing to measure')
        return
    # The running loop only: from 1 s after the first command to the last one (before, the
    # bridges read what queued while they were configured and activated).
    start_ns, end_ns = currents[0] + SETTLE_NS, currents[-1]
    print(f'window: {(end_ns - start_ns) * 1e-9:.1f} s of commands')
    for port in ports:
        sent, read = replies_read(notes, port)
        inside = (sent >= start_ns) & (sent < end_ns)
        sent, read = sent[inside], read[inside]
        replies = sum(1 for _, p, _ in notes['reply'] if p == port)
        span_s = (sent[-1] - sent[0]) * 1e-9 if sent.size > 1 else 0.0
        rate_hz = sent.size / span_s if span_s else 0.0
        device = 'netft record' if port == RDT_PORT else 'alpha5 reply'
        print(f'{device} (port {port}): {replies} sent, {read.size} of them in the window and '
              f'read by the bridge, {rate_hz:.0f}/s')
        total, after = latencies(sent, read, currents)
        print('  ' + figure(f'{device} -> CURRENT', total, after))
        if device == 'alpha5 reply':
            last = slice(ROUND - 1, None, ROUND)  # a round's last answer (in order)
            print('  ' + figure('alpha5 round-completing reply -> CURRENT (approx.: every '
                                f'{ROUND}th)', *latencies(sent[last], read[last], currents)))
        else:
            print('  ' + figure(f'{device} -> RC override', *latencies(sent, read, overrides)))


if __name__ == '__main__':
    main()
