"""Test-wide setup: the project's ROS 2 defaults (loopback-only Fast DDS profile) for rclpy.

Each test module also runs on a ROS domain of its own (``ROS_DOMAIN_ID``, set before the
module's fixtures, inherited by the node processes it starts; modules that choose their own
domain still do). Participants that one module leaves alive until garbage collection then
never discover the next module's: with every in-process test on domain 0, a whole-suite
run held 25 participants in one process discovering each other, and Fast DDS 2.14 livelocked
destroying one of them (rmw's ``destroy_participant`` spinning in
``DomainParticipant::set_listener`` while its discovery threads waited on the PDP mutex:
gdb, CI run of 2026-12-04, a test's teardown in ``destroy_node`` for minutes).
"""

import itertools
import os
from collections.abc import Iterator

import pytest
from uvms_common.ros_environment import ros_environment_defaults

# Before any test creates a DDS participant; a user's own settings win (see the module).
ros_environment_defaults()

#: Domains handed to test modules in turn (1-100: their UDP ports stay below Linux's
#: ephemeral range); 0 is left to whatever runs outside the tests.
_MODULE_DOMAINS = itertools.cycle(range(1, 101))


@pytest.fixture(scope='module', autouse=True)
def module_ros_domain() -> Iterator[int]:
    """A ROS domain for the module's nodes and the processes it starts (ROS_DOMAIN_ID)."""
    before = os.environ.get('ROS_DOMAIN_ID')
    domain = next(_MODULE_DOMAINS)
    os.environ['ROS_DOMAIN_ID'] = str(domain)
    yield domain
    if before is None:
        os.environ.pop('ROS_DOMAIN_ID', None)
    else:
        os.environ['ROS_DOMAIN_ID'] = before
