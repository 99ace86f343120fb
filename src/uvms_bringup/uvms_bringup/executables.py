"""How a node's process starts: its console script beside the interpreter, else its module.

``uvms launch`` starts each node as ``ros2 run`` would, by its console script; where the
script is missing or stale (an install older or newer than the sources), by the node's
module with the stop handlers first (``uvms_common.node_entry``).
"""

from __future__ import annotations

import importlib.util
import os
import re
import sys
from pathlib import Path

from uvms_bringup.launch_helpers import NodeSpec


def node_executable(spec: NodeSpec, bin_dir: Path | None = None) -> list[str]:
    """The command that starts a node: its console script beside the interpreter, else -m.

    Args:
        spec: The node.
        bin_dir: Directory of the console scripts (that of ``sys.executable`` if None).
    """
    script = (bin_dir if bin_dir is not None else Path(sys.executable).parent) / spec.executable
    if script.is_file() and os.access(script, os.X_OK) and _script_imports(script):
        return [str(script)]
    if spec.class_name:
        # As the console scripts do: the stop handlers before the node module's imports
        # (uvms_common.node_entry), so a stop during start-up ends it without a traceback.
        return [sys.executable, '-c', 'from uvms_common.node_entry import run_node_module; '
                f'run_node_module({spec.module!r})']
    return [sys.executable, '-m', spec.module]


def _script_imports(script: Path) -> bool:
    """Whether the module a console script imports exists in this tree.

    An install older or newer than the sources (a node moved to another package, its
    script regenerated) leaves a script that fails with ModuleNotFoundError; ``-m`` of the
    node module then starts it as the tree has it.
    """
    try:
        head = script.read_text(encoding='utf-8', errors='replace')[:2000]
    except OSError:
        return True
    match = re.search(r'^from ([\w.]+) import', head, re.MULTILINE)
    if match is None:
        return True
    try:
        return importlib.util.find_spec(match.group(1)) is not None
    except (ImportError, ValueError):
        return False
