"""``uvms hardware check``'s vehicle: ArduSub found, its ids, failsafes, outputs, arming.

What the ardusub_bridge needs of the vehicle (``ardusub_bridge_node``, docs/hardware.md):
our GCS id obeyed (``MAV_GCS_SYSID``); no other ground station with our id; before a launch,
disarmed with every thruster output at its Motor function (33..40: nothing left in
passthrough); while the bridge is active, **armed** (it arms at activate) and the outputs as
its thruster mode wants them: in ``script`` mode the watchdog script heard and the outputs at
Motor1..8, in ``passthrough`` mode each thruster output at RCIN of its channel (51..58). The
flight mode is said by name; the bridge does not depend on it (the script's forced outputs
and RCIN passthrough bypass the mixer: ``SRV_Channels``), and the twin models MANUAL only.
What it sends: HEARTBEATs as a GCS and parameter *reads*.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from typing import Any

from pymavlink import mavutil

from uvms_hardware.ardusub_link import K_MOTOR1, K_RCIN1, ArduSubLink, LinkSettings
from uvms_hardware.ardusub_restore import find_leftovers, leftovers_refusal
from uvms_hardware.ardusub_watchdog import SCRIPT_NAME
from uvms_hardware.ardusub_wire import GCS_ID_PARAMS, GCS_LISTEN_S
from uvms_hardware.errors import HardwareError
from uvms_hardware.hardware_check_status import BridgeStatus, CheckBounds, Device
from uvms_hardware.hardware_config import hardware_section
from uvms_hardware.t200_curve import T200Curve

#: Listening for the watchdog script's announcement (it says itself once a second) (s).
SCRIPT_LISTEN_S = 1.5
#: Listening for SYS_STATUS (the battery) (s).
BATTERY_LISTEN_S = 1.5
#: ArduSub's flight modes by custom_mode number (pymavlink's map of ArduSub's mode.h).
SUB_MODES: dict[int, str] = mavutil.mode_mapping_bynumber(mavutil.mavlink.MAV_TYPE_SUBMARINE)


def parameter_reads(channels: int) -> int:
    """Parameter reads of one check: GCS ids, 3 failsafes, the outputs twice (list, leftovers)."""
    return len(GCS_ID_PARAMS) + 3 + 2 * channels


def ardusub_bound_s(channels: int, bounds: CheckBounds) -> float:
    """The longest the vehicle's check takes (s): every wait at its end."""
    return (bounds.wait_s + max(GCS_LISTEN_S, parameter_reads(channels) * bounds.reply_s
                                * bounds.retries) + SCRIPT_LISTEN_S + BATTERY_LISTEN_S)


def mode_name(custom_mode: int) -> str:
    """``MANUAL (19)``: an ArduSub flight mode by name and number."""
    return f'{SUB_MODES.get(custom_mode, "unknown mode")} ({custom_mode})'


def check_ardusub(robot: str, values: Mapping[str, Any], device: Device, bounds: CheckBounds,
                  bridge: BridgeStatus | None) -> None:
    """The vehicle against what the bridge needs, given whether a bridge is active."""
    _, section = hardware_section(robot, 'ardusub')
    settings = LinkSettings(str(values['mavlink_url']),
                            tuple(int(c) for c in section['thruster_channels']),
                            tuple(int(d) for d in section['thruster_directions']),
                            int(values.get('gcs_system_id', 255)),
                            reply_timeout_s=bounds.reply_s, retries=bounds.retries)
    link = ArduSubLink(settings, T200Curve.from_section(section['t200']))
    active = bridge is not None and bridge.active
    try:
        link.open()
        link.wait_vehicle(bounds.wait_s)
        v = link.vehicle
        device.info(f'system {v.system_id} component {v.component_id}, '
                    f'{"armed" if v.armed else "disarmed"}, flight mode '
                    f'{mode_name(v.custom_mode)}')
        try:
            name, gcs_id = link.check_gcs_id()
            device.info(f'{name} = {gcs_id}: our RC overrides will be obeyed')
        except HardwareError as exc:
            device.problem(str(exc))
        for warning in link.failsafe_warnings():
            device.warn(warning)
        try:
            for warning in link.check_other_gcs():
                device.warn(warning)
        except HardwareError as exc:
            if active:  # on a router, the running bridge itself is a station with our id
                device.info(f'{exc} (or it is the active ardusub_bridge itself)')
            else:
                device.problem(str(exc))
        script_ms = link.wait_watchdog_script(SCRIPT_LISTEN_S)
        _check_outputs(link, device, bridge, script_ms)
        _check_arming(v.armed, device, bridge)
        end_s = time.monotonic() + BATTERY_LISTEN_S
        while math.isnan(v.voltage_v) and time.monotonic() < end_s:
            link.service()
            time.sleep(0.01)
        device.info(f'battery {v.voltage_v:.2f} V' if math.isfinite(v.voltage_v) else
                    'battery: no SYS_STATUS heard (the bridge asks for it when it runs)')
    except HardwareError as exc:
        device.problem(str(exc))
    finally:
        link.close()


def _check_outputs(link: ArduSubLink, device: Device, bridge: BridgeStatus | None,
                   script_ms: float | None) -> None:
    """Thruster outputs' functions as the bridge's thruster mode needs them."""
    channels = link.settings.thruster_channels
    functions = {c: link.read_param(f'SERVO{c}_FUNCTION') for c in channels}
    device.info('thruster outputs SERVOn_FUNCTION: ' + ', '.join(
        f'{c}={"?" if f is None else int(f)}' for c, f in functions.items())
        + ' (passthrough mode sets RCIN 51..58 and puts these back)')
    if script_ms is not None:
        device.info(f'{SCRIPT_NAME} heard (timeout {script_ms:g} ms): the thrusters stop '
                    'without the bridge')
    thruster_mode = bridge.values.get('thruster_mode', '') if bridge is not None else ''
    if bridge is not None and bridge.active and thruster_mode == 'passthrough':
        wrong = {c: f for c, f in functions.items() if f != float(K_RCIN1 + c - 1)}
        if wrong:
            device.problem(
                'not in passthrough while ardusub_bridge is active in passthrough mode: '
                + ', '.join(f'SERVO{c}_FUNCTION = {"?" if f is None else int(f)} (needs '
                            f'{K_RCIN1 + c - 1}, RCIN{c})' for c, f in wrong.items())
                + ": the bridge's PWMs reach no thruster there")
        return
    if bridge is not None and bridge.active and thruster_mode == 'script':
        if script_ms is None:
            device.problem(f'{SCRIPT_NAME} not heard while ardusub_bridge is active in script '
                           'mode: its PWMs on RC 9-16 reach no thruster')
        wrong = {c: f for c, f in functions.items() if f != float(K_MOTOR1 + c - 1)}
        if wrong:
            device.problem('ardusub_bridge is active in script mode, which needs Motor1..8: '
                           + ', '.join(f'SERVO{c}_FUNCTION = {"?" if f is None else int(f)} '
                                       f'(needs {K_MOTOR1 + c - 1})' for c, f in wrong.items()))
        return
    leftovers = find_leftovers(link)
    if leftovers is not None:
        device.problem(leftovers_refusal(leftovers, link.settings.url))
    if script_ms is None:
        device.warn(f'{SCRIPT_NAME} not heard: the bridge will use RC passthrough, and only its '
                    'process stops the thrusters (docs/hardware.md)')


def _check_arming(armed: bool, device: Device, bridge: BridgeStatus | None) -> None:
    """Armed while the bridge is active (it arms at activate); disarmed before it."""
    if bridge is not None and bridge.active:
        if not armed:
            device.problem('disarmed while ardusub_bridge is active: the bridge needs the '
                           'vehicle armed (it arms at activate; a failsafe or another station '
                           'disarmed it): `uvms lifecycle ardusub_bridge deactivate` then '
                           '`activate`')
        return
    if armed:
        device.warn('armed, and no ardusub_bridge is active: another station armed it (the '
                    'bridge arms at activate and disarms at its stop)')
    else:
        device.info('disarmed, as before a launch: the bridge arms it at activate')
