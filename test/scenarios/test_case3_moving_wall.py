"""Case III (paper sec. 5.2.3, Figs. 12-14): force tracking against a receding wall.

The wall (K_e = 1e4 N/m) starts moving away along +x at 0.05 m/s once the contact force has
reached 150 N; the end effector has to follow it while holding the force.
"""

from __future__ import annotations

import numpy as np
from scenario_runs import ScenarioResult
from uvms_analysis.metrics import SETTLING_BAND, hold, last_time_in_band

F_D_N = 150.0
WALL_SPEED_M_S = 0.05


def tracking_window(result: ScenarioResult) -> tuple[float, float]:
    """The window of the force-error metric: settling instant to the end of the constrained phase.

    This is the window of ``force_rms_error`` (uvms_analysis.metrics): from the first contact
    plus the settling time to the last sample in the F_d band before the release.
    """
    metrics, contact = result.metrics, result.run.contact
    assert contact is not None
    assert metrics.first_contact_time is not None and metrics.settling_time is not None
    start = metrics.first_contact_time + metrics.settling_time
    end = last_time_in_band(contact.t, contact.force[:, 0], F_D_N, metrics.first_contact_time,
                            float(contact.t[-1]), SETTLING_BAND)
    assert end is not None
    return start, end


def test_wall_recedes_at_5_cm_per_second_throughout_the_force_tracking(
    case3_moving_wall: ScenarioResult,
) -> None:
    """The wall moves at V_e = 0.05 m/s during the whole window of the force-error metric."""
    contact = case3_moving_wall.run.contact
    assert contact is not None
    start, end = tracking_window(case3_moving_wall)
    window = (contact.t >= start) & (contact.t <= end)
    assert end - start > 2.0
    np.testing.assert_allclose(contact.wall_velocity[window], WALL_SPEED_M_S)


def test_end_effector_follows_the_wall_more_than_10_cm_in_contact(
    case3_moving_wall: ScenarioResult,
) -> None:
    """While in contact the wall, and the end effector pressing on it, travel over 10 cm."""
    contact = case3_moving_wall.run.contact
    assert contact is not None
    wall = contact.wall_position[contact.in_contact]
    assert wall[-1] - wall[0] > 0.10


def test_force_tracking_rms_error_on_the_moving_wall_is_under_5_percent(
    case3_moving_wall: ScenarioResult,
) -> None:
    """RMS of F - F_d while the wall recedes (settled to release) is below 0.05 F_d."""
    contact, controller = case3_moving_wall.run.contact, case3_moving_wall.run.controller
    assert contact is not None and controller is not None
    start, end = tracking_window(case3_moving_wall)
    window = (contact.t >= start) & (contact.t <= end)
    f_d = hold(contact.t[window], controller.t, controller.F_d[:, 0])
    error = contact.force[window, 0] - f_d
    rms = float(np.sqrt(np.mean(error**2)))
    assert rms < 0.05 * F_D_N, f'RMS force error {rms:.2f} N'
