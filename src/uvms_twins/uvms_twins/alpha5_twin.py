"""A Reach Alpha 5 as the protocol document describes it, served over UDP on 127.0.0.1.

No ROS: a plain-Python protocol server (a background thread) with a plant-side API, so the
bridge can be tested against the vendor's behaviour rather than against itself::

    twin = Alpha5Twin(load_alpha5('bluerov2_alpha5', jaw_joint='jaw'), port=0)
    twin.start()                                   # twin.port: the port it bound
    twin.set_joint_state([0.1, 0.2, 0.3, 0.4, 0.01], [0.0] * 5)   # rad, rad/s; jaw m
    twin.joint_commands()  # {'joint_1': (Mode.CURRENT, 120.0), ...} (setpoints in SI / mA)
    twin.stop()

What it does (shared/robots/bluerov2_heavy_alpha5.md, "Reach Alpha 5"): each device has a
mode (Standby at power-up, assumed); MODE switches it; a control packet (POSITION, VELOCITY,
CURRENT) switches it to that control mode, except in Disable and Passive, which ignore control
packets; VELOCITY and CURRENT are clamped at the limits, a POSITION outside the limits is
ignored. A REQUEST is answered by the device it names, one frame per requested packet, all
in one datagram to the sender: POSITION, VELOCITY, CURRENT (the setpoint in Current mode,
else 0: the measured current is not modelled), MODE, the three limits ([max, min], from the
URDF and hardware.yaml), MODEL and HARDWARE_STATUS; other ids are not answered. Packets to
0xFF: a control or MODE packet reaches every device; a REQUEST is answered by NO device, the
twin's safest reading of "broadcast requests collide on RS-485". Limits packets sent by the
host are ignored (the document does not say a device takes them).

Assumed where the document is silent (for docs/hardware.md): what the arm does when the host
goes silent is **unknown**; the twin keeps the last command (the unsafe reading), so that the
bridge's own watchdog is what the tests see. MODEL's data layout is not documented: the twin
answers ``model_data`` (default: the ASCII text ``'alpha5'``). HARDWARE_STATUS' layout is
not documented either: the twin sends the bytes set by `set_hardware_status`, at 1 Hz to the
last host while any is non-zero.

The jaws (device 0x01, axis A): the twin serves them whenever the hardware file describes
them (``arm.jaw_device``), driven by the bridge or not, as the real arm has them. The
simulator has no jaw joint, so unless the plant sets them (``arm.jaw`` among the drives:
`set_joint_state`'s last value) the twin moves them itself: in Velocity mode at the setpoint,
in Position mode toward it at the speed limit, stopped at the position limits; still in the
other modes (Current makes no known speed: no Kt for the jaws), on ``clock`` (default: the
steady clock; a stand would give the plant's). `jaw_state` and `jaw_command` read them.

The bus (``bus=True``; off by default: with it the twin stand does not hold yet,
docs/hardware.md "The Alpha 5 bus"): the arm's RS-485 line at ``arm.serial_baud`` 8N1, half duplex
(``uvms_twins.rs485_bus``): every frame the twin receives and every answer it sends occupies
the line for its bytes (10 bits each: a 10-byte packet takes 0.87 ms at 115200); a frame is
applied when it has fully arrived, an answer is sent when it has fully gone, after whatever
held the line; a frame the host's adapter cannot hold (``buffer_bytes``) is lost, and one
written while an answer is on the line is counted in ``line.collisions``. So the answer rate
per joint and the rate at which commands take effect are the bus's, not the host's.
Without it the twin answers and applies each frame as it arrives (the protocol alone).

Faults a test can set: `set_silent` (a device answers and takes nothing: a broken cable, an
unpowered joint; the others go on), and ``drop_first_datagrams`` / `drop_datagrams` (the
next datagrams the server receives are lost before any device sees them, as on a lossy link).
"""

from __future__ import annotations

import math
import select
import socket
import threading
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from uvms_hardware.address import LOOPBACK
from uvms_hardware.hardware_config import Alpha5Hardware, Drive
from uvms_hardware.reach_protocol import Mode, PacketId

from uvms_hardware import latency_probe
from uvms_hardware import reach_protocol as rp
from uvms_twins.datagram_stamps import receive_stamped, stamp_arrivals
from uvms_twins.rs485_bus import DEFAULT_BUFFER_BYTES, HalfDuplexLine

#: UDP port of Reach's examples.
DEFAULT_PORT = 6789
#: Period of HARDWARE_STATUS while an error is set (s), as the document says.
STATUS_PERIOD_S = 1.0
_IGNORING_MODES = (Mode.DISABLE, Mode.PASSIVE)


@dataclass
class TwinDevice:
    """One device's state: its drive, mode, setpoint and the plant's joint state (SI)."""

    drive: Drive
    mode: Mode = Mode.STANDBY
    setpoint: float = 0.0
    position: float = 0.0
    velocity: float = 0.0
    hardware_status: bytes = b'\x00'
    silent: bool = False
    position_limits: tuple[float, float] = (0.0, 0.0)
    velocity_limit: float = 0.0
    current_limit_ma: float = 0.0
    received: deque[tuple[float, rp.Packet]] = field(default_factory=lambda: deque(maxlen=4096))
    sent: deque[tuple[float, rp.Packet]] = field(default_factory=lambda: deque(maxlen=4096))


def current_to_torque_n_m(drive: Drive, current_ma: float) -> float:
    """Joint torque (N m) of a CURRENT command (mA): I * Kt * gear ratio * efficiency."""
    return drive.torque_n_m(current_ma)


class Alpha5Twin:
    """Protocol server of an Alpha 5 (devices of ``arm.drives``) on UDP ``host:port``."""

    def __init__(self, arm: Alpha5Hardware, host: str = LOOPBACK, port: int = DEFAULT_PORT,
                 model_data: bytes = b'alpha5', drop_first_datagrams: int = 0,
                 clock: Callable[[], float] = time.monotonic, bus: bool = False,
                 buffer_bytes: int = DEFAULT_BUFFER_BYTES) -> None:
        drives = list(arm.drives)
        jaw = arm.jaw_device
        if jaw is not None and all(d.device_id != jaw.device_id for d in drives):
            drives.append(jaw)
        self.devices = {d.device_id: TwinDevice(
            d, position_limits=d.position_limits, velocity_limit=d.velocity_limit,
            current_limit_ma=d.current_limit_ma) for d in drives}
        #: The jaws' device when the twin moves them itself (the plant has no jaw), else None.
        self._own_jaw = jaw.device_id if jaw is not None and arm.jaw is None else None
        self._plant_ids = {d.device_id for d in arm.drives}
        self._jaw_moved_s: float | None = None
        self._clock = clock
        self.model_data = model_data
        self.splitter = rp.FrameSplitter()
        self._address = (host, port)
        self._lock = threading.Lock()
        self._socket: socket.socket | None = None
        self._thread: threading.Thread | None = None
        self._running = threading.Event()
        self._host: tuple[str, int] | None = None
        self._to_drop = drop_first_datagrams
        #: Datagrams lost on purpose so far.
        self.dropped = 0
        self.port = port
        #: The arm's line (None: ``bus=False``, every frame at once).
        self.line = HalfDuplexLine(arm.serial_baud, buffer_bytes) if bus else None
        self._sent_splitter = rp.FrameSplitter()

    # -- plant side ---------------------------------------------------------------------------
    def set_joint_state(self, positions: Sequence[float], velocities: Sequence[float]) -> None:
        """Joint positions (rad; jaw m) and velocities (rad/s; jaw m/s), in drive order."""
        with self._lock:
            for device, p, v in zip(self.devices.values(), positions, velocities, strict=False):
                device.position, device.velocity = float(p), float(v)

    def _plant_devices(self) -> list[TwinDevice]:
        return [d for i, d in self.devices.items() if i in self._plant_ids]

    def joint_state(self) -> tuple[dict[str, float], dict[str, float]]:
        """({joint: position}, {joint: velocity}) as the plant last set them (SI)."""
        with self._lock:
            devices = self._plant_devices()
            return ({d.drive.joint_name: d.position for d in devices},
                    {d.drive.joint_name: d.velocity for d in devices})

    def joint_commands(self) -> dict[str, tuple[Mode, float]]:
        """{joint: (mode, setpoint)} of the plant's joints: rad, rad/s (jaw m, m/s) or mA."""
        with self._lock:
            return {d.drive.joint_name: (d.mode, d.setpoint) for d in self._plant_devices()}

    def jaw_state(self) -> tuple[float, float] | None:
        """The jaws' (opening m, speed m/s) now, or None without jaws."""
        with self._lock:
            device = self.devices.get(rp.DeviceId.JAWS)
            if device is None:
                return None
            self._move_jaw(self._clock())
            return device.position, device.velocity

    def jaw_command(self) -> tuple[Mode, float] | None:
        """The jaws' (mode, setpoint: m, m/s or mA by mode), or None without jaws."""
        with self._lock:
            device = self.devices.get(rp.DeviceId.JAWS)
            return None if device is None else (device.mode, device.setpoint)

    def _move_jaw(self, t_s: float) -> None:
        """Move the jaws the twin moves itself up to ``t_s`` (s of ``clock``); lock held."""
        if self._own_jaw is None:
            return
        device = self.devices[self._own_jaw]
        dt_s = 0.0 if self._jaw_moved_s is None else max(0.0, t_s - self._jaw_moved_s)
        self._jaw_moved_s = t_s
        lower, upper = device.position_limits
        speed = 0.0
        if device.mode == Mode.VELOCITY:
            speed = device.setpoint
        elif device.mode == Mode.POSITION:
            gap = device.setpoint - device.position
            step = abs(gap) if dt_s <= 0.0 else min(abs(gap), device.velocity_limit * dt_s)
            device.position += math.copysign(step, gap)
            device.velocity = 0.0 if step == abs(gap) else math.copysign(
                device.velocity_limit, gap)
            return
        position = min(upper, max(lower, device.position + speed * dt_s))
        at_stop = (position >= upper and speed > 0.0) or (position <= lower and speed < 0.0)
        device.position, device.velocity = position, 0.0 if at_stop else speed

    def joint_torques_n_m(self) -> dict[str, float | None]:
        """{joint: torque (N m)} of the devices in Current mode (Kt, ratio, efficiency), else None.

        The plant applies these; in Velocity mode the plant's ``plant_side.ArmServo`` follows
        the speed setpoint; the other modes make no torque.
        """
        with self._lock:
            return {d.drive.joint_name: current_to_torque_n_m(d.drive, d.setpoint)
                    if d.mode == Mode.CURRENT else None for d in self.devices.values()}

    def set_hardware_status(self, device_id: int, status: bytes) -> None:
        """Set a device's HARDWARE_STATUS bytes (non-zero: an error, sent at 1 Hz)."""
        with self._lock:
            self.devices[device_id].hardware_status = bytes(status)

    def set_silent(self, device_id: int, silent: bool = True) -> None:
        """A silent device answers nothing (a broken cable, an unpowered joint)."""
        with self._lock:
            self.devices[device_id].silent = silent

    def drop_datagrams(self, count: int) -> None:
        """Lose the next ``count`` datagrams the server receives (before any device sees them)."""
        with self._lock:
            self._to_drop = count

    def set_position_limits(self, device_id: int, lower: float, upper: float) -> None:
        """A device configured with other limits than the URDF's (SI units)."""
        with self._lock:
            self.devices[device_id].position_limits = (lower, upper)

    def received(self, device_id: int) -> list[tuple[float, rp.Packet]]:
        """(monotonic time s, packet) of every packet addressed to the device, oldest first."""
        with self._lock:
            return list(self.devices[device_id].received)

    # -- protocol -----------------------------------------------------------------------------
    def handle(self, packet: rp.Packet, t_s: float = 0.0) -> bytes:
        """Apply one packet; return the frames answering it (empty if none)."""
        with self._lock:
            self._move_jaw(self._clock())
            if packet.device_id == rp.DeviceId.ALL:
                for device in self.devices.values():
                    device.received.append((t_s, packet))
                    if packet.packet_id != PacketId.REQUEST:
                        self._apply(device, packet)
                return b''
            target = self.devices.get(packet.device_id)
            if target is None or target.silent:
                return b''
            target.received.append((t_s, packet))
            if packet.packet_id == PacketId.REQUEST:
                return b''.join(self._answer(target, pid) for pid in packet.data)
            self._apply(target, packet)
            return b''

    def _apply(self, device: TwinDevice, packet: rp.Packet) -> None:
        pid = packet.packet_id
        if pid == PacketId.MODE and len(packet.data) == 1:
            mode = rp.mode_of(packet.data[0])
            if mode is not None:  # a value the document does not list is ignored
                device.mode = mode
            return
        if pid not in rp.CONTROL_MODES or len(packet.data) != 4 or device.mode in _IGNORING_MODES:
            return
        value = rp.packet_values_si(packet)[0]
        if pid == PacketId.POSITION:
            lower, upper = device.position_limits
            if not lower <= value <= upper:
                return
        elif pid == PacketId.VELOCITY:
            value = max(-device.velocity_limit, min(device.velocity_limit, value))
        else:
            value = max(-device.current_limit_ma, min(device.current_limit_ma, value))
        device.mode, device.setpoint = rp.CONTROL_MODES[PacketId(pid)], value

    def _answer(self, device: TwinDevice, packet_id: int) -> bytes:
        did = device.drive.device_id
        limits = {PacketId.POSITION_LIMITS: device.position_limits[::-1],
                  PacketId.VELOCITY_LIMITS: (device.velocity_limit, -device.velocity_limit),
                  PacketId.CURRENT_LIMITS: (device.current_limit_ma, -device.current_limit_ma)}
        if packet_id == PacketId.POSITION:
            return rp.encode_position(did, device.position)
        if packet_id == PacketId.VELOCITY:
            return rp.encode_velocity(did, device.velocity)
        if packet_id == PacketId.CURRENT:
            return rp.encode_current(did, device.setpoint if device.mode == Mode.CURRENT else 0.0)
        if packet_id == PacketId.MODE:
            return rp.encode_mode(did, device.mode)
        if packet_id in limits:
            upper, lower = limits[PacketId(packet_id)]
            return rp.encode_limits(did, packet_id, upper, lower)
        if packet_id == PacketId.MODEL:
            return rp.encode_packet(did, PacketId.MODEL, self.model_data)
        if packet_id == PacketId.HARDWARE_STATUS:
            return rp.encode_packet(did, PacketId.HARDWARE_STATUS, device.hardware_status)
        return b''

    def status_frames(self) -> bytes:
        """HARDWARE_STATUS of every device with an error set (sent once a second)."""
        with self._lock:
            return b''.join(
                rp.encode_packet(d.drive.device_id, PacketId.HARDWARE_STATUS, d.hardware_status)
                for d in self.devices.values() if any(d.hardware_status) and not d.silent)

    # -- server -------------------------------------------------------------------------------
    def start(self) -> None:
        """Bind the UDP socket (``port`` 0: an ephemeral one, then in ``self.port``); serve."""
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        sock.bind(self._address)
        self.port = sock.getsockname()[1]
        self._socket = sock
        self._running.set()
        self._thread = threading.Thread(target=self._serve, name='alpha5 twin', daemon=True)
        self._thread.start()

    def stop(self) -> None:
        """Stop serving and close the socket (idempotent)."""
        self._running.clear()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
            self._thread = None
        if self._socket is not None:
            self._socket.close()
            self._socket = None

    def _serve(self) -> None:
        sock = self._socket
        assert sock is not None
        next_status_s = time.monotonic() + STATUS_PERIOD_S
        port = sock.getsockname()[1]
        stamped = stamp_arrivals(sock)
        while self._running.is_set():
            wait_s = 0.05
            if self.line is not None:
                wait_s = min(wait_s, max(0.0, self.line.next_due_s() - time.monotonic()))
            readable, _, _ = select.select([sock], [], [], wait_s)
            now_s = time.monotonic()
            while readable:  # every datagram waiting, before the line runs on
                datagram, sender, arrived_s = receive_stamped(sock, stamped, now_s)
                with self._lock:
                    lost, self._to_drop = self._to_drop > 0, max(0, self._to_drop - 1)
                    self.dropped += lost
                if not lost:
                    self._host = sender
                    self._take(sock, datagram, sender, arrived_s, port)
                readable, _, _ = select.select([sock], [], [], 0.0)
            self._run_line(sock, time.monotonic(), port)
            if now_s >= next_status_s:
                next_status_s = now_s + STATUS_PERIOD_S
                status = self.status_frames()
                if status and self._host is not None:
                    if self.line is None:
                        sock.sendto(status, self._host)
                        latency_probe.note('reply', port)
                    else:
                        self.line.answer(now_s, status, self._host)

    def _take(self, sock: socket.socket, datagram: bytes, sender: tuple[str, int],
              arrived_s: float, port: int) -> None:
        """A datagram from the host: at once without a bus, else frame by frame on the line."""
        if self.line is None:
            reply = b''.join(self.handle(p, arrived_s) for p in self.splitter.feed(datagram))
            if reply:
                sock.sendto(reply, sender)
                latency_probe.note('reply', port)
            return
        # The line up to the write first: the adapter holds only what still waits then, however
        # late this thread woke.
        self._run_line(sock, arrived_s, port)
        for frame in _frames(datagram):
            self.line.write(arrived_s, frame, sender)

    def _run_line(self, sock: socket.socket, now_s: float, port: int) -> None:
        """The line carried up to ``now_s``: frames applied, answers that have gone sent."""
        if self.line is None:
            return
        for gone_s, reply, peer in self.line.run(now_s, self._apply_frame):
            self._note_sent(gone_s, reply)  # before the host can have it
            sock.sendto(reply, peer)
            latency_probe.note('reply', port)

    def _note_sent(self, gone_s: float, reply: bytes) -> None:
        """Keep (time the answer had gone, packet) per device: `sent`."""
        with self._lock:
            for packet in self._sent_splitter.feed(reply):
                device = self.devices.get(packet.device_id)
                if device is not None:
                    device.sent.append((gone_s, packet))

    def sent(self, device_id: int) -> list[tuple[float, rp.Packet]]:
        """(monotonic time s, packet) of every answer the device sent on the bus, oldest first.

        The time is when the answer had fully gone on the line (empty without a bus).
        """
        with self._lock:
            return list(self.devices[device_id].sent)

    def _apply_frame(self, frame: bytes, arrived_s: float) -> bytes:
        """A host frame that has fully arrived on the line: applied; the answer (b'': none)."""
        return b''.join(self.handle(p, arrived_s) for p in self.splitter.feed(frame))

    def __enter__(self) -> Alpha5Twin:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()


def _frames(datagram: bytes) -> list[bytes]:
    """The datagram's frames, each with its 0x00 terminator (a tail without one as it is)."""
    parts = datagram.split(b'\x00')
    frames = [part + b'\x00' for part in parts[:-1]]
    return frames + ([parts[-1]] if parts[-1] else [])
