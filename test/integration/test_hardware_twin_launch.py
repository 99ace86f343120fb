"""uvms launch --hardware twin: the whole robot's bridges against their twins, on the simulator.

The graph's inputs come from the four bridges (never from the simulator, whose device-side
topics are under /plant), its actuator command goes out through two of them, and the run ends
cleanly. At half speed: twelve processes want more than the 2 cores of a small machine in
real time (docs/hardware.md gives the figures), and a late control loop is not what this
test is about. The contact task against the twins is not a test of the suite: it needs the
machine to itself (docs/hardware.md, "What the twin test stand shows").
"""

from __future__ import annotations

import os
import subprocess
import sys
from collections import Counter
from pathlib import Path
from typing import Any

import pytest
from mcap.reader import make_reader
from rosbags.typesys import Stores, get_typestore

#: What each bridge publishes, and what the graph sends to two of them.
FROM_BRIDGES = ('/uvms/joint_states', '/uvms/wrench', '/uvms/imu', '/uvms/depth', '/uvms/dvl')
#: Topics whose first message the test reads (standard types: rosbags' own store).
FIRST_READ = ('/uvms/joint_states', '/uvms/odometry')
THROUGH_THE_GRAPH = ('/uvms/odometry/filtered', '/uvms/command/generalized_force',
                     '/uvms/command/actuators')


#: The layouts: the default (the robot loop: bridges, estimator, controller and allocator in
#: one process and one loop; the twins in the simulator's process), and one process per node
#: with the twins in a process of their own.
LAYOUTS = {'robot_loop': (), 'apart': ('--compose', 'none', '--twins-apart')}


@pytest.mark.parametrize('layout', list(LAYOUTS))
def test_the_graph_runs_on_the_bridges_against_the_twins(tmp_path: Path, layout: str) -> None:
    """Every input from a bridge, the estimate from them, the command out; exit 0.

    The run ends at its duration: the bridges put their devices back while the twins still
    answer (with the twins in the simulator's process, the simulator serves them until the
    launcher has stopped the robot process).
    """
    output = tmp_path / 'twin.mcap'
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p),
               PYTHONUNBUFFERED='1')
    process = subprocess.run(
        [sys.executable, '-m', 'uvms_cli.cli', 'launch', 'idle_wall', '--robot',
         'bluerov2_alpha5', '--hardware', 'twin', '--duration', '5', '--real-time-factor', '0.25',
         '--output', str(output), *LAYOUTS[layout]],
        env=env, capture_output=True, text=True, timeout=240, stdin=subprocess.DEVNULL)
    log = process.stderr
    assert process.returncode == 0, log[-3000:]
    if layout == 'robot_loop':
        assert 'hardware_twins' not in log, log[-3000:]
        assert 'twins of bluerov2_alpha5 in this process' in log
        assert '+netft_bridge+estimator+controller+thruster_allocator in one real-time loop' in log
    else:
        assert 'hardware_twins' in log and 'alpha5_bridge' in log
    assert 'NOT confirmed' not in log, log[-3000:]  # every device put back, confirmed
    counts: Counter[str] = Counter()
    typestore = get_typestore(Stores.ROS2_JAZZY)
    first: dict[str, object] = {}
    with output.open('rb') as stream:
        for schema, channel, message in make_reader(stream).iter_messages(log_time_order=True):
            counts[channel.topic] += 1
            if channel.topic in FIRST_READ and channel.topic not in first:
                first[channel.topic] = typestore.deserialize_cdr(message.data, schema.name)
    joints: Any = first.get('/uvms/joint_states')
    truth: Any = first.get('/uvms/odometry')
    missing = [t for t in (*FROM_BRIDGES, *THROUGH_THE_GRAPH) if counts[t] == 0]
    assert not missing, f'no message on {missing}: {dict(counts)}'
    assert not any(topic.startswith('/plant/') for topic in counts)  # the recorder's own
    assert joints is not None and list(joints.name) == ['joint_1', 'joint_2', 'joint_3',
                                                        'joint_4']
    # Physics held its first state until every bridge drove its device: the recording starts
    # at t = 0 and the arm never fell (limp before the arm bridge took it, its light links
    # trip the bridge's overspeed check within 0.1 s).
    assert truth.header.stamp.sec == 0 and truth.header.stamp.nanosec == 0
    assert 'tripped' not in log, log[-3000:]

