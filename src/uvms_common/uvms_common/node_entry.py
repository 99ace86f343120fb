"""Console-script entry of a node process: stop handlers first, then the node's imports.

``ros2 run`` and ``uvms launch`` start a node by its console script; the launcher may stop
it (SIGINT, then SIGTERM) at any moment, also while the node module is still importing
rclpy, numpy and Pinocchio. The entry installs the ``StopEvent`` before that import, and the
node's ``run_node`` takes it over, so such a stop ends the process with status 0 and no
traceback.
"""

from __future__ import annotations

import importlib
import sys

from uvms_common.stop_event import StopEvent


def run_node_module(module_name: str) -> None:
    """Import a node module with the stop handlers in place and run its ``main()``.

    Exits 0 without building the node when a stop signal arrived during the import.
    """
    stop = StopEvent()
    try:
        module = importlib.import_module(module_name)
        if stop.is_set():
            sys.exit(0)
        module.main()
    finally:
        stop.restore()
