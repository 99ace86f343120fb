"""The one base of every bridge node: the lifecycle written once, a device never left changed.

A bridge is a managed node over one device. The base runs the transitions and the subclass
says what each means for its device, through five hooks::

    class NetFtBridgeNode(BridgeNode):
        error_type = NetFtBridgeError             # what a failed autostart raises
        def configure_device(self) -> None: ...    # find and check; raise to refuse
        def activate_device(self) -> None: ...     # change the device (journal first)
        def put_device_back(self) -> list[str]: ...  # neutral, restore; the problems met
        def release_device(self) -> None: ...      # close the link
        def device_report(self) -> Report: ...     # /diagnostics

What the base guarantees, on every way out (as ros2_control's hardware components do):

- configure: a refusal (``HardwareError``, ``ValueError``, ``OSError``: the device's check)
  is one ``configure refused: ...`` line and FAILURE; anything else raised is logged with
  its traceback and ends in ERROR, then ``on_error``. Either way what configure had opened
  is released. A configure while a device is still held (after an error) puts that device
  back before it lets go of it: a second configure never loses the first's changes.
- activate: ``device_changed`` is set before the hook runs, so a refusal or an exception
  half-way through puts back whatever the hook had changed before the node answers. A stop
  during the node's build ends the process at once until then (configure changes nothing);
  from activate on it waits for the build and the put-back (``defer_stop_end``).
- deactivate, shutdown, ``on_error``, SIGINT and SIGTERM (``run_bridge``'s last word before
  the middleware teardown) put the device back; ``put_device_back`` is called at most once
  per activation and each of its problems is one error line.
- ``on_error`` (a transition that raised): device put back, link released, SUCCESS, so the
  node is unconfigured again, as rclcpp's lifecycle nodes recover.

Entities a configure creates (publishers, services, timers) are registered with ``own``
and destroyed in reverse order on cleanup and shutdown.
"""

from __future__ import annotations

import sys
import traceback
from collections.abc import Callable, Sequence
from typing import Any, ClassVar, TypeVar

from rclpy.exceptions import ParameterException
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from rclpy.qos import QoSProfile, ReliabilityPolicy
from uvms_common.diagnostics import ERROR, WARN, DiagnosticsPublisher, Report
from uvms_common.lifecycle import autostart, declare_autostart, guard_change_state, state_label
from uvms_common.node_main import run_node
from uvms_common.robot_parameters import declare_robot_name
from uvms_common.stop_event import defer_stop_end

from uvms_common import direct_topics
from uvms_hardware.device_clock import DeviceClock
from uvms_hardware.errors import HardwareError

__all__ = ['DEVICE_TOPIC_QOS', 'FAILURE', 'REFUSALS', 'SUCCESS', 'BridgeNode', 'run_bridge']

SUCCESS, FAILURE = TransitionCallbackReturn.SUCCESS, TransitionCallbackReturn.FAILURE
ERROR_RETURN = TransitionCallbackReturn.ERROR
#: What a device's check raises to refuse a transition: one line, no traceback.
REFUSALS: tuple[type[Exception], ...] = (HardwareError, ValueError, OSError)
#: A device topic's publisher (joint_states, imu, depth, dvl, wrench, ...): reliable, keep
#: last 100. A reliable writer drops what its history no longer holds, acknowledged or not:
#: with rclpy's depth 10 the recorder, at normal priority beside a SCHED_FIFO twin stand, lost
#: whatever came while it was starved (a stand's surge run kept 120 of 383 DVL reports, issue
#: 50). 100 is 2 s of the 50 Hz IMU, 0.2 s of a 500 Hz wrench; the commands' subscriptions
#: stay at depth 10 (only the newest matters).
DEVICE_TOPIC_QOS = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)

B = TypeVar('B', bound='BridgeNode')


class BridgeNode(LifecycleNode):
    """A managed node over one device; subclasses fill in the ``*_device`` hooks."""

    #: Raised by the constructor when autostart cannot configure and activate.
    error_type: ClassVar[type[Exception]] = HardwareError
    #: The task name of the node's /diagnostics status (``"<node>: <task>"``).
    diagnostics_task: ClassVar[str] = 'device'

    def __init__(self, node_name: str, **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        self._device_clock = DeviceClock(self)
        self.robot_name = declare_robot_name(self)
        #: Why the last configure or activate was refused ('' when it was not).
        self.refusal = ''
        #: True from the moment activate may change the device until it is put back.
        self.device_changed = False
        #: True while the device is driven or streamed (between activate and its way out).
        self.device_active = False
        #: True while configure's link is held (between configure and release).
        self.device_held = False
        self._entities: list[tuple[Callable[[Any], Any], Any]] = []
        self._starting = False

    def start(self) -> None:
        """Declare autostart, guard change_state, start /diagnostics, configure and activate.

        Call at the end of the subclass's constructor, after its parameters are declared.

        Raises:
            error_type: autostart could not configure and activate (the refusal named).
        """
        self._starting = declare_autostart(self)
        guard_change_state(self)
        self._diagnostics = DiagnosticsPublisher(self, self.robot_name)
        self._diagnostics.add(self.diagnostics_task, self._report)
        if self._starting and not autostart(self):
            message = self.refusal or f'{self.get_name()}: cannot configure and activate'
            self.destroy_node()
            raise self.error_type(message)

    # -- the subclass's hooks ----------------------------------------------------------------
    def configure_device(self) -> None:
        """Find the device and check it; raise a ``REFUSALS`` error naming what is wrong."""

    def activate_device(self) -> None:
        """Change on the device what driving it needs (journal the originals first)."""

    def put_device_back(self) -> list[str]:
        """Leave the device at rest and as found; return what could not be done."""
        return []

    def release_device(self) -> None:
        """Close the link (configure's counterpart); nothing is sent to the device here."""

    def device_report(self) -> Report:
        """The device's health while configured."""
        return Report(WARN, 'no report', {})

    # -- helpers for the subclass ------------------------------------------------------------
    def now_s(self) -> float:
        """The steady clock (s): the device's times (``uvms_hardware.device_clock``)."""
        return self._device_clock.now_s()

    def device_timer(self, period_s: float, callback: Callable[[], None],
                     then: Callable[[], None] | None = None) -> Any:
        """A timer on the steady clock, destroyed with the configure's other entities.

        ``then`` (a device's write) runs right after ``callback`` (its read); in the robot
        process (``uvms_common.direct_topics``) the loop calls ``callback`` at ``period_s``
        before its control step and ``then`` after it.
        """
        return self.own(*direct_topics.device_timer(self, period_s, callback,
                                                     self._device_clock.timer, then))

    def subscribe(self, msg_type: Any, topic: str, callback: Callable[[Any], None],
                  qos: Any) -> Any:
        """A subscription (direct in the robot process), destroyed with the entities."""
        return self.own(*direct_topics.subscribe(self, msg_type, topic, callback, qos))

    def own(self, destroy: Callable[[Any], Any], entity: Any) -> Any:
        """Register an entity configure created; ``destroy(entity)`` runs at release."""
        self._entities.append((destroy, entity))
        return entity

    def update_diagnostics(self) -> None:
        """Publish /diagnostics now (a change the graph may act on at once)."""
        self._diagnostics.update()

    # -- transitions ---------------------------------------------------------------------------
    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Check the device (a device still held is put back and released first)."""
        if self.device_held:
            self._put_back()
            self._release()
        self.refusal = ''
        self.device_held = True
        result = self._guarded('configure', self.configure_device)
        if result != SUCCESS:
            self._release()
        return result

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Change the device for driving; whatever fails half-way is put back."""
        self.refusal = ''
        defer_stop_end()  # a stop now waits for the build and the put-back
        self.device_changed = True
        result = self._guarded('activate', self.activate_device)
        if result != SUCCESS:
            self._put_back()
            return result
        self.device_active = True
        return super().on_activate(state)

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Put the device back (neutral, restored)."""
        self._put_back()
        return super().on_deactivate(state)

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Release the link and the entities."""
        self._release()
        return super().on_cleanup(state)

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        """From any state: put the device back, release everything."""
        self._put_back()
        self._release()
        return super().on_shutdown(state)

    def on_error(self, state: LifecycleState) -> TransitionCallbackReturn:
        """A transition raised: put the device back, release, back to unconfigured."""
        self.get_logger().error(f'error while {state.label}: device put back and released; '
                                'the node is unconfigured')
        self._put_back()
        self._release()
        return SUCCESS

    def destroy_node(self) -> None:
        """Shut down as rclcpp's lifecycle node does (device put back), then destroy."""
        if state_label(self) not in ('finalized', 'unknown') and self.context.ok():
            self.trigger_shutdown()
        self._put_back()
        if hasattr(self, '_diagnostics'):
            self._diagnostics.destroy()
        super().destroy_node()

    def put_back_now(self) -> None:
        """The process's last word to the device (``run_bridge``, before the teardown)."""
        self._put_back()

    # -- internals -----------------------------------------------------------------------------
    def _guarded(self, word: str, hook: Callable[[], None]) -> TransitionCallbackReturn:
        try:
            hook()
        except REFUSALS as exc:
            self.refusal = str(exc)
            self.get_logger().error(f'{word} refused: {exc}')
            return FAILURE
        except Exception as exc:  # a bug, not a refusal: the traceback says where
            self.refusal = f'{type(exc).__name__}: {exc}'
            self.get_logger().error(f'{word} raised {self.refusal}\n{traceback.format_exc()}')
            return ERROR_RETURN
        return SUCCESS

    def _put_back(self) -> None:
        self.device_active = False
        if not self.device_changed:
            return
        self.device_changed = False
        try:
            problems = self.put_device_back()
        except Exception as exc:
            problems = [f'{type(exc).__name__}: {exc}']
        for problem in problems:
            self.get_logger().error(f'putting the device back: {problem}')

    def _release(self) -> None:
        for destroy, entity in reversed(self._entities):
            try:
                destroy(entity)
            except Exception as exc:  # an entity already gone must not keep the link open
                self.get_logger().warning(f'release: {type(exc).__name__}: {exc}')
        self._entities = []
        if self.device_held:
            self.device_held = False
            self.release_device()

    def _report(self) -> Report:
        state = state_label(self)
        if not self.device_held:
            text = self.refusal or 'not configured'
            return Report(ERROR if self.refusal else WARN, f'{state}: {text}',
                          {'lifecycle_state': state})
        report = self.device_report()
        return Report(report.level, report.message, {'lifecycle_state': state,
                                                     **report.values})


def run_bridge(node_type: type[B], args: Sequence[str] | None, logger_name: str,
               startup_errors: tuple[type[Exception], ...] = ()) -> None:
    """Run a bridge node until SIGINT/SIGTERM and exit; the device is put back first."""
    sys.exit(run_node(node_type, args, logger_name,
                      (node_type.error_type, HardwareError, ParameterException,
                       *startup_errors),
                      close_output=lambda node: node.put_back_now()))
