"""A stop while a node is being built: at once where the build changes nothing, else after it.

A node's build (model, kernels, entities) took 4-8 s on a machine with two busy loops, and a
stop that waited for it outlived the 2 s issue 48 allows. A stand-in node process (started
as a console script starts it, ``uvms_common.node_entry``) builds for ``BUILD_S``; SIGINT
arrives mid-build:

- a node whose build has changed nothing outside the process ends at once, status 0,
  without a traceback;
- a node whose build has begun to (a bridge activating its device, the recorder opening its
  file: ``defer_stop_end``) finishes its build and its own end first, status 0.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

#: How long the stand-in's build takes (s): far beyond a prompt stop's bound.
BUILD_S = 6.0
#: A stop that does not wait for the build ends within this (s): the issue's 2 s, with the
#: interpreter's exit on a loaded machine inside it.
PROMPT_STOP_S = 2.0

STAND_IN = textwrap.dedent("""\
    import sys
    import time
    from pathlib import Path

    from rclpy.node import Node
    from uvms_common.node_main import run_node

    MARKER = Path(sys.argv[1])


    class Slow(Node):
        def __init__(self):
            super().__init__('slow_build', namespace='/stop_while_building')
            print('building', flush=True)
            time.sleep({build_s})  # the model and kernels of a real node, in Python
            MARKER.write_text('built')

        def destroy_node(self):
            MARKER.write_text('built and ended')
            super().destroy_node()


    def main():
        sys.exit(run_node(Slow, [], 'slow_build'))
""").format(build_s=BUILD_S)


def start_stand_in(tmp_path: Path, source: str = STAND_IN,
                   module: str = 'slow_build_node') -> tuple[subprocess.Popen[str], Path]:
    """A stand-in as a node process, once it says it is building; and its marker file."""
    (tmp_path / f'{module}.py').write_text(source, encoding='utf-8')
    marker = tmp_path / 'marker'
    env = {**os.environ, 'PYTHONPATH': os.pathsep.join([str(tmp_path), *sys.path])}
    process = subprocess.Popen(
        [sys.executable, '-c', 'from uvms_common.node_entry import run_node_module; '
         f'run_node_module({module!r})', str(marker)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    assert process.stdout is not None
    line = process.stdout.readline()
    assert line.strip() == 'building', process.stderr.read() if process.stderr else ''
    return process, marker


def test_a_stop_mid_build_of_a_node_that_changes_nothing_ends_it_at_once(
        tmp_path: Path) -> None:
    """SIGINT mid-build: status 0 within 2 s, no traceback, the build never finished."""
    process, marker = start_stand_in(tmp_path)
    time.sleep(0.5)
    sent = time.monotonic()
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=BUILD_S + 20.0)
    took_s = time.monotonic() - sent
    assert process.returncode == 0, err
    assert 'Traceback' not in err and 'KeyboardInterrupt' not in err, err
    assert not marker.exists()
    assert took_s < PROMPT_STOP_S, f'{took_s:.2f} s'


BRIDGE_STAND_IN = textwrap.dedent("""\
    import sys
    import time
    from pathlib import Path

    from rclpy.node import Node
    from uvms_common.node_main import run_node
    from uvms_common.stop_event import defer_stop_end

    MARKER = Path(sys.argv[1])


    class Bridge(Node):
        def __init__(self):
            super().__init__('slow_bridge', namespace='/stop_while_building')
            time.sleep(0.5)  # configure: the device checked, nothing changed
            defer_stop_end()  # activate: the device is about to change
            MARKER.write_text('changed')
            print('building', flush=True)
            time.sleep({build_s})
            MARKER.write_text('changed, built')

        def destroy_node(self):
            MARKER.write_text(MARKER.read_text() + ', put back')
            super().destroy_node()


    def main():
        sys.exit(run_node(Bridge, [], 'slow_bridge'))
""").format(build_s=BUILD_S)


@pytest.mark.timeout(120)
def test_a_stop_after_a_bridge_started_changing_its_device_waits_for_the_put_back(
        tmp_path: Path) -> None:
    """defer_stop_end (a bridge's activate): the build finishes, the node puts back, status 0."""
    process, marker = start_stand_in(tmp_path, BRIDGE_STAND_IN, 'slow_bridge_node')
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=BUILD_S + 60.0)
    assert process.returncode == 0, err
    assert marker.read_text() == 'changed, built, put back'
