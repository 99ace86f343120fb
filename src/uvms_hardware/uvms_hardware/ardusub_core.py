"""The ArduSub component's decisions, pure: no sockets, no clock of its own, no ROS.

What the running path decides each period, from times the caller passes (steady s) and what
the link last heard, so that a test (or a loop replaying a log) drives it without a vehicle::

    core = ArduSubCore(thrusters=8, watchdog_timeout_s=0.1, link_timeout_s=1.0)
    core.configured(now_s)                      # telemetry was asked for at configure
    problem = core.command(thrusts_n, now_s)    # None: taken (watchdog fed); else why not
    decision = core.poll(now_s, link_age_s)     # at each read: lost link, re-request due
    thrusts_n = core.output(now_s)              # at each write; None: 1500 us on every one

`Exchange` decides a request's tries (when to send it again, when no answer can come any
more) for the link's parameter reads and commands. The words at the edges: `choose_mode`
(script or passthrough, from what configure heard), `put_back_summary` (the console line of
a stop) and `ArduSubCore.health` (the report's level and line).
The link's conversations that wait for the vehicle's answers (configure, activate, restore,
each bounded) are driven in `uvms_hardware.ardusub_link`; the running path never waits.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from uvms_hardware.errors import DeviceCheckError
from uvms_hardware.watchdog import CommandWatchdog

#: Telemetry intervals are asked for again this often (s), as RDML's ardusub_manager does.
TELEMETRY_REQUEST_PERIOD_S = 20.0
PASSTHROUGH, SCRIPT = 'passthrough', 'script'
AUTO = 'auto'
WATCHDOG_CHOICES = (AUTO, SCRIPT, PASSTHROUGH)
#: Report levels (diagnostic_msgs numbering).
OK, WARN, ERROR = 0, 1, 2


@dataclass(frozen=True)
class LinkDecision:
    """What one read of the link decides.

    Attributes:
        request_telemetry: Ask for the telemetry intervals again now (without waiting).
        link_lost: The vehicle has been silent for more than ``link_timeout_s``.
        link_lost_changed: ``link_lost`` differs from the last read's (say so at once).
    """

    request_telemetry: bool
    link_lost: bool
    link_lost_changed: bool


class ArduSubCore:
    """Command watchdog, command checks, lost-link edge and telemetry re-requests."""

    def __init__(self, thrusters: int, watchdog_timeout_s: float, link_timeout_s: float,
                 request_period_s: float = TELEMETRY_REQUEST_PERIOD_S) -> None:
        """A core for ``thrusters`` thrusters.

        Args:
            thrusters: How many thrusts a command carries.
            watchdog_timeout_s: No command this long: neutral (s).
            link_timeout_s: Vehicle silent this long: the link is lost (s).
            request_period_s: Telemetry intervals asked for again this often (s).
        """
        self.thrusters = thrusters
        self.watchdog = CommandWatchdog(watchdog_timeout_s)
        self.link_timeout_s = link_timeout_s
        self.request_period_s = request_period_s
        #: The last command taken (N per thruster), None until one after activate.
        self.thrusts_n: tuple[float, ...] | None = None
        #: Commands refused (wrong length, not finite).
        self.rejected = 0
        self.link_lost = False
        self._next_request_s = math.inf

    def configured(self, now_s: float) -> None:
        """Telemetry was asked for at ``now_s``: the next request is one period later."""
        self._next_request_s = now_s + self.request_period_s

    def activated(self) -> None:
        """A new activation: no command yet (neutral until one comes)."""
        self.thrusts_n = None

    def command(self, thrusts_n: Sequence[float], now_s: float) -> str | None:
        """Take a command (feeds the watchdog); None, or why it was refused."""
        thrusts = tuple(float(t) for t in thrusts_n)
        if len(thrusts) != self.thrusters or not all(math.isfinite(t) for t in thrusts):
            self.rejected += 1
            return f'{len(thrusts)} thrusts (expected {self.thrusters} finite)'
        self.thrusts_n = thrusts
        self.watchdog.feed(now_s)
        return None

    def poll(self, now_s: float, link_age_s: float) -> LinkDecision:
        """At a read at ``now_s``, the vehicle last heard ``link_age_s`` ago (s)."""
        request = now_s >= self._next_request_s
        if request:  # a rebooted autopilot forgets the intervals
            self._next_request_s = now_s + self.request_period_s
        lost = link_age_s > self.link_timeout_s
        changed, self.link_lost = lost != self.link_lost, lost
        return LinkDecision(request, lost, changed)

    def output(self, now_s: float) -> tuple[float, ...] | None:
        """The thrusts (N) to send now; None: neutral (no command yet, or the watchdog expired)."""
        if self.thrusts_n is None or self.watchdog.expired(now_s):
            return None
        return self.thrusts_n

    def health(self, now_s: float, link_age_s: float, active: bool, warnings: Sequence[str],
               clocks_agree: bool = True) -> tuple[int, str]:
        """(level, message) of the report: silent vehicle, clocks, no command, warnings."""
        if link_age_s > self.link_timeout_s:
            return ERROR, f'vehicle silent for {link_age_s:.1f} s'
        if not clocks_agree:
            return WARN, ("the autopilot's clock does not run at the node clock's rate (beside "
                          "a simulator, the twin must run on the plant's time): telemetry "
                          'stamped at arrival')
        if active and self.watchdog.expired(now_s):
            return WARN, 'no command: thrusters neutral'
        return (WARN, warnings[0]) if warnings else (OK, 'running')


class Exchange:
    """One request and its answer: sent up to ``tries`` times, ``reply_timeout_s`` apart.

    Pure (the caller passes its steady time, s, and sends): each try waits
    ``reply_timeout_s`` for the answer, and nothing is sent or waited for past ``end_s``::

        exchange = Exchange(tries=3, reply_timeout_s=0.5)
        while not answered:
            if exchange.due(now_s): send(confirmation=exchange.sent - 1)
            elif exchange.over(now_s): break          # no answer
    """

    def __init__(self, tries: int, reply_timeout_s: float, end_s: float = math.inf) -> None:
        self.tries, self.reply_timeout_s, self.end_s = tries, reply_timeout_s, end_s
        #: Tries sent so far.
        self.sent = 0
        self._try_end_s = -math.inf

    def due(self, now_s: float) -> bool:
        """True when the request is to be sent now (counted): the first, or a try ran out."""
        if now_s >= self.end_s or self.sent >= self.tries or now_s < self._try_end_s:
            return False
        self.sent += 1
        self._try_end_s = min(self.end_s, now_s + self.reply_timeout_s)
        return True

    def over(self, now_s: float) -> bool:
        """True when no answer can come in time: ``end_s`` passed, or every try ran out."""
        return now_s >= self.end_s or (self.sent >= self.tries and now_s >= self._try_end_s)


def choose_mode(wanted: str, heard_timeout_ms: float | None, script_outputs: Sequence[int],
                thruster_channels: Sequence[int], script_name: str, script_wait_s: float
                ) -> str:
    """SCRIPT when the autopilot's watchdog script was heard (and is wanted), else PASSTHROUGH.

    Raises:
        DeviceCheckError: The script drives other outputs than the thrusters', or
            ``wanted`` is script and it was not heard.
    """
    if wanted not in WATCHDOG_CHOICES:
        raise DeviceCheckError(f'autopilot_watchdog = {wanted!r}: expected one of '
                               f'{", ".join(WATCHDOG_CHOICES)}')
    if wanted != PASSTHROUGH and heard_timeout_ms is not None:
        if set(script_outputs) != set(thruster_channels):
            raise DeviceCheckError(
                f'{script_name} drives outputs {list(script_outputs)}, thruster_channels '
                f'are {list(thruster_channels)}: make them the same')
        return SCRIPT
    if wanted == SCRIPT:
        raise DeviceCheckError(f'{script_name} not heard from the autopilot within '
                               f'{script_wait_s:g} s and autopilot_watchdog = script: install '
                               'it (docs/hardware.md)')
    return PASSTHROUGH


def put_back_summary(changed: Mapping[int, float], still_changed: Mapping[int, float],
                     problems: Sequence[str], mode: str) -> str:
    """The stop's one line: what was put back (after ``put back: ``).

    Args:
        changed: SERVOn_FUNCTIONs changed before the restore: output -> original value.
        still_changed: Those the restore did not read back.
        problems: What the restore reported.
        mode: PASSTHROUGH or SCRIPT.
    """
    if any('sent without confirmation' in p for p in problems):
        return ("vehicle silent: neutral, disarm, overrides released and the outputs' "
                'functions SENT, none confirmed')
    disarm = ('disarm NOT confirmed' if any(p.startswith(('disarm', 'arm:')) for p in problems)
              else 'disarmed')
    done = f'thrusters neutral (1500 us), {disarm}, RC overrides released'
    restored = {c: v for c, v in changed.items() if c not in still_changed}
    if restored:
        done += ', SERVOn_FUNCTION restored and read back (' + ', '.join(
            f'{c}={v:g}' for c, v in sorted(restored.items())) + ')'
    if still_changed:
        done += ', NOT read back: ' + ', '.join(
            f'SERVO{c}_FUNCTION' for c in sorted(still_changed)) + \
            ' (journal kept: uvms hardware restore ardusub)'
    if not changed:
        done += f'; no parameter had been changed ({mode} mode)'
    return done
