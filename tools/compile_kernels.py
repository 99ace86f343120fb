#!/usr/bin/env python3
"""Compile the hot path's Numba kernels into their on-disk cache (run by `make setup`).

Every kernel compiles on its first call in a process and is cached beside its module, so a
node starts on machine code; this runs each once so that no node or test pays the first
compilation (about 4 s on 2 cores) at start-up, or several at once in parallel processes.
"""

from __future__ import annotations

import sys
import time


def main() -> int:
    """Call every kernel once through the public model, controller and allocator API."""
    start = time.monotonic()
    import numpy as np
    from uvms_control.core.allocation import AllocatorParameters, ThrusterAllocator
    from uvms_control.core.parameters import ControllerParameters
    from uvms_control.core.unified_controller import UnifiedForceController
    from uvms_model.thrusters import ThrusterLayout

    from uvms_model import UvmsModel

    model = UvmsModel()
    q = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.6, -1.2])
    model.step(q, np.zeros(9), np.zeros(9), [1.0, 0.0, 0.0], 1e-3)
    model.step(q, np.zeros(9), np.zeros(9), None, 1e-3)
    model.step(q, np.zeros(9), np.zeros(9), None, 1e-3, method='semi_implicit_euler')
    model.task_space_terms(q, np.zeros(9))
    controller = UnifiedForceController(ControllerParameters.from_flat_dict(), model)
    controller.step_from_sensors(0.0, q, np.zeros(9), np.zeros(3))
    controller.step(0.002, q, np.zeros(9), np.array([100.0, 0.0, 0.0]))
    layout = ThrusterLayout.from_parameters()
    allocator = ThrusterAllocator(AllocatorParameters(
        layout.thrust_matrix(), layout.max_thrust_n, np.full(3, 100.0)))
    allocator.step(np.ones(9), 0.002)
    took_s = time.monotonic() - start
    print(f'compile_kernels: the hot path is compiled and cached ({took_s:.1f} s)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
