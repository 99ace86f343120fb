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


@kernel
def spatial_cross_force(nu: FloatArray, f: FloatArray) -> FloatArray:
    """ν ×* f = [ω × f_lin; v × f_lin + ω × f_ang] for ν = [v; ω] (Featherstone 2008, 2.9).

    With f = M_A ν this is the Coriolis-centripetal force C_A(ν) ν of added mass (Fossen 2011,
    eq. 6.43) in Kirchhoff's form. Compiled (numpy's cross costs 60 µs per call here).

    >>> spatial_cross_force(np.array([1.0, 0, 0, 0, 0, 1.0]), np.array([2.0, 0, 0, 0, 0, 0]))
    array([0., 2., 0., 0., 0., 0.])
    """
    out = np.zeros(6)
    for i in range(3):
        j, k = (i + 1) % 3, (i + 2) % 3
        out[i] = nu[3 + j] * f[k] - nu[3 + k] * f[j]
        out[3 + i] = (nu[j] * f[k] - nu[k] * f[j]) + (nu[3 + j] * f[3 + k] - nu[3 + k] * f[3 + j])
    return out
