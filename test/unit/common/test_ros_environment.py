"""`ros_environment_defaults` completes an environment with loopback-only DDS, never overriding."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
from uvms_common.ros_environment import loopback_profile_path, ros_environment_defaults


@pytest.fixture(autouse=True)
def prefix_without_ament_index(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    """An interpreter prefix without an ament index, so AMENT_PREFIX_PATH stays out of it."""
    monkeypatch.setattr(sys, 'prefix', str(tmp_path))


def test_empty_environment_gets_the_loopback_profile_and_system_default_discovery() -> None:
    """Nothing set: the shipped profile, SYSTEM_DEFAULT discovery and Fast DDS, all reported."""
    environ: dict[str, str] = {}
    applied = ros_environment_defaults(environ)
    assert environ == {
        'FASTRTPS_DEFAULT_PROFILES_FILE': str(loopback_profile_path()),
        'ROS_AUTOMATIC_DISCOVERY_RANGE': 'SYSTEM_DEFAULT',
        'RMW_IMPLEMENTATION': 'rmw_fastrtps_cpp',
    }
    assert applied == environ
    assert loopback_profile_path().is_file()


@pytest.mark.parametrize(
    'user',
    [
        {'FASTRTPS_DEFAULT_PROFILES_FILE': '/home/pilot/site.xml'},
        {'FASTDDS_DEFAULT_PROFILES_FILE': '/home/pilot/site.xml'},
        {'FASTRTPS_DEFAULT_PROFILES_FILE': '/home/pilot/site.xml',
         'ROS_AUTOMATIC_DISCOVERY_RANGE': 'SUBNET'},
    ],
    ids=['fastrtps-profile', 'fastdds-profile', 'profile-and-range'],
)
def test_user_profile_is_kept_and_discovery_left_to_it(user: dict[str, str]) -> None:
    """A profile of the user's own wins, and discovery is not forced to SYSTEM_DEFAULT."""
    environ = dict(user)
    applied = ros_environment_defaults(environ)
    assert environ == {**user, 'RMW_IMPLEMENTATION': 'rmw_fastrtps_cpp'}
    assert applied == {'RMW_IMPLEMENTATION': 'rmw_fastrtps_cpp'}


@pytest.mark.parametrize(
    'user',
    [{'ROS_AUTOMATIC_DISCOVERY_RANGE': 'LOCALHOST'}, {'ROS_LOCALHOST_ONLY': '1'}],
    ids=['discovery-range', 'localhost-only'],
)
def test_user_discovery_setting_is_kept_beside_the_default_profile(user: dict[str, str]) -> None:
    """A discovery setting of the user's stays as it is; only the profile is added."""
    environ = dict(user)
    ros_environment_defaults(environ)
    assert environ == {**user,
                       'FASTRTPS_DEFAULT_PROFILES_FILE': str(loopback_profile_path()),
                       'RMW_IMPLEMENTATION': 'rmw_fastrtps_cpp'}


def test_user_rmw_is_kept() -> None:
    """Another rmw chosen by the user is not replaced by Fast DDS."""
    environ = {'RMW_IMPLEMENTATION': 'rmw_cyclonedds_cpp'}
    applied = ros_environment_defaults(environ)
    assert environ['RMW_IMPLEMENTATION'] == 'rmw_cyclonedds_cpp'
    assert 'RMW_IMPLEMENTATION' not in applied


def test_empty_value_counts_as_unset() -> None:
    """A variable set to the empty string gets the default, as if it were not set."""
    environ = {'FASTRTPS_DEFAULT_PROFILES_FILE': '', 'RMW_IMPLEMENTATION': ''}
    ros_environment_defaults(environ)
    assert environ['FASTRTPS_DEFAULT_PROFILES_FILE'] == str(loopback_profile_path())
    assert environ['RMW_IMPLEMENTATION'] == 'rmw_fastrtps_cpp'


def test_second_call_changes_nothing() -> None:
    """Applying the defaults twice: the second call sets nothing and reports nothing."""
    environ: dict[str, str] = {}
    ros_environment_defaults(environ)
    before = dict(environ)
    assert ros_environment_defaults(environ) == {}
    assert environ == before


def test_ament_prefix_path_is_the_prefix_holding_an_ament_index(tmp_path: Path) -> None:
    """A wheel venv (an ament index under its prefix) becomes AMENT_PREFIX_PATH, if unset."""
    (tmp_path / 'share' / 'ament_index').mkdir(parents=True)
    environ: dict[str, str] = {}
    ros_environment_defaults(environ)
    assert environ['AMENT_PREFIX_PATH'] == str(tmp_path)
    kept = {'AMENT_PREFIX_PATH': '/opt/ros/jazzy'}
    ros_environment_defaults(kept)
    assert kept['AMENT_PREFIX_PATH'] == '/opt/ros/jazzy'
