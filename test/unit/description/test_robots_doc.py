"""docs/robots.md counts the files of a robot folder as the loader requires them."""

from __future__ import annotations

import re
from pathlib import Path

from uvms_description.robots import HYDRODYNAMICS_FILE, PARAMETER_FILES

DOC = Path(__file__).resolve().parents[3] / 'docs' / 'robots.md'
NUMBERS = {5: 'five', 6: 'six', 7: 'seven', 8: 'eight'}


def test_robots_doc_says_how_many_files_are_required() -> None:
    """One URDF, the hydrodynamics and the parameter files: the count the text gives."""
    required = 1 + len((HYDRODYNAMICS_FILE, *PARAMETER_FILES))
    text = DOC.read_text(encoding='utf-8')
    said = re.search(r'All (\w+) files are required', text)
    assert said is not None
    assert said.group(1) == NUMBERS[required]
    for name in (HYDRODYNAMICS_FILE, *PARAMETER_FILES):
        assert f'  {name} ' in text, name
