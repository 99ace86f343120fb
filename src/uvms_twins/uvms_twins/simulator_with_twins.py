"""The simulator with the protocol twins in its own process: the twin stand in one process.

``uvms launch --hardware twin`` runs the simulator (device-side topics under ``/plant``) and
the ``hardware_twins`` node beside it: every reading of the plant crosses DDS to the twins
and every actuator command crosses back. Here the twins (``uvms_twins.twin_stand``) are the
simulator's `PlantSide`: at each published state the simulator hands them its joint states
and wrench (as the devices deliver them) and each navigation reading when it is due, by call,
and takes their actuator command for the steps to the next state. No ``/plant`` topic, no
second node or executor: the twins' sockets are served by their own threads, as in the
``hardware_twins`` node, so a bridge's request never waits for a plant step.

The node is the simulator (node name ``simulator``, its parameters), plus the stand's
parameters under ``twins.`` (``twins.ardusub_bridge.connection``, ...: as the
``hardware_twins`` node's, `STAND_PARAMETERS`). Its device-side topics are remapped under
``/plant`` as the launch does for the two-process layout, so that nothing of it stands where
the bridges publish; it publishes none of them. Real time only (the twins run on wall time)::

    simulator_with_twins --ros-args -p robot_name:=bluerov2_alpha5 -p mode:=realtime
"""

from __future__ import annotations

import sys
import time
from typing import Any

from rclpy.exceptions import ParameterException
from uvms_common.node_construction import destroyed_if_construction_fails
from uvms_common.node_main import run_node
from uvms_hardware.errors import HardwareError
from uvms_model.nav_sensors import DepthReading, DvlReading, ImuReading, Reading
from uvms_sim.conversions import quaternion_from_rpy
from uvms_sim.errors import SimParameterError
from uvms_sim.plant import Observation
from uvms_sim.simulator_node import SimulatorNode

from uvms_common import process_stats
from uvms_twins.twin_stand import STAND_PARAMETERS, TwinStand

#: Prefix of the stand's parameters on the simulator node.
PREFIX = 'twins.'
#: How long the twins serve past the run's end while the launcher stops the bridges (s): a
#: bridge's put-back takes at most a few seconds (its journal's confirmations).
END_GRACE_S = 20.0
#: The simulator's device-side topics (relative names): under /plant, as the launch has them.
DEVICE_TOPICS = ('joint_states', 'wrench', 'imu', 'dvl', 'depth', 'position_fix',
                 'command/actuators')
#: Where those topics go.
PLANT_NAMESPACE = '/plant'


def device_topic_remaps(namespace: str = PLANT_NAMESPACE) -> list[str]:
    """``--ros-args -r`` rules of this node: its device-side topics under ``namespace``."""
    rules = ['--ros-args']
    for topic in DEVICE_TOPICS:
        rules += ['-r', f'{topic}:={namespace}/{topic}']
    return rules


class InProcessTwins:
    """The twin stand as the simulator's `PlantSide`: plant state in, actuator command out.

    Args:
        stand: The twins and their physics.
        joint_names: The plant's joints in its order (its commands' and observations').
        dvl_default_altitude: True: the DVL twin reports ``dvl_altitude_m`` as the
            ``hardware_twins`` node does (the dvl topic has no altitude); False: the
            reading's own altitude.
    """

    def __init__(self, stand: TwinStand, joint_names: tuple[str, ...],
                 dvl_default_altitude: bool = False) -> None:
        self.stand = stand
        missing = [j for j in stand.joints if j not in joint_names]
        if missing:
            raise SimParameterError(f'the arm twin drives {missing}, which the plant does not '
                                    f'have (its joints: {list(joint_names)})')
        # The arm's joints in the plant's coordinates, and the plant's torques from the arm's.
        self._arm_in_plant = [6 + joint_names.index(j) for j in stand.joints]
        self._plant_from_arm = [stand.joints.index(j) if j in stand.joints else -1
                                for j in joint_names]
        self._default_altitude = dvl_default_altitude
        self._t_s = 0.0

    def plant_s(self) -> float:
        """The plant's time of the last state handed over (s): the twins' plant clock."""
        return self._t_s

    def observe(self, seen: Observation) -> None:
        """The arm's joints and the wrist's wrench (ft_sensor_link) to the twins."""
        self._t_s = seen.t_ns * 1e-9
        q, w = seen.q, seen.w
        self.stand.set_joint_state([float(q[i]) for i in self._arm_in_plant],
                                   [float(w[i]) for i in self._arm_in_plant])
        self.stand.set_wrench(seen.sensor_force.tolist(), seen.sensor_torque.tolist())

    def reading(self, reading: Reading) -> None:
        """IMU, depth and DVL readings to the ArduSub and DVL twins (position fixes: none)."""
        if isinstance(reading, ImuReading):
            x, y, z, w = quaternion_from_rpy(*(float(a) for a in reading.rpy))
            rates, force = reading.w_body.tolist(), reading.f_body.tolist()
            self.stand.set_imu((w, x, y, z), (rates[0], rates[1], rates[2]),
                               (force[0], force[1], force[2]))
        elif isinstance(reading, DepthReading):
            self.stand.set_depth(float(reading.depth_m))
        elif isinstance(reading, DvlReading) and reading.valid:
            v = reading.v_dvl.tolist()
            self.stand.dvl_reading(
                (v[0], v[1], v[2]), float(reading.sigma_m_s), reading.t_ns * 1e-9,
                self._t_s, None if self._default_altitude else float(reading.altitude_m))

    def command(self, t_ns: int) -> tuple[list[float], list[float]] | None:
        """The twins' thrusts and joint torques (the plant's joint order), once driven.

        The DVL's loss of bottom lock is timed on the plant's clock here (no reading for
        ``dvl_lost_s`` of plant time), not the wall's as in the ``hardware_twins`` node.
        """
        command = self.stand.command(t_ns, t_ns * 1e-9)
        if command is None:
            return None
        thrust, arm_torques = command
        torques = [arm_torques[i] if i >= 0 else 0.0 for i in self._plant_from_arm]
        return thrust.tolist(), torques


class SimulatorWithTwins(SimulatorNode):
    """The ``simulator`` node serving the robot's devices as protocol twins in its process."""

    @destroyed_if_construction_fails
    def __init__(self, **kwargs: Any) -> None:
        cli_args = list(kwargs.pop('cli_args', None) or []) + device_topic_remaps()
        self.twins: InProcessTwins | None = None
        self._end_marked_s: float | None = None
        try:
            super().__init__(plant_side=self._build_twins, cli_args=cli_args, **kwargs)
            assert self.twins is not None
            self._diagnostics.add('twins', self.twins.stand.report)
        except BaseException:
            if self.twins is not None:  # a refused parameter after the twins were serving
                self.twins.stand.stop()
            raise

    def _build_twins(self, node: SimulatorNode) -> InProcessTwins:
        """The stand on this node's robot, with its ``twins.`` parameters."""
        values = {name: self.declare_parameter(PREFIX + name, default).value
                  for name, (default, _) in STAND_PARAMETERS.items()}
        holder: list[InProcessTwins] = []
        stand = TwinStand(node.robot_name, values, lambda: holder[0].plant_s(),
                          self.get_logger().info)
        try:
            twins = InProcessTwins(stand, node.joint_names)
        except SimParameterError:
            stand.stop()
            raise
        holder.append(twins)
        self.twins = twins
        self.get_logger().info(f'twins of {node.robot_name} in this process: '
                               f'{stand.summary()}')
        return twins

    def end_served(self) -> bool:
        """The process's end: its duration reached and, under a launcher, the devices put back.

        At its duration the plain simulator exits at once. Here its exit would take the twins
        with it while the bridges still put back what they changed on the devices (the
        vehicle's disarm, the arm's settings: "NOT confirmed"). Under ``uvms launch`` the node
        therefore marks the end reached (``process_stats.END_REACHED``: the launcher's cue to
        stop the bridges first, then this process) and keeps its twins serving until it is
        stopped, at most ``END_GRACE_S``; under ``ros2 run`` (no launcher) it ends at once.
        """
        if not self.finished:
            return False
        if self._end_marked_s is None:
            if not process_stats.mark_end_reached():
                return True
            self._end_marked_s = time.monotonic()
            self.get_logger().info('end reached: the twins serve until the bridges have put '
                                   'the devices back')
        return time.monotonic() - self._end_marked_s >= END_GRACE_S

    def destroy_node(self) -> None:
        """Stop the twins, then destroy the node."""
        if self.twins is not None:
            self.twins.stand.stop()
        super().destroy_node()


def main(args: list[str] | None = None) -> None:
    """Run the simulator with the twins until SIGINT/SIGTERM or the end of its duration."""
    sys.exit(run_node(SimulatorWithTwins, args, 'simulator',
                      (SimParameterError, ParameterException, HardwareError, ValueError,
                       OSError),
                      finished=lambda node: node.end_served()))


if __name__ == '__main__':
    main()
