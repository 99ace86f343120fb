"""The simulator's start-up in real time: the first state held until the control loop closes.

Real time: physics must not run before the controller (and every node of
``startup.nodes``) answers, or the arm falls and the vehicle drifts unseen. The simulator
publishes its initial state and holds it (time stands still), publishing it again every
``HOLD_REPUBLISH_S`` for a late subscriber, until the loop is closed; past
``startup.timeout_s`` it stops with an error naming the node that did not answer.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from rclpy.node import Node
from uvms_common.process_stats import mark_first_step

from uvms_sim.errors import StartupError
from uvms_sim.startup_watch import StartGates, StartupWatch

if TYPE_CHECKING:
    from uvms_sim.navigation_topics import NavigationTopics
    from uvms_sim.parameters import SimulatorSettings
    from uvms_sim.plant import Plant

#: Real time, start-up: wall time between re-publications of the held initial state (s).
HOLD_REPUBLISH_S = 0.1


class StartupHold(Node):
    """The start-up part of ``SimulatorNode`` (its attributes are the simulator's)."""

    _settings: SimulatorSettings
    _plant: Plant
    _startup: StartupWatch | None
    _gates: StartGates
    _published: int
    _held_published_ns: int
    _navigation: NavigationTopics | None

    def _publish_state(self) -> None:
        """Publish the current state (the simulator's)."""
        raise NotImplementedError

    def _watch_startup(self) -> None:
        """Start watching for the loop to close, with a log line (after the first state)."""
        cfg = self._settings
        realtime = cfg.mode != 'lockstep'
        if realtime and not cfg.startup.hold:
            return
        now_ns = self.get_clock().now().nanoseconds
        self._startup = StartupWatch(self, cfg.startup, realtime, now_ns)
        self._startup.held_stamp_ns = self._plant.t_ns
        timeout = cfg.startup.timeout_ns * 1e-9
        self.get_logger().info(
            f'holding the initial state at t = {self._plant.t_ns * 1e-9:.3f} s (time stands '
            f'still) until the control loop is closed: waiting for '
            f'{self._startup.core.waiting_for()} '
            f'({f"startup.timeout_s {timeout:g} s" if timeout else "no start-up timeout"})')

    def _check_startup_time(self) -> None:
        """Stop with an error naming the node that did not answer, once the timeout passed."""
        watch = self._startup
        now_ns = self.get_clock().now().nanoseconds
        if watch is not None and watch.core.expired(now_ns):
            msg = watch.failure(now_ns)
            self.get_logger().fatal(msg)
            raise StartupError(msg)

    def _startup_closed(self) -> None:
        """The loop is closed: log it and drop the start-up subscription and clients."""
        watch = self._startup
        if watch is None or not watch.core.closed:
            return
        self._startup = None
        watch.destroy()
        waited = (self.get_clock().now().nanoseconds - watch.core.start_ns) * 1e-9
        self.get_logger().info(f'control loop closed after {waited:.2f} s: physics runs')
        mark_first_step()

    def _loop_closed(self, now_ns: int) -> bool:
        """Real time: hold (re-publish) the initial state until the loop is closed."""
        if self._published == 0:
            if not self._gates.first_state(now_ns):
                return False
            if not self._settings.startup.hold:
                return True
            self._publish_state()
            self._held_published_ns = now_ns
            self._watch_startup()
        watch = self._startup
        if watch is None:
            return True
        if watch.core.closed and self._gates.physics(now_ns):
            self._startup_closed()
            return True
        self._check_startup_time()
        if now_ns - self._held_published_ns >= HOLD_REPUBLISH_S * 1e9:
            if self._navigation is not None:  # before /clock, as _publish_state sends it
                self._navigation.republish_held()
            self._publish_state()
            self._held_published_ns = now_ns
        watch.poll(now_ns)
        return False
