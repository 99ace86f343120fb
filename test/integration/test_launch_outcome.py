"""What ``uvms launch`` says at its end: a failed mission by its code, a recording from t = 0.

Each test launches a short graph, one process per node, on a ROS domain of its own.
"""

from __future__ import annotations

import os
import random
import subprocess
import sys
import textwrap
import threading
from pathlib import Path

from mcap.reader import make_reader
from rclpy.serialization import deserialize_message
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from uvms_bringup.launch_helpers import RECORDER
from uvms_bringup.processes import Launcher
from uvms_common.process_costs import CostWatch
from uvms_common.ros_environment import ros_environment_defaults
from uvms_scenarios.scenario import load_scenario
from uvms_tasks.mission_outcome import EXIT_MISSION_FAILED

from uvms_bringup import launcher as launcher_module

ros_environment_defaults()

BIN = Path(sys.executable).parent
#: A domain of this module only; the children get it through ROS_DOMAIN_ID.
DOMAIN_ID = random.SystemRandom().randint(141, 180)
#: A press where there is no wall: the path ends without contact (NO_CONTACT) 0.5 s after the
#: goal arrives. 6 s of simulated time: with the loop processes on SCHED_FIFO the loop closes
#: within a second, and the mission process (normal priority) takes up to 2 s more to find
#: the action server on a busy machine.
NO_CONTACT_SCENARIO = textwrap.dedent("""\
    name: no_contact
    description: a press with the wall switched off, which must end NO_CONTACT
    duration_s: 6.0
    simulator:
      wall_enabled: false
    mission:
      - name: press
        path: [[1.70, 0.0, -0.10], [1.72, 0.0, -0.10]]
        time_from_start_s: [0.0, 0.5]
        normal: [1.0, 0.0, 0.0]
        force_n: 20.0
        force_ramp_s: 0.5
        require_contact: true
""")
#: Wall time the recorder's process waits before it starts: longer than the other nodes
#: take to close the control loop and run the 1.5 s scenario (about 3 s + 1.5 s here).
RECORDER_DELAY_S = 8.0
#: Wall-clock limit of one launch (s): generous, for a slow machine under load.
LAUNCH_TIMEOUT_S = 120.0


def environment() -> dict[str, str]:
    """The environment of every process here: the project's defaults, our domain."""
    env = dict(os.environ)
    env['ROS_DOMAIN_ID'] = str(DOMAIN_ID)
    env['PYTHONUNBUFFERED'] = '1'
    return env


def test_a_failed_mission_is_said_by_its_code_and_exits_3(tmp_path: Path) -> None:
    """The mission ends NO_CONTACT: one line says so, no node is blamed, exit status 3."""
    scenario = tmp_path / 'no_contact.yaml'
    scenario.write_text(NO_CONTACT_SCENARIO, encoding='utf-8')
    result = subprocess.run([str(BIN / 'uvms'), 'launch', str(scenario)], capture_output=True,
                            text=True, env=environment(), timeout=LAUNCH_TIMEOUT_S, check=False)
    err = result.stderr
    assert result.returncode == EXIT_MISSION_FAILED == 3, err[-3000:]
    assert 'mission failed: NO_CONTACT (the path ended without contact)' in err.splitlines()
    assert not [line for line in err.splitlines() if line.startswith('uvms launch: error:')], err
    assert 'uvms launch: the simulator reached 6 s; every node stopped; the mission failed' in err


def test_a_recorder_that_starts_late_still_records_from_t0(tmp_path: Path) -> None:
    """The recorder's process starts seconds after the others: the recording begins at t = 0.

    The simulator publishes its first state only once the recorder's subscriptions are
    matched (``startup.recorder``, set by the launcher when it records).
    """
    scenario_file = tmp_path / 'free.yaml'
    scenario_file.write_text(textwrap.dedent("""\
        name: free
        description: the vehicle holding still, nothing to touch
        duration_s: 1.5
        simulator: {wall_enabled: false}
    """), encoding='utf-8')
    output = tmp_path / 'late.mcap'
    plans = launcher_module.plan_launch(load_scenario(scenario_file), 'realtime', tmp_path,
                                        duration_s=1.5, output_path=output)
    late = [plan if plan.spec is not RECORDER else plan.__class__(
        plan.spec, plan.label,
        ('sh', '-c', f'sleep {RECORDER_DELAY_S:g}; exec "$0" "$@"', *plan.command),
        plan.parameters_file) for plan in plans]
    lines: list[str] = []

    class Lines:
        def write(self, text: str) -> None:
            lines.append(text)

        def flush(self) -> None:
            pass

        def isatty(self) -> bool:
            return False

    launcher = Launcher(late, env=environment(), stdout=Lines(),  # type: ignore[arg-type]
                        stderr=Lines())  # type: ignore[arg-type]
    status = launcher_module.run_launch(launcher, threading.Event(), 'realtime', 1.5, True, '',
                                  CostWatch(tmp_path / 'stats'))
    assert status == 0, ''.join(lines)[-3000:]
    firsts: dict[str, object] = {}
    with output.open('rb') as stream:
        for _, channel, message in make_reader(stream).iter_messages(
                topics=['/clock', '/uvms/joint_states']):
            if channel.topic not in firsts:
                firsts[channel.topic] = deserialize_message(
                    message.data, Clock if channel.topic == '/clock' else JointState)
    clock, joints = firsts.get('/clock'), firsts.get('/uvms/joint_states')
    assert isinstance(clock, Clock) and isinstance(joints, JointState), ''.join(lines)[-3000:]
    assert (clock.clock.sec, clock.clock.nanosec) == (0, 0)
    assert (joints.header.stamp.sec, joints.header.stamp.nanosec) == (0, 0)
