"""The Reach Alpha 5 as a hardware component: no ROS, no waiting per period.

What the ``alpha5_bridge`` node did with its device, behind `HardwareComponent`'s lifecycle
(``uvms_hardware.component``), so that a bridge node or one real-time loop runs it:

- configure asks each device in turn (never a broadcast: answers collide on RS-485) for
  MODEL, MODE and its three limits (``uvms_hardware.alpha5_probe``, each request tried
  ``CONFIRM_TRIES`` times), asking again for ``startup_wait_s`` while not every device
  answers; refused, naming the joint and both values, where a limit differs from the URDF's
  (position, speed) or hardware.yaml's (current), or a device stays silent.
- activate sends MODE Standby to every device, each read back; refused, naming the device,
  where one does not confirm, or where a joint already moves over the trip speed.
- `read` drains the link (answers, HARDWARE_STATUS), trips on an overspeed and makes the
  round's joint state (and the jaws') once every driven joint answered again.
- `write` turns joint torques into CURRENT mA per joint (or the velocity fallback);
  `write_jaw` the jaws' speed into VELOCITY (mm/s on the wire). Both are written at once,
  or, with ``bus_schedule`` (off by default: the twin stand does not hold with it yet,
  docs/hardware.md "The Alpha 5 bus"), held for the bus's next command slot or free turn.
- `ask`, after the period's write, sends what the period asks of the wire: the next device's
  POSITION and VELOCITY request and, after ``watchdog_timeout_s`` without a command, VELOCITY
  0 to every joint (``Alpha5Core.tick``). With ``bus_schedule`` it takes the period's turn on
  the half-duplex bus (``uvms_hardware.alpha5_bus``, at hardware.yaml's
  ``alpha5.bus.command_rate_hz``): while no answer is expected, the watchdog's VELOCITY 0 and
  the jaws' frames, every joint's held CURRENT once per command slot, then the next device's
  request if its answer ends before the next slot. Asked
  after the commands, the answer comes back in the rest of the period and the next period's
  read takes it (through the twins without a bus, answer to CURRENT frame p50 2.7-2.8 ms at a
  2 ms period; docs/robot_process.md).
- put_back: VELOCITY 0 to every device at once, then device by device, each read back,
  VELOCITY 0 and the mode from before activate; what is not confirmed is a problem line.

``now_s`` is the steady clock (s) of the wire's timeouts.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from uvms_hardware import latency_probe
from uvms_hardware.alpha5_bus import BusSchedule, byte_time_s, cycle_budget
from uvms_hardware.alpha5_checks import (
    CONFIRM_TRIES,
    PUT_BACK_BUDGET_S,
    Setting,
    check_device,
    describe,
    put_back_bound_s,
)
from uvms_hardware.alpha5_core import FEEDBACK_REQUEST, Alpha5Core
from uvms_hardware.alpha5_feedback import JointSample
from uvms_hardware.alpha5_parameters import PARAMETERS
from uvms_hardware.alpha5_probe import confirm_setting, probe_device
from uvms_hardware.component import (
    OK,
    WARN,
    ComponentReport,
    HardwareComponent,
    LogFn,
    Throttle,
    python_log,
)
from uvms_hardware.errors import HardwareError
from uvms_hardware.hardware_config import Alpha5Hardware, Drive, hardware_section, load_alpha5
from uvms_hardware.reach_protocol import Mode, encode_request
from uvms_hardware.stop_report import write_stop_report
from uvms_hardware.transport import Link, open_link, parse_connection

__all__ = ['PARAMETERS', 'Alpha5BridgeError', 'Alpha5Component', 'Alpha5State',
           'jaw_default']

def bus_command_rate_hz(robot_name: str, arm: Alpha5Hardware) -> float:
    """The command slots' rate (Hz): hardware.yaml's ``alpha5.bus.command_rate_hz``.

    Without it, the budget of one CURRENT and one answered REQUEST per joint per cycle.

    Raises:
        Alpha5BridgeError: A rate whose commands and one request per slot do not fit the line.
    """
    _, section = hardware_section(robot_name, 'alpha5')
    bus = section.get('bus') or {}
    joints = len(arm.joints)
    rate_hz = float(bus.get('command_rate_hz', cycle_budget(arm.serial_baud, joints)))
    slot_bytes = joints * 10 + 8 + 20  # every joint's CURRENT and one answered REQUEST
    if not (rate_hz > 0.0 and rate_hz * slot_bytes * byte_time_s(arm.serial_baud) <= 1.0):
        raise Alpha5BridgeError(
            f'alpha5.bus.command_rate_hz = {rate_hz:g}: {joints} CURRENT frames and one '
            f'answered request ({slot_bytes} bytes) per slot do not fit {arm.serial_baud} baud '
            f'(at most {1.0 / (slot_bytes * byte_time_s(arm.serial_baud)):.0f} Hz)')
    return rate_hz


def jaw_default(robot_name: str) -> str:
    """The jaws' joint name the robot's hardware file gives ('' where none or unreadable)."""
    try:
        jaw = load_alpha5(robot_name, None).jaw
    except HardwareError:
        return ''  # configure names what is wrong with the file
    return '' if jaw is None else jaw.joint_name


class Alpha5BridgeError(HardwareError):
    """A parameter of the bridge is invalid, or the arm refuses configure or activate."""


@dataclass(frozen=True)
class Alpha5State:
    """What the last `read` gave.

    Attributes:
        joints: The arm joints' round, once every driven joint answered again (None: not
            yet); its ``oldest_answer_s`` on the steady clock.
        jaw: The jaws' opening (m) and speed (m/s), as a one-joint sample (None: no new one).
        tripped: The overspeed trip, when this read tripped ('' otherwise).
    """

    joints: JointSample | None = None
    jaw: JointSample | None = None
    tripped: str = ''


class Alpha5Component(HardwareComponent):
    """Reach Alpha 5: its devices checked, driven in Current mode, put back as found."""

    def __init__(self, values: Mapping[str, Any], robot_name: str, name: str = 'alpha5_bridge',
                 clock: Callable[[], float] | None = None, log: LogFn = python_log,
                 stop_requested: Callable[[], bool] = lambda: False) -> None:
        """Settings as `PARAMETERS` names them, for robot ``robot_name``."""
        super().__init__()
        self.values = dict(values)
        self.robot_name = robot_name
        self.name = name
        self.clock = clock or time.monotonic
        self.log = log
        self.stop_requested = stop_requested
        self.core: Alpha5Core | None = None
        self.link: Link | None = None
        self.modes_before: dict[int, Mode] = {}
        #: Every reason the last configure was refused, one per device problem.
        self.configure_errors: list[str] = []
        self.feedback_rate_hz = 0.0
        self.command_rate_hz = 0.0
        self.bus: BusSchedule | None = None
        self._urgent = b''
        self._asked_s = -math.inf
        self._state = Alpha5State()
        self._refused = Throttle(1.0)
        self._jaw_refused = Throttle(1.0)
        self._asking = Throttle(2.0)

    # -- lifecycle ---------------------------------------------------------------------------
    def configure(self) -> None:
        """Check the settings, open the link, check every device in turn.

        Raises:
            Alpha5BridgeError: A bad setting, or a device that is silent or whose limits
                differ (every device's problems in ``configure_errors``).
            HardwareError, ValueError, OSError: The hardware file, a setting, the link.
        """
        self.configure_errors = []
        try:
            self._configure()
        except (HardwareError, ValueError, OSError) as exc:
            self.configure_errors = self.configure_errors or [str(exc)]
            raise

    def _configure(self) -> None:
        v = self.values
        arm = load_alpha5(self.robot_name, str(v['jaw_joint']))
        core = Alpha5Core(arm, float(v['watchdog_timeout_s']), str(v['command_mode']),
                          float(v['velocity_gain_rad_s_per_n_m']),
                          float(v['silent_timeout_s']), float(v['overspeed_factor']))
        rate_hz = float(v['feedback_rate_hz'])
        if not rate_hz > 0.0:
            raise Alpha5BridgeError(f'feedback_rate_hz = {rate_hz}: expected > 0')
        bound_s = put_back_bound_s(len(arm.drives), CONFIRM_TRIES, float(v['confirm_timeout_s']))
        if not 0.0 < bound_s <= PUT_BACK_BUDGET_S:
            raise Alpha5BridgeError(
                f'confirm_timeout_s = {v["confirm_timeout_s"]}: the put-back of '
                f'{len(arm.drives)} devices could take {bound_s:g} s, more than '
                f'{PUT_BACK_BUDGET_S:g} s (or is no time at all)')
        self.configured = True
        self.link = link = open_link(parse_connection(str(v['connection']), arm.udp_port))
        deadline_s = self.clock() + float(v['startup_wait_s'])
        while True:
            self.modes_before.clear()
            errors = [e for drive in arm.drives for e in self._check(link, core, drive)]
            answered = all(d.device_id in self.modes_before for d in arm.drives)
            if answered or self.clock() >= deadline_s or self.stop_requested():
                break
            if self._asking(self.clock()):
                self.log('info', f'not every device answers on {v["connection"]} yet: '
                         'asking again')
        if errors:
            self.configure_errors = errors
            raise Alpha5BridgeError('; '.join(errors))
        self.core = core
        self.feedback_rate_hz = rate_hz
        self.command_rate_hz = bus_command_rate_hz(self.robot_name, arm)

    def _check(self, link: Link, core: Alpha5Core, drive: Drive) -> list[str]:
        timeout_s = float(self.values['answer_timeout_s'])
        answers, mode = probe_device(link, core.splitter, drive, timeout_s)
        if mode is not None:
            self.modes_before[drive.device_id] = mode
        return check_device(drive, answers, timeout_s)

    def activate(self) -> None:
        """MODE Standby to every device, each read back; then commands are taken.

        Raises:
            Alpha5BridgeError: A device did not confirm Standby, or a joint moves over the
                trip speed (named); the runner then puts back every device.
        """
        assert self.core is not None and self.link is not None
        self.bus = (BusSchedule(self.core.arm.serial_baud, self.command_rate_hz)
                    if bool(self.values['bus_schedule']) else None)
        self._urgent = b''
        self.link.read()  # answers still in flight from configure
        problems = self._confirm(self.core.standby_settings())
        if problems:
            raise Alpha5BridgeError('; '.join(problems))
        self.core.stop_driving()  # nothing is driven until the first command
        fast = self._fast_joints_now()
        if fast:
            raise Alpha5BridgeError(
                f'{", ".join(fast)}: over {self.core.overspeed_factor:g} x the speed limit, '
                'the bridge would trip at once; wait until the arm is still (after a trip: '
                'docs/hardware.md, "Recovering the arm after a trip")')
        self._state = Alpha5State()
        super().activate()

    def _fast_joints_now(self) -> list[str]:
        """Each device asked its speed now: the joints over the trip speed (activate)."""
        assert self.core is not None and self.link is not None
        timeout_s = float(self.values['confirm_timeout_s'])
        for drive in self.core.drives:
            self.link.send(encode_request(drive.device_id, FEEDBACK_REQUEST))
            deadline_s = self.clock() + timeout_s
            before = self.core.feedback[drive.device_id].velocity_s
            while (self.core.feedback[drive.device_id].velocity_s == before
                   and self.clock() < deadline_s):
                self.link.wait(deadline_s - self.clock())
                self.core.receive(self.link.read(), self.clock())
        fast = self.core.fast_joints()
        self.core.stop_driving()  # a trip receive() just found is said by the refusal
        return fast

    def put_back(self) -> list[str]:
        """VELOCITY 0 to every device at once, then each VELOCITY 0 and resting mode confirmed.

        Returns:
            One line per change a device did not confirm, naming it.
        """
        self.active = False
        core, link = self.core, self.link
        problems: list[str] = []
        if self.bus is not None:
            self.bus.hold(b'')
        self._urgent = b''
        if core is not None and link is not None:
            link.send(core.neutral_frames())  # every joint stops first, whatever follows
            self.log('info', core.ages.line())
            settings = core.restore_settings(self.modes_before)
            problems = self._confirm(settings)
            core.stop_driving()
            rest = ', '.join(f'{s.drive.joint_name} {s.label.removeprefix("MODE ")}'
                             for s in settings if s.label.startswith('MODE'))
            done = (f'every joint VELOCITY 0, then its mode from before ({rest}), '
                    + ('each read back' if not problems else
                       f'{len(problems)} of {len(settings)} changes NOT confirmed'))
            self.log('info', f'put back: {done}')
            write_stop_report(self.name, done, problems)
        return problems

    def release(self) -> None:
        """Close the link."""
        if self.link is not None:
            self.link.close()
        self.link, self.core = None, None
        super().release()

    def _confirm(self, settings: Sequence[Setting]) -> list[str]:
        """Each setting sent and read back (``confirm_setting``); what did not confirm."""
        assert self.core is not None and self.link is not None
        timeout_s = float(self.values['confirm_timeout_s'])
        problems = []
        for setting in settings:
            result = confirm_setting(self.link, self.core.splitter, setting, CONFIRM_TRIES,
                                     timeout_s)
            if not result.confirmed:
                seen = ('no MODE answer' if result.mode is None
                        else f'MODE reads {result.mode.name.capitalize()}')
                problems.append(f'{describe(setting.drive)}: {setting.label} not confirmed '
                                f'after {result.tries} tries of {timeout_s:g} s ({seen})')
        return problems

    # -- the loop ----------------------------------------------------------------------------
    def poll_period_s(self) -> float:
        """How often `read` should run (s): one device asked per call, each at the rate."""
        assert self.core is not None
        return self.core.poll_period_s(self.feedback_rate_hz)

    def read(self, now_s: float) -> None:
        """Answers taken, a trip found, the round's state made.

        Never waits. Only while active (nothing is asked of an arm not driven).
        """
        core, link = self.core, self.link
        self._state = Alpha5State()
        if core is None or link is None or not self.active:
            return
        tripped = core.overspeed
        core.receive(link.read(), now_s)
        if self.bus is not None and core.asked is not None and core.answered(
                core.asked, self._asked_s):
            self.bus.answered()  # the line is free: the next turn may write
        newly = core.overspeed if core.overspeed and not tripped else ''
        if newly:
            self.log('error', f'tripped: {newly}: VELOCITY 0 to every joint; commands refused '
                     'until `uvms hardware reset-trip` (docs/hardware.md, "Recovering the arm '
                     'after a trip")')
        self._state = Alpha5State(core.next_joint_state(now_s), core.next_jaw_state(now_s),
                                  newly)

    def ask(self, now_s: float) -> None:
        """This period's requests (and the watchdog's VELOCITY 0) sent; after the write.

        With ``bus_schedule``, the period's turn on the bus (``alpha5_bus``): while no answer
        is expected, the watchdog's VELOCITY 0 and the jaws' frames, every
        joint's held CURRENT once per command slot, then the next device's request (if its
        answer ends before the next slot). A command is held only while the core drives (a
        watchdog hold or a trip drops it). Never waits. Only while active.
        """
        core, link, bus = self.core, self.link, self.bus
        if core is None or link is None or not self.active:
            return
        if bus is None:  # unscheduled: the next request (and the watchdog's VELOCITY 0)
            link.send(core.tick(now_s)[0])
            return
        self._urgent += core.hold_frames(now_s)
        if not core.driving and bus.held:
            bus.hold(b'')
        sent_s = max(now_s, self.clock())  # the answers are reckoned from the write itself
        if not bus.line_free(sent_s):
            return
        slots, asked = bus.slots, bus.bytes_expected
        frames = bus.turn(sent_s, self._urgent, core.next_request)
        if bus.bytes_expected != asked:
            self._asked_s = now_s  # an answer read after this is the request's
        self._urgent = b''
        link.send(frames)
        if bus.slots != slots:
            latency_probe.note('current')

    def write(self, now_s: float, commands: Any = None) -> None:
        """Joint torques (N m) as ``(names, torques)`` to CURRENT (or VELOCITY) frames, held.

        With ``bus_schedule``, `ask` sends them at the bus's next command slot; without, they
        are written at once. Refused (one error line a second,
        nothing held) while tripped or for a bad command.
        """
        core, link, bus = self.core, self.link, self.bus
        if commands is None or core is None or link is None or not self.active:
            return
        names, torques = commands
        frames = core.command(now_s, list(names), list(torques))
        if not frames and self._refused(now_s):
            self.log('error', f'command refused: {core.last_rejection}')
        if bus is None:  # unscheduled: written at once
            link.send(frames)
            if frames:
                latency_probe.note('current')
        elif frames:
            bus.hold(frames)

    def write_jaw(self, now_s: float, speed_m_s: float) -> None:
        """The jaws' opening speed (m/s, + opens) to VELOCITY; refused while tripped.

        Sent at the bus's next free turn (`ask`) with ``bus_schedule``, else at once.
        """
        core = self.core
        if core is None or self.link is None or not self.active:
            return
        frames, refused = core.jaw_command(now_s, float(speed_m_s))
        if refused and self._jaw_refused(now_s):
            self.log('error', f'jaw command refused: {refused}')
        if self.bus is None:
            self.link.send(frames)
        else:
            self._urgent += frames

    def reset_trip(self) -> tuple[bool, str]:
        """Take commands again once no joint moves over the trip speed: (done, what was said)."""
        core = self.core
        if core is None or not self.active:
            return False, 'not active: activate instead'
        tripped = core.overspeed
        if not tripped:
            return True, 'not tripped: nothing to clear'
        why = core.reset_trip()
        return not why, why or f'trip cleared ({tripped}); commands are taken again'

    def state(self) -> Alpha5State:
        """What the last `read` gave (a round only when every joint answered afresh)."""
        return self._state

    def report(self, now_s: float) -> ComponentReport:
        """Bad frames, silent joints, HARDWARE_STATUS, watchdog; OK while not driving."""
        if self.core is None:
            return ComponentReport(WARN, 'not configured', {})
        if not self.active:
            return ComponentReport(OK, 'not driving', {})
        level, message, values = self.core.report(now_s)
        return ComponentReport(level, message, values)
