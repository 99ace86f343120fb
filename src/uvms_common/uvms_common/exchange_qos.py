"""QoS of the subscriptions that carry the lockstep exchange (states and commands).

A lockstep exchange waits for one message per topic and stamp; if that message is lost the
simulator waits out ``lockstep_timeout_s`` and steps on the last command. A reliable reader
with ``KEEP_LAST`` depth 10 drops its oldest unread samples when more arrive: measured under
load (issue 29) with another process flooding the input topics at 100 Hz, the controller's
executor fell more than 100 ms behind and the flood pushed the exchange's own joint state out
of the history (no generalized force at t = 0.348 s, one lockstep timeout). In lockstep one
message per topic and step is all the graph sends, so a deep reader history costs nothing
and holds the exchange's message behind seconds of foreign input. Timer mode (real time)
keeps depth 10: there a backlog is stale data to skip, not to work through.
"""

from __future__ import annotations

from rclpy.qos import QoSProfile, ReliabilityPolicy

#: Reader history of a lockstep input (messages): 10 s of a 100 Hz flood per topic.
LOCKSTEP_INPUT_DEPTH = 1000
#: Reader history of an input in real time (messages), as the publishers offer.
REALTIME_INPUT_DEPTH = 10


def input_qos(lockstep: bool) -> QoSProfile:
    """Reliable QoS of a subscription to a state or command topic of the control loop."""
    depth = LOCKSTEP_INPUT_DEPTH if lockstep else REALTIME_INPUT_DEPTH
    return QoSProfile(depth=depth, reliability=ReliabilityPolicy.RELIABLE)
