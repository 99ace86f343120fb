"""A launched, recorded contact task keeps its task record on a busy machine (issue 52, item 1).

``uvms launch SCENARIO --output FILE`` with two busy loops beside it, as a new user's
laptop running a build: the report row of the recording names the task (its goal id) and
the robot, with the task's F_d, in every run. Runs: ``UVMS_TASK_RECORD_RUNS`` (default 2;
the issue's acceptance is 10 of 10).

Measured (`uvms launch case1_ke1e4 --output`, two busy loops, 2 cores): before, the record
was in 3 recordings of 17. Two causes: the recorder's UDP socket overflows (70 695 datagrams
dropped in one run), and the one record, lost with them, is repaired by Fast DDS's reliable
protocol only while the controller lives, which ends its process a second or two later
without waiting; and a record that did arrive sat in the recorder's subscription when its
stop's drain ended. The recorder now writes what its subscriptions hold when it closes
(this module: 2 of 3 runs); with the controller also waiting for its records to be
acknowledged before it stops (a change in uvms_control, see docs/recording.md), 4 of 4 here
and 10 of 10 of case1_ke1e4.
"""

from __future__ import annotations

import csv
import io
import os
import random
import subprocess
import sys
import textwrap
from collections.abc import Iterator
from pathlib import Path

import pytest
from rclpy.serialization import deserialize_message
from uvms_common.ros_environment import ros_environment_defaults
from uvms_recording.mcap_reader import open_recording

from uvms_msgs.msg import ContactTaskRecord

ros_environment_defaults()

BIN = Path(sys.executable).parent
DOMAIN_ID = random.SystemRandom().randint(181, 200)
RUNS = int(os.environ.get('UVMS_TASK_RECORD_RUNS', '2'))
#: A press toward no wall: the task ends NO_CONTACT when its path ends, about a second of
#: simulated time before the run does (the mission process finds the action server within
#: 2-3 s here): the record goes out while the recorder is still busy with the graph.
SCENARIO = textwrap.dedent("""\
    name: press_late
    description: a press whose task ends shortly before the run, with no wall to touch
    duration_s: 7.0
    simulator:
      wall_enabled: false
    mission:
      - name: press
        path: [[1.70, 0.0, -0.10], [1.72, 0.0, -0.10]]
        time_from_start_s: [0.0, 3.0]
        normal: [1.0, 0.0, 0.0]
        force_n: 20.0
        force_ramp_s: 0.5
        require_contact: true
""")
LAUNCH_TIMEOUT_S = 180.0


@pytest.fixture
def busy_loops() -> Iterator[None]:
    """Two processes spinning at 100 % of a core each, for the test's length."""
    loops = [subprocess.Popen([sys.executable, '-c', 'while True: pass']) for _ in range(2)]
    try:
        yield
    finally:
        for loop in loops:
            loop.kill()
            loop.wait()


def environment() -> dict[str, str]:
    """The project's defaults on a domain of this module."""
    env = dict(os.environ)
    env['ROS_DOMAIN_ID'] = str(DOMAIN_ID)
    env['PYTHONUNBUFFERED'] = '1'
    return env


@pytest.mark.parametrize('run', range(RUNS))
def test_launched_recording_reports_its_task_and_robot_under_load(
        run: int, tmp_path: Path, busy_loops: None) -> None:
    """The report row names the task's goal id, the robot and the task's F_d; stderr is quiet."""
    scenario = tmp_path / 'press_late.yaml'
    scenario.write_text(SCENARIO, encoding='utf-8')
    output = tmp_path / f'run{run}.mcap'
    launch = subprocess.run([str(BIN / 'uvms'), 'launch', str(scenario), '--output', str(output)],
                            capture_output=True, text=True, env=environment(),
                            timeout=LAUNCH_TIMEOUT_S, check=False)
    assert 'contact task ended' in launch.stderr, launch.stderr[-3000:]
    records = [deserialize_message(message.data, ContactTaskRecord) for message
               in open_recording(output).messages(['/uvms/controller/task_record'])]
    assert len(records) == 1, launch.stderr[-3000:]
    report = subprocess.run([str(BIN / 'uvms'), 'report', str(output), '--format', 'csv'],
                            capture_output=True, text=True, env=environment(), timeout=120.0,
                            check=True)
    (row,) = csv.DictReader(io.StringIO(report.stdout))
    assert row['task'] == bytes(records[0].goal_id).hex()
    assert row['robot'] == 'paper_uvms'
    assert float(row['desired_force_N']) == 20.0
    assert 'no task record' not in report.stderr
