"""The task interface across processes: ``uvms launch idle_wall`` commanded from outside.

The graph runs one process per node in lockstep (deterministic, and as fast as this machine
allows); a user's ``uvms task FILE.yaml`` and a script's ContactTaskClient, each in another
process, press on the Case I wall through the ContactTask action and watch /diagnostics.
"""

from __future__ import annotations

import json
import os
import random
import signal
import subprocess
import sys
import textwrap
from collections.abc import Iterator
from pathlib import Path

import pytest
from uvms_common.ros_environment import ros_environment_defaults

ros_environment_defaults()

BIN = Path(sys.executable).parent
#: A domain of this module only; the children get it through ROS_DOMAIN_ID.
DOMAIN_ID = random.SystemRandom().randint(101, 140)
#: A press on the Case I wall from point A: 1.5 s to the wall, 2 s along it at 60 N.
TASK = textwrap.dedent("""\
    name: press
    path: [[1.70, 0.0, -0.10], [1.80, 0.0, -0.10], [1.80, 0.0, -0.09]]
    time_from_start_s: [0.0, 1.5, 3.5]
    normal: [1.0, 0.0, 0.0]
    force_n: 60.0
    force_ramp_s: 0.5
    require_contact: true
""")
#: Wall-clock limits (s): generous, for a slow machine under load.
START_TIMEOUT_S = 120.0
TASK_TIMEOUT_S = 300.0


def environment() -> dict[str, str]:
    """The environment of every process here: the project's defaults, our domain."""
    env = dict(os.environ)
    env['ROS_DOMAIN_ID'] = str(DOMAIN_ID)
    # This checkout's sources first (pytest's pythonpath), not the venv's installed ones.
    env['PYTHONPATH'] = os.pathsep.join(p for p in sys.path if p)
    return env


@pytest.fixture(scope='module')
def launch() -> Iterator[subprocess.Popen[str]]:
    """``uvms launch idle_wall --mode lockstep`` running until the module is done."""
    process = subprocess.Popen(
        [str(BIN / 'uvms'), 'launch', 'idle_wall', '--mode', 'lockstep'],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=environment())
    yield process
    process.send_signal(signal.SIGINT)
    try:
        output, _ = process.communicate(timeout=60.0)
    except subprocess.TimeoutExpired:
        process.kill()
        output, _ = process.communicate()
        pytest.fail(f'uvms launch did not stop within 60 s of SIGINT:\n{output[-3000:]}')
    assert process.returncode == 130, output[-3000:]


def test_uvms_task_presses_on_the_wall_of_a_launched_graph(
        launch: subprocess.Popen[str], tmp_path: Path) -> None:
    """``uvms task`` sends the file's goal to the running graph; it ends SUCCEEDED."""
    task = tmp_path / 'press.yaml'
    task.write_text(TASK, encoding='utf-8')
    result = subprocess.run(
        [str(BIN / 'uvms'), 'task', str(task), '--timeout', str(START_TIMEOUT_S)],
        capture_output=True, text=True, env=environment(), timeout=TASK_TIMEOUT_S, check=False)
    assert launch.poll() is None, 'the launched graph ended'
    assert result.returncode == 0, result.stdout + result.stderr
    assert 'SUCCEEDED' in result.stdout
    assert 'peak' in result.stdout


def test_press_whose_force_cannot_settle_ends_force_not_settled(
        launch: subprocess.Popen[str], tmp_path: Path) -> None:
    """F_d ramped over 20 s on a 2 s press: the force never reaches its band (issue 42)."""
    task = tmp_path / 'unsettled.yaml'
    task.write_text(TASK.replace('force_ramp_s: 0.5', 'force_ramp_s: 20.0'), encoding='utf-8')
    result = subprocess.run(
        [str(BIN / 'uvms'), 'task', str(task), '--timeout', str(START_TIMEOUT_S)],
        capture_output=True, text=True, env=environment(), timeout=TASK_TIMEOUT_S, check=False)
    assert result.returncode == 1, result.stdout + result.stderr
    assert 'FORCE_NOT_SETTLED' in result.stdout, result.stdout
    assert 'SUCCEEDED' not in result.stdout, result.stdout
    assert 'control periods missed' in result.stdout, result.stdout


def test_uvms_lifecycle_resets_the_controller_through_its_services(
        launch: subprocess.Popen[str]) -> None:
    """``uvms lifecycle controller reset``: deactivate then activate, on change_state."""
    def lifecycle(*args: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run([str(BIN / 'uvms'), 'lifecycle', 'controller', *args],
                              capture_output=True, text=True, env=environment(),
                              timeout=TASK_TIMEOUT_S, check=False)

    got = lifecycle('get', '--timeout', str(START_TIMEOUT_S))
    assert (got.returncode, got.stdout) == (0, '/uvms/controller: active\n'), got.stderr
    reset = lifecycle('reset')
    assert reset.returncode == 0, reset.stderr
    assert reset.stdout == '/uvms/controller: active -> inactive -> active\n'
    refused = lifecycle('activate')  # active already: no such transition from there
    assert refused.returncode == 1
    assert 'refused activate (it is active)' in refused.stderr


def test_uvms_task_prints_why_the_controller_rejected_a_goal(
        launch: subprocess.Popen[str], tmp_path: Path) -> None:
    """A goal over safety.max_contact_force_n: rejected, the reason printed, exit 1."""
    task = tmp_path / 'too_hard.yaml'
    task.write_text(TASK.replace('force_n: 60.0', 'force_n: 500.0'), encoding='utf-8')
    result = subprocess.run(
        [str(BIN / 'uvms'), 'task', str(task), '--timeout', str(START_TIMEOUT_S)],
        capture_output=True, text=True, env=environment(), timeout=TASK_TIMEOUT_S, check=False)
    assert result.returncode == 1, result.stdout + result.stderr
    assert result.stdout.strip() == (
        'press: REJECTED: force_n = 500.0: exceeds safety.max_contact_force_n = 400.0 N'), (
        result.stdout + result.stderr)


def test_script_client_gets_result_and_diagnostics_of_every_node(
        launch: subprocess.Popen[str]) -> None:
    """A script's ContactTaskClient presses again; /diagnostics names every node process."""
    script = textwrap.dedent(f"""\
        import json, sys
        import rclpy
        from diagnostic_msgs.msg import DiagnosticArray
        from rclpy.node import Node
        from uvms_tasks.client import ContactTaskClient
        from uvms_tasks.goals import goal_from_task
        from uvms_tasks.task_file import parse_task_document
        import yaml

        rclpy.init()
        node = Node('script', namespace='uvms')
        names = set()
        node.create_subscription(DiagnosticArray, '/diagnostics',
                                 lambda m: names.update(s.name for s in m.status), 10)
        client = ContactTaskClient(node)
        assert client.wait_for_server(timeout_s={START_TIMEOUT_S})
        task = parse_task_document(yaml.safe_load({TASK!r}), 'press')[0]
        outcome = client.run(goal_from_task(task), name='press')
        expected = {{'simulator', 'controller', 'thruster_allocator', 'visualizer'}}
        client.spin_until(lambda: expected <= {{n.split(':')[0] for n in names}}, 30.0)
        print(json.dumps({{'code': int(outcome.result.error_code),
                          'rms': outcome.result.rms_force_error_n,
                          'nodes': sorted({{n.split(':')[0] for n in names}})}}))
        client.destroy()
        node.destroy_node()
        rclpy.try_shutdown()
    """)
    result = subprocess.run([sys.executable, '-c', script], capture_output=True, text=True,
                            env=environment(), timeout=TASK_TIMEOUT_S, check=False)
    assert result.returncode == 0, result.stderr[-3000:]
    found = json.loads(result.stdout.strip().splitlines()[-1])
    assert found['code'] == 0
    assert found['rms'] < 3.0  # 5 % of the 60 N set-point
    assert {'simulator', 'controller', 'thruster_allocator', 'visualizer'} <= set(
        found['nodes'])
