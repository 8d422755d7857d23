"""Exact time stepping of a reduced model over a communication step h.

Over a step the inputs are ramped from their values r with their given velocities v,
r(t_k + s) = r + v·s (v = 0 is a held input). For q̇ = λq + b·r(t) this integrates exactly:

    q(h) = e^{λh} q + h·φ1(λh)·b r + h²·φ2(λh)·b v,
    φ1(z) = (e^z - 1)/z,  φ2(z) = (e^z - 1 - z)/z²,

the diagonal case of the matrix exponential of [[A, B, 0], [0, 0, I], [0, 0, 0]]·h, which
:class:`DenseStepper` evaluates with scipy's ``expm`` on the real block form as a cross-check
and for models that are not diagonal. The coefficients are cached per h, so a host that
varies its step pays for each distinct h once; a step then costs one element-wise product and
one (states × 2·inputs) matrix-vector product.

(The tire with its contact is stepped by the kernels of :mod:`.kernel_numpy` and
``native/c/kernel.c``, which use :func:`phi_functions` the same way.)
"""

from __future__ import annotations

import numpy as np

#: Below this |z| the φ-functions use their Taylor series (cancellation in e^z - 1 - z).
SERIES_LIMIT = 1e-3
_CACHE_SIZE = 64


def phi_functions(z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """φ1(z) = (e^z - 1)/z and φ2(z) = (e^z - 1 - z)/z², accurate for small |z| too."""
    z = np.asarray(z, dtype=complex)
    small = np.abs(z) < SERIES_LIMIT
    zs = np.where(small, 1.0, z)  # avoid 0/0 where the series takes over
    em1 = np.expm1(zs)
    phi1 = np.where(small, 1 + z / 2 + z**2 / 6 + z**3 / 24, em1 / zs)
    phi2 = np.where(small, 0.5 + z / 6 + z**2 / 24 + z**3 / 120, (em1 - zs) / zs**2)
    return phi1, phi2


class DiagonalStepper:
    """Steps q̇ = Λq + B r, y = Re(C q) + D r + E ṙ with inputs ramped over each step."""

    def __init__(self, eigenvalues, b, c, d, e):
        self.eigenvalues = np.asarray(eigenvalues, dtype=complex)
        self.b = np.asarray(b, dtype=complex)
        self.c = np.asarray(c, dtype=complex)
        self.de = np.hstack([np.asarray(d, float), np.asarray(e, float)])  # on [r, v]
        self.n_inputs = self.b.shape[1]
        self._cache: dict[float, tuple[np.ndarray, np.ndarray]] = {}

    @classmethod
    def from_reduced(cls, reduced) -> DiagonalStepper:
        return cls(reduced.eigenvalues, reduced.b, reduced.c, reduced.d, reduced.e)

    def coefficients(self, h: float) -> tuple[np.ndarray, np.ndarray]:
        """(e^{λh}, [h·φ1·B, h²·φ2·B]) for step h, cached."""
        cached = self._cache.get(h)
        if cached is None:
            z = self.eigenvalues * h
            phi1, phi2 = phi_functions(z)
            gain = np.hstack([(h * phi1)[:, None] * self.b, (h * h * phi2)[:, None] * self.b])
            cached = (np.exp(z), gain)
            if len(self._cache) >= _CACHE_SIZE:
                self._cache.pop(next(iter(self._cache)))
            self._cache[h] = cached
        return cached

    def step(self, q: np.ndarray, inputs: np.ndarray, h: float) -> np.ndarray:
        """New modal state after h; ``inputs`` = [r, v] at the start of the step."""
        decay, gain = self.coefficients(h)
        return decay * q + gain @ inputs

    def output(self, q: np.ndarray, inputs: np.ndarray) -> np.ndarray:
        """y = Re(C q) + D r + E v for ``inputs`` = [r, v]."""
        return (self.c @ q).real + self.de @ inputs


class DenseStepper:
    """The same exact step on a real (A, B, C, D, E) via the augmented matrix exponential."""

    def __init__(self, a, b, c, d, e):
        self.a, self.b, self.c = (np.asarray(x, dtype=float) for x in (a, b, c))
        self.de = np.hstack([np.asarray(d, float), np.asarray(e, float)])
        self.n_inputs = self.b.shape[1]
        self._cache: dict[float, tuple[np.ndarray, np.ndarray]] = {}

    @classmethod
    def from_reduced(cls, reduced) -> DenseStepper:
        a, b, c, d, e = reduced.real_form()
        return cls(a, b, c, d, e)

    def coefficients(self, h: float) -> tuple[np.ndarray, np.ndarray]:
        cached = self._cache.get(h)
        if cached is None:
            n, m = self.a.shape[0], self.n_inputs
            aug = np.zeros((n + 2 * m, n + 2 * m))
            aug[:n, :n] = self.a
            aug[:n, n : n + m] = self.b
            aug[n : n + m, n + m :] = np.eye(m)  # r' = v, v' = 0: the ramp
            import scipy.linalg as sla  # a cross-check and for dense models only

            expo = sla.expm(aug * h)
            cached = (expo[:n, :n], expo[:n, n:])
            if len(self._cache) >= _CACHE_SIZE:
                self._cache.pop(next(iter(self._cache)))
            self._cache[h] = cached
        return cached

    def step(self, x: np.ndarray, inputs: np.ndarray, h: float) -> np.ndarray:
        phi, gamma = self.coefficients(h)
        return phi @ x + gamma @ inputs

    def output(self, x: np.ndarray, inputs: np.ndarray) -> np.ndarray:
        return self.c @ x + self.de @ inputs
