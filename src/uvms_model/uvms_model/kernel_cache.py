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
from uvms_model.parameters import UvmsParameters

#: Arm angles away from the paper arm's singularities (rad), repeated for longer arms.
_ARM_WARM = (0.0, 0.6, -1.2)


def warm_state(model: UvmsModel) -> np.ndarray:
    """Q with the vehicle at the origin and the arm bent (``_ARM_WARM``), for warming up."""
    q = np.zeros(model.n_dof)
    q[6:] = np.resize(_ARM_WARM, model.n_joints)
    return q


def compile_model_kernels(model: UvmsModel | None = None) -> UvmsModel:
    """Call every model kernel once with the argument types the nodes use; return the model."""
    model = model if model is not None else UvmsModel()
    q, zeros = warm_state(model), np.zeros(model.n_dof)
    model.step(q, zeros, zeros, [1.0, 0.0, 0.0], 1e-3)
    model.step(q, zeros, zeros, None, 1e-3)
    model.step(q, zeros, zeros, None, 1e-3, method='semi_implicit_euler')
    model.step(q, zeros, zeros, None, 1e-3, current_ned=[0.1, 0.05, 0.0])
    model.bias_body(q, zeros, [0.1, 0.05, 0.0])
    model.task_space_terms(q, zeros)
    return model


def robot_models() -> list[UvmsModel]:
    """The model of every robot folder of uvms_description (a coefficient hull compiles more)."""
    from uvms_description.robots import robot_names, with_description_paths

    return [UvmsModel(UvmsParameters().updated(with_description_paths({}, name)))
            for name in robot_names()]


def main() -> int:
    """Compile and cache the model's kernels; one line on stdout with the time taken."""
    start = time.monotonic()
    for model in robot_models():
        compile_model_kernels(model)
    print(f'uvms_model: kernels compiled and cached ({time.monotonic() - start:.1f} s)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
