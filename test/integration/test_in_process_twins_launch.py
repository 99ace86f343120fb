"""uvms launch --hardware twin with the twins in the simulator's process: no /plant, no twins node.

The launch of ``test_hardware_twin_launch`` (idle_wall, bluerov2_alpha5, a quarter speed),
through ``in_process_twins_launch.py``: the ``uvms`` CLI with the simulator's process
``uvms_twins.simulator_with_twins`` and no ``hardware_twins`` process, as the change proposed
for uvms_bringup would launch it. The graph's inputs still come from the four bridges, the
loop closes on the twins' actuator command handed to the simulator by call, physics holds its
first state until then, and nothing is published under /plant.
"""

from __future__ import annotations

import os
import subprocess
import sys
from collections import Counter
from pathlib import Path
from typing import Any

from mcap.reader import make_reader
from rosbags.typesys import Stores, get_typestore

LAUNCH = Path(__file__).resolve().parent / 'in_process_twins_launch.py'
#: What each bridge publishes, and what the graph sends to two of them.
FROM_BRIDGES = ('/uvms/joint_states', '/uvms/wrench', '/uvms/imu', '/uvms/depth', '/uvms/dvl')
THROUGH_THE_GRAPH = ('/uvms/odometry/filtered', '/uvms/command/generalized_force',
                     '/uvms/command/actuators')


def test_the_graph_runs_on_the_bridges_against_the_twins_in_the_simulators_process(
        tmp_path: Path) -> None:
    """Every input from a bridge, the loop closed by the in-process twins; exit 0."""
    output = tmp_path / 'twin.mcap'
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p),
               PYTHONUNBUFFERED='1')
    process = subprocess.run(
        [sys.executable, str(LAUNCH), 'launch', 'idle_wall', '--robot', 'bluerov2_alpha5',
         '--hardware', 'twin', '--duration', '5', '--real-time-factor', '0.25',
         '--output', str(output)],
        env=env, capture_output=True, text=True, timeout=240, stdin=subprocess.DEVNULL)
    log = process.stderr
    assert process.returncode == 0, log[-3000:]
    assert 'hardware_twins' not in log, log[-3000:]
    assert 'twins of bluerov2_alpha5 in this process' in log
    assert '[uvms.simulator]: the bridges drive the arm and the vehicle' in log
    counts: Counter[str] = Counter()
    typestore = get_typestore(Stores.ROS2_JAZZY)
    truth: Any = None
    with output.open('rb') as stream:
        for schema, channel, message in make_reader(stream).iter_messages(log_time_order=True):
            counts[channel.topic] += 1
            if channel.topic == '/uvms/odometry' and truth is None:
                truth = typestore.deserialize_cdr(message.data, schema.name)
    missing = [t for t in (*FROM_BRIDGES, *THROUGH_THE_GRAPH) if counts[t] == 0]
    assert not missing, f'no message on {missing}: {dict(counts)}'
    assert not any(topic.startswith('/plant/') for topic in counts)
    # Physics held its first state until every bridge drove its device.
    assert truth.header.stamp.sec == 0 and truth.header.stamp.nanosec == 0
