"""`uvms tune` refuses a bad tune file before Ray starts, naming the key, with status 2."""

from __future__ import annotations

from pathlib import Path

import pytest

from uvms_cli import cli as uvms_cli
from uvms_tune import cli as tune_cli


def test_a_bad_tune_file_exits_2_naming_the_key(tmp_path: Path,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    """trials: 0 is refused in one line naming 'trials'; nothing else runs."""
    path = tmp_path / 'bad.yaml'
    path.write_text('name: b\nrobot: bluerov2_alpha5\ntrials: 0\n'
                    'gains: {hybrid.force_kp: {low: 0.01, high: 0.1}}\n'
                    'train: [{scenario: bluerov2_alpha5_contact}]\n', encoding='utf-8')
    assert tune_cli.main([str(path), '--out', str(tmp_path / 'out')]) == 2
    error = capsys.readouterr().err.strip().splitlines()
    assert error == [f"uvms tune: error: {path}: key 'trials': expected an integer >= 1, "
                     'got int 0']
    assert not (tmp_path / 'out').exists()


def test_uvms_hands_tune_to_uvms_tune() -> None:
    """`uvms tune` is a subcommand of the uvms command."""
    assert uvms_cli.DELEGATED['tune'][0] == 'uvms_tune.cli'
