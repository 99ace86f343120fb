"""What configure checks on an Alpha 5 device, and the confirmed settings of activate and put-back.

Pure (no I/O): the requests configure sends to each device, the limits it expects (the URDF's
position and speed, hardware.yaml's current) and what is wrong with a device's answers, each
message naming the joint and both values; a `Setting` (a change confirmed by reading the
device's MODE back, ``alpha5_probe.confirm_setting``) and the put-back's time bound.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from uvms_hardware import reach_protocol as rp
from uvms_hardware.errors import ProtocolError
from uvms_hardware.hardware_config import Drive
from uvms_hardware.reach_protocol import Mode, PacketId

#: Packets asked of every device at configure.
IDENTITY_REQUEST = (PacketId.MODEL, PacketId.MODE)
LIMITS_REQUEST = (PacketId.POSITION_LIMITS, PacketId.VELOCITY_LIMITS, PacketId.CURRENT_LIMITS)
#: Largest difference between a device's limit and ours that still agrees (float32 and the
#: URDF's two decimals; rad, m/s, mA alike).
LIMIT_TOLERANCE = 1e-3
#: Sends of one confirmed setting before it counts as not confirmed.
CONFIRM_TRIES = 3
#: Wait for the MODE answer of one try (s). The bus needs about 2 ms for a REQUEST and its
#: answer at 115200 baud (robots/bluerov2_heavy_alpha5.md); the device's own answer time is
#: not documented: 30 ms is 15 times the wire's and still fits the put-back in 0.9 s.
DEFAULT_CONFIRM_TIMEOUT_S = 0.03
#: The longest a put-back may take with every device silent (s): well under the 2 s a
#: launcher's stop leaves a bridge (the other bridges share it).
PUT_BACK_BUDGET_S = 1.0

def describe(drive: Drive) -> str:
    """``joint_2 (device 0x04, D)``: how messages name a joint."""
    return f'{drive.joint_name} (device {drive.device_id:#04x}, {drive.axis})'


def unit_of(drive: Drive, packet_id: int) -> str:
    """The unit of a limits packet of the device: mA; m or rad; m/s or rad/s (the jaws' m)."""
    if packet_id == PacketId.CURRENT_LIMITS:
        return 'mA'
    jaw = rp.is_length_packet(drive.device_id, PacketId.POSITION)
    if packet_id == PacketId.VELOCITY_LIMITS:
        return 'm/s' if jaw else 'rad/s'
    return 'm' if jaw else 'rad'


def expected_limits(drive: Drive) -> dict[int, tuple[float, float]]:
    """Our [max, min] per limits packet: URDF position and speed, hardware.yaml current."""
    return {PacketId.POSITION_LIMITS: (drive.position_limits[1], drive.position_limits[0]),
            PacketId.VELOCITY_LIMITS: (drive.velocity_limit, -drive.velocity_limit),
            PacketId.CURRENT_LIMITS: (drive.current_limit_ma, -drive.current_limit_ma)}


def check_device(drive: Drive, answers: Mapping[int, rp.Packet],
                 timeout_s: float) -> list[str]:
    """What is wrong with a device given its answers to the configure requests (empty: fine).

    Each message names the joint, and for a limit both values: the device's and ours.
    """
    name = describe(drive)
    if PacketId.MODEL not in answers:
        return [f'{name}: silent: no MODEL answer within {timeout_s:g} s']
    errors = []
    for packet_id, ours in expected_limits(drive).items():
        label = PacketId(packet_id).name
        packet = answers.get(packet_id)
        if packet is None:
            errors.append(f'{name}: no {label} answer within {timeout_s:g} s')
            continue
        try:
            values = rp.packet_values_si(packet)
        except ProtocolError as exc:
            errors.append(f'{name}: {label}: {exc}')
            continue
        unit = unit_of(drive, packet_id)
        if len(values) != 2 or any(abs(a - b) > LIMIT_TOLERANCE for a, b in zip(
                values, ours, strict=True)):
            shown = ', '.join(f'{v:.4g}' for v in values)
            errors.append(f'{name}: {label} [max, min] on the device [{shown}] {unit}, '
                          f'expected [{ours[0]:.4g}, {ours[1]:.4g}] {unit} (URDF / hardware.yaml)')
    return errors


@dataclass(frozen=True)
class Setting:
    """A change of one device that is confirmed by reading its MODE back.

    Attributes:
        drive: The device.
        frame: What to send (again on each try).
        accepted: The MODE values that confirm it.
        label: How messages name it (``MODE Standby``, ``VELOCITY 0``).
    """

    drive: Drive
    frame: bytes
    accepted: frozenset[Mode]
    label: str


def put_back_bound_s(devices: int, tries: int, timeout_s: float) -> float:
    """The longest a put-back takes (s): two settings per device, each ``tries`` waits."""
    return 2 * devices * tries * timeout_s
