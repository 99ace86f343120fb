"""A closed loop for the supervisor tests: TaskSupervisor on the real controller and UvmsModel.

The plant is the paper's UVMS (the controller's own model, exact) against a unilateral spring
wall normal to map_ned +x (no friction), read by an ideal wrist sensor (ee axes).
"""

from __future__ import annotations

import numpy as np
from uvms_control.core.law.unified_controller import ControllerResult, UnifiedForceController
from uvms_control.core.parameters import ControllerParameters
from uvms_control.core.task.contact_task import ContactTaskGoal, SafetyLimits
from uvms_control.core.task.task_supervisor import TaskEvent, TaskSupervisor

from uvms_model import UvmsModel

#: End effector near point A of the paper, (1.70, 0, -0.10) m in map_ned.
Q0 = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.927, -1.571])
#: The Case I wall (m) and its stiffness (N/m).
WALL_X = 1.7771
K_E = 1e4
WALL_NORMAL = np.array([1.0, 0.0, 0.0])
PLANT = UvmsModel()
X_A = PLANT.ee_position(Q0)


def press_goal(force_n: float = 100.0, start_time_s: float | None = None,
               normal: tuple[float, float, float] = (1.0, 0.0, 0.0),
               ramp_s: float = 1.0) -> ContactTaskGoal:
    """config/tasks/press_100n.yaml from X_A: to 2.3 cm past the wall in 2 s, 4 cm down in 4 s."""
    return ContactTaskGoal(
        path=np.array([X_A, [1.80, 0.0, X_A[2]], [1.80, 0.0, X_A[2] + 0.04]]),
        times=np.array([0.0, 2.0, 6.0]),
        velocities=None,
        accelerations=None,
        normal=np.array(normal),
        force_n=force_n,
        force_ramp_s=ramp_s,
        require_contact=force_n > 0.0,
        start_time_s=start_time_s,
    )


class Loop:
    """Supervisor + controller + plant stepped at dt (s).

    Args:
        limits: the safety limits.
        dt: control period (s); the plant integrates it in ``substeps`` steps.
        substeps: plant steps per control period.
        wall_x: wall position (m, map_ned x).
        overrides: controller parameters over the defaults.
    """

    def __init__(self, limits: SafetyLimits, dt: float = 0.002, substeps: int = 1,
                 wall_x: float = WALL_X, **overrides: object) -> None:
        params = ControllerParameters.from_flat_dict(dict(overrides))
        self.controller = UnifiedForceController(params, UvmsModel())
        self.supervisor = TaskSupervisor(self.controller, limits)
        self.dt = dt
        self.substeps = substeps
        self.wall_x = wall_x
        self.q = Q0.copy()
        self.w = np.zeros(9)
        self.k = 0
        self.events: list[tuple[float, TaskEvent]] = []
        self.last: ControllerResult | None = None
        self.tau_b = np.zeros(9)
        self.extra_force = np.zeros(3)  # a force added to the wall's (N, map_ned): a push

    @property
    def t(self) -> float:
        """Time of the next step (s)."""
        return self.k * self.dt

    def wall_force(self) -> np.ndarray:
        """Force the end effector exerts on the wall, plus ``extra_force`` (N, map_ned)."""
        x = float(PLANT.ee_position(self.q)[0])
        return K_E * max(x - self.wall_x, 0.0) * WALL_NORMAL + self.extra_force

    def sensor(self) -> np.ndarray:
        """The wrist-sensor reading (ee axes) of ``wall_force`` (N)."""
        return PLANT.ee_rotation(self.q).T @ self.wall_force()  # type: ignore[no-any-return]

    def advance(self, tau_b: np.ndarray) -> None:
        """The plant over one control period under tau_b."""
        h = self.dt / self.substeps
        for _ in range(self.substeps):
            self.q, self.w = PLANT.step(self.q, self.w, tau_b, -self.wall_force(), h)
        self.k += 1

    def step(self) -> ControllerResult:
        """One control step and one plant period."""
        t = self.t
        self.last, events = self.supervisor.step(t, self.q, self.w, self.sensor())
        self.events += [(t, event) for event in events]
        self.tau_b = self.last.tau_b
        self.advance(self.tau_b)
        return self.last

    def gap(self, duration_s: float) -> None:
        """Inputs missing for duration_s (s): the plant runs on the last command."""
        for _ in range(round(duration_s / self.dt)):
            self.advance(self.tau_b)

    def run(self, duration_s: float) -> list[ControllerResult]:
        """Step for duration_s (s)."""
        return [self.step() for _ in range(round(duration_s / self.dt))]

    def run_until_event(self, timeout_s: float) -> list[ControllerResult]:
        """Step until a task ends or timeout_s (s) has passed."""
        count = len(self.events)
        results = []
        end = self.t + timeout_s
        while len(self.events) == count and self.t < end:
            results.append(self.step())
        return results

    def contact_force(self) -> float:
        """|force on the wall| now (N)."""
        return float(np.linalg.norm(self.wall_force()))
