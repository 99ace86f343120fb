"""Compile the controller's Numba kernels: ``python -m uvms_control.kernel_cache``.

As ``uvms_model.kernel_cache`` for the model: run by ``setup.py install`` on the installed
copy of the package (its cache lives beside the installed modules), so that an installed
controller starts on machine code at its first start. The allocator's are compiled by
``uvms_thrusters.kernel_cache``.
"""

from __future__ import annotations

import sys
import time

import numpy as np
from uvms_model.kernel_cache import compile_model_kernels, robot_models, warm_state

from uvms_control.core.law.unified_controller import UnifiedForceController
from uvms_control.core.parameters import ControllerParameters


def compile_control_kernels() -> None:
    """Call every controller kernel once with the types the node uses."""
    for model in robot_models():
        compile_model_kernels(model)
        q, zeros = warm_state(model), np.zeros(model.n_dof)
        gains = ControllerParameters.from_flat_dict({
            'null_space.stiffness_1_s2': [4.0] * model.n_dof,
            'null_space.damping_1_s': [4.0] * model.n_dof})
        controller = UnifiedForceController(gains, model)
        controller.step_from_sensors(0.0, q, zeros, np.zeros(3))
        controller.step(0.002, q, zeros, np.array([100.0, 0.0, 0.0]))
        # The fuzzy switch runs only under a force set-point: compiled here, not in a
        # launched controller's first task step (0.26 s without a step: INPUTS_STALE, CI).
        controller.fuzzy.weight(0.5, 0.0)


def main() -> int:
    """Compile and cache the kernels; one line on stdout with the time taken."""
    start = time.monotonic()
    compile_control_kernels()
    print(f'uvms_control: kernels compiled and cached ({time.monotonic() - start:.1f} s)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
