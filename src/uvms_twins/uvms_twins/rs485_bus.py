"""A half-duplex RS-485 line as the Alpha 5 twin keeps it: every byte takes its time.

No sockets, no threads: the twin writes the host's frames in and runs the line up to now::

    line = HalfDuplexLine(baud=115200)
    line.write(t_s, frame, sender)                 # False: lost (the adapter overflowed)
    for gone_s, answer, peer in line.run(now_s, apply):   # apply(frame, arrived_s) -> answer
        sock.sendto(answer, peer)
    line.next_due_s()                              # when the next frame ends (inf: idle)

The facts (shared/robots/bluerov2_heavy_alpha5.md, "Device timing"): 115200 baud 8N1, half
duplex; 10 bits per byte, so a 10-byte packet takes 0.87 ms. What the twin assumes where the
sources are silent (docs/hardware.md, "The Alpha 5 bus"):

- one line, one frame at a time: the host's frames wait in its adapter, in order, until the
  line is free; a frame is applied when it has fully arrived, and the device's answer goes
  next (a device answers as soon as its request has arrived; its turn-round time is not
  documented: 0 here), ahead of host frames still waiting; an answer is sent when it has
  fully gone;
- the host's adapter holds at most ``buffer_bytes`` (256 assumed: an FTDI FT232R's transmit
  buffer; the adapter of a real arm is not documented): a frame that would overflow what is
  still waiting is lost whole;
- a host frame written while a device's answer is on the line would garble both on a real
  bus; the twin delivers both, after the answer, and counts it in ``collisions``, so that a
  bridge that writes across an answer is seen.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from uvms_hardware.alpha5_bus import byte_time_s

#: Bytes the host's USB-RS485 adapter holds before it loses a frame (assumed, above).
DEFAULT_BUFFER_BYTES = 256

Apply = Callable[[bytes, float], bytes]


@dataclass
class HalfDuplexLine:
    """One half-duplex line at ``baud`` 8N1: what arrives and goes when, what is lost.

    Attributes:
        baud: Line speed (bit/s).
        buffer_bytes: What the host's adapter holds while the line is busy.
        free_s: When the line's last frame ended (s; -inf: never used).
        received_bytes: Host bytes carried.
        sent_bytes: Device bytes carried.
        lost_frames: Host frames lost to a full adapter buffer.
        collisions: Host frames written while a device's answer was on the line.
    """

    baud: int
    buffer_bytes: int = DEFAULT_BUFFER_BYTES
    free_s: float = -math.inf
    received_bytes: int = 0
    sent_bytes: int = 0
    lost_frames: int = 0
    collisions: int = 0
    _adapter: deque[tuple[float, bytes, Any]] = field(default_factory=deque)
    _answers: deque[tuple[float, bytes, Any]] = field(default_factory=deque)

    @property
    def byte_s(self) -> float:
        """Time of one byte on the line (s)."""
        return byte_time_s(self.baud)

    def waiting_bytes(self) -> int:
        """Host bytes in the adapter, not yet on the line."""
        return sum(len(frame) for _, frame, _ in self._adapter)

    def write(self, t_s: float, frame: bytes, peer: Any = None) -> bool:
        """The host writes ``frame`` at ``t_s``; False: lost (the adapter's buffer is full)."""
        if self.waiting_bytes() + len(frame) > self.buffer_bytes:
            self.lost_frames += 1
            return False
        self._adapter.append((t_s, bytes(frame), peer))
        return True

    def answer(self, ready_s: float, frames: bytes, peer: Any = None) -> None:
        """The device has ``frames`` to send from ``ready_s`` (HARDWARE_STATUS, unasked)."""
        self._answers.append((ready_s, bytes(frames), peer))

    def _next(self) -> tuple[float, bool] | None:
        """(start s, is an answer) of the next frame on the line; answers first at a tie."""
        starts = []
        if self._answers:
            starts.append((max(self.free_s, self._answers[0][0]), 0))
        if self._adapter:
            starts.append((max(self.free_s, self._adapter[0][0]), 1))
        if not starts:
            return None
        start_s, kind = min(starts)
        return start_s, kind == 0

    def next_due_s(self) -> float:
        """When the next frame on the line has fully gone (s; inf: nothing waits)."""
        upcoming = self._next()
        if upcoming is None:
            return math.inf
        start_s, is_answer = upcoming
        frame = (self._answers if is_answer else self._adapter)[0][1]
        return start_s + len(frame) * self.byte_s

    def run(self, now_s: float, apply: Apply) -> list[tuple[float, bytes, Any]]:
        """Carry every frame that has fully gone by ``now_s``, in line order.

        Args:
            now_s: The clock the writes are stamped on (s).
            apply: Takes a host frame at the moment it has arrived; returns the device's
                answer (b'': none), which goes next.

        Returns:
            (gone s, answer, peer) of every answer that has fully gone, oldest first.
        """
        gone = []
        while (upcoming := self._next()) is not None:
            start_s, is_answer = upcoming
            queue = self._answers if is_answer else self._adapter
            _, frame, peer = queue[0]
            end_s = start_s + len(frame) * self.byte_s
            if end_s > now_s:
                break
            queue.popleft()
            self.free_s = end_s
            if is_answer:
                self.sent_bytes += len(frame)
                self.collisions += sum(1 for t_s, _, _ in self._adapter if start_s <= t_s < end_s)
                gone.append((end_s, frame, peer))
                continue
            self.received_bytes += len(frame)
            reply = apply(frame, end_s)
            if reply:
                self._answers.appendleft((end_s, reply, peer))
        return gone
