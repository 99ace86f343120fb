"""Matrix products written as loops, for the compiled kernels (no BLAS call at sizes 3-13)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from uvms_model.jit import kernel

FloatArray = NDArray[np.float64]


@kernel
def matmul(a: FloatArray, b: FloatArray) -> FloatArray:
    """The product a b as a new array, by loops (any memory layout)."""
    result = np.zeros((a.shape[0], b.shape[1]))
    for i in range(a.shape[0]):
        for k in range(a.shape[1]):
            a_ik = a[i, k]
            if a_ik != 0.0:
                for j in range(b.shape[1]):
                    result[i, j] += a_ik * b[k, j]
    return result


@kernel
def matvec(a: FloatArray, x: FloatArray) -> FloatArray:
    """The product a x as a new array, by loops."""
    result = np.zeros(a.shape[0])
    for i in range(a.shape[0]):
        total = 0.0
        for k in range(a.shape[1]):
            total += a[i, k] * x[k]
        result[i] = total
    return result
