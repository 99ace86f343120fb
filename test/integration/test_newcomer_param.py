"""``uvms param list|get|set NODE``: a running node's parameters without a ROS install (issue 52).

The node is a plain rclpy node with a declared float parameter and a range, spinning in a
thread on a context of its own, on a ROS domain of this module.
"""

from __future__ import annotations

import os
import random
import threading
from collections.abc import Iterator

import pytest
import rclpy
from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from uvms_common.ros_environment import ros_environment_defaults

from uvms_cli import param

ros_environment_defaults()
os.environ['ROS_DOMAIN_ID'] = str(random.SystemRandom().randint(141, 180))


@pytest.fixture(scope='module')
def controller() -> Iterator[Node]:
    """/uvms/controller with hybrid.force_kp (0.1, range 0-10) and a list, spinning."""
    context = Context()
    rclpy.init(args=[], context=context)
    node = Node('controller', namespace='/uvms', context=context)
    node.declare_parameter('hybrid.force_kp', 0.1, ParameterDescriptor(
        floating_point_range=[FloatingPointRange(from_value=0.0, to_value=10.0, step=0.0)]))
    node.declare_parameter('impedance.stiffness_n_m', [1.0, 2.0, 3.0])
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    thread = threading.Thread(target=executor.spin, daemon=True)
    thread.start()
    yield node
    executor.shutdown()
    node.destroy_node()
    rclpy.try_shutdown(context=context)
    thread.join(timeout=5.0)


def test_list_names_the_nodes_parameters(controller: Node,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    """``list`` prints the names, one a line, sorted."""
    assert param.main(['list', 'controller']) == 0
    names = capsys.readouterr().out.split()
    assert {'hybrid.force_kp', 'impedance.stiffness_n_m', 'use_sim_time'} <= set(names)
    assert names == sorted(names)


def test_set_then_get_changes_the_running_nodes_value(
        controller: Node, capsys: pytest.CaptureFixture[str]) -> None:
    """A YAML value, an integer for a float taken as a float; the node holds it after."""
    assert param.main(['set', 'controller', 'hybrid.force_kp', '2']) == 0
    assert capsys.readouterr().out.strip() == '/uvms/controller: hybrid.force_kp = 2.0'
    assert controller.get_parameter('hybrid.force_kp').value == 2.0
    assert param.main(['set', 'controller', 'impedance.stiffness_n_m', '[4, 5.5, 6]']) == 0
    assert param.main(['get', '/uvms/controller', 'impedance.stiffness_n_m']) == 0
    assert capsys.readouterr().out.strip().splitlines()[-1] == '[4.0, 5.5, 6.0]'


def test_a_value_out_of_range_is_refused_with_the_nodes_reason(
        controller: Node, capsys: pytest.CaptureFixture[str]) -> None:
    """Exit 1; the line names the parameter, the value and why the node refused it."""
    assert param.main(['set', 'controller', 'hybrid.force_kp', '11.0']) == 1
    err = capsys.readouterr().err
    assert err.startswith('uvms param: error: /uvms/controller refused hybrid.force_kp = 11.0: ')
    assert controller.get_parameter('hybrid.force_kp').value != 11.0


def test_a_missing_parameter_is_a_failure_naming_it(
        controller: Node, capsys: pytest.CaptureFixture[str]) -> None:
    """``get`` of a name the node does not have: exit 1 naming node and name."""
    assert param.main(['get', 'controller', 'hybrid.force_kpp']) == 1
    assert ("/uvms/controller has no parameter 'hybrid.force_kpp'"
            in capsys.readouterr().err)


def test_a_node_that_is_not_there_times_out_naming_it(
        capsys: pytest.CaptureFixture[str]) -> None:
    """No such node: exit 1 after --timeout, naming the node and the service it waited for."""
    assert param.main(['get', 'nosuch', 'x', '--timeout', '0.5']) == 1
    err = capsys.readouterr().err
    assert '/uvms/nosuch/get_parameters did not appear within 0.5 s: no node /uvms/nosuch' in err


def test_uvms_param_is_a_subcommand(capsys: pytest.CaptureFixture[str]) -> None:
    """``uvms param`` without an action is bad usage, listing the actions."""
    from uvms_cli import cli

    assert cli.main(['param']) == 2
    assert 'list,get,set' in capsys.readouterr().err.replace(' ', '')
