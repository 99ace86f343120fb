"""The shipped Foxglove layout: valid JSON naming only what the graph publishes."""

from __future__ import annotations

import json
import re
from typing import Any

import pytest
from rosbags.typesys.store import Nodetype
from uvms_recording.recorder_node import DEFAULT_TOPICS, parse_topic_spec
from uvms_recording.typestore import uvms_typestore

import uvms_description

LAYOUT = json.loads(uvms_description.foxglove_layout_path().read_text(encoding='utf-8'))
#: The graph's topics (name -> type), relative names in the /uvms namespace.
GRAPH_TOPICS = {
    (topic if topic.startswith('/') else f'/uvms/{topic}'): type_name
    for topic, type_name in map(parse_topic_spec, DEFAULT_TOPICS)
}
SCRIPT_PREFIX = '/studio_script/'


def scripts() -> list[dict[str, Any]]:
    """The layout's user scripts: name, inputs, output topic and output fields."""
    found = []
    for script in LAYOUT['userNodes'].values():
        source = script['sourceCode']
        inputs = json.loads(re.search(r'export const inputs = (\[.*?\]);', source).group(1))
        output = re.search(r'export const output = "(.*?)";', source).group(1)
        fields = re.search(r'type Output = \{(.*?)\};', source).group(1)
        found.append({'name': script['name'], 'inputs': inputs, 'output': output,
                      'fields': set(re.findall(r'(\w+): number', fields))})
    return found


def plot_paths() -> list[str]:
    """Every message path the plots draw."""
    return [series['value'] for panel_id, config in LAYOUT['configById'].items()
            if panel_id.startswith('Plot!') for series in config['paths']]


def three_d_topics() -> set[str]:
    """Topics the 3-D panel shows: its topic settings and its topic layers."""
    (config,) = (c for panel_id, c in LAYOUT['configById'].items() if panel_id.startswith('3D!'))
    layers = {layer['topic'] for layer in config['layers'].values()
              if layer.get('sourceType') == 'topic'}
    return set(config['topics']) | layers


def field_exists(type_name: str, path: list[str]) -> bool:
    """Whether a dotted field path names a field of a message type (rosbags typestore)."""
    fielddefs = uvms_typestore().fielddefs
    current: str | None = type_name
    for name in path:
        if current is None:
            return False  # a path going on past a number
        fields = dict(fielddefs[current][1])
        if name not in fields:
            return False
        node_type, detail = fields[name]
        current = detail if node_type == Nodetype.NAME else None
    return current is None


def test_layout_has_the_3d_view_and_the_plots_the_readme_names() -> None:
    """A 3-D panel drawing the URDF, and plots of F_e with F_d, W and the position errors."""
    panels = set(LAYOUT['configById'])
    assert {'3D!uvms', 'Plot!force', 'Plot!weight', 'Plot!position_error'} <= panels
    assert '/robot_description' in three_d_topics()
    assert '/uvms/markers' in three_d_topics()
    paths = plot_paths()
    assert '/uvms/controller/state.contact_force.x' in paths
    assert '/uvms/controller/state.desired_force.x' in paths
    assert '/uvms/controller/state.weight' in paths


def test_every_layout_panel_is_placed() -> None:
    """Each configured panel appears once in the layout tree, and nothing else does."""
    def leaves(node: Any) -> list[str]:
        if isinstance(node, str):
            return [node]
        return leaves(node['first']) + leaves(node['second'])

    assert sorted(leaves(LAYOUT['layout'])) == sorted(LAYOUT['configById'])


@pytest.mark.parametrize('topic', sorted(three_d_topics()))
def test_3d_panel_names_only_graph_topics(topic: str) -> None:
    """The 3-D panel's topics are published by the graph."""
    assert topic in GRAPH_TOPICS


@pytest.mark.parametrize('path', plot_paths())
def test_plot_paths_name_graph_topics_and_their_fields(path: str) -> None:
    """A plotted path is a field of a graph topic, or of a script fed by graph topics."""
    topic, *field_path = path.split('.')
    if topic.startswith(SCRIPT_PREFIX):
        (script,) = (s for s in scripts() if s['output'] == topic)
        assert field_path[0] in script['fields']
    else:
        assert topic in GRAPH_TOPICS
        assert field_exists(GRAPH_TOPICS[topic], field_path), path


def test_scripts_read_graph_topics_and_write_script_topics() -> None:
    """User scripts take graph topics as input and publish under /studio_script/ only."""
    assert scripts()
    for script in scripts():
        assert set(script['inputs']) <= set(GRAPH_TOPICS), script['name']
        assert script['output'].startswith(SCRIPT_PREFIX), script['name']


def test_field_check_rejects_what_is_no_number_field() -> None:
    """The oracle of the plot test: a misspelt field or a message-valued path fails it."""
    assert not field_exists('uvms_msgs/msg/ControllerState', ['contact_forse', 'x'])
    assert not field_exists('uvms_msgs/msg/ControllerState', ['contact_force'])
    assert not field_exists('uvms_msgs/msg/ControllerState', ['weight', 'x'])


def test_the_position_error_script_reads_existing_fields() -> None:
    """X and X_d the script subtracts are fields of uvms_msgs/ControllerState."""
    assert field_exists('uvms_msgs/msg/ControllerState', ['position', 'x'])
    assert field_exists('uvms_msgs/msg/ControllerState', ['desired_position', 'z'])
    (source,) = (s['sourceCode'] for s in LAYOUT['userNodes'].values())
    assert 'event.message.position' in source
    assert 'event.message.desired_position' in source


def test_3d_view_follows_a_frame_of_the_tf_tree() -> None:
    """The display frame is the ENU twin 'map' that /tf_static ties to map_ned."""
    assert LAYOUT['configById']['3D!uvms']['followTf'] == 'map'
