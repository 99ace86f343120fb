"""Case III (paper sec. 5.2.3, Figs. 12-14): force tracking against a receding wall.

The wall (K_e = 1e4 N/m) starts moving away along +x at 0.05 m/s once the contact force has
reached 150 N; the end effector has to follow it while holding the force. The wall's speed
and start force are config, checked in test/integration/test_graph_scenario_files.py; here
the claims are that the wall does move during the force tracking, and how well the force is
held while it does, against Case I's fixed wall.

The paper's other Case III claim, "the contact force has little effect on the vehicle"
(Fig. 14), is not tested on this run: the vehicle takes a share of every end-effector motion
(unweighted J⁺) and the end effector travels 17 cm with the wall, and a linear fit of the
vehicle's deviation from its free-motion path on the end effector's leaves 90 mm
unexplained (dynamics, the null-space pull back), so this run cannot separate the force's
share. test_unified_controller_claims.py tests it on Case I's fixed wall.
"""

from __future__ import annotations

import numpy as np
from scenario_runs import ScenarioResult
from uvms_analysis.metrics import SETTLING_BAND, hold, last_time_in_band

F_D_N = 150.0
#: RMS of F - F_d while the wall recedes, at most this factor times Case I's fixed-wall RMS:
#: measured 1.287 N against 1.061 N, 1.21 (1.65x margin).
TO_CASE_I = 2.0


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


def test_wall_recedes_throughout_the_force_tracking(
    case3_moving_wall: ScenarioResult,
) -> None:
    """The wall moves during the whole window of the force-error metric (9.02-12.13 s)."""
    contact = case3_moving_wall.run.contact
    assert contact is not None
    start, end = tracking_window(case3_moving_wall)
    window = (contact.t >= start) & (contact.t <= end)
    assert end - start > 2.0  # measured 3.10 s
    assert np.all(contact.wall_velocity[window] > 0.0)


def test_end_effector_follows_the_wall_more_than_10_cm_in_contact(
    case3_moving_wall: ScenarioResult,
) -> None:
    """While in contact the wall, and the end effector pressing on it, travel over 10 cm.

    Measured 16.7 cm (1.7x): the end effector stays on the wall for over 2 s of its motion.
    """
    contact = case3_moving_wall.run.contact
    assert contact is not None
    wall = contact.wall_position[contact.in_contact]
    assert wall[-1] - wall[0] > 0.10


def test_force_tracking_rms_error_on_the_moving_wall_is_within_twice_the_fixed_walls(
    case3_moving_wall: ScenarioResult, case1_ke1e4: ScenarioResult
) -> None:
    """RMS of F - F_d while the wall recedes (settled to release): below 2x Case I's."""
    contact, controller = case3_moving_wall.run.contact, case3_moving_wall.run.controller
    assert contact is not None and controller is not None
    start, end = tracking_window(case3_moving_wall)
    window = (contact.t >= start) & (contact.t <= end)
    f_d = hold(contact.t[window], controller.t, controller.F_d[:, 0])
    error = contact.force[window, 0] - f_d
    rms = float(np.sqrt(np.mean(error**2)))
    fixed = case1_ke1e4.metrics.force_rms_error
    assert fixed is not None
    assert rms < TO_CASE_I * fixed, f'RMS force error {rms:.3f} N, fixed wall {fixed:.3f} N'
