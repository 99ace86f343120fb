"""Where the robot loop's thread spends its CPU: per phase of a period and per published topic.

The robot process runs everything on one thread (the executor's), so the thread's own CPU
clock (``time.thread_time_ns``) splits it without a profiler: a relative measure that holds
under load (CPU time, not wall time). The loop charges each span of its period to a phase
(``outside``: the executor between two periods, its /clock time sources, services and the
nodes' other timers; ``read <node>``: a device's read and publish; ``control``: the chain from
the estimator to the writes it makes; ``write <node>``: a device's write after the chain) and
each publish on DDS to its topic (the middleware's send only, not the direct deliveries that
follow it, which belong to their phase).

Pure: no rclpy.
"""

from __future__ import annotations

import time
from collections import defaultdict
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

__all__ = ['LoopLedger', 'NullLedger', 'make_ledger']

#: Environment variable that switches the ledger on (``1``): its own cost is a few
#: microseconds per phase and publish (two reads of the thread's CPU clock, a system call
#: each), 5-10 % of the loop's CPU, so it is off unless a bench or a user asks for it.
LEDGER_ENV = 'UVMS_LOOP_CPU'


@dataclass
class LoopLedger:
    """CPU time (ns) and counts per phase and per published topic.

    The phases nest (a delivery inside the control chain, a publish inside a delivery): the
    time between two events is charged to the innermost phase open, so the figures add up to
    the thread's CPU and none is counted twice.
    """

    phase_ns: dict[str, int] = field(default_factory=lambda: defaultdict(int))
    phase_calls: dict[str, int] = field(default_factory=lambda: defaultdict(int))
    publish_ns: dict[str, int] = field(default_factory=lambda: defaultdict(int))
    publishes: dict[str, int] = field(default_factory=lambda: defaultdict(int))
    #: Publishes left out because no subscriber took the topic, per topic.
    skipped: dict[str, int] = field(default_factory=lambda: defaultdict(int))

    enabled = True
    clock: Callable[[], int] = time.thread_time_ns
    _stack: list[str] = field(default_factory=list)
    _since_ns: int | None = None

    def enter(self, phase: str) -> None:
        """From now on the thread's CPU goes to ``phase`` (until `leave`)."""
        now_ns = self.clock()
        if self._stack and self._since_ns is not None:
            self.phase_ns[self._stack[-1]] += now_ns - self._since_ns
        self._stack.append(phase)
        self.phase_calls[phase] += 1
        self._since_ns = now_ns

    def leave(self) -> int:
        """Close the innermost phase; the thread's CPU clock now (ns)."""
        now_ns = self.clock()
        if self._stack and self._since_ns is not None:
            self.phase_ns[self._stack.pop()] += now_ns - self._since_ns
        self._since_ns = now_ns
        return now_ns

    def switch(self, phase: str) -> None:
        """Close the innermost phase and open ``phase`` in its place."""
        self.leave()
        self.enter(phase)

    def publish(self, topic: str, send: Callable[[object], None], msg: object) -> None:
        """``send(msg)`` (a DDS publish), its CPU charged to ``topic`` and to ``dds publish``."""
        self.enter('dds publish')
        start_ns = self._since_ns or 0
        send(msg)
        self.publish_ns[topic] += self.leave() - start_ns
        self.publishes[topic] += 1

    def lines(self, periods: int, seconds: float) -> list[str]:
        """The figures: CPU per period by phase, and per topic its rate and cost per publish.

        Args:
            periods: The loop's periods over the figures.
            seconds: The wall time they took (s), for the rates.
        """
        if periods <= 0 or seconds <= 0.0:
            return ['robot loop CPU: no period']
        total = sum(self.phase_ns.values())
        phases = ', '.join(
            f'{name} {ns / periods / 1e3:.1f}' for name, ns in
            sorted(self.phase_ns.items(), key=lambda item: -item[1]) if ns > 0)
        sent = sum(self.publish_ns.values())
        topics = ', '.join(
            f'{topic} {self.publishes[topic] / seconds:.0f}/s x '
            f'{ns / max(self.publishes[topic], 1) / 1e3:.0f} us'
            for topic, ns in sorted(self.publish_ns.items(), key=lambda item: -item[1]))
        out = [f'robot loop CPU per period (us): {total / periods / 1e3:.0f} = {phases}; '
               f'{100.0 * total / (seconds * 1e9):.0f} % of one core over {seconds:.1f} s',
               f'robot loop DDS publishing: {sent / periods / 1e3:.0f} us per period '
               f'(within the phases): {topics or "none"}']
        if any(self.skipped.values()):
            out.append('robot loop: not published (no subscriber): ' + ', '.join(
                f'{topic} {n}' for topic, n in sorted(self.skipped.items()) if n))
        return out


class NullLedger(LoopLedger):
    """The ledger switched off: no clock read, nothing counted."""

    enabled = False

    def enter(self, phase: str) -> None:
        """Nothing."""

    def leave(self) -> int:
        """Nothing (0)."""
        return 0

    def switch(self, phase: str) -> None:
        """Nothing."""

    def publish(self, topic: str, send: Callable[[object], None], msg: object) -> None:
        """``send(msg)``."""
        send(msg)

    def lines(self, periods: int, seconds: float) -> list[str]:
        """No figures."""
        return []


def make_ledger(environ: Mapping[str, str]) -> LoopLedger:
    """A `LoopLedger` when ``UVMS_LOOP_CPU`` is ``1`` in ``environ``, else a `NullLedger`."""
    return LoopLedger() if environ.get(LEDGER_ENV, '') == '1' else NullLedger()
