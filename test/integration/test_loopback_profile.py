"""The loopback Fast DDS profile is the one in force, and discovery on it is fast and bounded.

Issue 48: a mission once did not find the controller's action server within 10 s. The
profile (``uvms_common/fastdds_loopback.xml``) sends 10 initial announcements 100 ms apart,
then one a second; a tag Fast DDS does not know makes it drop the whole participant profile
(``XMLPARSER Error``), and with it the loopback-only transport and these settings, with no
more than a log line: checked here on the file as shipped.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import time

from uvms_common.ros_environment import PROFILE_VARIABLES

#: The controller's side: an action server, then one line once it exists.
_SERVER = textwrap.dedent("""
    import rclpy
    from rclpy.action import ActionServer
    from rclpy.node import Node
    from rclpy.signals import SignalHandlerOptions
    from uvms_common.node_main import make_executor
    from uvms_common.ros_environment import ros_environment_defaults
    from uvms_msgs.action import ContactTask

    ros_environment_defaults()
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    node = Node('controller', namespace='profile_test')
    server = ActionServer(node, ContactTask, 'controller/contact_task', lambda handle: None)
    executor = make_executor()
    executor.add_node(node)
    print('serving', flush=True)
    while True:
        executor.spin_once(timeout_sec=0.1)
""")

#: The mission's side: how long from its node's creation until the server is found (s).
_CLIENT = textwrap.dedent("""
    import time
    import rclpy
    from rclpy.action import ActionClient
    from rclpy.node import Node
    from rclpy.signals import SignalHandlerOptions
    from uvms_common.node_main import make_executor
    from uvms_common.ros_environment import ros_environment_defaults
    from uvms_msgs.action import ContactTask

    ros_environment_defaults()
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    node = Node('mission', namespace='profile_test')
    started = time.monotonic()
    client = ActionClient(node, ContactTask, 'controller/contact_task')
    executor = make_executor()
    executor.add_node(node)
    while not client.server_is_ready() and time.monotonic() - started < 20.0:
        executor.spin_once(timeout_sec=0.05)
    print(f'found {client.server_is_ready()} {time.monotonic() - started:.3f}', flush=True)
""")


def _env() -> dict[str, str]:
    """The environment less any profile of the user's: the project's default applies."""
    return {k: v for k, v in os.environ.items() if k not in PROFILE_VARIABLES}


def test_fast_dds_reads_the_loopback_profile_without_an_error() -> None:
    """No ``XMLPARSER Error``: every setting of the profile is taken, none dropped."""
    code = ('import rclpy\nfrom uvms_common.ros_environment import ros_environment_defaults\n'
            "ros_environment_defaults()\nrclpy.init()\nnode = rclpy.create_node('profile')\n"
            "print('participant', flush=True)\n")
    result = subprocess.run([sys.executable, '-c', code], env=_env(), capture_output=True,
                            text=True, timeout=60, check=False)
    assert result.returncode == 0, result.stderr
    assert 'participant' in result.stdout
    assert 'XMLPARSER' not in result.stderr, result.stderr


def test_an_action_client_finds_a_running_server_within_its_bound() -> None:
    """A process that joins a running graph finds its action server well within 3 s."""
    server = subprocess.Popen([sys.executable, '-c', _SERVER], env=_env(),
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert server.stdout is not None
        assert server.stdout.readline().strip() == 'serving'
        time.sleep(0.5)
        result = subprocess.run([sys.executable, '-c', _CLIENT], env=_env(),
                                capture_output=True, text=True, timeout=60, check=False)
    finally:
        server.kill()
        server.communicate()
    assert result.returncode == 0, result.stderr
    words = result.stdout.split()
    assert words[:2] == ['found', 'True'], result.stdout + result.stderr
    assert float(words[2]) < 3.0, result.stdout
