"""Per-call costs on the robot loop's 500 Hz path, before and after, side by side in one run.

The robot process's ledger (``UVMS_LOOP_CPU=1``, ``uvms_hardware.loop_ledger``) showed where
its thread's CPU goes per period; this bench times, interleaved in one process, the old and
the new way of the pieces that were changed, and prints their ratio (a relative figure that
holds on a loaded machine, unlike the microseconds themselves):

- ``alpha5 feed``: the Alpha 5's answers split into frames byte by byte in Python (before)
  vs. by ``bytes.find`` of the terminator (``reach_protocol.FrameSplitter.feed``): one read's
  datagram, a joint's POSITION and VELOCITY answers;
- ``alpha5 request``: a joint's feedback REQUEST encoded (COBS, CRC) each poll (before) vs.
  encoded once per device (``alpha5_core``);
- ``loop /clock``: the period's time to the estimator's raw input as a ``Clock`` message
  built and serialized (before) vs. its 12 CDR bytes packed by ``struct`` (``robot_loop``);
- ``netft wrench``: one record as a ``WrenchStamped`` built field by field and serialized for
  the controller's raw input (before) vs. its CDR bytes written by ``struct`` into a
  preallocated payload (``cdr_codecs.PayloadWriter``), as the robot loop's Net F/T bridge
  publishes it now.

It asserts nothing. Usage::

    .venv/bin/python bench/bench_robot_loop_costs.py [--rounds N]
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from collections.abc import Callable

from bench_realtime_load import source_path

ROUNDS = 7
CALLS = 2000


def old_feed(splitter: object, chunk: bytes) -> list[object]:
    """``FrameSplitter.feed`` as it was: one Python iteration per byte."""
    s = splitter
    packets = []
    for byte in chunk:
        if byte != 0:
            if len(s._buffer) < s.MAX_ENCODED_BYTES:  # type: ignore[attr-defined]
                s._buffer.append(byte)  # type: ignore[attr-defined]
            else:
                s._overflow = True  # type: ignore[attr-defined]
            continue
        frame, overflow = bytes(s._buffer), s._overflow  # type: ignore[attr-defined]
        s._buffer.clear()  # type: ignore[attr-defined]
        s._overflow = False  # type: ignore[attr-defined]
        if overflow:
            s._count('length: frame longer than 64 bytes')  # type: ignore[attr-defined]
        elif frame:
            packet = s._decode(frame)  # type: ignore[attr-defined]
            if packet is not None:
                packets.append(packet)
    return packets


def per_call_us(job: Callable[[], object]) -> float:
    """CPU time of one call (us), the thread's own clock."""
    start = time.thread_time_ns()
    for _ in range(CALLS):
        job()
    return (time.thread_time_ns() - start) / CALLS / 1e3


def main() -> None:
    """Interleaved rounds of each pair; the medians and their ratio."""
    import sys

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--rounds', type=int, default=ROUNDS)
    args = parser.parse_args()
    sys.path[:0] = source_path().split(os.pathsep)
    from geometry_msgs.msg import WrenchStamped
    from rclpy.serialization import deserialize_message, serialize_message
    from uvms_common.cdr_codecs import MessageCodec, PayloadWriter
    from uvms_hardware.bridge_messages import stamp
    from uvms_hardware.reach_protocol import FrameSplitter, PacketId, encode_floats

    answer = (encode_floats(0x02, PacketId.POSITION, (1.25,))
              + encode_floats(0x02, PacketId.VELOCITY, (-0.5,)))
    old_splitter, new_splitter = FrameSplitter(), FrameSplitter()
    assert old_feed(old_splitter, answer) == new_splitter.feed(answer)

    wrench = ((1.0, -2.0, 3.5), (0.1, 0.2, -0.3))
    payload = PayloadWriter(MessageCodec(WrenchStamped, {'header.frame_id': 'ft_sensor_link'}),
                            ['wrench'])

    def typed() -> bytes:
        msg = WrenchStamped()
        msg.header.stamp = stamp(1_700_000_000_123_456_789)
        msg.header.frame_id = 'ft_sensor_link'
        (msg.wrench.force.x, msg.wrench.force.y, msg.wrench.force.z), (
            msg.wrench.torque.x, msg.wrench.torque.y, msg.wrench.torque.z) = wrench
        return serialize_message(msg)

    def raw() -> bytes:
        force, torque = wrench
        return payload.fill(1_700_000_000_123_456_789, (*force, *torque))

    # Equal as messages (rclpy leaves its alignment padding unwritten; ours is zeros).
    assert (deserialize_message(typed(), WrenchStamped)
            == deserialize_message(raw(), WrenchStamped)), 'the two wrench payloads differ'
    from rosgraph_msgs.msg import Clock
    from uvms_hardware.alpha5_core import FEEDBACK_REQUEST
    from uvms_hardware.reach_protocol import encode_request
    from uvms_hardware.robot_loop import _CLOCK_CDR, CDR_LE_HEADER

    requests = {0x02: encode_request(0x02, FEEDBACK_REQUEST)}

    def clock_typed() -> bytes:
        msg = Clock()
        msg.clock.sec, msg.clock.nanosec = divmod(1_700_000_000_123_456_789, 1_000_000_000)
        return serialize_message(msg)

    def clock_raw() -> bytes:
        return _CLOCK_CDR.pack(CDR_LE_HEADER, *divmod(1_700_000_000_123_456_789,
                                                      1_000_000_000))

    assert clock_typed() == clock_raw()
    pairs = {'alpha5 feed': (lambda: old_feed(old_splitter, answer),
                             lambda: new_splitter.feed(answer)),
             'netft wrench': (typed, raw),
             'alpha5 request': (lambda: encode_request(0x02, FEEDBACK_REQUEST),
                                lambda: requests[0x02]),
             'loop /clock': (clock_typed, clock_raw)}
    print(f'load: {" ".join(f"{v:.2f}" for v in os.getloadavg())}; {args.rounds} rounds of '
          f'{CALLS} calls, interleaved')
    for name, (before, after) in pairs.items():
        old_us, new_us = [], []
        for _ in range(args.rounds):
            old_us.append(per_call_us(before))
            new_us.append(per_call_us(after))
        ratios = [n / o for n, o in zip(new_us, old_us, strict=True)]
        print(f'{name}: before {statistics.median(old_us):.1f} us, after '
              f'{statistics.median(new_us):.1f} us per call (CPU); after/before median '
              f'{statistics.median(ratios):.2f} (rounds {min(ratios):.2f}-{max(ratios):.2f})')


if __name__ == '__main__':
    main()
