"""The autopilot watchdog script: its settings, the wire's toggle, and its model against itself."""

from __future__ import annotations

import shutil
import subprocess

import pytest
from uvms_hardware.ardusub_watchdog import (
    ScriptSettings,
    WatchdogScript,
    script_path,
    toggle_encode,
)

#: A Lua interpreter on this machine, if any (ArduPilot runs Lua 5.3; the script is 5.3/5.4).
LUA = shutil.which('lua5.3') or shutil.which('lua5.4') or shutil.which('lua')


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
    """The shipped script under Lua with ArduPilot's bindings stubbed; overrides per step."""
    def row(t: int, armed: bool, rc: dict[int, int]) -> str:
        values = ', '.join(f'[{k}]={v}' for k, v in rc.items())
        return f'{{t={t}, armed={"true" if armed else "false"}, rc={{{values}}}}}'

    rows = ', '.join(row(*step) for step in steps)
    harness = f"""
local now, armed, inputs = 0, false, {{}}
function millis() return now end
rc = {{}}
function rc:get_pwm(n) return inputs[n] end
arming = {{}}
function arming:is_armed() return armed end
SRV_Channels = {{}}
function SRV_Channels:set_output_pwm_chan_timeout(chan, pwm, timeout_ms)
  io.write(string.format('%d %d %d;', chan, pwm, timeout_ms))
end
gcs = {{}}
function gcs:send_named_float(name, value) end
function gcs:send_text(severity, text) end
local update = dofile('{script_path()}')
for _, step in ipairs({{{rows}}}) do
  now, armed, inputs = step.t, step.armed, step.rc
  update = update()
  io.write('\\n')
end
"""
    assert LUA is not None
    out = subprocess.run([LUA, '-'], input=harness, capture_output=True, text=True,
                         check=True).stdout
    result = []
    for line in out.splitlines():
        sets = [item.split() for item in line.split(';') if item.strip()]
        result.append({int(c) + 1: (int(p), int(t)) for c, p, t in sets})
    return result


@pytest.mark.skipif(LUA is None, reason='no Lua interpreter on this machine (apt: lua5.4)')
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
