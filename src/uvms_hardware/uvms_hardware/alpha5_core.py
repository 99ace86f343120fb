"""The Alpha 5 bridge's core: frames out, packets in, joint state and health; no ROS, no I/O.

The component (``alpha5_component``) owns the link and the clock and calls, per period
(configure's checks of each device are ``alpha5_checks``)::

    core = Alpha5Core(load_alpha5('bluerov2_alpha5'), watchdog_timeout_s=0.1)
    bus.hold(core.command(t_s, names, torques))     # on each ActuatorCommand (alpha5_bus)
    core.receive(link.read(), t_s)                  # every period
    link.send(bus.turn(t_s, core.hold_frames(t_s), core.next_request))  # the bus's turn
    sample = core.next_joint_state(t_s)             # every joint answered again, or None
    link.send(core.jaw_command(t_s, 0.002)[0])      # the jaws at 2 mm/s (when driven)
    jaw = core.next_jaw_state(t_s)                  # the jaws answered again, or None

Feedback asks one device at a time (REQUEST POSITION, VELOCITY), never all at once: broadcast
requests collide on RS-485. Commands: joint torque as CURRENT mA through Kt, gear ratio and
efficiency (``hardware.yaml``); or, with ``command_mode`` ``velocity`` (a fallback for arms
whose current mode is not to be used), VELOCITY = gain * torque, clamped at the joint's speed
limit: a plain admittance, documented as such. The watchdog sends VELOCITY 0 to every joint
when commands stop for ``watchdog_timeout_s``, and repeats it every ``HOLD_RESEND_S`` until a
new command arrives (a lost UDP datagram must not leave a joint driven). A joint reported
faster than ``overspeed_factor`` times its speed limit trips the core: VELOCITY 0 to every
joint as the watchdog does, every command refused until ``stop_driving`` (deactivate).
Activate's MODE Standby and the put-back's VELOCITY 0 and resting modes are `Setting`s, each
confirmed by its device's MODE read back (``alpha5_probe.confirm_setting``).

The jaws (device 0x01, when ``arm.jaw`` names them) are driven apart from the joints: a jaw
speed (m/s, ``jaw_command``) becomes VELOCITY (mm/s on the wire), sent when it changes and
again every ``HOLD_RESEND_S`` while it is fed; a watchdog of the same timeout sends VELOCITY 0
when jaw commands stop, and repeats it while it holds. They are asked their POSITION and
VELOCITY once every ``JAW_POLL_ROUNDS`` rounds of the joints (a slot of their own, so the
joints keep their rate), and their state comes from `next_jaw_state`, never in the joints'
sample. activate, the put-back and a trip treat them as every device.

A silent joint is silent: `next_joint_state` gives a joint state only when every driven
joint has answered since the last one it gave, within ``silent_timeout_s``; so no answer is
ever handed out twice, and a joint that stops answering stops the joint states at once (the
controller's input-age check then sees them go stale). Each sample carries the arrival time
of its oldest answer: the protocol has no device clock (no timestamp or sequence in any
packet of the document), so the time the bridge read the answer is the best the wire gives.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

from uvms_hardware import reach_protocol as rp
from uvms_hardware.alpha5_checks import Setting, describe, unit_of
from uvms_hardware.alpha5_feedback import DeviceFeedback, JointSample, SampleAges
from uvms_hardware.hardware_config import Alpha5Hardware, Drive
from uvms_hardware.reach_protocol import Mode, PacketId
from uvms_hardware.watchdog import CommandWatchdog

#: Command modes of the bridge.
COMMAND_MODES = ('current', 'velocity')
FEEDBACK_REQUEST = (PacketId.POSITION, PacketId.VELOCITY)
#: While the watchdog holds, VELOCITY 0 is sent again this often (s).
HOLD_RESEND_S = 0.1
#: A HARDWARE_STATUS error is reported this long after its last packet (s): it comes at 1 Hz.
STATUS_HOLD_S = 2.5
#: A joint reported faster than this many times its speed limit (the URDF's) trips the bridge:
#: VELOCITY 0 to every joint, commands refused until `Alpha5Core.reset_trip` (the arm still) or
#: deactivate and activate. In Current mode
#: nothing on the device holds a joint to its speed limit (the device clamps VELOCITY and
#: CURRENT setpoints, not the speed a current makes); a loop that lost its stability (found on
#: the twin stand with joint feedback far under the control rate) spins a joint up.
DEFAULT_OVERSPEED_FACTOR = 1.5
#: Modes the bridge restores at the end (others become Standby: the arm is left at rest).
RESTING_MODES = (Mode.STANDBY, Mode.DISABLE, Mode.PASSIVE)
#: Modes that ignore control packets (the document): a VELOCITY 0 has nothing to stop there.
IGNORING_MODES = frozenset({Mode.DISABLE, Mode.PASSIVE})
#: The jaws are asked their state once every this many rounds of the joints (25 Hz at the
#: default 125 Hz): a pilot watches them open, no control loop closes on them.
JAW_POLL_ROUNDS = 5


class Alpha5Core:
    """Commands, feedback polling, watchdog and health of one Alpha 5."""

    def __init__(self, arm: Alpha5Hardware, watchdog_timeout_s: float = 0.1,
                 command_mode: str = 'current', velocity_gain_rad_s_per_n_m: float = 0.1,
                 silent_timeout_s: float = 0.2,
                 overspeed_factor: float = DEFAULT_OVERSPEED_FACTOR) -> None:
        if command_mode not in COMMAND_MODES:
            raise ValueError(f'command_mode = {command_mode!r}: one of {", ".join(COMMAND_MODES)}')
        if not (math.isfinite(overspeed_factor) and overspeed_factor >= 1.0):
            raise ValueError(f'overspeed_factor = {overspeed_factor!r}: expected >= 1')
        if not (math.isfinite(silent_timeout_s) and silent_timeout_s > 0.0):
            raise ValueError(f'silent_timeout_s = {silent_timeout_s!r}: expected seconds > 0')
        self.arm = arm
        self.drives = arm.drives
        self.jaw = arm.jaw
        self.command_mode = command_mode
        self.velocity_gain = velocity_gain_rad_s_per_n_m
        self.silent_timeout_s = silent_timeout_s
        self.overspeed_factor = overspeed_factor
        #: Why the bridge tripped on a joint's speed ('' while it has not).
        self.overspeed = ''
        self.watchdog = CommandWatchdog(watchdog_timeout_s)
        self.splitter = rp.FrameSplitter()
        self.feedback = {d.device_id: DeviceFeedback() for d in self.drives}
        self._index = {d.joint_name: i for i, d in enumerate(arm.joints)}
        self._drive_of = {d.device_id: d for d in self.drives}
        self._slots = list(arm.joints) * (JAW_POLL_ROUNDS if arm.jaw else 1) + (
            [arm.jaw] if arm.jaw else [])
        #: Each device's feedback REQUEST frame, encoded once (it never changes).
        self._requests = {d.device_id: rp.encode_request(d.device_id, FEEDBACK_REQUEST)
                          for d in self._slots}
        self._next = 0
        #: The device of the last feedback request (None before one).
        self.asked: int | None = None
        self._holding = False
        self._driving = False
        self._last_hold_s = -math.inf
        self._given_s = [-math.inf] * len(arm.joints)
        #: How old the answers in the joint states given were (`next_joint_state`).
        self.ages = SampleAges()
        self.rejected_commands = 0
        self.last_rejection = ''
        self.jaw_watchdog = CommandWatchdog(watchdog_timeout_s)
        self._jaw_driving = self._jaw_holding = False
        self._jaw_sent = math.nan
        self._jaw_sent_s = self._jaw_hold_s = -math.inf
        self._jaw_given_s = -math.inf

    # -- commands -----------------------------------------------------------------------------
    def command(self, t_s: float, joint_names: Sequence[str],
                torques_n_m: Sequence[float]) -> bytes:
        """Frames of one ActuatorCommand's joint torques (N m); b'' if it is refused.

        ``joint_names`` empty means the URDF's arm joints in order. A command that names an
        unknown joint, misses one, or holds a non-finite torque is refused and counted (the
        watchdog is not fed, so the arm goes neutral if only such commands come).
        """
        names = list(joint_names) or [d.joint_name for d in self.arm.joints]
        problem = ''
        if self.overspeed:
            problem = (f'tripped: {self.overspeed}; `uvms hardware reset-trip` once the arm is '
                       'still (or deactivate and activate) to drive again')
        elif len(names) != len(torques_n_m):
            problem = f'{len(names)} joint names, {len(torques_n_m)} torques'
        elif set(names) != set(self._index):
            problem = f'joints {names}, expected {sorted(self._index)}'
        elif not all(math.isfinite(t) for t in torques_n_m):
            problem = f'non-finite torque in {list(torques_n_m)}'
        if problem:
            self.rejected_commands += 1
            self.last_rejection = problem
            return b''
        self.watchdog.feed(t_s)
        self._holding, self._driving = False, True
        by_name = dict(zip(names, torques_n_m, strict=True))
        return b''.join(self._command_frame(d, float(by_name[d.joint_name]))
                        for d in self.arm.joints)

    def jaw_command(self, t_s: float, speed_m_s: float) -> tuple[bytes, str]:
        """(frames, why refused or '') of a jaw speed (m/s, + opens) at ``t_s``.

        Clamped at the jaws' speed limit; sent as VELOCITY when it differs from the last
        sent or that is ``HOLD_RESEND_S`` old (a lost datagram is repaired), else b''.
        Refused without driven jaws, while tripped, or for a non-finite speed (the jaws'
        watchdog is not fed then).
        """
        jaw = self.jaw
        problem = ''
        if jaw is None:
            problem = 'the jaws are not driven (no jaw joint named)'
        elif self.overspeed:
            problem = f'tripped: {self.overspeed}'
        elif not math.isfinite(speed_m_s):
            problem = f'non-finite jaw speed {speed_m_s!r}'
        if problem or jaw is None:
            self.rejected_commands += 1
            self.last_rejection = problem
            return b'', problem
        self.jaw_watchdog.feed(t_s)
        self._jaw_driving, self._jaw_holding = True, False
        speed = max(-jaw.velocity_limit, min(jaw.velocity_limit, float(speed_m_s)))
        if speed == self._jaw_sent and t_s - self._jaw_sent_s < HOLD_RESEND_S:
            return b'', ''
        self._jaw_sent, self._jaw_sent_s = speed, t_s
        return rp.encode_velocity(jaw.device_id, speed), ''

    @property
    def jaw_holding(self) -> bool:
        """True while the jaws' watchdog holds them at VELOCITY 0."""
        return self._jaw_holding

    def _command_frame(self, drive: Drive, torque_n_m: float) -> bytes:
        if self.command_mode == 'current':
            return rp.encode_current(drive.device_id, drive.current_ma(torque_n_m))
        limit = drive.velocity_limit
        velocity = max(-limit, min(limit, self.velocity_gain * torque_n_m))
        return rp.encode_velocity(drive.device_id, velocity)

    def neutral_frames(self) -> bytes:
        """VELOCITY 0 to every driven device, one at a time (never a broadcast)."""
        return b''.join(rp.encode_velocity(d.device_id, 0.0) for d in self.drives)

    def restore_settings(self, modes: Mapping[int, Mode]) -> list[Setting]:
        """VELOCITY 0 to every device, then MODE back to its resting mode before activate.

        A device that rested in another mode (or did not say) is left in Standby. VELOCITY 0
        is confirmed by MODE Velocity (the control packet switched the mode; a requested
        VELOCITY is the joint's speed, not the setpoint, so it cannot confirm one), or by
        Disable and Passive, which ignore control packets: nothing is driven there.
        """
        stop = [Setting(d, rp.encode_velocity(d.device_id, 0.0),
                        frozenset({Mode.VELOCITY}) | IGNORING_MODES, 'VELOCITY 0')
                for d in self.drives]
        rest = []
        for d in self.drives:
            mode = modes.get(d.device_id, Mode.STANDBY)
            mode = mode if mode in RESTING_MODES else Mode.STANDBY
            rest.append(Setting(d, rp.encode_mode(d.device_id, mode), frozenset({mode}),
                                f'MODE {mode.name.capitalize()}'))
        return stop + rest

    def standby_settings(self) -> list[Setting]:
        """MODE Standby to every driven device (activate)."""
        return [Setting(d, rp.encode_mode(d.device_id, Mode.STANDBY), frozenset({Mode.STANDBY}),
                        'MODE Standby') for d in self.drives]

    def restore_frames(self, modes: Mapping[int, Mode]) -> bytes:
        """The frames of `restore_settings`, in order."""
        return b''.join(s.frame for s in self.restore_settings(modes))

    def fast_joints(self) -> list[str]:
        """Joints whose last reported speed is over the trip speed, each with it (empty: none)."""
        out = []
        for d in self.drives:
            speed = self.feedback[d.device_id].velocity
            if abs(speed) > self.overspeed_factor * d.velocity_limit:
                unit = unit_of(d, PacketId.VELOCITY_LIMITS)
                out.append(f'{describe(d)} at {speed:.3g} {unit}')
        return out

    def reset_trip(self) -> str:
        """Clear the overspeed trip if no joint moves over the trip speed; why not, else ''.

        The arm stays at VELOCITY 0 (the hold) until the next command, which is taken again.
        """
        fast = self.fast_joints()
        if fast:
            return (f'still over {self.overspeed_factor:g} x the speed limit: '
                    f'{", ".join(fast)}; wait until the arm is still')
        self.overspeed = ''
        return ''

    def stop_driving(self) -> None:
        """Forget the last command and a trip (deactivate): nothing is driven until a new one."""
        self._driving = self._holding = False
        self._jaw_driving = self._jaw_holding = False
        self._jaw_sent, self._jaw_sent_s = math.nan, -math.inf
        self.overspeed = ''

    def _check_speed(self, drive: Drive, velocity: float) -> None:
        """Trip (VELOCITY 0 to all, commands refused) on a joint over its speed limit."""
        limit = self.overspeed_factor * drive.velocity_limit
        if self.overspeed or not abs(velocity) > limit:  # NaN is no speed: not published
            return
        unit = unit_of(drive, PacketId.VELOCITY_LIMITS)
        self.overspeed = (f'{describe(drive)} at {velocity:.3g} {unit}, over '
                          f'{self.overspeed_factor:g} x its limit {drive.velocity_limit:g} {unit}')
        self._driving, self._holding, self._last_hold_s = False, True, -math.inf
        self._jaw_driving, self._jaw_holding = False, self.jaw is not None
        self._jaw_sent, self._jaw_hold_s = math.nan, -math.inf

    # -- the period ---------------------------------------------------------------------------
    def tick(self, t_s: float) -> tuple[bytes, bool]:
        """(frames to send now, True when this request starts a new feedback round).

        The frames: VELOCITY 0 to every joint when the watchdog trips and while it holds
        (the jaws too, on their own watchdog), then one feedback REQUEST to the next device
        in turn (the jaws once every ``JAW_POLL_ROUNDS`` rounds). The component sends the two
        apart (`hold_frames`, `next_request`) on its bus schedule (``alpha5_bus``).
        """
        frames = self.hold_frames(t_s)
        round_done = self._next % len(self.arm.joints) == 0 and (
            self._slots[self._next] is not self.jaw)
        return frames + self.next_request(), round_done

    def hold_frames(self, t_s: float) -> bytes:
        """The watchdog's frames at ``t_s`` (b'' while it does not hold).

        VELOCITY 0 to every joint when the watchdog trips and every ``HOLD_RESEND_S`` while
        it holds (the jaws too, on their own watchdog).
        """
        frames = b''
        if self._driving and self.watchdog.expired(t_s):
            self._driving, self._holding, self._last_hold_s = False, True, -math.inf
        if self._holding and t_s - self._last_hold_s >= HOLD_RESEND_S:
            frames += b''.join(rp.encode_velocity(d.device_id, 0.0) for d in self.arm.joints)
            self._last_hold_s = t_s
        if self.jaw is not None:
            if self._jaw_driving and self.jaw_watchdog.expired(t_s):
                self._jaw_driving, self._jaw_holding, self._jaw_hold_s = False, True, -math.inf
                self._jaw_sent = math.nan
            if self._jaw_holding and t_s - self._jaw_hold_s >= HOLD_RESEND_S:
                frames += rp.encode_velocity(self.jaw.device_id, 0.0)
                self._jaw_hold_s = t_s
        return frames

    def next_request(self) -> bytes:
        """The feedback REQUEST of the next device in turn.

        The jaws are asked once every ``JAW_POLL_ROUNDS`` rounds of the joints.
        """
        drive = self._slots[self._next]
        self._next = (self._next + 1) % len(self._slots)
        self.asked = drive.device_id
        return self._requests[drive.device_id]

    def answered(self, device_id: int, since_s: float) -> bool:
        """Whether the device's POSITION and VELOCITY have both arrived after ``since_s``."""
        feedback = self.feedback.get(device_id)
        return feedback is not None and feedback.oldest_s > since_s

    @property
    def driving(self) -> bool:
        """True while the joints take commands: a command came, no watchdog hold, no trip."""
        return self._driving

    def poll_period_s(self, rate_hz: float) -> float:
        """The period of `tick` (s) that asks every joint ``rate_hz`` times a second."""
        rounds = JAW_POLL_ROUNDS if self.jaw is not None else 1
        return rounds / (rate_hz * len(self._slots))

    @property
    def holding(self) -> bool:
        """True while the watchdog holds the arm at VELOCITY 0."""
        return self._holding

    def receive(self, chunk: bytes, t_s: float) -> None:
        """Take the device's bytes: feedback, HARDWARE_STATUS; bad frames are only counted."""
        for packet in self.splitter.feed(chunk):
            feedback = self.feedback.get(packet.device_id)
            if feedback is None:
                continue
            if packet.packet_id == PacketId.HARDWARE_STATUS:
                feedback.status, feedback.status_s = packet.data, t_s
            elif packet.packet_id in FEEDBACK_REQUEST and len(packet.data) == 4:
                value = rp.packet_values_si(packet)[0]
                if packet.packet_id == PacketId.POSITION:
                    feedback.position, feedback.position_s = value, t_s
                else:
                    feedback.velocity, feedback.velocity_s = value, t_s
                    self._check_speed(self._drive_of[packet.device_id], value)

    def joint_state(self) -> tuple[list[str], list[float], list[float]]:
        """(names, positions rad or m, velocities rad/s or m/s): the last reported, however old.

        For tests and tools; what is published comes from `next_joint_state`.
        """
        values = [self.feedback[d.device_id] for d in self.drives]
        return ([d.joint_name for d in self.drives], [v.position for v in values],
                [v.velocity for v in values])

    def next_jaw_state(self, t_s: float) -> JointSample | None:
        """The jaws' state (m, m/s) to publish at ``t_s``, or None (not driven, not fresh).

        As `next_joint_state` for the one device: both answers new since the last sample,
        within ``silent_timeout_s``, finite.
        """
        if self.jaw is None:
            return None
        v = self.feedback[self.jaw.device_id]
        if not (t_s - v.oldest_s <= self.silent_timeout_s and v.oldest_s > self._jaw_given_s
                and math.isfinite(v.position) and math.isfinite(v.velocity)):
            return None
        self._jaw_given_s = v.oldest_s
        return JointSample([self.jaw.joint_name], [v.position], [v.velocity], v.oldest_s)

    def next_joint_state(self, t_s: float) -> JointSample | None:
        """The joint state to publish at ``t_s``, or None while it would not be fresh.

        None unless every arm joint has answered both position and velocity since the last
        sample given, within ``silent_timeout_s``, with finite values: a sample never repeats
        an answer, so a joint that stops answering stops the samples at once (and a joint
        whose answer was lost in one round skips that round's sample). The jaws are never in
        it (`next_jaw_state`).
        """
        drives = self.arm.joints
        values = [self.feedback[d.device_id] for d in drives]
        if not all(t_s - v.oldest_s <= self.silent_timeout_s and v.oldest_s > given_s
                   for v, given_s in zip(values, self._given_s, strict=True)):
            return None
        positions, velocities = [v.position for v in values], [v.velocity for v in values]
        if not all(math.isfinite(x) for x in positions + velocities):
            return None
        self._given_s = [v.oldest_s for v in values]
        self.ages.add(t_s, self._given_s)
        return JointSample([d.joint_name for d in drives], positions, velocities,
                           min(self._given_s))

    # -- health -------------------------------------------------------------------------------
    def silent_joints(self, t_s: float) -> list[str]:
        """Joints that have not answered for ``silent_timeout_s``."""
        return [d.joint_name for d in self.drives
                if t_s - self.feedback[d.device_id].answer_s > self.silent_timeout_s]

    def status_errors(self, t_s: float) -> dict[str, str]:
        """{joint: HARDWARE_STATUS bytes as hex} of devices reporting errors lately."""
        return {d.joint_name: f.status.hex() for d in self.drives
                if any((f := self.feedback[d.device_id]).status)
                and t_s - f.status_s <= STATUS_HOLD_S}

    def report(self, t_s: float) -> tuple[int, str, dict[str, object]]:
        """(level 0 OK / 1 WARN / 2 ERROR, message, values) for /diagnostics."""
        silent, status = self.silent_joints(t_s), self.status_errors(t_s)
        s = self.splitter
        values: dict[str, object] = {
            'crc_errors': s.crc_errors, 'length_errors': s.length_errors,
            'cobs_errors': s.cobs_errors, 'packets': s.packets,
            'watchdog_trips': self.watchdog.trips, 'holding_velocity_0': self.holding,
            **({'jaw_watchdog_trips': self.jaw_watchdog.trips,
                'jaw_holding_velocity_0': self.jaw_holding} if self.jaw else {}),
            'rejected_commands': self.rejected_commands, 'silent_joints': ' '.join(silent),
            'overspeed': self.overspeed, 'joint_states_given': self.ages.given,
            **self.ages.figures_ms(),
            **{f'hardware_status.{k}': v for k, v in status.items()}}
        problems = [f'tripped: {self.overspeed}'] if self.overspeed else []
        if silent:
            problems.append(f'silent: {", ".join(silent)}')
        if status:
            problems.append(f'HARDWARE_STATUS errors: {", ".join(status)}')
        if problems:
            return 2, '; '.join(problems), values
        if s.bad_frames or self.rejected_commands or self.holding or self.jaw_holding:
            parts = [f'{s.bad_frames} bad frames dropped'] if s.bad_frames else []
            if self.rejected_commands:
                parts.append(f'{self.rejected_commands} commands refused ({self.last_rejection})')
            if self.holding:
                parts.append('no command: holding at VELOCITY 0')
            if self.jaw_holding:
                parts.append('no jaw command: the jaws at VELOCITY 0')
            return 1, '; '.join(parts), values
        return 0, 'running', values
