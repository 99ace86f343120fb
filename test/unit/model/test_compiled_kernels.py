"""The Numba kernels of the hot path compute what their Python source computes.

The same functions run as plain Python with UVMS_NO_JIT=1 (``uvms_model.jit``); a child
process does that, and its results must equal the compiled ones to rounding. The oracle tests
(``test_model_oracle``, the pure-Python reference model) check what both compute.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import numpy as np

#: Runs in both processes: RK4 steps, the controller's model set, controller steps and
#: allocator steps (saturation and thruster dynamics).
PROBE = textwrap.dedent("""
    import json, sys
    import numpy as np
    from uvms_model import UvmsModel
    from uvms_control.core.parameters import ControllerParameters
    from uvms_control.core.law.unified_controller import UnifiedForceController
    from uvms_model.integration import rk4_stage_input
    from uvms_model.thrusters import ThrusterLayout
    from uvms_thrusters.allocation import AllocatorParameters, ThrusterAllocator

    rng = np.random.default_rng(3)
    model = UvmsModel()
    controller = UnifiedForceController(ControllerParameters.from_flat_dict(), model)
    layout = ThrusterLayout.from_parameters()
    allocator = ThrusterAllocator(AllocatorParameters(layout.thrust_matrix(),
                                                      layout.max_thrust_n, np.full(3, 50.0)))
    out = []
    for k in range(20):
        q = np.concatenate((rng.uniform(-1, 1, 3), rng.uniform(-0.4, 0.4, 3),
                            [0.1, 0.9, -1.5] + rng.uniform(-0.2, 0.2, 3)))
        w = rng.normal(0.0, 0.4, 9)
        tau_b = rng.normal(0.0, 30.0, 9)
        force = rng.normal(0.0, 80.0, 3)
        q_new, w_new = model.step(q, w, tau_b, force if k % 2 else None, 1e-3)
        terms = model.task_space_terms(q, w=w)
        result = controller.step_from_sensors(0.002 * k, q, w, rng.uniform(0.0, 160.0) *
                                              np.array([1.0, 0.0, 0.0]))
        # Large enough to saturate some steps, with some long steps (several Euler sub-steps).
        output = allocator.step(rng.normal(0.0, 400.0, 9), 0.002 if k % 3 else 0.011)
        out += [*q_new, *w_new, *terms.M.ravel(), *terms.zeta, *terms.J.ravel(),
                *terms.J_dot_q_dot, *result.tau_b, result.W, *output.thrust,
                *output.joint_torques, *output.propeller_speed, *output.motor_current,
                output.allocation.saturation_scale, output.allocation.joint_scale]
    from uvms_thrusters.thruster_kernels import euler_step_bank
    compiled = hasattr(rk4_stage_input, 'py_func') and hasattr(euler_step_bank, 'py_func')
    json.dump({'values': out, 'compiled': compiled},
              sys.stdout)
""")


def probe(no_jit: bool) -> tuple[np.ndarray, bool]:
    """The probe's values and whether its kernels were compiled, from a child process."""
    # The child imports the modules this test does (pytest's pythonpath: the checkout's
    # sources), not whatever an editable install of another checkout puts on its path.
    env = {**os.environ, 'UVMS_NO_JIT': '1' if no_jit else '0',
           'PYTHONPATH': os.pathsep.join(sys.path)}
    process = subprocess.run([sys.executable, '-c', PROBE], capture_output=True, text=True,
                             env=env, timeout=120)
    assert process.returncode == 0, process.stderr
    result = json.loads(process.stdout)
    return np.array(result['values']), bool(result['compiled'])


def test_compiled_kernels_agree_with_their_python_source() -> None:
    """Dynamics, task-space terms, controller and allocator outputs: compiled = interpreted."""
    compiled, was_compiled = probe(no_jit=False)
    interpreted, was_interpreted = probe(no_jit=True)
    assert was_compiled and not was_interpreted
    np.testing.assert_allclose(compiled, interpreted, rtol=1e-10, atol=1e-9)
