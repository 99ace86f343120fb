#!/usr/bin/env python3
"""Compile the hot path's Numba kernels into their on-disk cache (run by `make setup`).

Every kernel compiles on its first call in a process and is cached beside its module, so a
node starts on machine code; this runs each once so that no node or test pays the first
compilation (about 4 s on 2 cores) at start-up, or several at once in parallel processes.
The calls live in ``uvms_model.kernel_cache``, ``uvms_control.kernel_cache`` and
``uvms_thrusters.kernel_cache``, which
``colcon build`` also runs on the installed packages (their setup.py).
"""

from __future__ import annotations

import sys
import time


def main() -> int:
    """Call every kernel once through the public model, controller and allocator API."""
    start = time.monotonic()
    from uvms_control.kernel_cache import compile_control_kernels
    from uvms_thrusters.kernel_cache import compile_thruster_kernels

    compile_control_kernels()
    compile_thruster_kernels()
    took_s = time.monotonic() - start
    print(f'compile_kernels: the hot path is compiled and cached ({took_s:.1f} s)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
