"""A pilot script given beside a scenario (``uvms run SCENARIO --pilot FILE``)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from uvms_control.core.errors import ControlParameterError
from uvms_control.core.pilot.script import script_text

from uvms_scenarios.scenario import PILOT_PARAMETER, Scenario, ScenarioError


def with_pilot(scenario: Scenario, path: str | Path) -> Scenario:
    """The scenario with the pilot script of a file (over its own ``pilot:``, if any).

    Raises:
        ScenarioError: the file cannot be read or holds a wrong entry (named).
    """
    try:
        text = script_text(str(Path(path).resolve()), Path.cwd())
    except ControlParameterError as exc:
        raise ScenarioError(f'--pilot: {exc}') from exc
    controller = {**scenario.overrides.get('controller', {}), PILOT_PARAMETER: text}
    return replace(scenario, overrides={**scenario.overrides, 'controller': controller})
