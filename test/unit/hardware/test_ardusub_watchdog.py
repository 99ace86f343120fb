"""The autopilot watchdog script: its settings, the wire's toggle, and its model against itself."""

from __future__ import annotations

import pytest
from lupa.lua53 import LuaRuntime  # Lua 5.3, as ArduPilot's scripting engine
from uvms_hardware.ardusub_watchdog import (
    ScriptSettings,
    WatchdogScript,
    script_path,
    toggle_encode,
)


def commands(pwm: int, steps: int, start_toggle: int = 0) -> list[dict[int, int]]:
    """RC inputs 9-16 as the bridge sends them, one message per step, toggling."""
    return [{k: toggle_encode(pwm, start_toggle + i) for k in range(9, 17)}
            for i in range(steps)]


def test_settings_are_read_from_the_shipped_script() -> None:
    """100 ms timeout, 10 ms period, thruster outputs 1-8 read from RC inputs 9-16."""
    s = ScriptSettings.from_source()
    assert (s.timeout_ms, s.period_ms, s.first_rc, s.outputs) == (100, 10, 9,
                                                                 (1, 2, 3, 4, 5, 6, 7, 8))
    assert [s.rc_channel(o) for o in s.outputs] == list(range(9, 17))


@pytest.mark.parametrize('pwm', [1100, 1500, 1501, 1899, 1900])
def test_the_toggle_costs_at_most_one_microsecond(pwm: int) -> None:
    """Both toggles stay within 1 µs of the PWM and differ in their lowest bit only."""
    even, odd = toggle_encode(pwm, 0), toggle_encode(pwm, 1)
    assert (even % 2, odd % 2) == (0, 1) and odd - even == 1
    assert abs(even - pwm) <= 1 and abs(odd - pwm) <= 1


def test_fresh_commands_drive_and_stale_ones_go_neutral_within_the_timeout() -> None:
    """Toggling inputs: outputs follow; no toggle for 100 ms: 1500 while armed."""
    script = WatchdogScript()
    t_ms, last = 0.0, {}
    for rc in commands(1700, 10):
        last = script.update(t_ms, True, rc)
        t_ms += 10.0
    assert last == {o: 1700 for o in range(1, 9)}
    held = commands(1700, 10)[-1]  # the bridge died: the inputs keep their last value
    for _ in range(10):
        last = script.update(t_ms, True, held)
        t_ms += 10.0
    assert last == {o: 1700 for o in range(1, 9)}  # 100 ms since the last toggle, not more
    assert script.update(t_ms + 10.0, True, held) == {o: 1500 for o in range(1, 9)}


def test_disarmed_the_script_sets_nothing() -> None:
    """Disarmed: no override, the outputs are their Motor function again."""
    script = WatchdogScript()
    for i, rc in enumerate(commands(1700, 5)):
        assert script.update(10.0 * i, False, rc) == {}


def test_a_pilot_ground_station_never_looks_like_the_bridge() -> None:
    """ArduSub's joystick writes constant lights and video values on 9-11: never fresh."""
    script = WatchdogScript()
    constant = {9: 1100, 10: 1100, 11: 1100, **{k: 1500 for k in range(12, 17)}}
    assert all(script.update(10.0 * i, True, constant) == {} for i in range(50))


def _lua_run(steps: list[tuple[int, bool, dict[int, int]]]) -> list[dict[int, tuple[int, int]]]:
    """The shipped script under Lua 5.3 (ArduPilot's), its bindings stubbed; overrides per step."""
    lua = LuaRuntime()
    harness = lua.execute("""
        local state = {now = 0, armed = false, inputs = {}, sets = {}}
        function millis() return state.now end
        rc = {}
        function rc:get_pwm(n) return state.inputs[n] end
        arming = {}
        function arming:is_armed() return state.armed end
        SRV_Channels = {}
        function SRV_Channels:set_output_pwm_chan_timeout(chan, pwm, timeout_ms)
          table.insert(state.sets, {chan, pwm, timeout_ms})
        end
        gcs = {}
        function gcs:send_named_float(name, value) end
        function gcs:send_text(severity, text) end
        return state
    """)
    # The script returns (update, period_ms) as ArduPilot's scheduler expects; so does update.
    update = lua.execute(script_path().read_text())[0]
    result = []
    for t_ms, armed, rc in steps:
        harness.now, harness.armed = t_ms, armed
        harness.inputs = lua.table_from(rc)
        harness.sets = lua.table()
        update = update()[0]
        result.append({int(row[1]) + 1: (int(row[2]), int(row[3]))
                       for row in harness.sets.values()})
    return result


def test_the_model_does_what_the_lua_script_does() -> None:
    """Same inputs to the Lua script and to WatchdogScript: the same overrides, step by step."""
    steps: list[tuple[int, bool, dict[int, int]]] = []
    t_ms = 0
    for i, rc in enumerate(commands(1650, 8) + [commands(1650, 8)[-1]] * 14
                           + commands(1300, 6) + [{9: 1100, 10: 1100}] * 3):
        steps.append((t_ms, i < 30, rc))
        t_ms += 10
    model = WatchdogScript(ScriptSettings.from_source())
    expected = [{o: (pwm, 100) for o, pwm in model.update(t, armed, rc).items()}
                for t, armed, rc in steps]
    assert _lua_run(steps) == expected
