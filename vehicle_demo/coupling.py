"""How large the communication step of :mod:`vehicle_demo.cosim` may be: the co-simulation
as the linear discrete-time map it is, and its spectral radius.

Both FMUs step exactly (matrix exponentials), so all the error and any instability come from
the coupling: the tire sees the rim move along the tangent at t_k for the whole step, and the
quarter car sees the tire force as a ramp between the ends of the step (Gauss-Seidel) or held
at its start value (Jacobi). With the tire's reduced model (the same one the FMU builds,
:func:`tire_fmu.core.reduction.reduce`) and the road held, one step maps

    [x_tire, x_car, F]_k  ->  [x_tire, x_car, F]_{k+1},

linear in the state; the scheme is stable while its spectral radius is at most 1 (the
physical modes are damped, so an exact scheme has radius exp(-min ζω·h) < 1). The stiff part
of the loop is the tire's rim feedthrough: about 10 MN/m of static stiffness between rim and
sidewall and 1.1 kN·s/m of damping acting on a 320 kg wheel, i.e. ω ≈ 170 rad/s, far below
1/h at h = 1e-4 s; :func:`stability_limit` finds the actual limit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from .quarter_car import QuarterCarParameters, state_space


def _car_step(params: QuarterCarParameters, h: float):
    a, b = state_space(params)
    aug = np.zeros((6, 6))
    aug[:4, :4] = a
    aug[:4, 4] = b
    aug[4, 5] = 1.0
    e = sla.expm(aug * h)
    return e[:4, :4], e[:4, 4], e[:4, 5]


def coupled_step_matrix(params: QuarterCarParameters, reduced, h: float,
                        scheme: str = "gauss-seidel") -> np.ndarray:
    """The one-step map of the co-simulation over [x_tire, x_car, F] (road held)."""
    from tire_fmu.core.stepping import DenseStepper

    stepper = DenseStepper.from_reduced(reduced)
    phi_t, gamma_t = stepper.coefficients(h)
    m = stepper.n_inputs
    g_z, g_v = gamma_t[:, 0], gamma_t[:, m]  # rim displacement and velocity columns
    c = stepper.c[0]
    d00, e00 = stepper.de[0, 0], stepper.de[0, m]
    phi_c, gamma0, gamma1 = _car_step(params, h)
    n = phi_t.shape[0]
    size = n + 5
    tire, car, force = slice(0, n), slice(n, n + 4), n + 4
    z_w, v_w = n + 2, n + 3
    step = np.zeros((size, size))
    step[tire, tire] = phi_t
    step[tire, z_w] = g_z
    step[tire, v_w] = g_v
    # the new force, read at the end of the tire's ramp of the rim
    new_force = np.zeros(size)
    new_force[tire] = c @ phi_t
    new_force[z_w] = c @ g_z + d00
    new_force[v_w] = c @ g_v + d00 * h + e00
    step[force] = new_force
    step[car, car] = phi_c
    if scheme == "gauss-seidel":  # the force ramps from F_k to F_{k+1}
        step[car, force] += gamma0 - gamma1 / h
        step[car] += np.outer(gamma1 / h, new_force)
    elif scheme == "jacobi":  # the force held at F_k
        step[car, force] += gamma0
    else:
        raise ValueError(f"scheme = {scheme!r}: must be 'gauss-seidel' or 'jacobi'")
    return step


def spectral_radius(params: QuarterCarParameters, reduced, h: float,
                    scheme: str = "gauss-seidel") -> float:
    return float(np.abs(np.linalg.eigvals(coupled_step_matrix(params, reduced, h,
                                                                 scheme))).max())


@dataclass(frozen=True)
class StabilityLimit:
    scheme: str
    max_stable_step_s: float  # largest h with spectral radius <= 1 (nan: none in the range)
    radius_at_default: float  # at h = 1e-4 s
    checked_up_to_s: float


def stability_limit(params: QuarterCarParameters, reduced, scheme: str = "gauss-seidel",
                    h_min: float = 1e-5, h_max: float = 2e-2) -> StabilityLimit:
    """Largest stable step: a log scan from h_min, then bisection on the first unstable
    interval. The radius falls back below 1 only where h aliases the modes, which a host
    must not rely on."""
    def stable(h):
        return spectral_radius(params, reduced, h, scheme) <= 1.0 + 1e-12

    grid = np.geomspace(h_min, h_max, 16)
    flags = [stable(h) for h in grid]
    if all(flags):
        limit = float("inf")
    elif not flags[0]:
        limit = float("nan")
    else:
        first_bad = flags.index(False)
        low, high = grid[first_bad - 1], grid[first_bad]
        for _ in range(16):  # the interval shrinks to 1e-5 of itself (log scale)
            mid = np.sqrt(low * high)
            low, high = (mid, high) if stable(mid) else (low, mid)
        limit = float(low)
    return StabilityLimit(scheme, limit, spectral_radius(params, reduced, 1e-4, scheme), h_max)
