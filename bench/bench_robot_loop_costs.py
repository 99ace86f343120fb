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
  publishes it now;
- ``device clock``: a bridge's steady time as ``Clock.now()`` of a steady rclpy clock (before)
  vs. ``time.monotonic_ns()`` (``device_clock.DeviceClock.now_s``, the same CLOCK_MONOTONIC);
- ``node clock``: a node's clock as ``get_clock().now().nanoseconds`` (before) vs.
  ``clock_read.now_ns`` (the same read, no ``Time`` built);
- ``odometry covariances``: the estimator's pose and twist covariances computed at each
  published estimate (before) vs. once per filter change (``eskf``), one change in 10
  periods as at the twin stand (IMU 50 Hz, control 500 Hz);
- ``actuators to 2 bridges``: the allocator's CDR command deserialized for each typed
  subscriber (before) vs. once (``robot_loop.deliver``);
- ``t200 pwm x8``: a period's 8 thrusts to PWM with each branch of the curve found by
  ``np.flatnonzero`` per call (before) vs. found once per curve (``t200_curve``);
- ``device clock estimate``: one arrival of a 500 Hz stream taken and ``rates_agree`` asked
  (as the Net F/T bridge does each record) with the rate history's convex hull built at each
  ask (before) vs. once per finished block (``device_time``);
- ``device clock stamp``: one record of a 500 Hz stream (the Net F/T's) taken and stamped
  with the envelope fitted anew at each new minimum of the filling bucket (before) vs. only
  when a finished bucket comes or goes (``device_time``: the filling one is not in the fit).

The pairs are checked to give the same values first. It asserts nothing else. Usage::

    .venv/bin/python bench/bench_robot_loop_costs.py [--rounds N]
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import time
from collections.abc import Callable
from typing import Any

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


def old_pwm_from_thrust(curve: Any, thrust_n: float, voltage_v: float | None) -> float:
    """``T200Curve.pwm_from_thrust`` as it was: both branches found at each call."""
    import math

    import numpy as np
    if not math.isfinite(thrust_n) or thrust_n == 0.0:
        return float(curve.neutral_pwm_us)
    grid, thrust = curve._grid
    target = thrust_n / curve.voltage_scale(voltage_v)
    if target > 0.0:
        start = int(np.flatnonzero(thrust <= 0.0)[-1])
        g, f = grid[start:], thrust[start:]
    else:
        stop = int(np.flatnonzero(thrust >= 0.0)[0])
        g, f = grid[:stop + 1], thrust[:stop + 1]
    return float(np.interp(target, f, g))


def period_pairs() -> dict[str, tuple[Callable[[], object], Callable[[], object]]]:
    """The pairs of the per-period cuts (clock reads, covariances, deserialization, PWM)."""
    import numpy as np
    from rclpy.clock import Clock, ClockType, ROSClock
    from rclpy.serialization import deserialize_message, serialize_message
    from uvms_common.clock_read import now_ns
    from uvms_hardware.device_clock import DeviceClock
    from uvms_hardware.device_time import DeviceClockEstimator, lower_envelope
    from uvms_hardware.hardware_config import hardware_section
    from uvms_hardware.t200_curve import T200Curve
    from uvms_model.nav_sensor_parameters import NavigationParameters
    from uvms_navigation.eskf import ErrorStateEkf, EstimatorSettings

    from uvms_msgs.msg import ActuatorCommand

    steady = Clock(clock_type=ClockType.STEADY_TIME)
    device = DeviceClock.__new__(DeviceClock)  # no node: now_s reads no node
    device.clock = steady
    ros = ROSClock()
    ekf = ErrorStateEkf(EstimatorSettings(NavigationParameters()))
    ekf.reset_from_ahrs(0, [0.0, 0.0, 2.0], [0.1, -0.05, 0.7])
    ekf.predict(20_000_000, [0.01, 0.02, -0.01], [0.1, 0.0, -9.8])
    assert np.array_equal(ekf.pose_covariance(), ekf._pose_covariance())
    periods = [0, 0]

    def covariances_before() -> object:
        return ekf._pose_covariance(), ekf._twist_covariance()

    def covariances_after() -> object:
        periods[0] += 1
        if periods[0] % 10 == 0:
            ekf.cov = ekf.cov.copy()  # a filter change: a new covariance array
        return ekf.pose_covariance(), ekf.twist_covariance()

    command = ActuatorCommand(thrust=[1.5, -2.0, 0.3, 0.0, 4.0, -6.0, 2.5, -0.7],
                              joint_names=['a', 'b', 'c', 'd', 'e'],
                              joint_torques=[0.1, 0.2, 0.3, 0.4, 0.5])
    data = serialize_message(command)

    def deserialize_each() -> object:
        return [deserialize_message(data, ActuatorCommand) for _ in range(2)]

    def deserialize_once() -> object:
        msg = deserialize_message(data, ActuatorCommand)
        return [msg, msg]

    curve = T200Curve.from_section(hardware_section('bluerov2_alpha5', 'ardusub')[1]['t200'])
    thrusts = command.thrust.tolist()
    assert [old_pwm_from_thrust(curve, t, 15.8) for t in thrusts] == [
        curve.pwm_from_thrust(t, 15.8) for t in thrusts]
    estimates = [DeviceClockEstimator(), DeviceClockEstimator()]
    arrivals = [0, 0]

    def arrival(which: int) -> DeviceClockEstimator:
        estimate = estimates[which]
        arrivals[which] += 1
        device_s = arrivals[which] / 500.0
        estimate.add(device_s, device_s + 3.0 + 0.0005 * (arrivals[which] * 7919 % 13))
        return estimate

    def rates_agree_before() -> object:
        finished = [point for _, point in arrival(0)._history][:-1]
        return len(finished) < 4 or abs(lower_envelope(finished, math.inf)[2]) < 0.01

    for _ in range(5000):
        assert rates_agree_before() == arrival(1).rates_agree

    class RefitAtEveryMinimum(DeviceClockEstimator):
        """Before: the envelope fitted anew at each new minimum of the filling bucket."""

        def add(self, device_s: float, arrival_s: float) -> None:
            buckets = len(self._buckets)
            super().add(device_s, arrival_s)
            self._dirty = self._dirty or len(self._buckets) == buckets

    stamped = [RefitAtEveryMinimum(5.0, 0.1, 0.1), DeviceClockEstimator(5.0, 0.1, 0.1)]
    records = [0, 0]

    def stamp_record(which: int) -> float | None:
        """A Net F/T record at 500 Hz taken and stamped (``netft_core``'s estimator)."""
        records[which] += 1
        device_s = records[which] / 500.0
        delay_s = 0.0002 + 0.001 * ((records[which] * 7919) % 101) / 101.0
        stamped[which].add(device_s, device_s + 3.0 + delay_s)
        return stamped[which].to_local(device_s)

    for _ in range(5000):
        assert stamp_record(0) == stamp_record(1)
    return {'device clock': (lambda: steady.now().nanoseconds * 1e-9, device.now_s),
            'node clock': (lambda: ros.now().nanoseconds, lambda: now_ns(ros)),
            'odometry covariances': (covariances_before, covariances_after),
            'actuators to 2 bridges': (deserialize_each, deserialize_once),
            't200 pwm x8': (lambda: [old_pwm_from_thrust(curve, t, 15.8) for t in thrusts],
                            lambda: [curve.pwm_from_thrust(t, 15.8) for t in thrusts]),
            'device clock estimate': (rates_agree_before, lambda: arrival(1).rates_agree),
            'device clock stamp': (lambda: stamp_record(0), lambda: stamp_record(1))}


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
    pairs.update(period_pairs())
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
