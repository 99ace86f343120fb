"""Where each node process spends its CPU: cProfile statistics split by kind of work.

The node processes write their statistics when ``UVMS_PROFILE`` names a directory
(``uvms_common.node_main.profiled``: cProfile on ``time.thread_time``, so the figures are the
CPU time of the spinning thread, not wall time; Fast DDS's own receive and event threads are
not in them). This script reads those files and splits each node's time into:

- ``publish``: rclpy's publish into the middleware (``publish_raw``/``publish``, C++);
- ``executor + take``: the executor's own C++ time in ``spin_once`` (waiting is not CPU), the
  take of each message and the call into Python;
- ``rclpy python``: rclpy's Python layers (``Publisher.publish``, clocks and times,
  ``context.ok``, the TimeSource's /clock callback);
- ``typed messages``: message classes built or (de)serialized in Python (``*/msg/_*.py``,
  ``rclpy_deserialize``/``rclpy_serialize``);
- ``codec``: our raw CDR codecs (``cdr_codecs``, ``hot_messages``, ``raw_conversions``);
- ``core``: the pure cores (``uvms_model``, ``uvms_control.core``, ``uvms_navigation`` filter);
- ``recording``: the MCAP writer (``mcap`` and ``uvms_recording.mcap_writer``);
- ``node glue``: the rest of our node code (callbacks, diagnostics, gates, logging);
- ``other``: numpy, the standard library and builtins called from anywhere.

cProfile adds its own cost to every Python call (more in code with many small calls), so the
shares are a guide to where the time goes, not the node's CPU figure: bench_realtime measures
that without a profiler.

Usage::

    UVMS_PROFILE=/tmp/prof .venv/bin/python bench/bench_realtime.py case1_ke1e4
    .venv/bin/python bench/profile_nodes.py /tmp/prof [--top 12]
"""

from __future__ import annotations

import argparse
import pstats
from collections import defaultdict
from pathlib import Path

KINDS = ('publish', 'executor + take', 'rclpy python', 'typed messages', 'codec', 'core',
         'recording', 'node glue', 'other')


def kind_of(filename: str, function: str) -> str:
    """The kind of work of one profiled function (see the module docstring)."""
    if filename == '~':  # built-in functions
        if 'publish' in function and '_rclpy_pybind11' in function:
            return 'publish'
        if 'spin_once' in function or 'spin_until_future' in function:
            return 'executor + take'
        if 'rclpy_deserialize' in function or 'rclpy_serialize' in function:
            return 'typed messages'
        if '_rclpy_pybind11' in function:
            return 'rclpy python'
        return 'other'
    path = filename.replace('\\', '/')
    if '/msg/_' in path or '/srv/_' in path or '/action/_' in path:
        return 'typed messages'
    if any(name in path for name in ('cdr_codecs', 'hot_messages', 'raw_conversions')):
        return 'codec'
    if '/mcap/' in path or 'mcap_writer' in path:
        return 'recording'
    if '/rclpy/' in path:
        return 'rclpy python'
    if any(name in path for name in ('/uvms_model/', '/uvms_control/core/', '/eskf')):
        return 'core'
    if '/uvms_' in path:
        return 'node glue'
    return 'other'


def split(path: Path) -> tuple[dict[str, float], float, list[tuple[float, int, str]]]:
    """Seconds of self time per kind, the total, and the functions by self time."""
    stats = pstats.Stats(str(path)).stats  # type: ignore[attr-defined]
    seconds: dict[str, float] = defaultdict(float)
    functions = []
    for (filename, line, function), (_, calls, tottime, _, _) in stats.items():
        seconds[kind_of(filename, function)] += tottime
        short = filename.split('/src/')[-1].split('site-packages/')[-1]
        functions.append((tottime, calls, f'{short}:{line}({function})'))
    functions.sort(reverse=True)
    return seconds, sum(seconds.values()), functions


def main() -> None:
    """Print one block per profiled node process."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('directory', type=Path, help='the UVMS_PROFILE directory')
    parser.add_argument('--top', type=int, default=8, help='functions listed per node')
    args = parser.parse_args()
    for path in sorted(args.directory.glob('*.prof')):
        seconds, total, functions = split(path)
        print(f'{path.stem}: {total:.2f} s of CPU in the spinning thread')
        print('  ' + ', '.join(f'{kind} {100.0 * seconds[kind] / total:.0f} %'
                               for kind in KINDS if seconds[kind] > 0.005 * total))
        for tottime, calls, name in functions[:args.top]:
            print(f'    {tottime:7.3f} s {calls:8d} calls {1e6 * tottime / max(calls, 1):7.1f} '
                  f'us/call  {name}')


if __name__ == '__main__':
    main()
