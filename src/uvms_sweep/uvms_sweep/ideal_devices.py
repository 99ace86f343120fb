"""``--ideal-devices`` of ``uvms run``, ``launch``, ``sweep`` and ``tune``: the paper's rates.

A robot that declares its device timing (its ``device_timing.yaml``, docs/robots.md "Device
timing") runs with it by default: the simulator samples, delays and holds the sensors and
latches the commands at the devices' rates (``devices.*``), and the controller holds its force
loop at the arm's command rate (``arm.command_rate_hz``, ``arm.force_latency_s``). The flag
sets both back, together (the controller's held-slot prediction at ideal devices makes the
contact unstable): every sample with every state, every command at once, the controller's
two keys 0. A robot without device timing runs the same with and without it.

    overrides = with_ideal_devices(scenario.overrides)   # run, launch (over --params-file)
    request['overrides'] = with_ideal_devices(request['overrides'])   # sweep and tune points
"""

from __future__ import annotations

import argparse
from collections.abc import Iterable, Mapping
from typing import Any

#: What ``--ideal-devices`` sets, per node: the simulator's ideal devices and the controller
#: at every state (docs/hardware.md, "Device timing").
IDEAL_DEVICES: dict[str, dict[str, Any]] = {
    'simulator': {'devices.ideal': True},
    'controller': {'arm.command_rate_hz': 0.0, 'arm.force_latency_s': 0.0},
}
#: Help of the flag, the same on every command.
IDEAL_DEVICES_HELP = (
    "ideal devices, the paper's rates: the simulator gives every sensor with every state and "
    "applies every command at once (devices.ideal true), and the controller's "
    "arm.command_rate_hz and arm.force_latency_s are 0, whatever the robot's "
    'device_timing.yaml declares and over --params-file (docs/hardware.md, "Device timing")')


def add_ideal_devices_argument(parser: argparse.ArgumentParser) -> None:
    """``--ideal-devices`` (a switch) on a command's parser."""
    parser.add_argument('--ideal-devices', action='store_true', help=IDEAL_DEVICES_HELP)


def with_ideal_devices(
    overrides: Mapping[str, Mapping[str, Any]],
    nodes: Iterable[str] = tuple(IDEAL_DEVICES),
) -> dict[str, dict[str, Any]]:
    """Per-node parameter overrides with the ideal devices' values over them.

    Args:
        overrides: Node name to dotted parameter name to value (a scenario's, a point's).
        nodes: The nodes to set back (``simulator``, ``controller``); the default both.

    Returns:
        A new mapping; ``overrides`` is left as it was.

    >>> with_ideal_devices({'simulator': {'devices.ideal': False, 'wall.k_e': 1.0}})['simulator']
    {'devices.ideal': True, 'wall.k_e': 1.0}
    """
    merged = {node: dict(values) for node, values in overrides.items()}
    for node in nodes:
        merged.setdefault(node, {}).update(IDEAL_DEVICES[node])
    return merged
