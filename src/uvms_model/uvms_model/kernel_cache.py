"""Compile the model's Numba kernels into their cache: ``python -m uvms_model.kernel_cache``.

Every kernel compiles on its first call and is cached beside its module (``jit.kernel``),
keyed by that module's path. An installed package (``colcon build``: a copy under
``install/uvms_model/lib/python3.X/site-packages``) therefore has a cache of its own, empty
until a first run fills it: ``setup.py install`` runs this module on the installed copy, so
that a node starts on machine code instead of compiling for seconds at its first start.
"""

from __future__ import annotations

import sys
import time

import numpy as np

from uvms_model.model import UvmsModel

#: A configuration of the arm away from its singularities (rad), vehicle at the origin.
_Q_WARM = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.6, -1.2])


def compile_model_kernels(model: UvmsModel | None = None) -> UvmsModel:
    """Call every model kernel once with the argument types the nodes use; return the model."""
    model = model if model is not None else UvmsModel()
    zeros = np.zeros(9)
    model.step(_Q_WARM, zeros, zeros, [1.0, 0.0, 0.0], 1e-3)
    model.step(_Q_WARM, zeros, zeros, None, 1e-3)
    model.step(_Q_WARM, zeros, zeros, None, 1e-3, method='semi_implicit_euler')
    model.task_space_terms(_Q_WARM, zeros)
    return model


def main() -> int:
    """Compile and cache the model's kernels; one line on stdout with the time taken."""
    start = time.monotonic()
    compile_model_kernels()
    print(f'uvms_model: kernels compiled and cached ({time.monotonic() - start:.1f} s)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
