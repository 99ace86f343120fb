"""The ArduSub twin takes overrides into its RC inputs at 50 Hz, as ArduSub's RC read does.

ArduSub stores RC_CHANNELS_OVERRIDE on receipt and reads its RC inputs in ``fifty_hz_loop``
(``rc().read_input()``, scheduled at 50 Hz in ``ArduSub/ArduSub.cpp``): a passthrough output
and the watchdog script's ``rc:get_pwm`` change only at those reads, whatever rate the
bridge sends at (issue 49: the twin used to apply each override at once).
"""

from __future__ import annotations

import itertools
import statistics
import time

from test_mavlink_twin import gcs, override, wait
from uvms_twins.ardusub_twin import RC_READ_HZ, ArduSubTwin
from uvms_twins.periodic_task import next_run_s

#: The bridge's override rate (ardusub_bridge ``override_rate_hz`` default).
BRIDGE_RATE_HZ = 60.0


def test_a_passthrough_output_changes_only_at_the_50_hz_rc_read() -> None:
    """Overrides at 200 Hz, each a new value: the output changes about 50 times a second."""
    with ArduSubTwin(parameters={'SERVO1_FUNCTION': 51}) as twin:
        conn = gcs(twin)
        override(conn, [1600] + [0] * 7)
        wait(lambda: twin.servo_outputs_us()[0] == 1600, 2.0, 'the first override')
        changes: list[float] = []
        last = twin.servo_outputs_us()[0]
        start = time.monotonic()
        next_send = start
        value = 1600
        while time.monotonic() - start < 1.0:
            now = time.monotonic()
            if now >= next_send:
                value += 1  # a new value each message: every read finds another
                override(conn, [value] + [0] * 7)
                next_send += 1.0 / 200.0
            output = twin.servo_outputs_us()[0]
            if output != last:
                changes.append(now)
                last = output
            time.sleep(0.0005)
        conn.close()
        reads = twin.rc_read_times()
    spacing = statistics.median(b - a for a, b in zip(reads[-40:], reads[-39:], strict=False))
    assert abs(spacing - 1.0 / RC_READ_HZ) < 0.003, f'RC reads {spacing * 1e3:.1f} ms apart'
    # One change per RC read, not one per message (200).
    assert RC_READ_HZ * 0.8 <= len(changes) <= RC_READ_HZ * 1.1, (
        f'{len(changes)} output changes in 1 s')


def test_the_watchdog_script_keeps_driving_at_the_bridges_rate_through_the_50_hz_reads() -> None:
    """Toggled overrides at 60 Hz on RC 9-16, read at 50 Hz: no neutral in 3 s (no aliasing).

    Between two reads one or two messages arrive; two leave the toggle as it was, so the
    script sees no flip at that read, but never for 100 ms (its timeout) at 60 Hz.
    """
    with ArduSubTwin(watchdog_script=True) as twin:
        conn = gcs(twin)
        conn.mav.command_long_send(1, 1, 400, 0, 1.0, 0, 0, 0, 0, 0, 0)  # arm
        wait(lambda: twin.armed, 2.0, 'armed')
        start = time.monotonic()
        next_send = start
        parity = 0
        lowest = 2000
        while time.monotonic() - start < 3.0:
            now = time.monotonic()
            if now >= next_send:
                override(conn, [0] * 8, [1700 + parity] * 8 + [0, 0])
                parity ^= 1
                next_send += 1.0 / BRIDGE_RATE_HZ
            if now - start > 0.5:  # the script has taken over the outputs
                lowest = min(lowest, *twin.servo_outputs_us()[:8])
            time.sleep(0.001)
        conn.close()
    assert lowest >= 1690, f'an output went to {lowest} us while the bridge was commanding'


def test_a_read_that_ran_late_is_not_caught_up_with_reads_back_to_back() -> None:
    """As AP_Scheduler: a late RC read runs once; the next is a period after it, not at once.

    The twin's loop polls every 2 ms at most; a thread that got no CPU for 70 ms (a busy
    machine) then finds three reads missed. Before, it read again at once (reads 0 ms apart).
    """
    period = 1.0 / RC_READ_HZ
    assert next_run_s(1.0, 1.0015, period) == 1.0 + period  # on time: the grid is kept
    reads, due = [], 0.0
    polls = [k * 0.002 for k in range(200)]
    polls = [t for t in polls if not 0.1 < t < 0.17] + [0.17 + k * 0.002 for k in range(3)]
    for now in sorted(set(polls)):
        if now >= due:
            reads.append(now)
            due = next_run_s(due, now, period)
    spacings = [b - a for a, b in itertools.pairwise(reads)]
    assert min(spacings) > period - 0.0025, f'reads {min(spacings) * 1e3:.1f} ms apart'
    assert max(spacings) < 0.1, 'the reads went on after the stall'
