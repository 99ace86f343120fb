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

import atexit
import itertools
import os
import shutil
import tempfile
from collections.abc import Iterator

import pytest
from uvms_common.ros_environment import ros_environment_defaults

# Before any test creates a DDS participant; a user's own settings win (see the module).
ros_environment_defaults()
# The hardware bridges journal what they change on a device (uvms_hardware.device_journal):
# the tests' journals go to a folder of the run's own, never to the user's ~/.local/state.
if 'UVMS_JOURNAL_DIR' not in os.environ:
    os.environ['UVMS_JOURNAL_DIR'] = tempfile.mkdtemp(prefix='uvms-test-journal-')
    # Removed with the pytest process (a suite run made 70 of them, left behind in /tmp).
    atexit.register(shutil.rmtree, os.environ['UVMS_JOURNAL_DIR'], ignore_errors=True)

#: Domains handed to test modules in turn (1-100: their UDP ports stay below Linux's
#: ephemeral range); 0 is left to whatever runs outside the tests. tools/run_suite.py starts
#: each of its pytest processes at another one (UVMS_TEST_DOMAIN_START), within the range of
#: its lane (UVMS_TEST_DOMAINS, ``LOW-HIGH``), so that tests running at once in its two lanes
#: never share a domain.
_LOW, _, _HIGH = os.environ.get('UVMS_TEST_DOMAINS', '1-100').partition('-')
_FIRST_DOMAIN = min(max(int(os.environ.get('UVMS_TEST_DOMAIN_START', _LOW)), int(_LOW)),
                    int(_HIGH))
_MODULE_DOMAINS = itertools.cycle([*range(_FIRST_DOMAIN, int(_HIGH) + 1),
                                   *range(int(_LOW), _FIRST_DOMAIN)])
#: tools/run_suite.py's progress file: the test now running, named in its summary when the
#: process has to be killed.
_PROGRESS = os.environ.get('UVMS_TEST_PROGRESS')


def pytest_runtest_logstart(nodeid: str, location: tuple[str, int | None, str]) -> None:
    """Write the id of the test that starts to the suite runner's progress file."""
    if _PROGRESS:
        with open(_PROGRESS, 'w') as progress:
            progress.write(nodeid)


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
