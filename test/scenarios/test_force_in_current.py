"""Force control in an ocean current (issue 30): Case I and the BlueROV2 in 0.2 m/s.

Both scenarios (``case1_current``, ``bluerov2_alpha5_current``) put the contact task in a
current of 0.2 m/s flowing along the wall's plane (map_ned +y), which the controller does
not know; the runs are shortened to 14 s (touch at 8.05 s, release at about 12.4 s). The
bounds are the issue's: RMS force error under 5 % of F_d, errors along the wall under 5 mm.
The current shows in the along-wall error, which is zero in still water (docs/results.md).
"""

from __future__ import annotations

import numpy as np
import pytest
from scenario_runs import ScenarioResult

#: Issue 30: end-effector errors along the wall (y, z) below 5 mm while in contact.
ALONG_WALL_BOUND_M = 5e-3
#: The current pushes the end effector along the wall: more than this in contact (still
#: water: 0.00 mm in y, docs/results.md).
PUSHED_ALONG_WALL_M = 5e-4


@pytest.mark.parametrize(('scenario', 'f_d'), [('case1_current', 150.0),
                                                ('bluerov2_alpha5_current', 20.0)])
def test_force_is_held_in_a_current(
    request: pytest.FixtureRequest, scenario: str, f_d: float
) -> None:
    """One contact, RMS F - F_d after settling under 5 % of F_d, along-wall errors under 5 mm."""
    result: ScenarioResult = request.getfixturevalue(scenario)
    metrics = result.metrics
    assert metrics.contact_count == 1
    assert metrics.force_rms_error is not None and metrics.force_rms_error < 0.05 * f_d
    assert metrics.max_error_y_contact is not None and metrics.max_error_z_contact is not None
    assert metrics.max_error_y_contact < ALONG_WALL_BOUND_M
    assert metrics.max_error_z_contact < ALONG_WALL_BOUND_M
    assert metrics.max_error_y_contact > PUSHED_ALONG_WALL_M  # the current did act


@pytest.mark.parametrize(('scenario', 'sigma'), [('case1_current', 0.05),
                                                 ('bluerov2_alpha5_current', 0.0)])
def test_recording_holds_the_current_applied(
    request: pytest.FixtureRequest, scenario: str, sigma: float
) -> None:
    """/uvms/ocean/current: every 2 ms, toward east (map_ned +y), 0.2 m/s (+- its noise)."""
    result: ScenarioResult = request.getfixturevalue(scenario)
    current = result.run.current
    assert current is not None
    np.testing.assert_allclose(np.diff(current.t), 0.002, atol=1e-9)
    np.testing.assert_allclose(current.velocity[:, [0, 2]], 0.0, atol=1e-12)
    speed = current.velocity[:, 1]
    assert speed[0] == pytest.approx(0.2)
    if sigma == 0.0:
        np.testing.assert_allclose(speed, 0.2)
    else:  # 14 s of a process with T = 60 s: it wanders, but within a few sigma
        assert np.ptp(speed) > 0.0 and np.all(np.abs(speed - 0.2) < 4.0 * sigma)
