"""What a live Foxglove view costs the lockstep graph: real-time factor with and without it.

One process, one scenario (default case1_ke1e4, recorder on), three lockstep runs of the
in-process graph (as ``uvms run`` builds it):

1. without the ``foxglove_server`` node (the graph as ``uvms run`` without ``--foxglove``);
2. with it, in one run: a stretch of simulated time with no client connected, then a
   client (a separate process speaking Foxglove's WebSocket protocol, as the app would,
   subscribed to every advertised channel and draining what arrives) joins, and a second
   stretch of the same length is timed with it connected.

Printed: the real-time factor (simulated s per wall s) of each stretch, the ratios against
the run without the node and, in the same run, client connected / no client; and how many
messages and bytes the client received. A benchmark prints figures, it asserts nothing;
the machine's load average is printed with them.

Usage::

    .venv/bin/python bench/bench_foxglove.py [SCENARIO] [--stretch S] [--warmup S]
"""

from __future__ import annotations

import argparse
import os
import random
import subprocess
import sys
import tempfile
import textwrap
import time
from dataclasses import dataclass, field
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
for package in ('uvms_common', 'uvms_description', 'uvms_model', 'uvms_sim', 'uvms_control',
                'uvms_thrusters',
                'uvms_bringup'):
    sys.path.insert(0, str(REPO / 'src' / package))

from uvms_bringup.launch_helpers import FOXGLOVE_SERVER, resolve_scenario_path  # noqa: E402
from uvms_common.ros_environment import ros_environment_defaults  # noqa: E402
from uvms_run.graph import Graph, build_graph, run_graph  # noqa: E402
from uvms_scenarios.scenario import load_scenario  # noqa: E402

#: The client process: connect, subscribe to every channel, say so, drain until killed.
CLIENT = textwrap.dedent("""
    import json, signal, sys
    from websockets.sync.client import connect
    url = sys.argv[1]
    ws = connect(url, subprotocols=['foxglove.sdk.v1'], max_size=None, proxy=None,
                 legacy=True)
    channels = {}
    while not channels:
        frame = ws.recv()
        if isinstance(frame, str):
            message = json.loads(frame)
            if message['op'] == 'advertise':
                channels = {c['id']: c['topic'] for c in message['channels']}
    ws.send(json.dumps({'op': 'subscribe', 'subscriptions': [
        {'id': i, 'channelId': cid} for i, cid in enumerate(channels, start=1)]}))
    print('subscribed', len(channels), flush=True)
    count = size = 0
    def report(*_):
        print('received', count, size, flush=True)
        sys.exit(0)
    signal.signal(signal.SIGTERM, report)
    try:
        while True:
            frame = ws.recv()
            if isinstance(frame, bytes) and frame[0] == 1:
                count += 1
                size += len(frame) - 13
    except Exception:  # the server stopped with the run
        report()
""")


@dataclass
class Stretches:
    """Wall-clock times at which the simulation crossed given simulated times."""

    marks_s: list[float]
    on_mark: dict[int, object] = field(default_factory=dict)
    wall_s: list[float] = field(default_factory=list)

    def __call__(self, graph: Graph) -> None:
        """on_spin hook: note the wall time of each mark; run its action, if any."""
        while len(self.wall_s) < len(self.marks_s) and (
                graph.simulator.sim_time_ns * 1e-9 >= self.marks_s[len(self.wall_s)]):
            index = len(self.wall_s)
            action = self.on_mark.get(index)
            if callable(action):
                action(graph)
            self.wall_s.append(time.monotonic())

    def rtf(self, first: int, last: int) -> float:
        """Real-time factor between two marks."""
        sim_s = self.marks_s[last] - self.marks_s[first]
        return sim_s / (self.wall_s[last] - self.wall_s[first])


def run(scenario_path: Path, duration_s: float, foxglove: bool, marks: Stretches,
        output: Path) -> Graph:
    """One lockstep run with the recorder, timed at the marks."""
    scenario = load_scenario(scenario_path).with_changes(duration_s=duration_s)
    graph = build_graph(scenario, 'lockstep', output_path=output,
                        foxglove=('127.0.0.1', 0) if foxglove else None)
    run_graph(graph, on_spin=marks)
    return graph


def main(argv: list[str] | None = None) -> int:
    """Run the three stretches and print their real-time factors and ratios."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('scenario', nargs='?', default='case1_ke1e4')
    parser.add_argument('--stretch', type=float, default=4.0,
                        help='simulated seconds of each timed stretch (default 4)')
    parser.add_argument('--warmup', type=float, default=1.0,
                        help='simulated seconds before the first stretch (default 1)')
    args = parser.parse_args(argv)
    ros_environment_defaults()
    os.environ.setdefault('ROS_DOMAIN_ID', str(random.SystemRandom().randint(101, 149)))
    scenario_path = resolve_scenario_path(args.scenario)
    w, s = args.warmup, args.stretch

    with tempfile.TemporaryDirectory(prefix='bench_foxglove_') as tmp:
        plain = Stretches([w, w + s])
        run(scenario_path, w + s + 0.1, False, plain, Path(tmp) / 'plain.mcap')

        client: dict[str, subprocess.Popen[str]] = {}

        def connect_client(graph: Graph) -> None:
            port = graph.nodes[FOXGLOVE_SERVER.name].port
            process = subprocess.Popen([sys.executable, '-c', CLIENT, f'ws://127.0.0.1:{port}'],
                                       stdout=subprocess.PIPE, text=True)
            assert process.stdout is not None
            print(f'client: {process.stdout.readline().strip()} channels', file=sys.stderr)
            client['process'] = process

        live = Stretches([w, w + s, w + s + 0.5, w + 2 * s + 0.5], {2: connect_client})
        run(scenario_path, w + 2 * s + 0.6, True, live, Path(tmp) / 'live.mcap')
        process = client['process']
        process.terminate()
        received = process.communicate(timeout=30.0)[0].split()

    rtf_plain = plain.rtf(0, 1)
    rtf_idle = live.rtf(0, 1)
    rtf_client = live.rtf(2, 3)
    load = ', '.join(f'{x:.2f}' for x in os.getloadavg())
    print(f'bench_foxglove: {args.scenario}, lockstep with recorder, stretches of {s:g} s '
          f'simulated (load average {load})')
    print(f'{"run":<44}{"real-time factor":>18}{"ratio":>10}')
    print(f'{"without foxglove_server":<44}{rtf_plain:>17.2f}x{1.0:>10.2f}')
    print(f'{"foxglove_server, no client":<44}{rtf_idle:>17.2f}x{rtf_idle / rtf_plain:>10.2f}')
    print(f'{"foxglove_server, a client on every channel":<44}{rtf_client:>17.2f}x'
          f'{rtf_client / rtf_plain:>10.2f}')
    print(f'same run, client connected / no client: {rtf_client / rtf_idle:.2f}')
    if len(received) == 3:
        print(f'the client received {received[1]} messages, {int(received[2]) / 1e6:.1f} MB')
    return 0


if __name__ == '__main__':
    sys.exit(main())
