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

:class:`FusedStep` folds the output readout, a map from the caller's own input coordinates and
the static offset into the coefficients of one h, so that a simulator keeping its state in one
real buffer [q, p, 1] advances with three BLAS-level calls and no allocation (the FMU's hot
path, where the cost of a numpy call is its overhead, not its arithmetic).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
from scipy.linalg.blas import dgemv as _dgemv

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

    def fused(self, h: float, input_map: np.ndarray, offset: np.ndarray) -> FusedStep:
        """The step over h with the readout at its end folded in (see :class:`FusedStep`).

        ``input_map`` (2·inputs × p) turns the caller's p input values into [r, v];
        ``offset`` is added to every output (the static values).
        """
        decay, gain = self.coefficients(h)
        m, k = self.n_inputs, decay.size
        # outputs are read at the ramp's end: [r + v h, v] = ramp_end @ [r, v]
        ramp_end = np.eye(2 * m)
        ramp_end[:m, m:] = h * np.eye(m)
        input_map = np.asarray(input_map, dtype=float)
        on_q = self.c * decay[None, :]
        on_p = (self.c @ gain + self.de @ ramp_end) @ input_map
        # Re(c q) = Re c·Re q - Im c·Im q, and p is real: one real product on the buffer
        readout = np.empty((on_q.shape[0], 2 * k + on_p.shape[1] + 1), order="F")
        readout[:, 0:2 * k:2] = on_q.real
        readout[:, 1:2 * k:2] = -on_q.imag
        readout[:, 2 * k:-1] = on_p.real
        readout[:, -1] = offset
        gain_p = gain @ input_map
        gain_real = np.empty((2 * k, gain_p.shape[1]), order="F")
        gain_real[0::2], gain_real[1::2] = gain_p.real, gain_p.imag
        return FusedStep(h=h, decay=decay, gain=gain_real, readout=readout)


@dataclass(frozen=True, eq=False)
class FusedStep:
    """One step over ``h`` for a state kept in one real buffer b = [q, p, 1]: the modal state
    q as (real, imaginary) pairs, then p, the inputs at the step's start in the caller's
    coordinates:

        y(t + h) = readout @ b,    q(t + h) = decay * q + gain @ p.

    The readout is taken before q moves: it carries C·e^{λh} on q and C·Γ plus the
    feedthrough at the ramp's end on p, so both come from the state at t. ``gain`` gives
    the real and imaginary parts of Γ·p interleaved, as q is stored.
    """

    h: float
    decay: np.ndarray  # (k,) complex
    gain: np.ndarray  # (2k, p) real, Fortran order
    readout: np.ndarray  # (outputs, 2k + p + 1) real, Fortran order

    def bind(self, buffer: np.ndarray, y: np.ndarray) -> Callable[[], None]:
        """``advance()``: write the outputs at t + h into ``y`` and move q to t + h, both in
        place, for a contiguous float64 ``buffer`` laid out as above.

        BLAS through scipy's wrappers with positional arguments and arrays already
        contiguous in Fortran order: the wrappers then neither copy nor parse keywords
        (overwrite_y=1 writes into the given view), and a step costs about a third less than
        with numpy's ``dot`` and ``+=``.
        """
        readout, decay, gain = self.readout, self.decay, self.gain
        k2 = 2 * decay.size
        q_real, p = buffer[:k2], buffer[k2:k2 + gain.shape[1]]
        q = q_real.view(complex)
        if not decay.size:  # no modes kept: nothing for BLAS to do that numpy cannot
            def advance_numpy() -> None:
                np.dot(readout, buffer, out=y)
                q[:] = decay * q
                q_real[:] += gain @ p
            return advance_numpy

        dgemv, multiply = _dgemv, np.multiply  # closure cells: the cheapest lookups

        def advance() -> None:
            dgemv(1.0, readout, buffer, 0.0, y, 0, 1, 0, 1, 0, 1)
            multiply(q, decay, q)  # out given positionally: no keyword parsing
            dgemv(1.0, gain, p, 1.0, q_real, 0, 1, 0, 1, 0, 1)  # q += gain @ p
        return advance


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
