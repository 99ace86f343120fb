"""The Alpha 5 bridge core: configure checks, commands, feedback in turn, watchdog, health."""

from __future__ import annotations

import math

import pytest
from uvms_hardware.alpha5_checks import check_device
from uvms_hardware.alpha5_core import JAW_POLL_ROUNDS, Alpha5Core
from uvms_hardware.hardware_config import load_alpha5
from uvms_hardware.reach_protocol import Mode, PacketId
from uvms_twins.alpha5_twin import Alpha5Twin

from uvms_hardware import reach_protocol as rp

ARM = load_alpha5('bluerov2_alpha5')


def packets(frames: bytes) -> list[rp.Packet]:
    """Every packet of a byte string of frames."""
    splitter = rp.FrameSplitter()
    out = list(splitter.feed(frames))
    assert splitter.bad_frames == 0
    return out


def configure_answers(twin: Alpha5Twin, device_id: int) -> dict[int, rp.Packet]:
    """A device's answers to the bridge's configure requests, by packet id."""
    request = rp.encode_request(device_id, [PacketId.MODEL, PacketId.MODE, *(
        PacketId.POSITION_LIMITS, PacketId.VELOCITY_LIMITS, PacketId.CURRENT_LIMITS)])
    return {p.packet_id: p for p in packets(twin.handle(rp.decode_frame(request)))}


def test_device_matching_the_urdf_passes() -> None:
    """The twin's limits are the URDF's: no error for any joint."""
    twin = Alpha5Twin(ARM, port=0)
    for drive in ARM.joints:
        assert check_device(drive, configure_answers(twin, drive.device_id), 0.2) == []


def test_limit_mismatch_names_the_joint_and_both_values() -> None:
    """A shoulder limited to 0..3.8 rad is refused, naming joint_2, 3.8 and 3.49."""
    twin = Alpha5Twin(ARM, port=0)
    twin.set_position_limits(0x04, 0.0, 3.8)
    (error,) = check_device(ARM.joints[1], configure_answers(twin, 0x04), 0.2)
    assert 'joint_2' in error and '3.8' in error and '3.49' in error


def test_silent_device_is_named() -> None:
    """No MODEL answer: 'joint_4 ... silent'."""
    (error,) = check_device(ARM.joints[3], {}, 0.2)
    assert error.startswith('joint_4 (device 0x02, B): silent')


def test_torques_become_currents_per_joint_in_device_order() -> None:
    """1 N m on every joint is CURRENT 1/(Kt ratio eff) mA to each of devices 5, 4, 3, 2."""
    core = Alpha5Core(ARM)
    names = ['joint_4', 'joint_3', 'joint_2', 'joint_1']
    sent = packets(core.command(0.0, names, [1.0, 1.0, 1.0, 1.0]))
    assert [(p.device_id, p.packet_id) for p in sent] == [(d, PacketId.CURRENT)
                                                         for d in (5, 4, 3, 2)]
    assert sent[0].floats()[0] == pytest.approx(1000.0 / (0.0134 * 1754.4 * 0.86), rel=1e-6)
    assert sent[3].floats()[0] == pytest.approx(1000.0 / (0.0271 * 340.4 * 0.77), rel=1e-6)


def test_velocity_fallback_sends_gain_times_torque_clamped() -> None:
    """In velocity mode 2 N m at gain 0.1 is 0.2 rad/s; 10 N m is clamped at 0.5 rad/s."""
    core = Alpha5Core(ARM, command_mode='velocity', velocity_gain_rad_s_per_n_m=0.1)
    sent = packets(core.command(0.0, [], [2.0, 10.0, 0.0, 0.0]))
    assert [p.packet_id for p in sent] == [PacketId.VELOCITY] * 4
    assert [p.floats()[0] for p in sent[:2]] == pytest.approx([0.2, 0.5])


@pytest.mark.parametrize(('names', 'torques'), [
    (['joint_1', 'joint_2'], [0.0, 0.0]), ([], [0.0, math.nan, 0.0, 0.0]),
    (['joint_1', 'joint_2', 'joint_3', 'jaw'], [0.0] * 4)])
def test_bad_command_is_refused_and_counted(names: list[str], torques: list[float]) -> None:
    """Missing joints, NaN torques or unknown names send nothing and count one refusal."""
    core = Alpha5Core(ARM)
    assert core.command(0.0, names, torques) == b''
    assert core.rejected_commands == 1


def test_feedback_asks_one_device_at_a_time_in_turn() -> None:
    """Each tick requests POSITION and VELOCITY of the next device; never 0xFF."""
    core = Alpha5Core(ARM)
    ticks = [core.tick(0.001 * i) for i in range(8)]
    requests = [packets(frames)[-1] for frames, _ in ticks]
    assert [r.device_id for r in requests] == [5, 4, 3, 2, 5, 4, 3, 2]
    assert all(r.data == bytes((PacketId.POSITION, PacketId.VELOCITY)) for r in requests)
    assert [done for _, done in ticks] == [True, False, False, False] * 2


def test_watchdog_sends_velocity_0_to_every_joint_and_holds() -> None:
    """No command for 0.1 s: VELOCITY 0 to devices 5-2, repeated while no command comes."""
    core = Alpha5Core(ARM, watchdog_timeout_s=0.1)
    core.command(0.0, [], [1.0] * 4)
    assert [p.packet_id for p in packets(core.tick(0.05)[0])] == [PacketId.REQUEST]
    tripped = packets(core.tick(0.11)[0])[:-1]
    assert [(p.device_id, p.packet_id, p.floats()) for p in tripped] == [
        (d, PacketId.VELOCITY, (0.0,)) for d in (5, 4, 3, 2)]
    assert len(packets(core.tick(0.15)[0])) == 1  # not yet resent
    assert len(packets(core.tick(0.22)[0])) == 5  # resent after HOLD_RESEND_S
    core.command(0.3, [], [1.0] * 4)
    assert not core.holding and len(packets(core.tick(0.31)[0])) == 1


def test_no_neutral_before_the_first_command() -> None:
    """Before any command nothing but feedback requests is sent."""
    core = Alpha5Core(ARM)
    assert [len(packets(core.tick(t)[0])) for t in (0.0, 0.5, 1.0)] == [1, 1, 1]


def test_restore_is_velocity_0_then_the_resting_mode() -> None:
    """Deactivate: VELOCITY 0, then MODE Standby (Disable kept if the device was disabled)."""
    core = Alpha5Core(ARM)
    sent = packets(core.restore_frames({5: Mode.DISABLE, 4: Mode.VELOCITY}))
    assert [p.packet_id for p in sent[:4]] == [PacketId.VELOCITY] * 4
    assert [(p.device_id, p.data[0]) for p in sent[4:]] == [
        (5, Mode.DISABLE), (4, Mode.STANDBY), (3, Mode.STANDBY), (2, Mode.STANDBY)]


def test_jaw_feedback_is_in_metres() -> None:
    """The jaw answering 10 mm is 0.01 m in the joint state."""
    arm = load_alpha5('bluerov2_alpha5', jaw_joint='jaw')
    core, twin = Alpha5Core(arm), Alpha5Twin(arm, port=0)
    twin.set_joint_state([0.1, 0.2, 0.3, 0.4, 0.01], [0.0] * 5)
    for _ in range(4 * JAW_POLL_ROUNDS + 1):  # the jaws are asked once every 5 rounds
        frames, _ = core.tick(0.0)
        for packet in packets(frames):
            core.receive(twin.handle(packet), 0.0)
    names, q, _ = core.joint_state()
    assert names[-1] == 'jaw' and q == pytest.approx([0.1, 0.2, 0.3, 0.4, 0.01])


def test_bad_frames_are_counted_and_survived() -> None:
    """A corrupted answer is dropped and counted; the next good one is taken."""
    core = Alpha5Core(ARM)
    good = rp.encode_position(0x05, 1.25)
    bad = bytearray(good)
    bad[2] ^= 0x40
    core.receive(bytes(bad) + good, 1.0)
    assert core.splitter.bad_frames == 1 and core.feedback[5].position == pytest.approx(1.25)
    level, message, values = core.report(1.0)
    assert values['packets'] == 1 and 'silent' in message and level == 2


def test_hardware_status_error_is_an_error_in_the_report() -> None:
    """A non-zero HARDWARE_STATUS from the elbow makes the report an ERROR naming joint_3."""
    core = Alpha5Core(ARM)
    for d in (5, 4, 3, 2):
        core.receive(rp.encode_position(d, 0.5), 1.0)
    core.receive(rp.encode_packet(0x03, PacketId.HARDWARE_STATUS, b'\x04\x00'), 1.0)
    level, message, _ = core.report(1.1)
    assert level == 2 and 'joint_3' in message
    assert core.report(5.0)[0] == 2  # silent by then, the status itself expired
    assert core.status_errors(5.0) == {}


def test_a_joint_over_its_speed_limit_trips_every_joint_to_velocity_0_until_reset() -> None:
    """joint_2 at 2x its limit: VELOCITY 0 to all, commands refused naming it, ERROR; reset.

    After stop_driving (deactivate) a command drives again.
    """
    core = Alpha5Core(ARM)
    names = [d.joint_name for d in ARM.joints]
    assert core.command(0.0, names, [0.1] * len(names))
    shoulder = ARM.joints[1]
    core.receive(rp.encode_velocity(shoulder.device_id, 1.4 * shoulder.velocity_limit), 0.01)
    assert not core.overspeed  # within 1.5 x its limit
    core.receive(rp.encode_velocity(shoulder.device_id, -2.0 * shoulder.velocity_limit), 0.02)
    assert 'joint_2' in core.overspeed
    frames, _ = core.tick(0.02)
    zeros = [p for p in packets(frames) if p.packet_id == PacketId.VELOCITY]
    assert sorted(p.device_id for p in zeros) == sorted(d.device_id for d in ARM.drives)
    assert all(rp.packet_values_si(p)[0] == 0.0 for p in zeros)
    assert core.command(0.03, names, [0.1] * len(names)) == b''
    assert 'joint_2' in core.last_rejection and 'deactivate' in core.last_rejection
    level, message, values = core.report(0.03)
    assert level == 2 and message.startswith('tripped: joint_2')
    assert 'joint_2' in str(values['overspeed'])
    core.stop_driving()
    assert core.command(0.04, names, [0.1] * len(names))


def test_an_overspeed_factor_under_1_is_refused() -> None:
    """A trip below the joint's own limit would stop every normal motion: refused."""
    with pytest.raises(ValueError, match='overspeed_factor'):
        Alpha5Core(ARM, overspeed_factor=0.9)


def answer_round(core: Alpha5Core, twin: Alpha5Twin, t_s: float) -> None:
    """One feedback round at ``t_s``: each device asked in turn, its answer taken."""
    for _ in core.drives:
        frames, _ = core.tick(t_s)
        for packet in packets(frames):
            core.receive(twin.handle(packet), t_s)


def test_a_joint_that_stops_answering_gives_no_joint_state() -> None:
    """joint_3 silent after 0.01 s: no joint state at all from then on; its answer again: one.

    Before, every round gives one, stamped with its oldest answer's arrival. The old core
    republished joint_3's last answer each round for as long as the others answered.
    """
    core, twin = Alpha5Core(ARM, silent_timeout_s=0.2), Alpha5Twin(ARM, port=0)
    answer_round(core, twin, 0.0)
    answer_round(core, twin, 0.01)
    sample = core.next_joint_state(0.01)
    assert sample is not None and sample.oldest_answer_s == 0.01
    twin.set_silent(0x03)
    given = []
    for t_s in (0.02, 0.05, 0.15, 0.25, 0.5):
        answer_round(core, twin, t_s)
        given.append(core.next_joint_state(t_s))
    assert given == [None] * 5
    assert core.silent_joints(0.5) == ['joint_3']
    twin.set_silent(0x03, False)
    answer_round(core, twin, 0.6)
    assert core.next_joint_state(0.6) is not None


def test_a_joint_state_is_never_given_twice() -> None:
    """Without a new answer since the last joint state, there is no next one."""
    core, twin = Alpha5Core(ARM), Alpha5Twin(ARM, port=0)
    answer_round(core, twin, 0.0)
    assert core.next_joint_state(0.0) is not None
    assert core.next_joint_state(0.002) is None


def test_a_joint_state_is_stamped_with_its_oldest_answer() -> None:
    """Answers at 1.000 s (joint_1) and 1.006 s (the others): the sample says 1.000 s."""
    core = Alpha5Core(ARM)
    for t_s, device_id in ((1.0, 5), (1.002, 4), (1.004, 3), (1.006, 2)):
        core.receive(rp.encode_position(device_id, 0.5) + rp.encode_velocity(device_id, 0.0),
                     t_s)
    sample = core.next_joint_state(1.008)
    assert sample is not None and sample.oldest_answer_s == 1.0
    assert sample.names == ['joint_1', 'joint_2', 'joint_3', 'joint_4']


def test_the_report_says_how_old_the_answers_of_a_joint_state_were() -> None:
    """Answers at 1.000-1.006 s given at 1.008 s: oldest 8 ms, newest 2 ms, one given.

    A polled bus answers the joints one after another: what the controller is told is this
    old before it even leaves the bridge (docs/hardware.md, "The Alpha 5 bus").
    """
    core = Alpha5Core(ARM)
    assert core.report(0.0)[2]['joint_states_given'] == 0
    for t_s, device_id in ((1.0, 5), (1.002, 4), (1.004, 3), (1.006, 2)):
        core.receive(rp.encode_position(device_id, 0.5) + rp.encode_velocity(device_id, 0.0),
                     t_s)
    assert core.next_joint_state(1.008) is not None
    values = core.report(1.008)[2]
    assert values['joint_states_given'] == 1
    assert values['joint_state_age_oldest_ms_p50'] == pytest.approx(8.0)
    assert values['joint_state_age_newest_ms_p50'] == pytest.approx(2.0)
