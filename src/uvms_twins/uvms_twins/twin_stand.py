"""The twin stand's core: the four protocol twins and the physics between them and the plant.

No ROS: whoever holds the plant feeds it by calls and takes the actuator command it returns.
The ``hardware_twins`` node (``uvms_twins.twins_node``) feeds it from the simulator's
``/plant`` topics; ``uvms_twins.simulator_with_twins`` from the simulator's own state, in
its process::

    stand = TwinStand('bluerov2_alpha5', {}, plant_clock_s=lambda: t_s, log=print)
    stand.set_imu((1.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, -9.81))
    stand.set_joint_state(positions, velocities)   # both heard: the twins serve
    command = stand.command(plant_ns, now_s)       # None until the bridges drive the devices

Each twin serves its socket in a thread of its own (``ardusub_twin``, ``alpha5_twin``,
``dvl_twin``, ``netft_twin``): a bridge's request never waits for the plant, nor the plant
for a bridge.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
from uvms_common.diagnostics import OK, WARN, Report
from uvms_hardware.address import parse_host_port
from uvms_hardware.errors import AddressError
from uvms_hardware.hardware_config import hardware_section, load_alpha5, load_netft
from uvms_hardware.netft_core import DEFAULT_ROT_LINK_FROM_SENSOR
from uvms_hardware.reach_protocol import Mode
from uvms_hardware.transport import parse_connection

from uvms_twins.alpha5_twin import Alpha5Twin
from uvms_twins.ardusub_twin import ArduSubTwin
from uvms_twins.dvl_twin import DvlTwin
from uvms_twins.netft_twin import NetFtTwin
from uvms_twins.plant_side import (
    SERVO_BANDWIDTH_RAD_S,
    ArmServo,
    JointInertia,
    ThrusterTwin,
    effort_limits_n_m,
    joint_torques,
)

#: Arm modes in which a bridge drives a joint (Standby, Disable, Passive: not driven).
CONTROL_MODES = (Mode.CURRENT, Mode.VELOCITY, Mode.POSITION)
#: Standard gravity (m/s^2): the pressure of a depth.
GRAVITY_M_S2 = 9.80665
#: The stand's settings: name -> (default, description); the nodes declare them so.
STAND_PARAMETERS: dict[str, tuple[Any, str]] = {
    'battery_voltage_v': (16.0, 'Battery voltage the ArduSub twin reports and the T200 curve '
                                'is read at (V)'),
    'netft_rate_hz': (500.0, 'Records per second the Net F/T twin streams (Hz): the '
                             "simulator's wrench rate; more would repeat its values"),
    'dvl_lost_s': (0.5, 'No DVL reading from the simulator for this long: no bottom lock (s)'),
    'dvl_idle_rate_hz': (2.0, 'Reports per second of the DVL twin while no reading comes (Hz; '
                              'assumed: a DVL without lock still answers its pings)'),
    'arm_servo_bandwidth_rad_s': (SERVO_BANDWIDTH_RAD_S, "Bandwidth of the arm devices' own "
                                  'speed loop in Velocity mode (rad/s; plant_side.ArmServo)'),
    'alpha5_bus': (False, "The Alpha 5 twin keeps the arm's half-duplex RS-485 line at "
                          'arm.serial_baud (uvms_twins.rs485_bus): every frame and answer takes '
                          "its time; with the bridge's bus_schedule (docs/hardware.md, 'The "
                          "Alpha 5 bus'). Off: every frame answered and applied at once"),
    'dvl_altitude_m': (1.85, 'Altitude the DVL twin reports when the reading has none (m)'),
    'ardusub_bridge.connection': ('udpout:127.0.0.1:14551', 'Where the ArduSub bridge '
                                  'connects (the twin listens there)'),
    'dvl_bridge.connection': ('127.0.0.1:16171', 'Where the DVL bridge connects'),
    'alpha5_bridge.connection': ('udp:127.0.0.1:6789', 'Where the Alpha 5 bridge connects'),
    'netft_bridge.connection': ('127.0.0.1:49152', 'Where the Net F/T bridge connects'),
}


def checked_settings(settings: Mapping[str, Any], where: str) -> dict[str, Any]:
    """A hardware file's ``twins:`` mapping: each a setting of the stand, of its default's type.

    Args:
        settings: Setting name -> value (``alpha5_bus: true``).
        where: What to name in an error (the hardware file).

    Returns:
        The settings, an integer given for a float setting made a float.

    Raises:
        ValueError: An unknown setting (the known ones listed), a connection (the bridges'
            section of the file sets those), or a value of another type than its default's.
    """
    known = {name: default for name, (default, _) in STAND_PARAMETERS.items()
             if not name.endswith('.connection')}
    out: dict[str, Any] = {}
    for name, value in settings.items():
        if name not in known:
            raise ValueError(f'{where}: twins.{name}: not a setting of the stand; known: '
                             f'{", ".join(sorted(known))} (connections are the bridges\' '
                             'own, under bridges:)')
        default = known[name]
        numeric = (isinstance(default, float) and isinstance(value, int)
                   and not isinstance(value, bool))
        if type(value) is not type(default) and not numeric:
            raise ValueError(f'{where}: twins.{name} = {value!r}: expected a '
                             f'{type(default).__name__} (default {default!r})')
        out[name] = float(value) if numeric else value
    return out

def ardusub_listen_address(url: str) -> tuple[str, int]:
    """The address the twin listens on for a bridge's ``udpout:HOST:PORT``.

    Raises:
        AddressError: Another kind of URL (the twin serves UDP only).
    """
    kind, _, rest = url.partition(':')
    if kind != 'udpout':
        raise AddressError(f'ardusub_bridge.mavlink_url = {url!r}: the ArduSub twin serves a '
                           'bridge on udpout:HOST:PORT only')
    host, port = parse_host_port(rest, 14550, 'ardusub_bridge.mavlink_url')
    return host, port


class TwinStand:
    """Serves the four twins; takes the plant's measurements, gives its actuator command.

    Args:
        robot: Robot folder name (its hardware.yaml, thrusters.yaml and URDF).
        values: `STAND_PARAMETERS` names -> values (missing ones take their defaults).
        plant_clock_s: The plant's time (s): the DVL's clock (as a real one is synchronised to
            the vehicle's, its time_of_validity is when the plant measured, whatever the
            real-time factor) and the jaws' (the plant has none, they move on its time).
        log: Where the stand says what changed (one line each).

    Raises:
        AddressError: A connection the twins cannot serve (a serial arm, a TCP ArduSub).
        HardwareError: The robot folder's hardware file is wrong.
    """

    def __init__(self, robot: str, values: Mapping[str, Any],
                 plant_clock_s: Callable[[], float], log: Callable[[str], None]) -> None:
        v = {name: values.get(name, default) for name, (default, _) in STAND_PARAMETERS.items()}
        self._log = log
        self.voltage_v = float(v['battery_voltage_v'])
        self._dvl_lost_s = float(v['dvl_lost_s'])
        self._altitude_m = float(v['dvl_altitude_m'])
        _, ardusub = hardware_section(robot, 'ardusub')
        self._rho = float(ardusub['depth']['water_density_kg_m3'])
        self._surface_pa = float(ardusub['depth']['surface_pressure_pa'])
        host, port = ardusub_listen_address(str(v['ardusub_bridge.connection']))
        # The autopilot runs our watchdog script, as a deployed vehicle should (docs/hardware.md):
        # the stand's bridge then drives the thrusters through it, changing no parameter.
        self.ardusub = ArduSubTwin(port=port, host=host, watchdog_script=True)
        host, port = parse_host_port(str(v['dvl_bridge.connection']), 16171)
        self.dvl = DvlTwin(host=host, port=port, rate_hz=float(v['dvl_idle_rate_hz']),
                           clock=plant_clock_s)
        arm = load_alpha5(robot)
        link = parse_connection(str(v['alpha5_bridge.connection']), 6789,
                                'alpha5_bridge.connection')
        if link.kind != 'udp':
            raise AddressError(f'alpha5_bridge.connection = {link}: the Alpha 5 twin serves '
                               'UDP only (a serial bridge needs the real arm)')
        self.arm = Alpha5Twin(arm, host=link.target, port=link.number, clock=plant_clock_s,
                              bus=bool(v['alpha5_bus']))
        host, port = parse_host_port(str(v['netft_bridge.connection']), load_netft(robot).port)
        self.netft = NetFtTwin(host=host, port=port, rate_hz=float(v['netft_rate_hz']))
        self.connections = {name: str(v[f'{name}.connection'])
                            for name in ('ardusub_bridge', 'dvl_bridge', 'alpha5_bridge',
                                         'netft_bridge')}
        # A device always has a state, so a twin serves only once the plant has given it one:
        # before, the bridges would configure on zeros and the estimator start from them.
        self._waiting_for = {'joint_states', 'imu'}
        # And the plant hears from the devices only once the bridges drive them: the simulator
        # holds its first state until an actuator command comes, and one sent before the arm
        # is driven would start physics with the arm limp (its light links fall at ~60 rad/s^2).
        self.driven = False
        self.joints: tuple[str, ...] = tuple(d.joint_name for d in arm.drives)
        self._effort = effort_limits_n_m(robot)
        self._servo = ArmServo(JointInertia(robot), self._effort,
                               float(v['arm_servo_bandwidth_rad_s']))
        self.thrusters = ThrusterTwin.for_robot(robot)
        self._rot_sensor_from_link = np.array(DEFAULT_ROT_LINK_FROM_SENSOR).reshape(3, 3).T
        self._last_plant_ns: int | None = None
        self._last_dvl_s = -float('inf')
        self.ticks = 0

    @property
    def serving(self) -> bool:
        """Whether the twins serve (the plant gave them a state)."""
        return not self._waiting_for

    def _heard(self, kind: str) -> None:
        """The plant's first ``kind``: once joint states and IMU came, the twins serve."""
        if not self._waiting_for:
            return
        self._waiting_for.discard(kind)
        if not self._waiting_for:
            for twin in (self.ardusub, self.dvl, self.arm, self.netft):
                twin.start()
            self._log('the plant has a state: the twins serve')

    def set_joint_state(self, positions_rad: Sequence[float],
                        velocities_rad_s: Sequence[float]) -> None:
        """The arm's joints (in ``joints``' order) as the plant has them."""
        self.arm.set_joint_state(positions_rad, velocities_rad_s)
        self._heard('joint_states')

    def set_wrench(self, force_link_n: Sequence[float], torque_link_n_m: Sequence[float]) -> None:
        """The wrist sensor's reading in ft_sensor_link (N, N m): the Net F/T's, in its axes."""
        force = self._rot_sensor_from_link @ np.asarray(force_link_n, dtype=float)
        torque = self._rot_sensor_from_link @ np.asarray(torque_link_n_m, dtype=float)
        self.netft.set_wrench((float(force[0]), float(force[1]), float(force[2])),
                              (float(torque[0]), float(torque[1]), float(torque[2])))

    def set_imu(self, quaternion_wxyz: tuple[float, float, float, float],
                rates_rad_s: tuple[float, float, float],
                specific_force_m_s2: tuple[float, float, float]) -> None:
        """The IMU's attitude (base_link_frd in map_ned), rates and specific force."""
        self.ardusub.set_plant_state(quaternion_wxyz=quaternion_wxyz, rates_rad_s=rates_rad_s,
                                     specific_force_m_s2=specific_force_m_s2,
                                     voltage_v=self.voltage_v)
        self._heard('imu')

    def set_depth(self, depth_m: float) -> None:
        """The depth (m, down): the Bar30's pressure."""
        self.ardusub.set_plant_state(
            pressure_pa=self._surface_pa + self._rho * GRAVITY_M_S2 * depth_m)

    def dvl_reading(self, v_dvl_m_s: tuple[float, float, float], sigma_m_s: float,
                    time_of_validity_s: float, now_s: float,
                    altitude_m: float | None = None) -> None:
        """One valid DVL reading, sent at once (the reading's sigma as the figure of merit).

        Args:
            v_dvl_m_s: Velocity in dvl_link (m/s).
            sigma_m_s: Its standard deviation (the bridge's variance: fom^2).
            time_of_validity_s: When the plant measured it (plant time, s).
            now_s: The clock ``command`` is given (for the loss of the bottom lock).
            altitude_m: The reading's altitude (m); None: ``dvl_altitude_m``.
        """
        self._last_dvl_s = now_s
        self.dvl.report(v_dvl_m_s, True, sigma_m_s,
                        self._altitude_m if altitude_m is None else altitude_m,
                        time_of_validity_s=time_of_validity_s)

    def command(self, plant_ns: int, now_s: float) -> tuple[np.ndarray, list[float]] | None:
        """The actuator command from the devices, once the bridges drive them.

        The propellers turn in the plant's time (``plant_ns``), not the wall's: at a
        real-time factor of 0.5 they would otherwise spin up twice as fast.

        Args:
            plant_ns: The plant's time (ns).
            now_s: The clock of DVL loss (the feeder's clock, s).

        Returns:
            Thrusts (N, thrusters.yaml's order) and joint torques (N m, ``joints``' order);
            None before the bridges drive the arm and the vehicle.
        """
        if now_s - self._last_dvl_s > self._dvl_lost_s:
            self.dvl.set_velocity((0.0, 0.0, 0.0), False, 10.0, -1.0)
        last_ns = plant_ns if self._last_plant_ns is None else self._last_plant_ns
        dt_s = min(max((plant_ns - last_ns) * 1e-9, 0.0), 0.1)
        self._last_plant_ns = plant_ns
        thrust = self.thrusters.step(self.ardusub.servo_outputs_us(), self.voltage_v, dt_s)
        commands = self.arm.joint_commands()
        if not self.driven:
            self.driven = self.ardusub.armed and bool(self.ardusub.overrides()) and all(
                mode in CONTROL_MODES for mode, _ in commands.values())
            if not self.driven:
                return None
            self._log('the bridges drive the arm and the vehicle: actuator commands to the '
                      'plant')
        positions, velocities = self.arm.joint_state()
        servo = self._servo.torques(commands, positions, velocities, dt_s)
        torques = joint_torques(commands, self.arm.joint_torques_n_m(), self._effort, servo)
        self.ticks += 1
        return thrust, [torques[j] for j in self.joints]

    def report(self) -> Report:
        """The stand's /diagnostics status."""
        if self._waiting_for:
            return Report(WARN, f'waiting for the plant\'s {", ".join(sorted(self._waiting_for))}',
                          {'ticks': self.ticks})
        if not self.driven:
            return Report(WARN, 'waiting for the bridges to drive the arm and the vehicle',
                          {'armed': self.ardusub.armed})
        return Report(OK, 'serving', {'ticks': self.ticks, 'armed': self.ardusub.armed})

    def summary(self) -> str:
        """Where each twin serves (one line)."""
        host, port = self.ardusub.address
        c = self.connections
        return (f'ArduSub udpin:{host}:{port}, DVL {c["dvl_bridge"]}, Alpha 5 '
                f'{c["alpha5_bridge"]}, Net F/T {c["netft_bridge"]}')

    def stop(self) -> None:
        """Stop the twins (each stop is safe on a twin that never started)."""
        for twin in (self.ardusub, self.dvl, self.arm, self.netft):
            twin.stop()
