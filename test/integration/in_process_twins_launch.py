"""``uvms launch`` with the twins in the simulator's process, until uvms_bringup chooses it.

Run as ``python test/integration/in_process_twins_launch.py launch ... --hardware twin``: the
``uvms`` CLI with three of the launcher's names replaced, as the change proposed for
uvms_bringup would have it (the simulator's process is ``uvms_twins.simulator_with_twins``,
no ``hardware_twins`` process, the twins' connections as the simulator's ``twins.``
parameters). Nothing else of the launch changes.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any


def patch_launcher() -> None:
    """Replace the launcher's hardware nodes, parameters and simulator executable."""
    from uvms_bringup.hardware_plan import HardwarePlan
    from uvms_bringup.launch_helpers import HARDWARE_TWINS, SIMULATOR, NodeSpec

    from uvms_bringup import launcher

    nodes_of, parameters_of = launcher.hardware_nodes, launcher.hardware_parameters
    executable_of = launcher.node_executable

    def hardware_nodes(nodes: Sequence[NodeSpec], plan: HardwarePlan) -> list[NodeSpec]:
        return [spec for spec in nodes_of(nodes, plan) if spec is not HARDWARE_TWINS]

    def hardware_parameters(nodes: Sequence[NodeSpec], plan: HardwarePlan
                            ) -> dict[str, dict[str, Any]]:
        values = parameters_of(nodes, plan)
        if plan.twins:
            values[SIMULATOR.name].update(
                {f'twins.{name}': value for name, value in plan.twin_parameters().items()})
        return values

    def node_executable(spec: NodeSpec, bin_dir: Path | None = None) -> list[str]:
        if spec is SIMULATOR:
            return [sys.executable, '-c', 'from uvms_common.node_entry import run_node_module; '
                    "run_node_module('uvms_twins.simulator_with_twins')"]
        return executable_of(spec, bin_dir)

    launcher.hardware_nodes = hardware_nodes  # type: ignore[assignment]
    launcher.hardware_parameters = hardware_parameters  # type: ignore[assignment]
    launcher.node_executable = node_executable  # type: ignore[assignment]


if __name__ == '__main__':
    patch_launcher()
    from uvms_cli.cli import main

    sys.argv[0] = 'uvms'
    main()
