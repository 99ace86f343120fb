"""The Alpha 5 bridge's bus schedule: what the host may put on the half-duplex line, and when.

No ROS, no I/O: the component (``alpha5_component``) asks it each period what to send::

    bus = BusSchedule(baud=115200, command_rate_hz=77.0)
    bus.hold(core.command(t_s, names, torques))   # the latest command, held between slots
    frames = bus.turn(t_s, urgent, next_request)   # commands at a slot, then one REQUEST

The facts (shared/robots/bluerov2_heavy_alpha5.md, "Device timing"): RS-485 at 115200 baud
8N1, half duplex ("data can not be transmitted and received simultaneously": reach_robotics_sdk
rs_protocol); one float packet is 10 bytes on the wire, 0.87 ms. So the host's bytes queue
behind its own bytes (the adapter sends them in turn), but nothing is sent while a device's
answer is expected on the line: a REQUEST's answer (POSITION + VELOCITY, 20 bytes) is
reckoned from the end of the host's bytes, and the line is the device's until it ends.

The schedule:

- **commands** (the held CURRENT frame of every joint, all at once) go out once per slot, on
  a grid of ``1 / command_rate_hz`` from the first command (as the simulator latches arm
  commands at its slots: ``uvms_sim.device_timing``), at the first turn at or after the slot
  time while no answer is expected; in between the latest command is only held;
- **urgent** frames (the watchdog's VELOCITY 0, the jaws' VELOCITY) go out at the first turn
  while no answer is expected;
- **one REQUEST** per turn, after those, while no answer is expected and (while commands are
  held) its answer ends before the next slot: a request never delays a command slot.

After a request the line is the device's until its answer has been seen (`answered`: the
component reads it before its next turn), or ``ANSWER_TIMEOUT_S`` after its reckoned end (a
silent device; the bus's own timeout is not documented). The answer's reckoned end decides
only whether a request fits before the next slot.
"""

from __future__ import annotations

import math
from collections.abc import Callable

#: Bits on the line per byte: start, 8 data, stop (8N1).
BITS_PER_BYTE = 10
#: Bytes of one answer to a feedback REQUEST (POSITION + VELOCITY, 10 each).
FEEDBACK_ANSWER_BYTES = 20
#: An answer not seen this long after its reckoned end is given up (s): the line is the
#: host's again (a silent device; the bus's own timeout is not documented).
ANSWER_TIMEOUT_S = 0.02
#: A turn this much before a slot still counts as at it (s): a loop's tick a little early
#: must not slip a whole slot (an answer's end has no such slack: it is never crossed).
EARLY_S = 1e-4


def byte_time_s(baud: int) -> float:
    """Time one byte takes on the line (s) at ``baud`` 8N1."""
    if baud <= 0:
        raise ValueError(f'baud = {baud}: expected > 0')
    return BITS_PER_BYTE / baud


def cycle_budget(baud: int, joints: int, command_bytes: int = 10, request_bytes: int = 8,
                 answer_bytes: int = FEEDBACK_ANSWER_BYTES) -> float:
    """Cycles per second (Hz) of one CURRENT and one answered REQUEST per joint (derived)."""
    return 1.0 / (joints * (command_bytes + request_bytes + answer_bytes) * byte_time_s(baud))


class BusSchedule:
    """The host's turns on a half-duplex bus: held commands at slots, requests in between.

    Attributes:
        bytes_sent: Bytes the host put on the line.
        bytes_expected: Answer bytes reckoned for its requests.
        slots: Command slots sent.
        skipped_requests: Turns whose request was left out so as not to delay a slot.
        answers_seen: Requests whose answer was seen (the rest timed out).
    """

    def __init__(self, baud: int, command_rate_hz: float,
                 answer_bytes: int = FEEDBACK_ANSWER_BYTES) -> None:
        if not (math.isfinite(command_rate_hz) and command_rate_hz > 0.0):
            raise ValueError(f'command_rate_hz = {command_rate_hz!r}: expected Hz > 0')
        self.byte_s = byte_time_s(baud)
        self._awaiting = False
        self.slot_s = 1.0 / command_rate_hz
        self.answer_bytes = answer_bytes
        self._held = b''
        self._next_slot_s: float | None = None
        self._tx_end_s = -math.inf
        self._answer_end_s = -math.inf
        self.bytes_sent = 0
        self.bytes_expected = 0
        self.slots = 0
        self.skipped_requests = 0
        self.answers_seen = 0

    @property
    def held(self) -> bytes:
        """The command frames held for the next slot (b'': none)."""
        return self._held

    def hold(self, frames: bytes) -> None:
        """Hold ``frames`` (every joint's command) for the next slot; b'' holds nothing."""
        self._held = bytes(frames)
        if not frames:
            self._next_slot_s = None  # the next command starts a grid of its own

    def line_free(self, t_s: float) -> bool:
        """Whether no answer is expected on the line at ``t_s``.

        The last request's answer has been seen (`answered`), or ``ANSWER_TIMEOUT_S`` has
        passed after its reckoned end: the host's own clock and writes may come late on a
        busy host, the answer's arrival cannot.
        """
        return not self._awaiting or t_s >= self._answer_end_s + ANSWER_TIMEOUT_S

    def answered(self) -> None:
        """The last request's answer has fully arrived: the line is free."""
        self._awaiting = False
        self.answers_seen += 1

    def answer_end_s(self) -> float:
        """When the last request's answer is reckoned to end (s; -inf before any)."""
        return self._answer_end_s

    def _put(self, t_s: float, frames: bytes) -> bytes:
        self._tx_end_s = max(t_s, self._tx_end_s) + len(frames) * self.byte_s
        self.bytes_sent += len(frames)
        return frames

    def _slot_due(self, t_s: float) -> bool:
        if not self._held:
            return False
        if self._next_slot_s is None:
            self._next_slot_s = t_s
        return t_s >= self._next_slot_s - EARLY_S

    def turn(self, t_s: float, urgent: bytes = b'',
             next_request: Callable[[], bytes] | None = None) -> bytes:
        """The frames to send at ``t_s`` (b'' while an answer is expected).

        Args:
            t_s: The steady clock (s).
            urgent: Frames that go at the first free turn (watchdog, jaws).
            next_request: Gives the next feedback REQUEST frame; called only when one is sent.
        """
        if not self.line_free(t_s):
            return b''
        out = self._put(t_s, urgent) if urgent else b''
        if self._slot_due(t_s):
            assert self._next_slot_s is not None
            out += self._put(t_s, self._held)
            self.slots += 1
            while self._next_slot_s <= t_s + EARLY_S:  # no catch-up burst after a late turn
                self._next_slot_s += self.slot_s
        if next_request is None:
            return out
        start_s = max(t_s, self._tx_end_s)
        # The request's length is not known before it is made: the feedback REQUEST is 8.
        end_s = start_s + (8 + self.answer_bytes) * self.byte_s
        if self._held and self._next_slot_s is not None and end_s > self._next_slot_s + EARLY_S:
            self.skipped_requests += 1
            return out
        request = next_request()
        out += self._put(t_s, request)
        self._answer_end_s = self._tx_end_s = self._tx_end_s + self.answer_bytes * self.byte_s
        self._awaiting = True
        self.bytes_expected += self.answer_bytes
        return out
