"""Docstrings follow the Google convention, configured as ruff's pydocstyle rules are."""

from ament_pep257.main import main
import pytest

# pydocstyle's google convention, plus D105/D107 as in pyproject.toml's ruff settings.
GOOGLE_CONVENTION_IGNORES = [
    'D105', 'D107', 'D203', 'D204', 'D213', 'D215', 'D400', 'D401', 'D404', 'D406', 'D407',
    'D408', 'D409', 'D413',
]


@pytest.mark.linter
@pytest.mark.pep257
def test_pep257() -> None:
    """Every module, class and function has a Google-style docstring."""
    rc = main(argv=['.', 'test', '--ignore', *GOOGLE_CONVENTION_IGNORES])
    assert rc == 0, 'Found code style errors / warnings'
