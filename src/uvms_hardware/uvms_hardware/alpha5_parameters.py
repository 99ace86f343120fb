"""The Alpha 5 bridge's settings: the bridge node's parameters, declared once.

``alpha5_component.Alpha5Component`` reads them (``values``); ``alpha5_bridge_node`` declares
them as ROS parameters with these defaults and descriptions (units in each).
"""

from __future__ import annotations

from typing import Any

from uvms_hardware.alpha5_checks import CONFIRM_TRIES, DEFAULT_CONFIRM_TIMEOUT_S, PUT_BACK_BUDGET_S
from uvms_hardware.alpha5_core import DEFAULT_OVERSPEED_FACTOR

__all__ = ['PARAMETERS']

#: The settings (the bridge node's parameters): name, default, description (unit). The
#: jaw_joint default (None) is the robot's hardware file's (`jaw_default`).
PARAMETERS: tuple[tuple[str, Any, str], ...] = (
    ('connection', 'udp:127.0.0.1:6789',
     'udp:HOST:PORT, or serial:DEVICE[:BAUD] (8N1, 115200 unless given)'),
    ('watchdog_timeout_s', 0.1, 'No command for this long: VELOCITY 0 to every joint (s)'),
    ('feedback_rate_hz', 125.0,
     'Turns on the bus: the poll timer runs at this rate x devices (Hz); each device is asked '
     'at most this often, and less where the bus is full (hardware.yaml alpha5.bus: about '
     '44 Hz per joint at 77 Hz of commands on 115200 baud); joint_states once per round'),
    ('command_mode', 'current',
     'current: torque as CURRENT mA (Kt, gear, efficiency); velocity: a fallback, '
     'VELOCITY = velocity_gain_rad_s_per_n_m * torque'),
    ('velocity_gain_rad_s_per_n_m', 0.1, 'Admittance of the velocity fallback (rad/s per N m)'),
    ('jaw_joint', None,
     "The jaws' joint name, driven from command/jaw; empty: the jaws are not driven. "
     "Default: hardware.yaml's alpha5.jaw.joint_name (empty where it names none)"),
    ('answer_timeout_s', 0.2, 'Time a device has to answer at configure (s)'),
    ('startup_wait_s', 10.0,
     'While no device answers at all, configure asks again for this long (s): the arm or its '
     'link may come up after the bridge (launch order); 0 asks once'),
    ('silent_timeout_s', 0.2,
     'A joint without an answer this long is silent: no joint_states, diagnostics ERROR (s)'),
    ('overspeed_factor', DEFAULT_OVERSPEED_FACTOR,
     'A joint reported faster than this many times its URDF speed limit trips the bridge: '
     'VELOCITY 0 to every joint, commands refused until ~/reset_trip or deactivate and '
     'activate (>= 1)'),
    ('bus_schedule', False,
     "Schedule the half-duplex bus (uvms_hardware.alpha5_bus): each joint's latest CURRENT "
     'once per slot at hardware.yaml alpha5.bus.command_rate_hz, requests only while no '
     'answer is on the line. Off: every command written at once, one request per poll '
     '(the twin stand does not hold with it yet: docs/hardware.md "The Alpha 5 bus")'),
    ('confirm_timeout_s', DEFAULT_CONFIRM_TIMEOUT_S,
     f'Wait for a MODE read-back when activate or the put-back confirms a change (s); '
     f'{CONFIRM_TRIES} tries per change, and the whole put-back with every device silent '
     f'must fit {PUT_BACK_BUDGET_S:g} s'),
)
