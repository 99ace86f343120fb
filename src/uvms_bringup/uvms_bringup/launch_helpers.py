"""What the graph is made of, shared by the in-process runner and the ROS 2 launch file.

Pure Python (no rclpy, no launch): which nodes run, from which package and executable,
with which parameter files and which per-mode parameters. ``uvms_run.graph`` builds
the nodes in one process from it; ``launch/uvms.launch.py`` starts them as processes.
"""

from __future__ import annotations

import importlib.util
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml
from uvms_scenarios.scenario import ParameterValue, Scenario
from uvms_tasks.mission_outcome import MISSION_READY_TOPIC
from uvms_tasks.task_file import Yaml12Loader
from uvms_viz.foxglove_defaults import FOXGLOVE_HOST, FOXGLOVE_PORT

#: Namespace of the robot's nodes and topics (``/clock``, ``/tf`` stay global).
DEFAULT_NAMESPACE = 'uvms'

#: Execution modes of the graph.
MODES = ('lockstep', 'realtime')

#: Parameter of the controller and the allocator selecting what triggers a step, per mode.
TRIGGER_PARAMETER = 'trigger_mode'
#: In both modes a step runs when the data of one stamp has arrived (``lockstep``: the
#: controller on each state, the allocator on each command), so each state the simulator
#: publishes is answered once. In real time the simulator alone keeps the wall clock; a
#: controller on its own 500 Hz timer (``timer``) beats against the simulator's timer and
#: found no new state in 13-18 % of its periods (bench_realtime, 2026-12-03), 0.0 % so.
TRIGGER = {'lockstep': 'lockstep', 'realtime': 'lockstep'}


@dataclass(frozen=True)
class NodeSpec:
    """One node of the graph.

    Attributes:
        name: Node name (also the scenario section of its overrides).
        package: ROS package of the executable.
        executable: Console script that ``ros2 run`` starts.
        module: Python module holding the node class and ``main``.
        class_name: Node class in that module.
        parameter_files: Files of ``config/`` loaded with ``--params-file``, in order.
        uses_sim_time: Whether the node runs on ``/clock`` (all but the clock source).
        finishes: Whether the node ends by itself, exit status 0, without ending the run
            (the mission node, once its goals are done).
        takes_robot: Whether the node declares ``robot_name`` (loads a robot folder).
    """

    name: str
    package: str
    executable: str
    module: str
    class_name: str
    parameter_files: tuple[str, ...]
    uses_sim_time: bool = True
    finishes: bool = False
    takes_robot: bool = False


SIMULATOR = NodeSpec(
    'simulator', 'uvms_sim', 'simulator', 'uvms_sim.simulator_node', 'SimulatorNode',
    ('robot.yaml',), uses_sim_time=False, takes_robot=True,
)
CONTROLLER = NodeSpec(
    'controller', 'uvms_control', 'controller', 'uvms_control.controller_node',
    'ControllerNode', ('robot.yaml', 'controller.yaml'), takes_robot=True,
)
THRUSTER_ALLOCATOR = NodeSpec(
    'thruster_allocator', 'uvms_thrusters', 'thruster_allocator',
    'uvms_thrusters.thruster_allocator_node', 'ThrusterAllocatorNode',
    ('robot.yaml', 'controller.yaml'), takes_robot=True,
)
VISUALIZER = NodeSpec(
    'visualizer', 'uvms_viz', 'visualizer', 'uvms_viz.visualizer_node',
    'VisualizerNode', (),
)
FOXGLOVE_SERVER = NodeSpec(
    'foxglove_server', 'uvms_viz', 'foxglove_server', 'uvms_viz.foxglove_server_node',
    'FoxgloveServerNode', (),
)
RECORDER = NodeSpec(
    'recorder', 'uvms_recording', 'recorder', 'uvms_recording.recorder_node', 'RecorderNode', (),
)
#: The navigation filter (uvms_navigation), when a scenario asks for it (``uses_estimator``).
ESTIMATOR = NodeSpec(
    'estimator', 'uvms_navigation', 'estimator', 'uvms_navigation.estimator_node',
    'EstimatorNode', (), takes_robot=True,
)
#: The hardware bridges (uvms_hardware; ``uvms launch --hardware``), by node name.
HARDWARE_BRIDGES = {
    name: NodeSpec(name, 'uvms_hardware', name, f'uvms_hardware.{name}_node', class_name, (),
                   takes_robot=True)
    for name, class_name in (('ardusub_bridge', 'ArduSubBridgeNode'),
                             ('dvl_bridge', 'DvlBridgeNode'),
                             ('alpha5_bridge', 'Alpha5BridgeNode'),
                             ('netft_bridge', 'NetFtBridgeNode'))}
#: The protocol twins on the simulator (``uvms launch --hardware twin``).
HARDWARE_TWINS = NodeSpec(
    'hardware_twins', 'uvms_twins', 'hardware_twins', 'uvms_twins.twins_node',
    'TwinsNode', (), takes_robot=True,
)
#: The simulator with the protocol twins in its own process (``uvms launch --hardware twin``,
#: the default; ``--twins-apart`` runs ``HARDWARE_TWINS`` instead). The launch keeps calling
#: the node ``SIMULATOR`` (its remaps, start-up gates, scheduling and end are the simulator's);
#: only its executable is this one (``launcher.node_command``).
SIMULATOR_WITH_TWINS = NodeSpec(
    'simulator', 'uvms_twins', 'simulator_with_twins', 'uvms_twins.simulator_with_twins',
    'SimulatorWithTwins', ('robot.yaml',), uses_sim_time=False, takes_robot=True,
)
#: What the recorder records beside its defaults when the estimator runs.
NAVIGATION_TOPICS = (
    'imu:sensor_msgs/msg/Imu',
    'dvl:geometry_msgs/msg/TwistWithCovarianceStamped',
    'depth:geometry_msgs/msg/PoseWithCovarianceStamped',
    'position_fix:geometry_msgs/msg/PoseWithCovarianceStamped',
    'odometry/filtered:nav_msgs/msg/Odometry',
)

#: Sends a scenario's mission through the ContactTask action (``uvms_tasks``), then exits.
#: Not on /clock: its goals carry their start times on the controller's clock, and a /clock
#: subscription would cost every lockstep period a message for nothing.
MISSION = NodeSpec(
    'mission', 'uvms_tasks', 'mission', 'uvms_tasks.mission_node', 'MissionNode', (),
    uses_sim_time=False, finishes=True,
)

#: The processes of the control loop, given SCHED_FIFO by ``uvms launch`` (DESIGN.md, "Real
#: time on a busy computer"), with the hardware bridges and, on the test stand, the twins that
#: stand for the devices. The recorder, visualizer, mission and Foxglove server stay at normal
#: priority.
LOOP_NODES = (SIMULATOR, CONTROLLER, THRUSTER_ALLOCATOR, ESTIMATOR, *HARDWARE_BRIDGES.values(),
              HARDWARE_TWINS)
#: The bridges that only read sensors (DVL, Net F/T): SCHED_FIFO below the control loop
#: (``launch_layout.node_scheduling``), so that a sensor's stream never delays a control period
#: (issue 46). The actuator bridges (ArduSub, Alpha 5) carry the loop's commands: at its
#: priority.
SENSOR_BRIDGES = (HARDWARE_BRIDGES['dvl_bridge'], HARDWARE_BRIDGES['netft_bridge'])

#: The nodes that always run, in start order; the Foxglove server joins for a live view and
#: the recorder, last, when there is an output.
CORE_NODES = (SIMULATOR, CONTROLLER, THRUSTER_ALLOCATOR, VISUALIZER)

def uses_estimator(scenario: Scenario | None) -> bool:
    """Whether a scenario runs the estimator.

    It does with an ``estimator:`` section or a controller on ``state_source: estimate``
    (whose simulator then needs ``navigation.enabled: true``).
    """
    if scenario is None:
        return False
    controller = scenario.overrides.get('controller', {})
    return 'estimator' in scenario.overrides or controller.get('state_source') == 'estimate'


def recorder_wait(spec: NodeSpec, record: bool,
                  scenario: Scenario | None = None) -> dict[str, ParameterValue]:
    """The simulator's ``startup.recorder`` when a recorder runs in a process of its own.

    The simulator then publishes its first state only once the recorder's subscriptions to
    the state topics are matched, so the recording starts at t = 0 however long the
    recorder's process takes to start (``uvms launch``, ``uvms.launch.py``; in one process
    the graph runner builds the recorder before the first state goes out). A scenario that
    gives the recorder its own ``topics`` gives the simulator them too
    (``startup.recorder_topics``): it waits only for the state topics among them.
    """
    if spec is not SIMULATOR or not record:
        return {}
    values: dict[str, ParameterValue] = {'startup.recorder': RECORDER.name}
    topics = scenario.node_overrides(RECORDER.name).get('topics') if scenario else None
    if isinstance(topics, list) and topics:
        values['startup.recorder_topics'] = [str(entry).rsplit(':', 1)[0] for entry in topics]
    return values


def mission_wait(spec: NodeSpec, mission: bool) -> dict[str, ParameterValue]:
    """The simulator's ``startup.mission`` when the run has a mission.

    The simulator then publishes its first state only once the mission has found the
    controller's action server (its latched ``mission/ready``), so that no goal starts late
    however long discovery takes (issue 48: a mission once did not find the server in 10 s).
    """
    return {'startup.mission': MISSION_READY_TOPIC} if spec is SIMULATOR and mission else {}


def graph_nodes(record: bool, foxglove: bool = False, mission: bool = False,
                estimator: bool = False) -> tuple[NodeSpec, ...]:
    """The nodes of a run; estimator, mission sender, live view and recorder (last) if asked."""
    return (SIMULATOR, *((ESTIMATOR,) if estimator else ()), *CORE_NODES[1:],
            *((MISSION,) if mission else ()),
            *((FOXGLOVE_SERVER,) if foxglove else ()), *((RECORDER,) if record else ()))


def mission_file_text(scenario: Scenario) -> str:
    """The scenario's ``mission:`` as the text of a mission file ('' without a mission)."""
    if not scenario.mission:
        return ''
    document = yaml.load(scenario.path.read_text(encoding='utf-8'), Loader=Yaml12Loader)
    return yaml.safe_dump({'mission': document['mission']}, sort_keys=False)


def write_mission_file(scenario: Scenario, directory: Path) -> Path:
    """The scenario's ``mission:`` as a mission file in directory, for the mission process."""
    path = directory / 'mission.yaml'
    path.write_text(mission_file_text(scenario), encoding='utf-8')
    return path


def node_parameters(
    spec: NodeSpec,
    scenario: Scenario | None,
    mode: str,
    duration_s: float | None = None,
    output_path: str | None = None,
    foxglove_address: tuple[str, int] | None = None,
    robot: str | None = None,
) -> dict[str, ParameterValue]:
    """Parameters of one node beyond its parameter files: scenario overrides and mode.

    Args:
        spec: The node.
        scenario: The scenario, or None for the defaults of the parameter files.
        mode: ``lockstep`` or ``realtime``.
        duration_s: Simulated time after which the simulator stops stepping; None or 0 runs
            forever.
        output_path: MCAP file of the recorder.
        foxglove_address: Host and port of the Foxglove server (default ones if None).
        robot: Robot folder for every node that takes ``robot_name``; None: the scenario's
            ``robot:``, else the nodes' default.

    Returns:
        Parameter name to value; later entries win over the parameter files.
    """
    if mode not in MODES:
        msg = f'mode must be one of {", ".join(MODES)}, got {mode!r}'
        raise ValueError(msg)
    values: dict[str, ParameterValue] = {}
    if scenario is not None:
        values.update(scenario.node_overrides(spec.name))
    robot = robot if robot is not None else (scenario.robot if scenario is not None else None)
    if robot is not None and spec.takes_robot:
        values['robot_name'] = robot
    if spec.uses_sim_time:
        values['use_sim_time'] = True
    if spec is SIMULATOR:
        values['mode'] = mode
        values['duration_s'] = float(duration_s or 0.0)
    elif spec in (CONTROLLER, THRUSTER_ALLOCATOR):
        values[TRIGGER_PARAMETER] = TRIGGER[mode]
        if spec is CONTROLLER and mode == 'realtime' and uses_estimator(scenario):
            # The estimate arrives after the state it is stamped with, and not for every
            # stamp under load: a controller waiting for complete stamps stalled (INPUTS_STALE),
            # one on its timer beat against the states (docs/running.md). It steps on each
            # estimate instead, with the latest joint states and wrench.
            values[TRIGGER_PARAMETER] = 'odometry'
    elif spec is FOXGLOVE_SERVER:
        host, port = foxglove_address or (FOXGLOVE_HOST, FOXGLOVE_PORT)
        values['host'] = host
        values['port'] = int(port)
    elif spec is RECORDER:
        if output_path is not None:
            values['output_path'] = output_path
        values['run.scenario'] = scenario.name if scenario is not None else ''
        values['run.seed'] = scenario.seed if scenario is not None else 0
        values['run.mode'] = mode
        # The goals the run sends, so that replay can re-run the controller on them too.
        values['run.mission'] = mission_file_text(scenario) if scenario is not None else ''
        if uses_estimator(scenario) and 'topics' not in values:
            from uvms_recording.recorded_topics import DEFAULT_TOPICS  # rclpy: only when needed

            values['topics'] = [*DEFAULT_TOPICS, *NAVIGATION_TOPICS]
    return values


def file_parameters(path: Path, node_name: str, namespace: str) -> dict[str, Any]:
    """Flat parameters that a ROS 2 parameter file gives one node.

    Reads the sections that apply to ``/namespace/node_name``: ``/**``, ``/**/node_name``,
    ``node_name`` and ``/namespace/node_name``, later ones winning as in rcl.
    """
    data = yaml.safe_load(path.read_text(encoding='utf-8')) or {}
    keys = ('/**', f'/**/{node_name}', node_name, f'/{namespace.strip("/")}/{node_name}')
    values: dict[str, Any] = {}
    for key in keys:
        section = data.get(key, {}) or {}
        values.update(flat_parameters(section.get('ros__parameters', {}) or {}))
    return values


def parameters_file_text(values_by_node: Mapping[str, Mapping[str, Any]]) -> str:
    """ROS 2 parameter file text, node name -> nested ``ros__parameters``."""
    document = {node: {'ros__parameters': _nest(values)}
                for node, values in sorted(values_by_node.items())}
    return yaml.safe_dump(document, sort_keys=True)


def flat_parameters(section: Mapping[str, Any], prefix: str = '') -> dict[str, Any]:
    """Nested parameter mappings to dotted names, as rcl reads them."""
    flat: dict[str, Any] = {}
    for key, value in section.items():
        if isinstance(value, Mapping):
            flat.update(flat_parameters(value, f'{prefix}{key}.'))
        else:
            flat[f'{prefix}{key}'] = value
    return flat


def _nest(values: Mapping[str, Any]) -> dict[str, Any]:
    """Dotted names to nested mappings, as parameter files write them."""
    nested: dict[str, Any] = {}
    for name, value in values.items():
        *groups, leaf = name.split('.')
        target = nested
        for group in groups:
            target = target.setdefault(group, {})
        target[leaf] = value
    return nested


def config_dir() -> Path:
    """Directory of the parameter files (robot.yaml, controller.yaml, scenarios/).

    Looked up in this order: the copy a wheel install bundles (``uvms_bringup/_config``),
    the source checkout (``config/`` at the repository top), the ROS 2 share directory
    (``share/uvms_bringup/config`` after ``colcon build``).

    Raises:
        FileNotFoundError: None of them holds ``robot.yaml``.
    """
    here = Path(__file__).resolve().parent
    candidates = [here / '_config', here.parents[2] / 'config']
    if importlib.util.find_spec('ament_index_python') is not None:
        from ament_index_python.packages import (  # type: ignore[import-not-found]
            PackageNotFoundError,
            get_package_share_directory,
        )

        try:
            candidates.append(Path(get_package_share_directory('uvms_bringup')) / 'config')
        except (PackageNotFoundError, OSError, ValueError):
            # Not installed by colcon, or no ament index at all: a wheel venv has no
            # AMENT_PREFIX_PATH and ament_index_python raises an OSError then.
            pass
    for candidate in candidates:
        if (candidate / 'robot.yaml').is_file():
            return candidate
    msg = 'no parameter directory with robot.yaml in ' + ', '.join(map(str, candidates))
    raise FileNotFoundError(msg)


def resolve_scenario_path(name_or_path: str, directory: Path | None = None) -> Path:
    """A scenario given as a file path, or as a name of ``config/scenarios/NAME.yaml``.

    Raises:
        FileNotFoundError: no such file; the message lists the scenarios there are.
    """
    path = Path(name_or_path)
    base = directory if directory is not None else config_dir()
    if path.exists():
        return path
    if path.suffix not in ('.yaml', '.yml'):
        path = base / 'scenarios' / f'{name_or_path}.yaml'
        if path.exists():
            return path
    names = sorted(p.stem for p in (base / 'scenarios').glob('*.yaml'))
    msg = (f'no scenario {name_or_path!r}: {path} does not exist; the scenarios in '
           f'{base / "scenarios"} are {", ".join(names) if names else "(none)"}')
    raise FileNotFoundError(msg)
