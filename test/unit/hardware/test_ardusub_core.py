"""The ArduSub component's pure decisions: watchdog, commands, lost link, mode, stop line."""

from __future__ import annotations

import pytest
from uvms_hardware.ardusub_core import (
    ERROR,
    OK,
    PASSTHROUGH,
    SCRIPT,
    WARN,
    ArduSubCore,
    Exchange,
    choose_mode,
    put_back_summary,
)
from uvms_hardware.errors import DeviceCheckError

from uvms_hardware import ardusub_wire

ALL = (1, 2, 3, 4, 5, 6, 7, 8)


def core() -> ArduSubCore:
    """Eight thrusters, 0.1 s command watchdog, 1 s link timeout, re-request every 20 s."""
    made = ArduSubCore(8, watchdog_timeout_s=0.1, link_timeout_s=1.0)
    made.configured(0.0)
    made.activated()
    return made


def test_neutral_until_a_command_and_again_once_commands_stop() -> None:
    """No command: None (neutral); a command: its thrusts; 0.1 s without: neutral, one trip."""
    c = core()
    assert c.output(0.0) is None
    assert c.command([10.0] * 8, 0.0) is None
    assert c.output(0.05) == (10.0,) * 8
    assert c.output(0.2) is None and c.watchdog.trips == 1
    assert c.output(0.3) is None and c.watchdog.trips == 1  # never resumes on an old command
    c.command([-5.0] * 8, 0.4)
    assert c.output(0.45) == (-5.0,) * 8


def test_a_bad_command_is_refused_and_counted_and_not_taken() -> None:
    """Wrong length or a NaN: refused (named), counted; the last good command stays."""
    c = core()
    c.command([1.0] * 8, 0.0)
    assert c.command([1.0] * 7, 0.01) == '7 thrusts (expected 8 finite)'
    assert c.command([float('nan')] * 8, 0.02) is not None
    assert c.rejected == 2 and c.output(0.05) == (1.0,) * 8
    assert c.output(0.15) is None  # the refused ones did not feed the watchdog


def test_activate_forgets_the_last_activation_s_command() -> None:
    """After a new activate nothing is sent but neutral until a new command arrives."""
    c = core()
    c.command([3.0] * 8, 0.0)
    c.activated()
    assert c.output(0.01) is None


def test_lost_link_edge_and_telemetry_requests() -> None:
    """The lost link is said once at each edge; the intervals asked for every 20 s."""
    c = core()
    first = c.poll(0.5, link_age_s=0.2)
    assert not first.link_lost and not first.link_lost_changed and not first.request_telemetry
    lost = c.poll(1.0, link_age_s=1.5)
    assert lost.link_lost and lost.link_lost_changed
    assert not c.poll(1.1, link_age_s=1.6).link_lost_changed
    back = c.poll(1.2, link_age_s=0.01)
    assert not back.link_lost and back.link_lost_changed
    assert c.poll(20.0, 0.0).request_telemetry and not c.poll(20.1, 0.0).request_telemetry
    assert c.poll(40.0, 0.0).request_telemetry


def test_health_levels() -> None:
    """Silent vehicle ERROR; clocks apart WARN; no command WARN; warnings WARN; else OK."""
    c = core()
    assert c.health(0.0, 1.5, True, [])[0] == ERROR
    assert c.health(0.0, 0.1, True, [], clocks_agree=False)[0] == WARN
    assert c.health(0.0, 0.1, True, []) == (WARN, 'no command: thrusters neutral')
    c.command([0.0] * 8, 0.0)
    assert c.health(0.01, 0.1, True, ['FS_GCS_ENABLE = 0']) == (WARN, 'FS_GCS_ENABLE = 0')
    assert c.health(0.01, 0.1, True, []) == (OK, 'running')


def test_mode_choice() -> None:
    """Script when heard and wanted, passthrough otherwise; refusals named."""
    assert choose_mode('auto', 100.0, ALL, ALL, 'wd.lua', 1.5) == SCRIPT
    assert choose_mode('auto', None, ALL, ALL, 'wd.lua', 1.5) == PASSTHROUGH
    assert choose_mode('passthrough', 100.0, ALL, ALL, 'wd.lua', 1.5) == PASSTHROUGH
    with pytest.raises(DeviceCheckError, match='not heard'):
        choose_mode('script', None, ALL, ALL, 'wd.lua', 1.5)
    with pytest.raises(DeviceCheckError, match='make them the same'):
        choose_mode('auto', 100.0, (1, 2, 3, 4), ALL, 'wd.lua', 1.5)


def test_put_back_summary() -> None:
    """What a stop says: restored outputs, those not read back, a silent vehicle."""
    assert put_back_summary({}, {}, [], SCRIPT) == (
        'thrusters neutral (1500 us), disarmed, RC overrides released; no parameter had been '
        'changed (script mode)')
    line = put_back_summary({1: 33.0, 2: 34.0}, {2: 34.0}, ['SERVO2_FUNCTION not read back'],
                            PASSTHROUGH)
    assert 'restored and read back (1=33)' in line and 'NOT read back: SERVO2_FUNCTION' in line
    assert 'disarm NOT confirmed' in put_back_summary({}, {}, ['disarm: refused'], SCRIPT)
    assert put_back_summary({}, {}, ['... sent without confirmation'], SCRIPT).startswith(
        'vehicle silent')


def test_mode_words_are_the_wires() -> None:
    """The core's mode words are ardusub_wire's (the link's `mode`)."""
    assert (PASSTHROUGH, SCRIPT) == (ardusub_wire.PASSTHROUGH, ardusub_wire.SCRIPT)


def test_an_exchange_sends_each_try_after_the_last_one_s_wait() -> None:
    """Three tries 0.5 s apart; over once the third try's wait ran out."""
    exchange = Exchange(tries=3, reply_timeout_s=0.5)
    assert exchange.due(0.0) and exchange.sent == 1
    assert not exchange.due(0.4) and not exchange.over(0.4)
    assert exchange.due(0.5) and exchange.sent == 2
    assert exchange.due(1.0) and exchange.sent == 3
    assert not exchange.due(1.2) and not exchange.over(1.2)
    assert not exchange.due(1.5) and exchange.over(1.5)


def test_an_exchange_never_sends_or_waits_past_its_end() -> None:
    """end_s cuts the tries and the last wait (a restore's budget)."""
    exchange = Exchange(tries=3, reply_timeout_s=0.5, end_s=0.7)
    assert exchange.due(0.0)
    assert exchange.due(0.5) and exchange.sent == 2
    assert not exchange.due(0.69) and exchange.over(0.7) and not exchange.due(0.7)
    late = Exchange(tries=3, reply_timeout_s=0.5, end_s=1.0)
    assert not late.due(1.0) and late.over(1.0) and late.sent == 0
