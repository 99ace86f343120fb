"""Another git revision of this repository, extracted beside the working tree, to run against it.

The A/B benchmarks (``bench_ab_cpu``, ``bench_realtime_ab``, ``bench_navigation_cpu``) time
the same job on two trees in alternation; this module gives them the other tree.
"""

from __future__ import annotations

import io
import subprocess
import tarfile
from collections.abc import Sequence
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def extract_revision(rev: str, dest: Path, folders: Sequence[str] = ('src', 'config')) -> Path:
    """Write ``folders`` of git revision ``rev`` into ``dest`` (created); return ``dest``."""
    archive = subprocess.run(['git', 'archive', rev, *folders], cwd=REPO,
                             capture_output=True, check=True).stdout
    with tarfile.open(fileobj=io.BytesIO(archive)) as tar:
        tar.extractall(dest, filter='data')
    return dest


def python_path(root: Path) -> str:
    """PYTHONPATH importing a tree's packages (uvms_msgs is the built one of the venv)."""
    return ':'.join(str(p) for p in sorted((root / 'src').glob('uvms_*'))
                    if p.name != 'uvms_msgs')
