"""Compile the allocator's Numba kernels: ``python -m uvms_thrusters.kernel_cache``.

As ``uvms_model.kernel_cache`` for the model: run by ``setup.py install`` on the installed
copy of the package (its cache lives beside the installed modules), so that an installed
allocator starts on machine code at its first start.
"""

from __future__ import annotations

import sys
import time

import numpy as np
from uvms_model.kernel_cache import robot_models
from uvms_model.thrusters import ThrusterLayout

from uvms_thrusters.allocation import AllocatorParameters, ThrusterAllocator
from uvms_thrusters.fault_parameters import FAULT_PARAMETER_SPECS, equip, fault_settings


def compile_thruster_kernels() -> None:
    """Call every allocator kernel once with the types the node uses."""
    for model in robot_models():
        layout = ThrusterLayout.from_parameters()
        allocator = ThrusterAllocator(AllocatorParameters(
            layout.thrust_matrix(), layout.max_thrust_n, np.full(model.n_joints, 100.0)))
        allocator.step(np.ones(model.n_dof), 0.002)
        equip(allocator, fault_settings({s.name: s.default for s in FAULT_PARAMETER_SPECS},
                                        layout.count))  # compiles the fault detector's kernel


def main() -> int:
    """Compile and cache the kernels; one line on stdout with the time taken."""
    start = time.monotonic()
    compile_thruster_kernels()
    print(f'uvms_thrusters: kernels compiled and cached ({time.monotonic() - start:.1f} s)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
