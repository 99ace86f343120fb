"""ROS 2 environment defaults that everything the project starts runs with: loopback-only DDS.

Applied by every node's ``main`` (``uvms_common.node_main``), the ``uvms`` command, the
launch file, the tests and the benchmarks, before ``rclpy.init`` creates a DDS participant. Each
variable is set only where the user has not set it: a user's own choice always wins.

- ``FASTRTPS_DEFAULT_PROFILES_FILE``: the project's Fast DDS profile
  (``uvms_common/fastdds_loopback.xml``): UDPv4 restricted to 127.0.0.1 (no shared memory),
  no builtin transports, discovery by unicast to 127.0.0.1.
- ``ROS_AUTOMATIC_DISCOVERY_RANGE``: ``SYSTEM_DEFAULT``, which leaves transports and
  discovery to that profile. ``LOCALHOST`` would not keep the traffic on loopback:
  rmw_fastrtps_cpp (Jazzy, participant.cpp) then appends a UDPv4 transport of its own with
  no interface restriction, which binds 0.0.0.0 and the machine's other addresses (measured
  with the profile in force).
- ``RMW_IMPLEMENTATION``: ``rmw_fastrtps_cpp``, the one rmw the PyPI wheels carry.
- ``AMENT_PREFIX_PATH``: the venv, when it holds an ament index (a wheel venv), so that
  ament_index lookups find the wheels' and our packages as on a sourced install.
"""

from __future__ import annotations

import os
import sys
from collections.abc import MutableMapping
from pathlib import Path

PROFILE_VARIABLES = ('FASTRTPS_DEFAULT_PROFILES_FILE', 'FASTDDS_DEFAULT_PROFILES_FILE')
DISCOVERY_VARIABLES = ('ROS_AUTOMATIC_DISCOVERY_RANGE', 'ROS_LOCALHOST_ONLY')
PROFILE_FILE_NAME = 'fastdds_loopback.xml'


def loopback_profile_path() -> Path:
    """The shipped loopback-only Fast DDS profile (package data of uvms_common)."""
    return Path(__file__).resolve().parent / PROFILE_FILE_NAME


def ros_environment_defaults(
    environ: MutableMapping[str, str] | None = None,
) -> dict[str, str]:
    """Set the project's ROS 2 defaults where unset; return what was set.

    Args:
        environ: The environment to complete (``os.environ`` if None).

    Returns:
        Variable name to the value this call set (empty when the user had set them all).
    """
    env = os.environ if environ is None else environ
    applied: dict[str, str] = {}

    def set_default(name: str, value: str) -> None:
        if not env.get(name):
            env[name] = value
            applied[name] = value

    if not any(env.get(name) for name in PROFILE_VARIABLES):
        set_default('FASTRTPS_DEFAULT_PROFILES_FILE', str(loopback_profile_path()))
        if not any(env.get(name) for name in DISCOVERY_VARIABLES):
            set_default('ROS_AUTOMATIC_DISCOVERY_RANGE', 'SYSTEM_DEFAULT')
    set_default('RMW_IMPLEMENTATION', 'rmw_fastrtps_cpp')
    index = Path(sys.prefix) / 'share' / 'ament_index'
    if index.is_dir():
        set_default('AMENT_PREFIX_PATH', sys.prefix)
    return applied


def network_summary(environ: MutableMapping[str, str] | None = None) -> list[str]:
    """Lines describing the DDS network settings in force, with a warning where they leak."""
    env = os.environ if environ is None else environ
    profile = next((env[name] for name in PROFILE_VARIABLES if env.get(name)), '')
    discovery = env.get('ROS_AUTOMATIC_DISCOVERY_RANGE', '') or '(unset: SUBNET)'
    lines = [f'DDS profile {profile or "(none: Fast DDS builtin transports, all interfaces)"}',
             f'discovery   ROS_AUTOMATIC_DISCOVERY_RANGE={discovery}']
    if profile and Path(profile).name == PROFILE_FILE_NAME and discovery == 'LOCALHOST':
        lines.append('warning: with ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST rmw_fastrtps_cpp '
                     'adds an unrestricted UDPv4 transport (binds 0.0.0.0); unset it or set '
                     'SYSTEM_DEFAULT to stay on loopback')
    return lines
