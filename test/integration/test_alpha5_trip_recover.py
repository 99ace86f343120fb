"""Recovering the arm after an overspeed trip (issue 52 item 3), the bridge and the twin's servo.

On the twin stand the bridge tripped, and ``deactivate`` / ``activate`` both said yes while the
arm tripped again at once: the twin made no torque in Velocity mode, so after the trip's
VELOCITY 0 the arm flailed (2-17 rad/s measured), and the controller, still fed joint states,
kept driving the vehicle around an arm it no longer drove. Now: the twin's devices follow
their speed setpoint (VELOCITY 0 holds the joint), a tripped bridge publishes no joint
states (the controller's input-age check zeroes its output), ``~/reset_trip`` takes commands
again once the arm is still, and an activate with a joint over the trip speed is refused,
naming it, instead of tripping at once.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping

import pytest
from std_srvs.srv import Trigger
from test_alpha5_bridge import FAILURE, JOINTS, SUCCESS, Rig
from uvms_hardware.reach_protocol import Mode
from uvms_twins.plant_side import ArmServo, effort_limits_n_m, joint_torques

ROBOT = 'bluerov2_alpha5'
#: The trip speed of every joint: 1.5 x the URDF's 0.5 rad/s.
TRIP_RAD_S = 0.75


class FixedInertia:
    """A joint's effective inertia that does not depend on where the arm is."""

    def __init__(self, inertias: Mapping[str, float]) -> None:
        self.inertias = dict(inertias)

    def effective_kg_m2(self, positions: Mapping[str, float]) -> dict[str, float]:
        """The same inertias wherever the arm is."""
        return dict(self.inertias)


def simulate(inertia_kg_m2: float, gravity_n_m: float, delay_s: float, v0_rad_s: float,
             duration_s: float, dt_s: float = 0.001) -> list[tuple[float, float, float]]:
    """One joint under the twin's servo at VELOCITY 0, its torque applied ``delay_s`` late.

    Returns (t, position, speed) every step; the joint starts at ``v0_rad_s`` (a trip's).
    """
    servo = ArmServo(FixedInertia({'joint_3': inertia_kg_m2}), {'joint_3': 9.0})  # type: ignore[arg-type]
    q, v = 0.0, v0_rad_s
    lag = [0.0] * max(1, round(delay_s / dt_s))
    out = []
    for k in range(round(duration_s / dt_s)):
        torque = joint_torques({'joint_3': (Mode.VELOCITY, 0.0)}, {'joint_3': None},
                               effort_limits_n_m(ROBOT),
                               servo.torques({'joint_3': (Mode.VELOCITY, 0.0)}, {'joint_3': q},
                                             {'joint_3': v}, dt_s))['joint_3']
        lag.append(torque)
        applied = lag.pop(0)
        v += (applied - gravity_n_m) / inertia_kg_m2 * dt_s
        q += v * dt_s
        out.append((k * dt_s, q, v))
    return out


@pytest.mark.parametrize('inertia_kg_m2', [1.7e-4, 3e-3, 3e-2])  # wrist, elbow, shoulder
@pytest.mark.parametrize('delay_s', [0.002, 0.02, 0.04])
def test_velocity_zero_stops_a_spinning_joint_and_holds_it(inertia_kg_m2: float,
                                                           delay_s: float) -> None:
    """From 3 rad/s under a gravity load: under 0.05 rad/s within 1 s, and stays still.

    The light wrist as the heavy shoulder, with up to 40 ms of loop delay (a late node on a
    busy machine): the gains follow the inertia, so none goes unstable.
    """
    gravity = 0.2 * 9.0 * min(1.0, inertia_kg_m2 / 3e-2)  # a share of the effort limit
    run = simulate(inertia_kg_m2, gravity, delay_s, 3.0, 3.0)
    after = [abs(v) for t, _, v in run if t >= 1.0]
    assert max(after) < 0.05, (inertia_kg_m2, delay_s, max(after))
    late = [q for t, q, _ in run if t >= 2.0]
    assert max(late) - min(late) < 1e-3  # held, not creeping


def test_other_modes_stay_limp() -> None:
    """Standby, Disable, Passive: no torque (what the arm does there is not documented)."""
    servo = ArmServo(FixedInertia({j: 1e-3 for j in JOINTS}), effort_limits_n_m(ROBOT))  # type: ignore[arg-type]
    commands = {'joint_1': (Mode.STANDBY, 0.0), 'joint_2': (Mode.DISABLE, 0.0),
                'joint_3': (Mode.PASSIVE, 0.0), 'joint_4': (Mode.VELOCITY, 0.0)}
    held = servo.torques(commands, dict.fromkeys(JOINTS, 0.5), dict.fromkeys(JOINTS, 1.0), 0.002)
    torques = joint_torques(commands, dict.fromkeys(JOINTS), effort_limits_n_m(ROBOT), held)
    assert torques['joint_1'] == torques['joint_2'] == torques['joint_3'] == 0.0
    assert torques['joint_4'] < 0.0


@pytest.fixture
def rig() -> Iterator[Rig]:
    """A fresh twin and executor, closed after the test."""
    made = Rig()
    yield made
    made.close()


def spin_answer(rig: Rig, client: object, request: Trigger.Request) -> Trigger.Response:
    """Call a service of the bridge on the rig's executor; its answer."""
    future = client.call_async(request)  # type: ignore[attr-defined]
    rig.spin_until(future.done, 5.0)
    return future.result()


def trip(rig: Rig) -> None:
    """The twin reports joint_3 at 1 rad/s while the bridge drives: the bridge trips."""
    bridge = rig.bridge
    assert bridge is not None
    rig.spin_for(0.2, command=[0.0] * 4)
    rig.twin.set_joint_state([1.0, 1.0, 1.0, 1.0, 0.01], [0.0, 0.0, 1.0, 0.0, 0.0])
    rig.spin_until(lambda: bool(bridge.core and bridge.core.overspeed), 5.0)


def test_a_tripped_bridge_resets_once_the_arm_is_still(rig: Rig) -> None:
    """Tripped: joints held at VELOCITY 0, joint states go on; reset_trip refused at 1 rad/s.

    Cleared at rest; a command is then taken again: the joints go to Current mode.
    """
    bridge = rig.start_bridge(jaw_joint='')
    client = rig.probe.create_client(Trigger, 'alpha5_bridge/reset_trip')
    trip(rig)
    rig.spin_for(0.1)
    rig.states.clear()
    rig.spin_for(0.5, command=[0.0] * 4)
    assert rig.states  # a controller reset can take its hold where the arm is
    assert all(rig.twin.joint_commands()[j][0] == Mode.VELOCITY for j in JOINTS)
    refused = spin_answer(rig, client, Trigger.Request())
    assert not refused.success
    assert 'joint_3 (device 0x03, C) at 1 rad/s' in refused.message
    rig.twin.set_joint_state([1.0, 1.0, 1.0, 1.0, 0.01], [0.0] * 5)
    rig.spin_for(0.2)
    cleared = spin_answer(rig, client, Trigger.Request())
    assert cleared.success, cleared.message
    assert not bridge.core.overspeed  # type: ignore[union-attr]
    rig.states.clear()
    rig.spin_for(0.5, command=[0.1, 0.1, 0.1, 0.1])
    assert rig.states
    assert all(rig.twin.joint_commands()[j][0] == Mode.CURRENT for j in JOINTS)


def test_an_activate_with_a_joint_over_the_trip_speed_is_refused_naming_it(rig: Rig) -> None:
    """Deactivated after a trip, the arm still moving: activate refused, not a trip at once."""
    bridge = rig.start_bridge(jaw_joint='')
    trip(rig)
    assert bridge.trigger_deactivate() == SUCCESS
    rig.twin.set_joint_state([1.0, 1.0, 1.0, 1.0, 0.01], [1.67, 0.0, 0.0, 0.0, 0.0])
    assert bridge.trigger_activate() == FAILURE
    assert 'joint_1 (device 0x05, E) at 1.67 rad/s: over 1.5 x the speed limit' in bridge.refusal
    rig.twin.set_joint_state([1.0, 1.0, 1.0, 1.0, 0.01], [0.0] * 5)
    assert bridge.trigger_activate() == SUCCESS
    assert not bridge.core.overspeed  # type: ignore[union-attr]
    rig.states.clear()
    rig.spin_for(0.5, command=[0.0] * 4)
    assert rig.states and not math.isnan(rig.states[-1].position[0])
