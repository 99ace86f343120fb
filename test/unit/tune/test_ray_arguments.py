"""``uvms sweep`` and ``uvms tune`` take the same Ray options, defined once in uvms_sweep.cli."""

from __future__ import annotations

import argparse
from collections.abc import Callable

import pytest
from uvms_sweep.cli import build_parser as sweep_parser
from uvms_tune.cli import build_parser as tune_parser

PARSERS: dict[str, tuple[Callable[[], argparse.ArgumentParser], list[str]]] = {
    'sweep': (sweep_parser, ['sweep.yaml', '--out', 'out']),
    'tune': (tune_parser, ['tune.yaml']),
}


@pytest.mark.parametrize('command', sorted(PARSERS))
def test_ray_options_parse_alike(command: str) -> None:
    """--address, -j and -q mean the same in both commands."""
    build, positional = PARSERS[command]
    args = build().parse_args([*positional, '--address', 'auto', '-j', '3', '-q'])
    assert (args.address, args.workers, args.quiet) == ('auto', 3, True)
    args = build().parse_args(positional)
    assert (args.address, args.workers, args.quiet) == (None, None, False)


@pytest.mark.parametrize('command', sorted(PARSERS))
def test_zero_workers_is_refused_with_the_same_line(
        command: str, capsys: pytest.CaptureFixture[str]) -> None:
    """-j 0: usage error naming the bound, in both commands."""
    build, positional = PARSERS[command]
    with pytest.raises(SystemExit):
        build().parse_args([*positional, '-j', '0'])
    assert 'argument --workers/-j: expected an integer >= 1, got 0' in capsys.readouterr().err

