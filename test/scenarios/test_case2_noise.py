"""Case II (paper sec. 5.3.2, Fig. 11): force tracking with a noisy wrist force sensor.

The Case I wall (K_e = 1e4 N/m) with sensor noise of 0.1 % of the 400 N range (JR3), so the
controller sees about 0.4 N of noise on each force axis. "Can tolerate force sensor noise"
is judged against Case I on the same wall without noise.
"""

from __future__ import annotations

import numpy as np
from scenario_runs import ScenarioResult
from uvms_analysis.metrics import hold

#: Noise standard deviation of the Case II sensor: 0.1 % of its 400 N range (N).
NOISE_STD_N = 0.4
#: Case II metrics at most this factor times Case I's (same wall, no noise): measured
#: RMS 1.179 / 1.061 N = 1.11, settling 0.884 / 0.880 s = 1.005.
TO_CASE_I = 1.5


def test_controller_sees_the_sensor_noise(case2_noise: ScenarioResult) -> None:
    """Measured F_e minus the true contact force has a spread of about 0.4 N in contact."""
    controller, contact = case2_noise.run.controller, case2_noise.run.contact
    assert controller is not None and contact is not None
    in_contact = hold(controller.t, contact.t, contact.in_contact).astype(bool)
    truth = hold(controller.t, contact.t, contact.force[:, 0])
    noise = controller.F_e[in_contact, 0] - truth[in_contact]
    # Measured 0.385 N: the bounds say "the configured noise reaches the controller".
    assert 0.75 * NOISE_STD_N < float(np.std(noise)) < 1.25 * NOISE_STD_N


def test_noisy_force_tracking_rms_error_is_within_1_5_times_the_noise_free_one(
    case2_noise: ScenarioResult, case1_ke1e4: ScenarioResult
) -> None:
    """RMS of F - F_d after settling, up to the release: below 1.5x Case I's on the same wall."""
    noisy, clean = case2_noise.metrics.force_rms_error, case1_ke1e4.metrics.force_rms_error
    assert noisy is not None and clean is not None
    assert noisy < TO_CASE_I * clean, f'{noisy:.3f} N against {clean:.3f} N without noise'


def test_noisy_contact_force_settles_within_1_5_times_the_noise_free_time(
    case2_noise: ScenarioResult, case1_ke1e4: ScenarioResult
) -> None:
    """The noise does not keep the force out of the F_d ± 5 % band: settled by 1.5x Case I's."""
    noisy, clean = case2_noise.metrics.settling_time, case1_ke1e4.metrics.settling_time
    assert noisy is not None and clean is not None
    assert noisy < TO_CASE_I * clean, f'{noisy:.3f} s against {clean:.3f} s without noise'
