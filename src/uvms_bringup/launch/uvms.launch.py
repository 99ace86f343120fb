r"""Launch the UVMS graph on ROS 2 Jazzy: simulator, controller, allocator, visualizer, recorder.

Usage::

    ros2 launch uvms_bringup uvms.launch.py
    ros2 launch uvms_bringup uvms.launch.py scenario:=case1_ke1e4 mode:=lockstep \\
        output_path:=/tmp/case1.mcap
    ros2 launch uvms_bringup uvms.launch.py foxglove:=true   # live view, ws://127.0.0.1:8765

Each node is its own process in the namespace ``/uvms`` (``/clock``, ``/tf`` and
``/tf_static`` stay global), with the parameter files installed in
``share/uvms_bringup/config`` and the scenario's overrides. The simulator is the clock
source (``/clock``); the other nodes run on simulated time unless ``use_sim_time:=false``.
Keep the traffic on this machine with ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from ament_index_python.packages import get_package_share_directory
from launch import LaunchContext, LaunchDescription
from launch.actions import DeclareLaunchArgument, OpaqueFunction
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node
from uvms_bringup.declared import check_scenario_overrides
from uvms_bringup.launch_helpers import (
    DEFAULT_NAMESPACE,
    MISSION,
    MODES,
    RECORDER,
    file_parameters,
    graph_nodes,
    mission_wait,
    node_parameters,
    parameters_file_text,
    recorder_wait,
    resolve_scenario_path,
    uses_estimator,
    write_mission_file,
)
from uvms_scenarios.scenario import load_scenario
from uvms_viz.foxglove_defaults import FOXGLOVE_HOST, FOXGLOVE_PORT


def _launch_nodes(context: LaunchContext) -> list[Node]:
    """Build the node actions once the launch arguments are known."""
    config = os.path.join(get_package_share_directory('uvms_bringup'), 'config')
    scenario_arg = LaunchConfiguration('scenario').perform(context)
    mode = LaunchConfiguration('mode').perform(context)
    use_sim_time = LaunchConfiguration('use_sim_time').perform(context).lower() in ('true', '1')
    duration_s = float(LaunchConfiguration('duration').perform(context))
    output_path = LaunchConfiguration('output_path').perform(context)
    namespace = LaunchConfiguration('namespace').perform(context)
    foxglove = LaunchConfiguration('foxglove').perform(context).lower() in ('true', '1')
    robot = LaunchConfiguration('robot').perform(context) or None
    foxglove_address = (LaunchConfiguration('foxglove_host').perform(context),
                        int(LaunchConfiguration('foxglove_port').perform(context)))
    if mode not in MODES:
        msg = f"launch argument mode:={mode}: expected one of {', '.join(MODES)}"
        raise ValueError(msg)
    scenario = None
    if scenario_arg:
        scenario = load_scenario(resolve_scenario_path(scenario_arg, Path(config)))
        scenario = scenario.with_changes(robot=robot)
        # Typed as uvms run and uvms launch type them (an int on a float parameter is a float).
        scenario = check_scenario_overrides(scenario, config=Path(config),
                                            namespace=namespace or DEFAULT_NAMESPACE)
    actions = []
    run_values = {}
    mission = scenario is not None and bool(scenario.mission)
    for spec in graph_nodes(record=bool(output_path), foxglove=foxglove, mission=mission,
                            estimator=uses_estimator(scenario)):
        overrides = node_parameters(spec, scenario, mode, duration_s, output_path or None,
                                    foxglove_address, robot)
        overrides.update(recorder_wait(spec, bool(output_path), scenario))
        overrides.update(mission_wait(spec, mission))
        if spec is MISSION:
            assert scenario is not None
            overrides['mission_file'] = str(write_mission_file(
                scenario, Path(tempfile.mkdtemp(prefix='uvms_mission_'))))
        if spec.uses_sim_time:
            overrides['use_sim_time'] = use_sim_time
        if spec is RECORDER:
            # What the other nodes were given, so that replay can rebuild the controller.
            overrides['run.parameters'] = parameters_file_text(run_values)
        else:
            values = {}
            for file in spec.parameter_files:
                values.update(file_parameters(Path(config, file), spec.name, namespace))
            run_values[f'/{namespace.strip("/")}/{spec.name}'] = {**values, **overrides}
        actions.append(
            Node(
                package=spec.package,
                executable=spec.executable,
                name=spec.name,
                namespace=namespace,
                parameters=[
                    *(os.path.join(config, file) for file in spec.parameter_files),
                    overrides,
                ],
                output='screen',
                emulate_tty=True,
            )
        )
    return actions


def generate_launch_description() -> LaunchDescription:
    """Launch arguments and the nodes of the graph."""
    return LaunchDescription([
        DeclareLaunchArgument(
            'scenario', default_value='',
            description='Scenario name (config/scenarios/NAME.yaml) or path to a scenario '
                        'file; empty: the defaults of the parameter files.',
        ),
        DeclareLaunchArgument(
            'robot', default_value='',
            description="Robot folder of uvms_description (robots/NAME); empty: the "
                        "scenario's robot:, else paper_uvms.",
        ),
        DeclareLaunchArgument(
            'mode', default_value='realtime', choices=list(MODES),
            description='realtime: the simulator on a wall-clock timer, controller and '
                        'allocator answering each state; lockstep: the simulator waits for the '
                        'actuator command of each step (deterministic).',
        ),
        DeclareLaunchArgument(
            'use_sim_time', default_value='true', choices=['true', 'false'],
            description='Whether controller, allocator and recorder run on /clock.',
        ),
        DeclareLaunchArgument(
            'duration', default_value='0.0',
            description='Simulated seconds after which the simulator stops stepping; '
                        '0 runs until Ctrl-C.',
        ),
        DeclareLaunchArgument(
            'output_path', default_value='',
            description='MCAP file to record every topic of the graph to; empty: no recorder.',
        ),
        DeclareLaunchArgument(
            'namespace', default_value=DEFAULT_NAMESPACE,
            description='Namespace of the nodes and their topics.',
        ),
        DeclareLaunchArgument(
            'foxglove', default_value='false', choices=['true', 'false'],
            description='Start foxglove_server: the live view for the Foxglove app.',
        ),
        DeclareLaunchArgument(
            'foxglove_port', default_value=str(FOXGLOVE_PORT),
            description='TCP port of the Foxglove live view.',
        ),
        DeclareLaunchArgument(
            'foxglove_host', default_value=FOXGLOVE_HOST,
            description='Address the live view binds; 127.0.0.1 keeps it on this machine.',
        ),
        OpaqueFunction(function=_launch_nodes),
    ])
