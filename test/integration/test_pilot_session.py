"""Issue 51's acceptance: a scripted pilot session in lockstep, read back from its recording.

``config/pilot/press_100n_session.yaml``: the paper's robot drives 1 m forward, yaws 90 deg,
lowers the arm 5 cm, press_100n starts (the mission sends it once the pilot is done), the
pilot takes back control 4 s into it; the task ends CANCELED with the force released and the
arm backed off, as on a cancel, and the vehicle then holds where the pilot released it.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from rosbags.highlevel import AnyReader
from uvms_analysis.pilot_plots import mode_changes
from uvms_analysis.plots import plot_recording
from uvms_analysis.series import load_run
from uvms_run.graph import build_graph, run_graph
from uvms_scenarios.scenario import load_scenario

SESSION = Path(__file__).resolve().parents[2] / 'config' / 'pilot' / 'press_100n_session.yaml'
WALL_X = 1.7771
#: When each step of the session is over (s, simulated): the drive, the yaw, the arm's move.
DRIVEN_S, TURNED_S, LOWERED_S = 6.5, 14.5, 17.5
TAKE_BACK_S = 22.5  # the pilot's input, 4 s into press_100n (it starts at 18.5 s)


class Session:
    """The recording's vehicle poses, end-effector positions and contact forces, by time."""

    def __init__(self, path: Path, outcome: object) -> None:
        self.path = path
        self.outcome = outcome
        odometry, state, contact = [], [], []
        with AnyReader([path]) as reader:
            topics = ('/uvms/odometry', '/uvms/controller/state', '/uvms/contact')
            connections = [c for c in reader.connections if c.topic in topics]
            for connection, _, raw in reader.messages(connections=connections):
                msg = reader.deserialize(raw, connection.msgtype)
                t = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
                if connection.topic == '/uvms/odometry':
                    p, q = msg.pose.pose.position, msg.pose.pose.orientation
                    yaw = math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y**2 + q.z**2))
                    odometry.append((t, p.x, p.y, p.z, yaw))
                elif connection.topic == '/uvms/controller/state':
                    state.append((t, msg.position.x, msg.position.y, msg.position.z))
                else:
                    contact.append((t, msg.force.x))
        self.odometry, self.state, self.contact = (np.array(a) for a in (odometry, state,
                                                                          contact))

    @staticmethod
    def at(series: np.ndarray, t_s: float) -> np.ndarray:
        """The first sample at or after t_s, without its time."""
        return series[np.searchsorted(series[:, 0], t_s), 1:]  # type: ignore[no-any-return]

    def between(self, series: np.ndarray, start_s: float, end_s: float) -> np.ndarray:
        """The samples between two times, without their times."""
        keep = (series[:, 0] >= start_s) & (series[:, 0] <= end_s)
        return series[keep, 1:]  # type: ignore[no-any-return]


@pytest.fixture(scope='module')
def session(tmp_path_factory: pytest.TempPathFactory) -> Session:
    """The 36 s session, recorded."""
    path = tmp_path_factory.mktemp('pilot') / 'session.mcap'
    graph = build_graph(load_scenario(SESSION), 'lockstep', output_path=path)
    mission = graph.nodes['mission']
    result = run_graph(graph)
    assert not result.interrupted
    assert result.lockstep_timeouts == 0
    return Session(path, mission.results[0])


pytestmark = pytest.mark.timeout(1200)  # 36 s simulated: 4 min seen on 2 loaded cores


def test_the_pilot_drives_one_metre_forward(session: Session) -> None:
    """Facing west, 1 m forward: the vehicle ends 1 m west of where it began, within 5 cm."""
    start, driven = session.at(session.odometry, 0.5), session.at(session.odometry, DRIVEN_S)
    assert np.linalg.norm(driven[:3] - start[:3]) == pytest.approx(1.0, abs=0.05)
    assert driven[1] - start[1] == pytest.approx(-1.0, abs=0.05)  # west: -y in map_ned


def test_the_pilot_yaws_ninety_degrees(session: Session) -> None:
    """The heading turns 90 deg within 3 deg, and the vehicle turns in place."""
    before, after = session.at(session.odometry, DRIVEN_S), session.at(session.odometry,
                                                                       TURNED_S)
    assert math.degrees(after[3] - before[3]) == pytest.approx(90.0, abs=3.0)
    assert np.linalg.norm(after[:3] - before[:3]) < 0.05


def test_the_pilot_lowers_the_arm_five_centimetres(session: Session) -> None:
    """The end effector goes 5 cm down (map_ned +z), the vehicle stays."""
    before, after = session.at(session.state, TURNED_S), session.at(session.state, LOWERED_S)
    assert after[2] - before[2] == pytest.approx(0.05, abs=0.005)
    vehicle = session.between(session.odometry, TURNED_S, LOWERED_S)[:, :3]
    assert np.max(np.linalg.norm(vehicle - vehicle[0], axis=1)) < 0.05


def test_taking_back_control_cancels_the_task_and_the_arm_backs_off(session: Session) -> None:
    """press_100n pressed 100 N; the pilot's input ended it CANCELED and the arm backed off."""
    outcome = session.outcome
    assert outcome.code == 'CANCELED', outcome.describe()  # type: ignore[attr-defined]
    assert session.at(session.contact, TAKE_BACK_S - 0.1)[0] == pytest.approx(100.0, abs=10.0)
    assert np.all(session.between(session.contact, TAKE_BACK_S + 2.0, 36.0) == 0.0)
    x_after = session.at(session.state, TAKE_BACK_S + 3.0)[0]
    assert x_after < WALL_X - 0.02  # backed off (retreat_m 5 cm from the pressed position)


def test_then_the_vehicle_holds_where_the_pilot_released_it(session: Session) -> None:
    """For 10 s after the task's retreat, the vehicle stays within 5 cm of its release position."""
    released = session.at(session.odometry, LOWERED_S)[:3]
    held = session.between(session.odometry, TAKE_BACK_S + 2.0, TAKE_BACK_S + 12.0)[:, :3]
    distance = np.linalg.norm(held - released, axis=1)
    print(f'hold: the vehicle at most {np.max(distance) * 100:.1f} cm from its release position')
    assert np.max(distance) < 0.05


def test_uvms_plot_draws_the_session_shaded_by_mode(session: Session, tmp_path: Path) -> None:
    """pilot_session.png from the recording: every mode of the session in its shading."""
    written = plot_recording(session.path, tmp_path)
    assert tmp_path / 'pilot_session.png' in written
    modes = [mode for _, mode in mode_changes(session.path, load_run(session.path).time_origin_ns)]
    assert {'pilot', 'task', 'hold'} <= set(modes)
    assert modes.index('pilot') < modes.index('task')  # the pilot drove, then the task ran
