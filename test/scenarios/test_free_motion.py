"""Free motion: the whole graph tracks the paper's half circle within 0.05 mm after 1 s."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from rosbags.highlevel import AnyReader
from uvms_run.graph import build_graph, run_graph
from uvms_scenarios.scenario import load_scenario

SCENARIO = Path(__file__).resolve().parents[2] / 'config' / 'scenarios' / 'free_motion.yaml'
#: Hold at A for 2 s, then 4 s of the 16 s half circle: the start of the arc, where the
#: reference accelerates from rest (quintic time scaling).
DURATION_S = 6.0
#: Largest |X - X_d| from t = 1 s (m): measured 0.024 mm (2.1x).
TRACKING_BOUND_M = 5e-5


def positions(path: Path) -> tuple[dict[int, np.ndarray], dict[int, np.ndarray]]:
    """End-effector position (simulator ground truth) and reference X_d, by stamp (ns)."""
    actual: dict[int, np.ndarray] = {}
    desired: dict[int, np.ndarray] = {}
    with AnyReader([path]) as reader:
        wanted = [c for c in reader.connections
                  if c.topic in ('/uvms/ee_pose', '/uvms/controller/state')]
        for connection, _, raw in reader.messages(connections=wanted):
            msg = reader.deserialize(raw, connection.msgtype)
            t_ns = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
            if connection.topic == '/uvms/ee_pose':
                p = msg.pose.position
                actual[t_ns] = np.array([p.x, p.y, p.z])
            else:
                p = msg.desired_position
                desired[t_ns] = np.array([p.x, p.y, p.z])
    return actual, desired


@pytest.fixture(scope='module')
def free_motion_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A lockstep run of the free-motion scenario, recorded."""
    path = tmp_path_factory.mktemp('free_motion') / 'free_motion.mcap'
    scenario = load_scenario(SCENARIO).with_changes(duration_s=DURATION_S)
    run_graph(build_graph(scenario, 'lockstep', output_path=path))
    return path


def test_end_effector_follows_half_circle_within_0_05_mm_after_first_second(
    free_motion_run: Path,
) -> None:
    """|X - X_d| < 0.05 mm from t = 1 s on, X the simulator's ground truth."""
    actual, desired = positions(free_motion_run)
    times = sorted(t for t in desired if t >= 1_000_000_000 and t in actual)
    assert times[-1] == round(DURATION_S * 1e9)
    errors = np.array([np.linalg.norm(actual[t] - desired[t]) for t in times])
    largest = errors.max()
    assert largest < TRACKING_BOUND_M, f'largest error {largest * 1e3:.4f} mm'


def test_reference_moves_along_the_circle_during_the_run(free_motion_run: Path) -> None:
    """The reference leaves A toward +x and down: the test tracks a moving target.

    Measured after 6 s: 32 mm along x, 5.2 mm down (the bounds: a third and a fifth of it).
    """
    _, desired = positions(free_motion_run)
    start, end = desired[0], desired[max(desired)]
    assert end[0] - start[0] > 0.01
    assert end[2] - start[2] > 0.001
