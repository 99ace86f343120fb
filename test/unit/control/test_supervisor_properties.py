"""Property-based test of the task supervisor in closed loop (hypothesis, stateful).

Random sequences of goals (paths, forces, ramps, stamps, normals, some unsafe), cancels,
preemptions, safety-limit changes, lifecycle transitions (deactivate = abort_all(INACTIVE) and
zero command; activate = controller reset + supervisor reset), input gaps (abort_all
(INPUTS_STALE), the plant on the last command, then zero as the allocator's watchdog does, then
recapture_hold) and wall moves, run on TaskSupervisor + UnifiedForceController + the paper's
UVMS against a K_e = 1e4 N/m wall (``closed_loop_plant.Loop``) at 100 Hz to keep 500 sequences
within CI's budget. After every control step:

- nothing raises;
- |F_e| is above ``safety.max_contact_force_n`` for at most ``FEW`` periods in a row unless a
  retreat or the safe hold runs;
- F_d never grows unless a goal with force_n > 0 follows its path, is zero in SAFE_HOLD, and
  zero in HOLD once ``retreat_time_s`` has passed since a goal last pressed;
- every goal gets exactly one result (checked at each result and after a final deactivation);
- after a result (other than INVALID_GOAL) |F_e| falls under the contact threshold within
  ``retreat_time_s`` plus ``MARGIN_S``, unless a goal follows a path or releases its force
  meanwhile, or the wall moved onto the arm (a contact no goal made).

Profiles (``UVMS_HYPOTHESIS_PROFILE``): ``ci`` (default) runs 500 sequences derandomized (the
same sequences every run, reproducible in CI); ``quick`` 50; ``random`` 500 fresh ones;
``explore`` 300 fresh ones without shrinking (a hunt for failures).
"""

from __future__ import annotations

import math
import os
from collections.abc import Hashable

import numpy as np
from closed_loop_plant import X_A, Loop
from hypothesis import HealthCheck, Phase, event, settings
from hypothesis import strategies as st
from hypothesis.stateful import RuleBasedStateMachine, initialize, rule
from uvms_control.core.task.contact_task import ContactTaskGoal, SafetyLimits, TaskCode
from uvms_control.core.task.task_supervisor import SupervisorState, TaskEvent, with_limits

DT = 0.01  # control period (s)
THRESHOLD_N = 5.0  # the paper robot's force.contact_threshold_n
FEW = 3  # control periods
MARGIN_S = 1.5  # the back-off after the ramp-down, and the arm's lag (s)
WATCHDOG_S = 0.2  # the allocator's watchdog_timeout_s: then zero thrust and torque
#: Zero command (inactive, input gaps) in one sequence at most (s): longer, the paper's
#: vehicle, left alone, pitches toward the Euler-angle singularity (its arm is not neutrally
#: buoyant), which ends the plant.
ZERO_COMMAND_BUDGET_S = 1.0
STEPS = st.integers(0, 120)  # control steps after each command
LIMITS = SafetyLimits(max_contact_force_n=250.0, sensor_range_n=1000.0)

_COMMON = {'deadline': None, 'database': None, 'stateful_step_count': 10,
           'suppress_health_check': [HealthCheck.too_slow, HealthCheck.data_too_large]}
settings.register_profile('ci', max_examples=500, derandomize=True, **_COMMON)
settings.register_profile('quick', max_examples=50, derandomize=True, **_COMMON)
settings.register_profile('random', max_examples=500, **_COMMON)
settings.register_profile('explore', max_examples=300, phases=[Phase.generate], **_COMMON)
settings.register_profile('ci-unshrunk', max_examples=500, derandomize=True,
                          phases=[Phase.generate], **_COMMON)
PROFILE = settings.get_profile(os.environ.get('UVMS_HYPOTHESIS_PROFILE', 'ci'))


class SupervisorInClosedLoop(RuleBasedStateMachine):
    """The supervisor, its controller and the plant, under random commands."""

    def __init__(self) -> None:
        super().__init__()
        self.loop = Loop(LIMITS, dt=DT)
        self.active = True
        self.goals: dict[Hashable, ContactTaskGoal] = {}
        self.results: dict[Hashable, TaskCode] = {}
        self.next_id = 0
        self.over_limit = 0
        self.previous_f_d = 0.0
        self.last_pressing_s = -math.inf
        self.deadlines: list[float] = []
        self.unowned_contact = False
        self.seen_state = SupervisorState.HOLD
        self.zero_command_s = 0.0

    # ------------------------------------------------------------------ bookkeeping

    def record(self, events: list[TaskEvent]) -> None:
        """Take results: exactly one per goal; a deadline for the contact to go."""
        for ended in events:
            assert ended.goal_id in self.goals, f'a result for an unknown goal {ended.goal_id}'
            assert ended.goal_id not in self.results, (
                f'a second result for {ended.goal_id}: {ended.result.code.name} after '
                f'{self.results[ended.goal_id].name}')
            self.results[ended.goal_id] = ended.result.code
            hypothesis_event(f'result {ended.result.code.name}')
            if ended.result.code != TaskCode.INVALID_GOAL:
                self.deadlines.append(self.loop.t + self.loop.supervisor.limits.retreat_time_s
                                      + MARGIN_S)

    def step(self) -> None:
        """One control step and the invariants after it."""
        loop, supervisor = self.loop, self.loop.supervisor
        count = len(loop.events)
        result = loop.step()
        self.record([event for _, event in loop.events[count:]])
        t, state, limits = loop.t, supervisor.state, supervisor.limits
        force = float(np.linalg.norm(result.F_e))
        protected = state in (SupervisorState.RETREATING, SupervisorState.SAFE_HOLD)
        self.over_limit = self.over_limit + 1 if force > limits.max_contact_force_n \
            and not protected else 0
        assert self.over_limit <= FEW, (
            f'|F_e| = {force:.0f} N above {limits.max_contact_force_n} N for {self.over_limit} '
            f'periods in {state.name}')
        f_d = float(np.linalg.norm(result.F_d))
        running = supervisor.goal_id
        pressing = (state == SupervisorState.FOLLOWING and running is not None
                    and self.goals[running].force_n > 0.0)
        if pressing:
            self.last_pressing_s = t
        elif t - self.last_pressing_s > 1.5 * DT:  # the ramp-down starts where the ramp is at t
            assert f_d <= self.previous_f_d + 1e-9, f'F_d grew to {f_d} N in {state.name}'
        if state == SupervisorState.HOLD and t - self.last_pressing_s > limits.retreat_time_s \
                + 2 * DT:
            assert f_d == 0.0, f'F_d = {f_d} N in HOLD'
        self.previous_f_d = f_d
        if state != self.seen_state:
            self.seen_state = state
            hypothesis_event(f'state {state.name}')
        if force >= THRESHOLD_N:
            hypothesis_event('contact')
        if force < THRESHOLD_N:
            self.unowned_contact = False
        if force < THRESHOLD_N or self.unowned_contact or (
                running is not None and state in (SupervisorState.FOLLOWING,
                                                  SupervisorState.RELEASING)):
            self.deadlines = []
        assert all(t <= deadline for deadline in self.deadlines), (
            f'|F_e| = {force:.1f} N still at t = {t:.2f} s, a result came at '
            f'{min(self.deadlines) - limits.retreat_time_s - MARGIN_S:.2f} s')

    # ------------------------------------------------------------------ rules

    @initialize(wall_gap=st.floats(0.005, 0.06))
    def place_wall(self, wall_gap: float) -> None:
        """The wall somewhere in front of the end effector; the first step."""
        self.loop.wall_x = float(X_A[0]) + wall_gap
        self.step()

    def run(self, steps: int) -> None:
        """Control steps."""
        for _ in range(steps):
            self.step()

    @rule(steps=STEPS)
    def wait(self, steps: int) -> None:
        """Control steps only."""
        self.run(steps)

    @rule(reach=st.floats(-0.03, 0.12), drop=st.floats(-0.05, 0.05),
          duration=st.sampled_from([0.1, 0.4, 1.0, 2.0]), second=st.booleans(),
          force=st.sampled_from([0.0, 0.0, 2.0, 40.0, 100.0, 200.0, 300.0]),
          ramp=st.sampled_from([0.01, 0.2, 0.5, 1.5]),
          delay=st.sampled_from([None, 0.0, 0.5, 2.0, 100.0]),
          normal=st.sampled_from([(1.0, 0.0, 0.0), (1.0, 0.0, 0.0), (-1.0, 0.0, 0.0),
                                  (0.8, 0.0, 0.6)]),
          steps=STEPS)
    def submit(self, reach: float, drop: float, duration: float, second: bool, force: float,
               ramp: float, delay: float | None, normal: tuple[float, float, float],
               steps: int) -> None:
        """A goal from the current X_d (toward or past the wall, maybe down along it), steps."""
        self.send(reach, drop, duration, second, force, ramp, delay, normal)
        self.run(steps)

    def send(self, reach: float, drop: float, duration: float, second: bool, force: float,
             ramp: float, delay: float | None, normal: tuple[float, float, float]) -> None:
        """Submit one goal (while inactive the task server answers INACTIVE)."""
        last = self.loop.last
        base = X_A if last is None else last.X_d
        points = [base, base + np.array([reach, 0.0, 0.0])]
        times = [0.0, duration]
        if second:
            points.append(points[-1] + np.array([0.0, 0.0, drop]))
            times.append(duration + 1.0)
        goal = ContactTaskGoal(
            path=np.array(points), times=np.array(times), velocities=None, accelerations=None,
            normal=np.array(normal), force_n=force, force_ramp_s=ramp,
            require_contact=force > 0.0,
            start_time_s=None if delay is None else self.loop.t + delay)
        goal_id = self.next_id
        self.next_id += 1
        self.goals[goal_id] = goal
        if not self.active:
            self.record([TaskEvent(goal_id, _inactive())])
            return
        self.record(self.loop.supervisor.submit(goal_id, goal, self.loop.t))

    @rule(pick=st.integers(0, 1000), steps=STEPS)
    def cancel(self, pick: int, steps: int) -> None:
        """Cancel a goal, running or not (an unknown or ended one: refused), steps."""
        goal_id = pick % max(self.next_id, 1)
        accepted = self.loop.supervisor.cancel(goal_id)
        assert not accepted or goal_id not in self.results
        self.run(steps)

    @rule(force_limit=st.sampled_from([80.0, 150.0, 250.0, 400.0]),
          tracking=st.sampled_from([0.03, 0.1, 0.2]), steps=STEPS)
    def change_limits(self, force_limit: float, tracking: float, steps: int) -> None:
        """New safety limits at run time (set_parameters), steps."""
        self.loop.supervisor.limits = with_limits(self.loop.supervisor.limits,
                                                  max_contact_force_n=force_limit,
                                                  max_position_error_m=tracking)
        self.run(steps)

    @rule(off_s=st.sampled_from([0.02, 0.1, 0.3]), while_off=st.booleans(),
          before_first=st.booleans(), steps=STEPS)
    def cycle_lifecycle(self, off_s: float, while_off: bool, before_first: bool,
                        steps: int) -> None:
        """Deactivate (goals INACTIVE, zero command), maybe a goal while off, activate.

        Activation is a controller reset and a supervisor reset; a goal may arrive before the
        first step after it (queued until then).
        """
        self.record(self.loop.supervisor.abort_all(TaskCode.INACTIVE, 'deactivated'))
        self.active = False
        self.loop.tau_b = np.zeros(9)
        if while_off:
            self.send(0.05, 0.0, 1.0, False, 100.0, 0.5, None, (1.0, 0.0, 0.0))
        off_s = min(off_s, ZERO_COMMAND_BUDGET_S - self.zero_command_s)
        self.loop.gap(off_s)
        self.zero_command_s += off_s
        self.loop.controller.reset()
        self.record(self.loop.supervisor.reset())
        self.active = True
        self.previous_f_d = 0.0
        if before_first:
            self.send(0.05, 0.0, 1.0, False, 100.0, 0.5, None, (1.0, 0.0, 0.0))
        self.run(max(steps, 1))

    @rule(gap_s=st.sampled_from([0.05, 0.3, 0.6]), steps=STEPS)
    def input_gap(self, gap_s: float, steps: int) -> None:
        """Stale inputs: goals end INPUTS_STALE; the last command, then the watchdog's zero."""
        gap_s = min(gap_s, ZERO_COMMAND_BUDGET_S - self.zero_command_s)
        self.record(self.loop.supervisor.abort_all(TaskCode.INPUTS_STALE, 'inputs stale'))
        self.loop.gap(min(gap_s, WATCHDOG_S))
        self.loop.tau_b = np.zeros(9)
        self.loop.gap(max(gap_s - WATCHDOG_S, 0.0))
        self.zero_command_s += gap_s
        self.loop.supervisor.recapture_hold()
        self.previous_f_d = 0.0
        self.run(max(steps, 1))

    @rule(shift=st.floats(-0.03, 0.03), steps=STEPS)
    def move_wall(self, shift: float, steps: int) -> None:
        """The wall moves (Case III); onto the arm it makes a contact no goal owns."""
        self.loop.wall_x += shift
        if shift < 0.0:
            self.unowned_contact = True
            self.deadlines = []
        self.run(steps)

    def teardown(self) -> None:
        """Let pending releases finish, then deactivate: every goal has exactly one result."""
        if self.active:
            while self.deadlines and self.loop.t <= max(self.deadlines) + DT:
                self.step()
            self.record(self.loop.supervisor.abort_all(TaskCode.INACTIVE, 'deactivated'))
        missing = sorted(set(self.goals) - set(self.results))
        assert not missing, f'goals without a result: {missing}'


def hypothesis_event(name: str) -> None:
    """Count what the sequences reach (``--hypothesis-show-statistics``)."""
    event(name)


def _inactive() -> TaskResultLike:
    return TaskResultLike(TaskCode.INACTIVE, 'inactive', 0.0, 0.0, math.nan, math.nan)


# The result type itself: the task server answers a goal to an inactive node with it.
from uvms_control.core.task.contact_task import TaskResult as TaskResultLike  # noqa: E402

SupervisorInClosedLoop.TestCase.settings = PROFILE
TestSupervisorInClosedLoop = SupervisorInClosedLoop.TestCase
