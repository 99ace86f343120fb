"""``uvms launch --hardware twin|FILE``: which bridges run, where they connect, and the twins.

A hardware file (``config/hardware/*.yaml``) names each bridge's connection as that bridge's
parameters; ``twins: true`` starts the protocol twins where the bridges connect, fed by the
simulator, and ``twins: {alpha5_bus: true}`` starts them with settings of the stand
(``uvms_twins.twin_stand.checked_settings``). The same file with the pool's addresses and
``twins: false`` drives the robot::

    twins: true
    bridges:
      ardusub_bridge: {mavlink_url: 'udpout:127.0.0.1:14551'}
      dvl_bridge: {address: '127.0.0.1:16171'}
      alpha5_bridge: {connection: 'udp:127.0.0.1:6789'}
      netft_bridge: {address: '127.0.0.1:49152'}

Pure: reads the file, checks it, and says what the launch changes. The bridges then stand where
the simulator's topics were: with twins the simulator's measurement topics and its actuator
input are remapped under ``/plant`` (where the twins read and write), its ground truth
(``odometry``, ``contact``, ``ee_pose``, ``/clock``) stays where it is, for judging; the
controller runs on the estimate (a robot has no ground truth), and the allocator sends desired
thrusts (the propellers, or the twins' thruster model, do the dynamics).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import yaml
from uvms_scenarios.scenario import Scenario
from uvms_sim.parameters import SPECS_BY_NAME as SIMULATOR_SPECS

from uvms_bringup.launch_helpers import HARDWARE_BRIDGES, HARDWARE_TWINS, SIMULATOR, NodeSpec

#: The bridges a hardware file may name, in start order.
BRIDGES = ('ardusub_bridge', 'dvl_bridge', 'alpha5_bridge', 'netft_bridge')
#: The parameter of each bridge that names its connection (required in the file).
CONNECTION_PARAMETER = {'ardusub_bridge': 'mavlink_url', 'dvl_bridge': 'address',
                        'alpha5_bridge': 'connection', 'netft_bridge': 'address'}
#: The managed nodes the simulator waits for before physics starts (its own default).
SIMULATOR_STARTUP_NODES = SIMULATOR_SPECS['startup.nodes'].default
#: Where the simulator's device-side topics go when the twins stand in for the devices.
PLANT_NAMESPACE = '/plant'
#: The simulator's topics that the bridges replace (relative names, as the simulator's).
PLANT_TOPICS = ('joint_states', 'wrench', 'imu', 'dvl', 'depth', 'position_fix',
                'command/actuators')
#: What a shipped example file holds where only the user knows the value.
PLACEHOLDER = 'SET-ME'
#: The shipped hardware file that ``--hardware twin`` names.
TWIN = 'twin'
#: Depth of the twins' pool (m): a flat bottom for the DVL where the scenario has none.
TWIN_POOL_DEPTH_M = 2.0


class HardwareFileError(ValueError):
    """A hardware file that cannot be used: the message names the file and the key."""


@dataclass(frozen=True)
class HardwarePlan:
    """What a hardware file asks of a launch.

    Attributes:
        path: The hardware file.
        twins: Whether the protocol twins (fed by the simulator) stand in for the devices.
        bridges: Bridge node name -> its parameters from the file, in start order.
        twins_in_simulator: With twins: True serves them in the simulator's process
            (``uvms_twins.simulator_with_twins``: no /plant topics, no process of their
            own), False in the ``hardware_twins`` node beside it (``--twins-apart``).
        twin_settings: The stand's settings the file sets (``twins:`` as a mapping).
    """

    path: Path
    twins: bool
    bridges: dict[str, dict[str, Any]] = field(default_factory=dict)
    twins_in_simulator: bool = True
    twin_settings: dict[str, Any] = field(default_factory=dict)

    def simulator_remaps(self) -> list[tuple[str, str]]:
        """``--ros-args -r`` rules moving the simulator's device-side topics under /plant."""
        if not self.twins:
            return []
        return [(topic, f'{PLANT_NAMESPACE}/{topic}') for topic in PLANT_TOPICS]

    def twin_parameters(self) -> dict[str, Any]:
        """The twins node's parameters: each twin where its bridge connects, the settings."""
        return {**{f'{name}.connection': self.bridges[name][CONNECTION_PARAMETER[name]]
                   for name in self.bridges}, **self.twin_settings}


def hardware_file_path(name_or_path: str, config: Path) -> Path:
    """``twin`` or a name of ``config/hardware/`` or a path -> the hardware file.

    Raises:
        HardwareFileError: No such file (naming the files there are).
    """
    path = Path(name_or_path)
    if path.suffix not in ('.yaml', '.yml'):
        path = config / 'hardware' / f'{name_or_path}.yaml'
    if not path.is_file():
        known = sorted(p.stem for p in (config / 'hardware').glob('*.yaml'))
        raise HardwareFileError(f'hardware file {name_or_path!r}: no such file ({path}); '
                                f'shipped: {", ".join(known) or "none"}')
    return path


def load_hardware_plan(path: Path) -> HardwarePlan:
    """Read and check a hardware file.

    Raises:
        HardwareFileError: Unknown keys or bridges, a bridge without its connection, or a
            file that is not a mapping (each message names the file and the key).
    """
    try:
        document = yaml.safe_load(path.read_text(encoding='utf-8'))
    except yaml.YAMLError as exc:
        raise HardwareFileError(f'{path}: not YAML: {exc}') from exc
    if not isinstance(document, Mapping):
        raise HardwareFileError(f'{path}: expected a mapping with twins: and bridges:')
    unknown = set(document) - {'twins', 'bridges'}
    if unknown:
        raise HardwareFileError(f'{path}: unknown keys {sorted(unknown)}; '
                                'expected twins: and bridges:')
    twins = document.get('twins', False)
    settings: dict[str, Any] = {}
    if isinstance(twins, Mapping):  # the stand's names and types: the twins check them
        settings, twins = dict(twins), True
    if not isinstance(twins, bool):
        raise HardwareFileError(f'{path}: twins = {twins!r}: expected true, false or a '
                                "mapping of the stand's settings")
    bridges = document.get('bridges') or {}
    if not isinstance(bridges, Mapping):
        raise HardwareFileError(f'{path}: bridges: expected a mapping of bridge names')
    plan: dict[str, dict[str, Any]] = {}
    for name in bridges:
        if name not in BRIDGES:
            raise HardwareFileError(f'{path}: bridges.{name}: unknown bridge; '
                                    f'expected one of {", ".join(BRIDGES)}')
    for name in BRIDGES:
        if name not in bridges:
            continue
        parameters = dict(bridges[name] or {})
        for key, value in parameters.items():
            if isinstance(value, str) and PLACEHOLDER in value:
                raise HardwareFileError(f'{path}: bridges.{name}.{key} = {value!r}: '
                                        "set it to your device's address first")
        if CONNECTION_PARAMETER[name] not in parameters:
            raise HardwareFileError(f'{path}: bridges.{name}.{CONNECTION_PARAMETER[name]} '
                                    'is required (where the bridge connects)')
        plan[name] = parameters
    if not plan:
        raise HardwareFileError(f'{path}: bridges: names no bridge')
    return HardwarePlan(path, twins, plan, twin_settings=settings)


def hardware_scenario(scenario: Scenario, plan: HardwarePlan) -> Scenario:
    """The scenario as it runs on the hardware of ``plan``.

    The controller runs on the estimate (a robot has no ground truth); the allocator sends
    desired thrusts (the propellers do the dynamics); with twins, the simulator measures
    with its navigation sensors, over a flat bottom ``TWIN_POOL_DEPTH_M`` down unless the
    scenario sets one, and hands every sample on at once (ideal devices: the twins and
    bridges keep the devices' own timing).
    """
    overrides = {node: dict(values) for node, values in scenario.overrides.items()}
    overrides.setdefault('controller', {})['state_source'] = 'estimate'
    overrides.setdefault('thruster_allocator', {})['thruster_output'] = 'desired'
    if plan.twins:
        simulator = overrides.setdefault('simulator', {})
        simulator['navigation.enabled'] = True
        # The twins keep the devices' timing (their rates, the RC loop, the bus): a simulator
        # that also held its samples to it would apply the delays twice.
        simulator['devices.ideal'] = True
        if not simulator.get('world.seabed_depth_m'):
            simulator['world.seabed_depth_m'] = TWIN_POOL_DEPTH_M
    return replace(scenario, overrides=overrides)


def hardware_nodes(nodes: Sequence[NodeSpec], plan: HardwarePlan) -> list[NodeSpec]:
    """The launch's nodes on hardware: the bridges where the simulator stood.

    With twins the simulator stays (holding the twins, or followed by their node), then the
    bridges; without, the bridges replace it (the robot is the plant).
    """
    out: list[NodeSpec] = []
    for spec in nodes:
        if spec is SIMULATOR:
            if plan.twins:
                out += [SIMULATOR] if plan.twins_in_simulator else [SIMULATOR, HARDWARE_TWINS]
            out += [HARDWARE_BRIDGES[name] for name in plan.bridges]
        else:
            out.append(spec)
    return out


def hardware_parameters(nodes: Sequence[NodeSpec], plan: HardwarePlan
                        ) -> dict[str, dict[str, Any]]:
    """Parameters per node name that the hardware adds: connections, and the clock.

    Without twins there is no simulator and so no ``/clock``: every node runs on wall time.
    """
    values: dict[str, dict[str, Any]] = {name: dict(p) for name, p in plan.bridges.items()}
    simulator: dict[str, Any] = {}
    if plan.twins and plan.twins_in_simulator:
        simulator.update({f'twins.{name}': value
                          for name, value in plan.twin_parameters().items()})
    elif plan.twins:
        values[HARDWARE_TWINS.name] = plan.twin_parameters()
    # The simulator holds its first state until the loop is closed, and through the twins the
    # loop is closed only once every bridge drives its device: before, the arm twin makes no
    # torque (limp) and the estimator has no IMU, so physics started with the controller
    # alone would let the arm fall and the vehicle drift unseen.
    simulator['startup.nodes'] = [*SIMULATOR_STARTUP_NODES, *plan.bridges]
    values[SIMULATOR.name] = simulator
    for spec in nodes:
        if spec.uses_sim_time:
            values.setdefault(spec.name, {})['use_sim_time'] = plan.twins
    return values
