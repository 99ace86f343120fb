"""Numba's ``njit`` for the hot path, typed for mypy and cached on disk.

The kernels compile on first use and are cached beside their module in ``__pycache__`` (where
that is read-only, in Numba's user-wide cache directory; NUMBA_CACHE_DIR overrides both), so a
node starts on the cached machine code after the first run on a machine. ``UVMS_NO_JIT=1``
runs the same functions as plain Python, for a debugger or a line profiler; results agree to
rounding.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import TypeVar, cast

import numba

F = TypeVar('F', bound=Callable[..., object])


def kernel(function: F) -> F:
    """Compile ``function`` in nopython mode (no Python objects inside), cached, no fastmath.

    IEEE arithmetic as written (no ``fastmath``), so a kernel gives what the Python
    expression it replaces gives, to the last bits of reassociated sums only.
    """
    if os.environ.get('UVMS_NO_JIT') == '1':
        return function
    return cast(F, numba.njit(cache=True, nogil=True, error_model='numpy')(function))
