"""config/sweeps/quick.yaml: a first sweep of 2-4 points, shown first where sweeps are taught."""

from __future__ import annotations

import re
from pathlib import Path

from uvms_scenarios.scenario import contact_estimate, load_scenario
from uvms_sweep.maps import log_scale
from uvms_sweep.sweep_file import load_sweep

ROOT = Path(__file__).resolve().parents[3]
QUICK = ROOT / 'config' / 'sweeps' / 'quick.yaml'


def test_quick_sweep_has_two_to_four_points_that_settle() -> None:
    """2-4 points, each long enough for F_d to be reached (no 'ended before settling' run)."""
    sweep = load_sweep(QUICK)
    scenario = load_scenario(sweep.scenario_path)
    duration_s = sweep.duration_s if sweep.duration_s is not None else scenario.duration_s
    points = sweep.points(scenario.name, duration_s, scenario.seed)
    assert 2 <= len(points) <= 4
    estimate = contact_estimate(scenario)
    assert estimate is not None
    assert duration_s >= estimate.force_reached_s + 2.0
    assert [axis.name for axis in sweep.axes] == ['simulator.contact.stiffness_n_m']
    assert log_scale(sweep.axes[0])


def _sweep_section(text: str, heading: str) -> str:
    start = text.index(heading)
    end = text.find('\n#', start + len(heading))
    return text[start:end if end >= 0 else None]


def test_readme_and_sweeps_doc_show_the_quick_sweep_first() -> None:
    """The first `uvms sweep` command of README's sweep section and of docs/sweeps.md."""
    for path, heading in ((ROOT / 'README.md', '### Parameter sweeps'),
                          (ROOT / 'docs' / 'sweeps.md', '# Parameter sweeps')):
        section = _sweep_section(path.read_text(encoding='utf-8'), heading)
        first = re.search(r'^uvms sweep (\S+)', section, re.MULTILINE)
        assert first is not None, path
        assert first.group(1) == 'config/sweeps/quick.yaml', path
