"""Who owns the robot: the pilot, a task or the hold; the hand-over between them.

One owner at a time (``PilotMode``):

- ``task``: a ContactTask goal runs (or waits to start, or its arm backs off). A goal takes
  control from the pilot (the pilot's velocities are zeroed; the vehicle's slows down at the
  pilot's rate limit). Pilot input then cancels the task as a cancel does (force released,
  the arm backs off) unless ``refuse_during_contact`` and the task holds a contact; input
  during the back-off is ignored. The task's end returns to ``hold``.
- ``pilot``: a pilot message asked for motion within the deadman. The references come from
  ``PilotMotion``, started where the controller held the vehicle (its null-space posture) and
  the end effector (the hold point), so nothing jumps.
- ``hold``: station keeping: the vehicle at the pose the pilot released (or where it has been
  held since activation), the end effector at its hold point. No pilot message asking for
  motion for the deadman (or a hold request) releases the pilot.

Everything runs in ``before_step``, on the control loop's clock, before the task supervisor's
step: lockstep stays deterministic. Each switch comes back as one line (``Switch``).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np

from uvms_control.core.pilot.inputs import PilotTwist
from uvms_control.core.pilot.limits import PilotLimits
from uvms_control.core.pilot.motion import PilotMotion
from uvms_control.core.pilot.supervisor import PilotedSupervisor
from uvms_control.core.task.safety_checks import MAX_MOTION_STEP_S
from uvms_control.core.task.task_supervisor import SupervisorState


class PilotMode(enum.Enum):
    """The owner of the robot (published as its value)."""

    PILOT = 'pilot'
    TASK = 'task'
    HOLD = 'hold'


@dataclass(frozen=True)
class Switch:
    """A change of owner: the new mode and why, in one line."""

    mode: PilotMode
    reason: str

    def line(self) -> str:
        """The console line of the switch."""
        return f'mode {self.mode.value}: {self.reason}'


class PilotHandover:
    """Modes and hand-over between the pilot, the tasks and the hold.

    Args:
        supervisor: the task supervisor (and through it, the controller), piloted.
        limits: the robot's pilot limits.
    """

    def __init__(self, supervisor: PilotedSupervisor, limits: PilotLimits) -> None:
        self.supervisor = supervisor
        self.limits = limits
        self.motion = PilotMotion(limits)
        self.mode = PilotMode.HOLD
        #: Why pilot input was last refused or ignored (None: it was not), for /diagnostics.
        self.refusal: str | None = None
        self._asked = False  # a message asked for motion since the last step
        self._canceled: object | None = None  # the goal pilot input canceled
        self._refused_goal: object | None = None
        self._t_last: float | None = None
        self._pending: list[Switch] = []
        self._notes: list[str] = []

    # ------------------------------------------------------------------ inputs

    def vehicle(self, t_s: float, twist: PilotTwist) -> None:
        """A checked vehicle twist arrived at t_s (s, controller clock)."""
        self.motion.command_vehicle(t_s, twist)
        self._asked |= not twist.is_zero

    def ee(self, t_s: float, twist: PilotTwist) -> None:
        """A checked end-effector velocity arrived at t_s (s)."""
        self.motion.command_ee(t_s, twist)
        self._asked |= not twist.is_zero

    def jaw(self, t_s: float, speed_m_s: float) -> None:
        """A checked jaw speed arrived at t_s (s)."""
        self.motion.command_jaw(t_s, speed_m_s)
        self._asked |= speed_m_s != 0.0

    def jaw_command_m_s(self) -> float:
        """The jaw speed to forward now (m/s, + opens): the pilot's, in pilot mode only.

        Deadman-limited and within ``limits.jaw_speed_m_s`` (``PilotMotion``: a jaw message
        older than the deadman is a zero target, reached within 0.1 s); zero in hold and task
        mode, so a task or a released pilot never leaves the jaw moving.
        """
        return self.motion.jaw_speed_m_s if self.mode == PilotMode.PILOT else 0.0

    def hold(self) -> tuple[bool, str]:
        """Switch to hold now (the hold service): (success, message).

        Without a task: the pilot's velocities slow to zero at the rate limits and the pose
        reached is held. A running task is canceled as a cancel does (the arm backs off, then
        holds); during a back-off or the safe hold nothing changes (success False).
        """
        supervisor = self.supervisor
        self.motion.stop()
        self._asked = False
        goal = supervisor.goal_id
        if goal is not None:
            if supervisor.state == SupervisorState.RETREATING:
                return False, f'not now: {self.refusal_now()}; the hold follows it'
            supervisor.cancel(goal)
            return True, ('the task is canceled: its force is released, the arm backs off, '
                          'then holds')
        if supervisor.safe_hold:
            return True, f'already holding: {self.refusal_now()}'
        if self.mode == PilotMode.PILOT:
            self._switch(PilotMode.HOLD, 'hold asked: the pilot is released, the pose reached '
                                         'is held')
        return True, 'holding'

    # ------------------------------------------------------------------ the step

    def take_switches(self) -> list[Switch]:
        """The switches since the last call, in order."""
        switches, self._pending = self._pending, []
        return switches

    def take_notes(self) -> list[str]:
        """Lines about pilot input refused or ignored (each said when it first happens)."""
        notes, self._notes = self._notes, []
        return notes

    def before_step(self, t_s: float) -> None:
        """Decide the owner at t_s (s) and apply the pilot's references; before the step."""
        dt = 0.0 if self._t_last is None else min(max(t_s - self._t_last, 0.0),
                                                  MAX_MOTION_STEP_S)
        self._t_last = t_s
        asked, self._asked = self._asked, False
        supervisor = self.supervisor
        if supervisor.last_result is None and not supervisor.has_goal:
            self.reset()  # activation or a re-captured hold: nothing to drive from yet
            if asked:
                self._refuse(f'pilot input refused: {self.refusal_now()}')
            return
        if supervisor.has_goal:
            self._during_task(asked)
        elif self.mode == PilotMode.TASK:
            self._canceled = self._refused_goal = None
            self._switch(PilotMode.HOLD, 'the task ended: station keeping')
        refusal = self.refusal_now()
        if refusal is not None and not supervisor.has_goal:
            if asked:
                self._refuse(f'pilot input refused: {refusal}')
            self.motion.stop()
        driving = self.motion.driving(t_s) and refusal is None
        if driving and self.mode == PilotMode.HOLD:
            self.refusal = None
            if self._start():
                self._switch(PilotMode.PILOT, 'the pilot drives')
        elif not driving and self.mode == PilotMode.PILOT:
            self._switch(PilotMode.HOLD, 'the pilot released: station keeping where the '
                                         'motion stops')
        if self.motion.started and (self.mode == PilotMode.PILOT or self.motion.moving):
            self._apply(t_s, dt, ee=self.mode != PilotMode.TASK and refusal is None)

    def reset(self) -> None:
        """Forget the pilot (activation, re-captured hold): hold, nothing moving."""
        if self.motion.started:
            self.motion = PilotMotion(self.limits)
        self._asked = False
        if self.mode != PilotMode.HOLD:
            self._switch(PilotMode.HOLD, 'the controller re-captured its hold')

    # ------------------------------------------------------------------ helpers

    def refusal_now(self) -> str | None:
        """Why a pilot may not move the hold point now, or None when it may."""
        supervisor = self.supervisor
        if supervisor.safe_hold:
            return (f'the controller is in {supervisor.breach}; clear it with '
                    '`uvms lifecycle controller reset`')
        if supervisor.state == SupervisorState.RETREATING:
            return 'the arm is backing off'
        if supervisor.has_goal:
            return 'a task runs'
        if supervisor.releasing:
            return 'the arm is letting go of a contact'
        return None if supervisor.last_result is not None else 'no state since activation'

    def _in_contact(self) -> bool:
        """The running task measured a contact at the last step (force along its normal)."""
        progress = self.supervisor.progress()
        threshold = self.supervisor.controller.task.contact_threshold_n
        return progress is not None and progress.force_n >= threshold

    def _during_task(self, asked: bool) -> None:
        supervisor = self.supervisor
        goal = supervisor.goal_id
        if self.mode != PilotMode.TASK:
            was_pilot = self.mode == PilotMode.PILOT
            self.motion.stop()
            task = supervisor.controller.task
            if task.path is None and task.ready:  # a waiting goal: the hold point stops
                task.follow(task.state(0.0)[:3], (0.0, 0.0, 0.0))
            self._switch(PilotMode.TASK, 'a task took control from the pilot' if was_pilot
                         else 'a task runs')
        if not asked or goal is None or goal == self._canceled:
            if asked and goal is not None:
                self._refuse("pilot input ignored: the canceled task's arm backs off first")
            return
        self.motion.stop()
        if supervisor.state == SupervisorState.RETREATING:
            self._refuse(f'pilot input ignored: {self.refusal_now()}')
            return
        if self.limits.refuse_during_contact and self._in_contact():
            if goal != self._refused_goal:
                self._refused_goal = goal
                self._refuse('pilot input refused: the task holds a contact '
                             '(pilot.refuse_during_contact)')
            return
        if supervisor.cancel(goal):
            self._canceled = goal
            self._notes.append('pilot input: the task is canceled as a cancel does (force '
                               'released, the arm backs off), then hold')

    def _start(self) -> bool:
        """Start the motion from the held vehicle pose and hold point; False if none yet."""
        supervisor = self.supervisor
        controller = supervisor.controller
        eta = controller.vehicle_reference
        if eta is None or supervisor.last_result is None or not controller.task.ready:
            return False
        self.motion.start(eta, np.array(controller.task.state(0.0)[:3]))  # a hold: no t
        return True

    def _apply(self, t_s: float, dt: float, ee: bool) -> None:
        reference = self.motion.step(t_s, dt)
        controller = self.supervisor.controller
        controller.set_vehicle_reference(reference.eta, reference.eta_dot)
        if ee:  # in a task, the task owns X_d: the vehicle's posture slows down alone
            self.supervisor.follow(reference.X_d.tolist(), reference.X_dot_d.tolist())

    def _switch(self, mode: PilotMode, reason: str) -> None:
        self.mode = mode
        self._pending.append(Switch(mode, reason))

    def _refuse(self, reason: str) -> None:
        if reason != self.refusal:
            self._notes.append(reason)
        self.refusal = reason
