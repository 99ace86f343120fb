"""Claims that hold in every case of the unified controller (paper sec. 5.2-5.3, Figs. 7, 10, 14).

Each of Cases I-IV: one contact without bouncing, Y and Z errors of a few millimetres,
release of the wall when the half circle turns back, and free motion along the circle
after it. The vehicle barely feels the 150 N it pushes with.
"""

from __future__ import annotations

import numpy as np
import pytest
from scenario_runs import ScenarioResult
from uvms_analysis.metrics import contact_intervals, hold

UNIFIED_CASES = ('case1_ke1e4', 'case1_ke1e5', 'case2_noise', 'case3_moving_wall',
                 'case4_model_error')
#: The reference holds A for 2 s, then runs the half circle in 16 s: it stops at D at 18 s.
REFERENCE_END_S = 18.0
#: Time after the release by which the end effector must be back on the circle (s). The
#: impedance law (P = 50 kg, B_d = 1000 N s/m, K = 3000 N/m) has its slow pole at 3.7 1/s,
#: so 2 s is over seven time constants: a 0.2 m offset has decayed below 0.1 mm.
RESUME_AFTER_S = 2.0
#: Largest |Y_d - Y| and |Z_d - Z| over a run (m): measured at most 1.87 mm (Case I, 1e5;
#: e_y at most 0.10 mm, Case II): 2.1x.
YZ_ERROR_BOUND_M = 4e-3
#: Largest ‖X_d - X‖ from RESUME_AFTER_S after the release to the end (m), per case, 2-3x
#: the measured 0.009, 0.010, 0.348, 0.133 and 0.019 mm (floored at 0.03 mm: the noise-free
#: fixed-wall cases end back on the circle to within 10 µm).
RESUME_BOUND_M = {'case1_ke1e4': 3e-5, 'case1_ke1e5': 3e-5, 'case2_noise': 7e-4,
                  'case3_moving_wall': 3e-4, 'case4_model_error': 5e-5}
#: Largest distance of the vehicle from its free-motion path on Case I (m): measured 16.7 mm
#: (1.2x); the vehicle's own free-motion excursion is 86 mm.
VEHICLE_DEVIATION_BOUND_M = 0.02


@pytest.fixture(params=UNIFIED_CASES)
def unified(request: pytest.FixtureRequest) -> ScenarioResult:
    """A run of the unified controller (fuzzy switch) against a wall."""
    result: ScenarioResult = request.getfixturevalue(request.param)
    return result


def release_time(result: ScenarioResult) -> float:
    """End of the last contact interval: the first sample out of contact after it (s)."""
    contact = result.run.contact
    assert contact is not None
    intervals = contact_intervals(contact.in_contact)
    assert intervals, 'the run never touches the wall'
    stop = intervals[-1][1]
    assert stop < contact.t.size, 'the run ends in contact'
    return float(contact.t[stop])


def test_end_effector_touches_the_wall_once_without_bouncing(unified: ScenarioResult) -> None:
    """Exactly one contact interval: a stable contact, no bounce off the wall."""
    assert unified.metrics.contact_count == 1


def test_y_and_z_position_errors_stay_under_4_mm(unified: ScenarioResult) -> None:
    """|Y_d - Y| and |Z_d - Z| below 4 mm over the whole run, contact included (Fig. 10)."""
    assert unified.metrics.max_error_y is not None and unified.metrics.max_error_z is not None
    assert unified.metrics.max_error_y < YZ_ERROR_BOUND_M
    assert unified.metrics.max_error_z < YZ_ERROR_BOUND_M


def test_end_effector_leaves_the_wall_before_the_half_circle_ends(
    unified: ScenarioResult,
) -> None:
    """Contact ends while the reference still moves back (C' to C of Fig. 7)."""
    assert release_time(unified) < REFERENCE_END_S


def test_end_effector_resumes_the_half_circle_after_release(unified: ScenarioResult) -> None:
    """From 2 s after leaving the wall to the end, |X_d - X| stays within 2-3x its measured value.

    C to D of Fig. 7: 0.03 mm on the fixed walls, 0.3 mm on the moving one, 0.7 mm with noise.
    """
    controller = unified.run.controller
    assert controller is not None
    after = controller.t >= release_time(unified) + RESUME_AFTER_S
    assert controller.t[after].size > 0 and controller.t[-1] >= REFERENCE_END_S
    errors = np.linalg.norm(controller.X_d[after] - controller.X[after], axis=1)
    largest = errors.max()
    assert largest < RESUME_BOUND_M[unified.name], f'largest error {largest * 1e3:.3f} mm'


def test_contact_force_barely_moves_the_vehicle(
    case1_ke1e4: ScenarioResult, free_motion: ScenarioResult
) -> None:
    """With 150 N on the wall the vehicle path stays within 2 cm of its free-motion path.

    Unreacted, 150 N for the 4.4 s of contact would push the 530 kg vehicle
    ½ (F/m) t² = 2.7 m (before drag and added mass). Tested on Case I's fixed wall, where the
    end effector barely leaves its free-motion path (18.5 mm, the wall being inside the
    circle); the paper states it for Case III (Fig. 14), whose end effector travels 17 cm with
    the wall and takes the vehicle along (see test_case3_moving_wall.py).
    """
    contact, free = case1_ke1e4.run.odometry, free_motion.run.odometry
    assert contact is not None and free is not None
    free_position = hold(contact.t, free.t, free.position)
    deviation = np.linalg.norm(contact.position - free_position, axis=1)
    largest = deviation.max()
    assert largest < VEHICLE_DEVIATION_BOUND_M, f'largest deviation {largest * 1e3:.1f} mm'
