"""The controller node's safety: checked parameter transactions, halts, faults, the allocator.

``ControllerSafety`` holds the methods of ``ControllerNode`` that keep it safe, in a module
of their own: a ``set_parameters`` call checked whole before anything changes; control
stopped (zero command, the running task ended INPUTS_STALE) while inputs are stale or the
thruster allocator is not active, and the hold re-captured when it resumes; any exception
answered with zero generalized force (``_fault``). They use the node's ``core``,
``supervisor``, ``tasks``, ``_gains``, ``_safety``, ``_active``, ``_entities``,
``_allocator``, ``_halted``, ``_faults``, ``_last_stamp_ns``, ``_watchdog_ns`` and ``_zero``.
"""

from __future__ import annotations

from typing import Any

from rcl_interfaces.msg import SetParametersResult
from rclpy.parameter import Parameter

from uvms_control.core.errors import ControlParameterError
from uvms_control.core.parameters import ControllerParameters
from uvms_control.core.task.contact_task import SafetyLimits, TaskCode
from uvms_control.node_safety import AllocatorWatch, guarded


def safety_limits(values: dict[str, Any]) -> SafetyLimits:
    """``safety.*`` parameter values as limits."""
    return SafetyLimits(**{name.removeprefix('safety.'): float(value)
                           for name, value in values.items()})


class ControllerSafety:
    """Safety methods of the controller node (a mixin of ``ControllerNode``)."""

    core: Any
    supervisor: Any
    tasks: Any
    _gains: dict[str, Any]
    _safety: dict[str, Any]
    _active: bool
    _entities: list[Any]
    _allocator: AllocatorWatch | None
    _halted: str | None
    _faults: Any
    _last_stamp_ns: int
    _watchdog_ns: int

    def _on_set_parameters(self, parameters: list[Parameter]) -> SetParametersResult:
        """Take new gains or limits at run time: checked whole first, then all or nothing.

        Ranges and types as in the files, list lengths against the robot's 6 + n, the
        stability of the sampled loops (``UnifiedForceController.check_gains``) and a contact
        threshold below every open goal's force; only then does anything change, and the new
        gains ramp in (``set_gains``). Any exception refuses the call with its text.
        """
        try:
            gains, safety, params, limits = self._checked_parameters(parameters)
        except Exception as error:  # a refused call, never a dead node
            reason = (str(error) if isinstance(error, (ControlParameterError, TypeError,
                                                       ValueError))
                      else f'{type(error).__name__}: {error}')
            return SetParametersResult(successful=False, reason=reason)
        try:
            if self.core is not None:
                self.core.set_gains(params)
            if self.supervisor is not None:
                self.supervisor.limits = limits
        except Exception as error:
            self._fault('set_parameters', error)
            return SetParametersResult(successful=False, reason=f'{type(error).__name__}: '
                                                                f'{error}')
        self._gains, self._safety = gains, safety
        return SetParametersResult(successful=True)

    def _checked_parameters(self, parameters: list[Parameter]) -> tuple[
            dict[str, Any], dict[str, Any], ControllerParameters, SafetyLimits]:
        """The gains and limits a set_parameters call asks for, checked whole; nothing changes.

        Raises:
            ControlParameterError: naming the parameter, its value and what is valid.
        """
        gains, safety = dict(self._gains), dict(self._safety)
        for parameter in parameters:
            value = parameter.value
            value = list(value) if not isinstance(value, (str, bool, int, float)) else value
            if parameter.name in gains:
                gains[parameter.name] = value
            elif parameter.name in safety:
                safety[parameter.name] = value
        params = ControllerParameters.from_flat_dict(gains)
        limits = safety_limits(safety)
        if self.core is not None:
            self.core.check_gains(params)
        forces = [force for force in self.tasks.open_goal_forces() if force > 0.0]
        if forces and params.contact_threshold >= min(forces):
            raise ControlParameterError('force.contact_threshold_n', params.contact_threshold,
                                        f'below the force_n = {min(forces):g} N of an open '
                                        'contact task')
        return gains, safety, params, limits

    def _watch_allocator(self, allocator: str) -> None:
        """Follow the thruster allocator's lifecycle state (its transition_event), if named."""
        if not allocator:
            return
        self._allocator = AllocatorWatch(self, allocator, self._on_allocator_change)
        self._entities.append((self.destroy_subscription, self._allocator.subscription))

    @guarded('allocator transition callback')
    def _on_allocator_change(self, active: bool, label: str) -> None:
        """Allocator inactive: end a running task INPUTS_STALE and command zero; active: resume."""
        if active:
            self.get_logger().info('the thruster allocator is active: control resumes')
            return
        reason = f'the thruster allocator is {label}'
        self.get_logger().warn(f'{reason}: publishing zero generalized force')
        self._halt(reason)
        if self._entities and self._active:
            self._zero(self.get_clock().now().nanoseconds, None)

    def _halt(self, reason: str) -> None:
        """Control stopped (stale inputs, allocator): end a running task INPUTS_STALE, once."""
        if self._halted is not None:
            return
        self._halted = reason
        if self.supervisor is not None and self._active:
            self.tasks.finish(self.supervisor.abort_all(TaskCode.INPUTS_STALE, reason))

    def _may_step(self, t_ns: int) -> bool:
        """Whether control may step at t_ns; zero command when not, hold re-captured on resume.

        Not while the allocator is inactive. A gap longer than watchdog_timeout_s since the
        last step ends a running task (the path's time ran on without control) and, as on any
        resume, the hold point becomes the position measured at this step; a goal that
        arrived while control was stopped ends INPUTS_STALE then.
        """
        if self._allocator is not None and not self._allocator.active:
            self._zero(t_ns, None)
            self._last_stamp_ns = t_ns  # a re-published state gets this zero again
            return False
        if self._last_stamp_ns >= 0 and t_ns - self._last_stamp_ns > self._watchdog_ns:
            self._halt(f'no control step for {(t_ns - self._last_stamp_ns) * 1e-9:.3f} s '
                       '(more than watchdog_timeout_s)')
        if self._halted is not None:
            assert self.supervisor is not None
            # A goal taken while control was stopped was checked against an old position.
            self.tasks.finish(self.supervisor.abort_all(
                TaskCode.INPUTS_STALE, f'arrived while control was stopped ({self._halted})'))
            self.supervisor.recapture_hold()
            self._halted = None
        return True

    def _fault(self, where: str, error: BaseException, t_ns: int | None = None) -> None:
        """Answer an exception: zero command, running tasks ended INACTIVE, logged, counted."""
        text = self._faults.record(where, error, 'zero generalized force, tasks ended, '
                                   'holding the measured position at the next step')
        try:
            if self.supervisor is not None and self._active:
                self.tasks.finish(self.supervisor.abort_all(
                    TaskCode.INACTIVE, f'the controller failed ({text}): task ended'))
                self.supervisor.recapture_hold()
            if self._entities:
                self._zero(self.get_clock().now().nanoseconds if t_ns is None else t_ns, None)
        except Exception as again:  # the answer itself failed: log, go on
            self.get_logger().error(f'answering a fault failed too: {type(again).__name__}: '
                                    f'{again}', throttle_duration_sec=1.0)
