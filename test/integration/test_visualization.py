"""A lockstep recording carries what Foxglove and RViz need to draw the run.

Read with rosbags (an oracle independent of the recorder): /robot_description parses as a
URDF (Pinocchio's parser), /tf holds the robot's frames, and the markers sit where the
contact and controller topics of the same stamps say.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections import defaultdict
from pathlib import Path
from typing import Any

import pinocchio as pin
import pytest
from rosbags.highlevel import AnyReader
from uvms_recording.typestore import uvms_typestore
from uvms_run.graph import build_graph, run_graph
from uvms_scenarios.scenario import load_scenario
from uvms_viz.marker_geometry import WALL_THICKNESS_M

SCENARIOS = Path(__file__).resolve().parents[2] / 'config' / 'scenarios'
DURATION_S = 0.6
TRAIL_LENGTH = 5


def ns(stamp: Any) -> int:
    """Nanoseconds of a builtin_interfaces/Time."""
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


@pytest.fixture(scope='module')
def messages(tmp_path_factory: pytest.TempPathFactory) -> dict[str, list[tuple[Any, Any]]]:
    """(log time, message) per topic of a recorded Case III run, a short trail."""
    path = tmp_path_factory.mktemp('viz') / 'case3.mcap'
    scenario = load_scenario(SCENARIOS / 'case3_moving_wall.yaml').with_changes(
        duration_s=DURATION_S)
    graph = build_graph(scenario, 'lockstep', output_path=path,
                        extra_overrides={'visualizer': {'trail_length': TRAIL_LENGTH}})
    run_graph(graph)
    result: dict[str, list[tuple[Any, Any]]] = defaultdict(list)
    with AnyReader([path], default_typestore=uvms_typestore()) as reader:
        for connection, log_time, raw in reader.messages():
            result[connection.topic].append(
                (log_time, reader.deserialize(raw, connection.msgtype)))
    return result


def test_robot_description_is_recorded_once_and_parses_as_the_urdf(
        messages: dict[str, list[tuple[Any, Any]]]) -> None:
    """One latched message; Pinocchio builds the vehicle's three-joint arm from it."""
    ((_, msg),) = messages['/robot_description']
    robot = ET.fromstring(msg.data)
    assert robot.tag == 'robot'
    assert {'base_link_frd', 'link_1', 'link_2', 'link_3', 'ee_link'} <= {
        link.get('name') for link in robot.iter('link')}
    model = pin.buildModelFromXML(msg.data)
    assert [name for name in model.names if name.startswith('joint_')] == [
        'joint_1', 'joint_2', 'joint_3']


def test_tf_draws_the_urdf_links(messages: dict[str, list[tuple[Any, Any]]]) -> None:
    """/tf and /tf_static name every link of the URDF under map_ned and map."""
    ((_, description),) = messages['/robot_description']
    links = {link.get('name') for link in ET.fromstring(description.data).iter('link')}
    children = {t.child_frame_id for topic in ('/tf', '/tf_static')
                for _, msg in messages[topic] for t in msg.transforms}
    parents = {t.header.frame_id for topic in ('/tf', '/tf_static')
               for _, msg in messages[topic] for t in msg.transforms}
    assert links <= children
    assert {'map', 'map_ned'} <= parents | children


def test_markers_come_at_20_hz_of_simulated_time_in_map_ned(
        messages: dict[str, list[tuple[Any, Any]]]) -> None:
    """One MarkerArray every 50 ms simulated, from t = 0, all four markers in map_ned."""
    arrays = [msg for _, msg in messages['/uvms/markers']]
    stamps = [ns(array.markers[0].header.stamp) for array in arrays]
    assert stamps == [k * 50_000_000 for k in range(len(stamps))]
    assert len(stamps) == round(DURATION_S * 20) + 1
    for array in arrays:
        assert [m.ns for m in array.markers] == ['wall', 'contact_force', 'reference', 'trail']
        assert {m.header.frame_id for m in array.markers} == {'map_ned'}


def test_markers_sit_where_contact_and_controller_state_say(
        messages: dict[str, list[tuple[Any, Any]]]) -> None:
    """Wall face on the contact's wall position, X_d and the arrow's tail from the state."""
    contact = {ns(msg.header.stamp): msg for _, msg in messages['/uvms/contact']}
    state = {ns(msg.header.stamp): msg for _, msg in messages['/uvms/controller/state']}
    for _, array in messages['/uvms/markers']:
        wall, force, reference, trail = array.markers
        t_ns = ns(wall.header.stamp)
        face_x = wall.pose.position.x - 0.5 * wall.scale.x
        assert face_x == pytest.approx(contact[t_ns].wall_position, abs=1e-12)
        assert wall.scale.x == pytest.approx(WALL_THICKNESS_M)
        x_d = state[t_ns].desired_position
        assert (reference.pose.position.x, reference.pose.position.y,
                reference.pose.position.z) == (x_d.x, x_d.y, x_d.z)
        x = state[t_ns].position
        tail = force.points[0]
        assert (tail.x, tail.y, tail.z) == (x.x, x.y, x.z)
        assert (trail.points[-1].x, trail.points[-1].y, trail.points[-1].z) == (x.x, x.y, x.z)


def test_trail_keeps_at_most_its_length(messages: dict[str, list[tuple[Any, Any]]]) -> None:
    """The trail grows one point per marker instant up to trail_length, then slides."""
    lengths = [len(array.markers[3].points) for _, array in messages['/uvms/markers']]
    assert lengths[:TRAIL_LENGTH] == list(range(1, TRAIL_LENGTH + 1))
    assert set(lengths[TRAIL_LENGTH:]) == {TRAIL_LENGTH}
