"""Tune files: the shipped ones load, and a bad key is refused naming it."""

from __future__ import annotations

from pathlib import Path

import pytest
from uvms_tune.errors import TuneError
from uvms_tune.tune_file import load_tune_file, parse_tune_file

TUNES = Path(__file__).resolve().parents[3] / 'config' / 'tunes'
GOOD = {
    'name': 't', 'robot': 'bluerov2_alpha5', 'trials': 3,
    'gains': {'hybrid.force_kp': {'low': 0.01, 'high': 0.1, 'log': True}},
    'train': [{'scenario': 'bluerov2_alpha5_contact', 'duration_s': 12.0, 'seeds': [1, 2]}],
}


@pytest.mark.parametrize('path', sorted(TUNES.glob('*.yaml')), ids=lambda p: p.stem)
def test_shipped_tune_files_load(path: Path) -> None:
    """Every file of config/tunes follows the schema."""
    tune = load_tune_file(path)
    assert tune.gains and tune.train


def test_seeds_expand_into_one_run_each() -> None:
    """A scenario with two seeds is two training runs."""
    tune = parse_tune_file(GOOD, Path('t.yaml'))
    assert [run.seed for run in tune.train] == [1, 2]


@pytest.mark.parametrize(('change', 'key'), [
    ({'trials': 0}, "'trials'"),
    ({'gains': {'hybrid.force_kq': {'low': 0.1, 'high': 1.0}}}, "'gains.hybrid.force_kq'"),
    ({'gains': {'hybrid.force_kp': {'low': 0.1, 'high': 0.01}}}, "'gains.hybrid.force_kp.high'"),
    ({'gains': {'hybrid.force_kp': {'low': 0.0, 'high': 0.1, 'log': True}}},
     "'gains.hybrid.force_kp.low'"),
    ({'train': [{'scenario': 'no_such_scenario'}]}, "'train[0].scenario'"),
    ({'objective': {'worst': 2.0}}, "'objective.worst'"),
    ({'start': {'hybrid.force_ki': 0.1}}, "'start.hybrid.force_ki'"),
    ({'budget': 3}, "'budget'"),
])
def test_a_bad_key_is_refused_naming_it(change: dict[str, object], key: str) -> None:
    """The error names the offending key."""
    with pytest.raises(TuneError, match=key.replace('[', r'\[').replace(']', r'\]')):
        parse_tune_file({**GOOD, **change}, Path('t.yaml'))


def test_unreadable_yaml_names_the_file(tmp_path: Path) -> None:
    """A YAML syntax error is a TuneError naming the file."""
    path = tmp_path / 'bad.yaml'
    path.write_text('name: [', encoding='utf-8')
    with pytest.raises(TuneError, match=r'bad\.yaml'):
        load_tune_file(path)
