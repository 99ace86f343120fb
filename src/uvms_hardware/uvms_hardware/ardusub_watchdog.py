"""The autopilot-side thruster watchdog: where its Lua script is, its settings, and a model of it.

``autopilot/uvms_thruster_watchdog.lua`` runs on ArduSub and returns the thrusters to neutral
on its own when the bridge stops commanding them (its header says how, with its ArduPilot
sources). This module is its Python side, without ROS:

- `script_path` finds the shipped script (source checkout, else the package's share folder);
- `ScriptSettings.from_source` reads its ``local NAME = value`` settings, so that the bridge
  and the twin use the script's own numbers, never a copy of them;
- `toggle_encode` is what the bridge puts on the wire (the lowest bit of every value of one
  message is the toggle the script watches);
- `WatchdogScript` is the script's ``update()`` written again, step for step, for the twin.
"""

from __future__ import annotations

import importlib.util
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path

#: The script's file name, as it must be copied to the autopilot's ``scripts`` folder.
SCRIPT_NAME = 'uvms_thruster_watchdog.lua'
#: NAMED_VALUE_FLOAT name of the script's 1 Hz announcement (value: TIMEOUT_MS).
ANNOUNCE_NAME = 'UVMS_WD'


def script_path() -> Path:
    """The shipped Lua script: the source checkout's, else ``share/uvms_hardware/autopilot``.

    ``share`` of a colcon install (the ament index), else of the Python prefix (a wheel).

    Raises:
        FileNotFoundError: neither holds it.
    """
    here = Path(__file__).resolve().parent
    candidates = [here.parent / 'autopilot' / SCRIPT_NAME,
                  Path(sys.prefix) / 'share' / 'uvms_hardware' / 'autopilot' / SCRIPT_NAME]
    if importlib.util.find_spec('ament_index_python') is not None:
        from ament_index_python.packages import (  # type: ignore[import-not-found]
            PackageNotFoundError,
            get_package_share_directory,
        )

        try:
            share = Path(get_package_share_directory('uvms_hardware'))
            candidates.append(share / 'autopilot' / SCRIPT_NAME)
        except (PackageNotFoundError, OSError, ValueError):
            pass
    for candidate in candidates:
        if candidate.is_file():
            return candidate
    raise FileNotFoundError(f'{SCRIPT_NAME} not found in {", ".join(map(str, candidates))}')


@dataclass(frozen=True)
class ScriptSettings:
    """The script's settings (its ``local NAME = value`` lines)."""

    timeout_ms: int = 100
    period_ms: int = 10
    first_rc: int = 9
    outputs: tuple[int, ...] = (1, 2, 3, 4, 5, 6, 7, 8)
    neutral_us: int = 1500
    min_us: int = 1100
    max_us: int = 1900
    announce_ms: int = 1000

    @classmethod
    def from_source(cls, path: Path | None = None) -> ScriptSettings:
        """Read the settings from the script (the shipped one by default).

        Raises:
            ValueError: a setting missing from the script (named).
        """
        text = (path or script_path()).read_text()

        def number(name: str) -> int:
            match = re.search(rf'^local {name} = (\d+)\s*$', text, re.MULTILINE)
            if match is None:
                raise ValueError(f'{SCRIPT_NAME}: no "local {name} = <integer>" line')
            return int(match.group(1))

        outputs = re.search(r'^local OUTPUTS = \{([\d,\s]+)\}', text, re.MULTILINE)
        if outputs is None:
            raise ValueError(f'{SCRIPT_NAME}: no "local OUTPUTS = {{...}}" line')
        return cls(number('TIMEOUT_MS'), number('PERIOD_MS'), number('FIRST_RC'),
                   tuple(int(n) for n in outputs.group(1).split(',')), number('NEUTRAL_US'),
                   number('MIN_US'), number('MAX_US'), number('ANNOUNCE_MS'))

    def rc_channel(self, output: int) -> int:
        """The RC input channel (1-based) the script reads for thruster ``output``."""
        return self.first_rc + output - 1


def toggle_encode(pwm_us: int, toggle: int) -> int:
    """``pwm_us`` with its lowest bit replaced by ``toggle`` (0 or 1): 2 µs of resolution."""
    return pwm_us - pwm_us % 2 + (toggle & 1)


@dataclass
class WatchdogScript:
    """The Lua script's ``update()``, step for step (the twin runs it every ``period_ms``).

    ``update`` takes what the script reads (milliseconds since boot, armed, ``rc:get_pwm`` of
    each channel) and returns the overrides it sets: output (1-based) -> PWM, each for
    ``timeout_ms``; empty when it sets none.
    """

    settings: ScriptSettings = field(default_factory=ScriptSettings)
    last_parity: int = -1
    flipped: bool = False
    last_flip_ms: float = 0.0
    driving: bool = False
    last_announce_ms: float = 0.0

    def read_inputs(self, rc_pwm: dict[int, int]) -> tuple[list[int] | None, int | None]:
        """The script's ``read_inputs``: values with the toggle cleared and the toggle."""
        s, values, parity = self.settings, [], None
        for output in s.outputs:
            pwm = rc_pwm.get(s.rc_channel(output))
            if pwm is None or pwm < 1000 or pwm > 2000:
                return None, None
            bit = pwm % 2
            if parity is None:
                parity = bit
            elif parity != bit:
                return None, None
            values.append(pwm - bit)
        return values, parity

    def update(self, now_ms: float, armed: bool, rc_pwm: dict[int, int]) -> dict[int, int]:
        """One run of the script; the overrides it sets (output -> PWM)."""
        s = self.settings
        values, parity = self.read_inputs(rc_pwm)
        if parity is not None and parity != self.last_parity:
            if self.last_parity != -1:
                self.flipped, self.last_flip_ms = True, now_ms
            self.last_parity = parity
        fresh = self.flipped and now_ms - self.last_flip_ms <= s.timeout_ms
        if not armed:
            self.driving = False
            return {}
        if fresh and values is not None:
            self.driving = True
            return {output: max(s.min_us, min(s.max_us, value))
                    for output, value in zip(s.outputs, values, strict=True)}
        if self.driving:
            return {output: s.neutral_us for output in s.outputs}
        return {}

    def announce_due(self, now_ms: float) -> bool:
        """True once every ``announce_ms``: the script sends NAMED_VALUE_FLOAT 'UVMS_WD'."""
        if now_ms - self.last_announce_ms >= self.settings.announce_ms:
            self.last_announce_ms = now_ms
            return True
        return False
