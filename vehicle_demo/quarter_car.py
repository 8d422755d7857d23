"""The quarter car and its frequency-domain references.

Coordinates are deviations from static equilibrium, z up: body z_b, wheel z_w, road z_r
(at the front of the tire's contact zone). Gravity on body and wheel is balanced by the
suspension preload and the tire's static load (m_b + m_w)·g, so only deviations appear:

    m_b z̈_b = -k_s (z_b - z_w) - c_s (ż_b - ż_w)
    m_w z̈_w =  k_s (z_b - z_w) + c_s (ż_b - ż_w) + ΔF_rim,

ΔF_rim the dynamic part of the tire's force on the rim. The tire enters as a two-port,

    F_rim(ω) = F_static + H_rim(ω)·z_w(ω) + H_road(ω)·z_r(ω),

from the full (unreduced) ring model (:func:`full_tire_two_port`) or a massless spring-damper
(:func:`spring_damper_two_port`). Both references are exact in the frequency domain; the
co-simulation (:mod:`vehicle_demo.cosim`) is checked against the first one.

The ring tire is not massless: part of its 121 kg moves with the rim when the road is held
still (:func:`tire_rim_side_mass_kg`, about 40 kg at the default load), which lowers wheel hop
by several percent compared with a massless tire of the same stiffness. The analytic
frequencies therefore come in both versions (:func:`analytic_frequencies`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse.linalg as spla

from .vehicle_demo_quarter_car_dynamics import (  # noqa: F401 -- the car is defined there
    QuarterCarError,
    QuarterCarParameters,
    two_mass_state_space,
)

#: Names of the ride responses, all per unit road height at the front of the contact zone.
RIDE_OUTPUTS = ("body_acc", "wheel_acc", "rim_load", "contact_force")
RIDE_UNITS = {"body_acc": "(m/s²)/m", "wheel_acc": "(m/s²)/m", "rim_load": "N/m",
              "contact_force": "N/m"}
RIDE_LABELS = {"body_acc": "road → body acceleration", "wheel_acc": "road → wheel acceleration",
               "rim_load": "road → dynamic rim load", "contact_force": "road → contact force"}


def state_space(params: QuarterCarParameters) -> tuple[np.ndarray, np.ndarray]:
    """(A, B) of x = [z_b, ż_b, z_w, ż_w] with input ΔF_rim (N)."""
    return two_mass_state_space(params.body_mass_kg, params.wheel_mass_kg,
                                params.suspension_stiffness_n_per_m,
                                params.suspension_damping_n_s_per_m)


@dataclass(frozen=True)
class AnalyticFrequencies:
    """Undamped natural frequencies of the two-mass car on a tire spring."""

    body_bounce_hz: float
    wheel_hop_hz: float
    tire_stiffness_n_per_m: float
    unsprung_mass_kg: float  # wheel + the tire mass counted with it


def analytic_frequencies(params: QuarterCarParameters, tire_stiffness_n_per_m: float,
                         tire_mass_kg: float = 0.0) -> AnalyticFrequencies:
    """Eigenfrequencies of [[m_b, 0], [0, m_w + m_t]] and [[k_s, -k_s], [-k_s, k_s + k_t]].

    ``tire_mass_kg`` is the tire mass moving with the rim (0 for the classic massless tire).
    """
    m_b, m_u = params.body_mass_kg, params.wheel_mass_kg + tire_mass_kg
    k_s, k_t = params.suspension_stiffness_n_per_m, tire_stiffness_n_per_m
    # det(K - ω²M) = 0 is a quadratic in ω²
    a = m_b * m_u
    b = -(k_s * m_u + (k_s + k_t) * m_b)
    c = k_s * k_t
    root = math.sqrt(b * b - 4 * a * c)
    low, high = (-b - root) / (2 * a), (-b + root) / (2 * a)
    return AnalyticFrequencies(math.sqrt(low) / (2 * math.pi), math.sqrt(high) / (2 * math.pi),
                               k_t, m_u)


# -- the tire as a two-port ------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class TireTwoPort:
    """Tire FRFs per unit rim displacement and per unit road height (at the zone front).

    Rows follow :data:`tire_fmu.core.io_model.OUTPUTS`: rim_Fz (force on the rim, up),
    rim_Fx, contact_Fz (road on tire, up), deflection.
    """

    label: str
    freqs_hz: np.ndarray
    rim: np.ndarray  # (4, nf) complex
    road: np.ndarray  # (4, nf) complex
    static_load_n: float
    static_stiffness_n_per_m: float


def full_tire_two_port(model, freqs_hz) -> TireTwoPort:
    """The full (unreduced) ring model at its operating point (``tire_fmu.core``)."""
    from tire_fmu.core.io_model import build_io_model

    freqs_hz = np.asarray(freqs_hz, dtype=float)
    io = build_io_model(model)
    return TireTwoPort("full ring model", freqs_hz, io.frequency_response("rim", freqs_hz),
                       io.frequency_response("road", freqs_hz), model.patch.load_n,
                       model.static_vertical_stiffness_n_per_m)


def spring_damper_two_port(stiffness_n_per_m: float, damping_n_s_per_m: float, freqs_hz,
                           static_load_n: float, road_delay_s: float = 0.0) -> TireTwoPort:
    """A massless point-contact tire: F = k (z_r(t - τ) - z_w) + c (ż_r(t - τ) - ż_w).

    τ puts the point contact at the contact centre, where the ring model measures the road at
    the front of its contact zone.
    """
    freqs_hz = np.asarray(freqs_hz, dtype=float)
    omega = 2 * np.pi * freqs_hz
    spring = stiffness_n_per_m + 1j * omega * damping_n_s_per_m
    delay = np.exp(-1j * omega * road_delay_s)
    zeros = np.zeros_like(spring)
    rim = np.vstack([-spring, zeros, -spring, -np.ones_like(spring)])
    road = np.vstack([spring * delay, zeros, spring * delay, delay])
    return TireTwoPort("spring-damper tire", freqs_hz, rim, road, static_load_n,
                       stiffness_n_per_m)


def _low_frequency_series(model) -> tuple[complex, complex, complex]:
    """Taylor coefficients y0, y1, y2 of the rim force per unit rim displacement (road held),
    H_rim(ω) = y0 + iω y1 + (iω)² y2 + ..., from three static solves:
    K U0 = B_z r, K U1 = B_v r - D U0, K U2 = -D U1 - M U0."""
    from tire_fmu.core.io_model import build_io_model

    io = build_io_model(model)
    r = np.zeros(io.n_inputs)
    r[0] = 1.0  # the rim input
    solve = spla.splu(model.stiffness.tocsc()).solve
    u0 = solve(io.b_disp @ r)
    u1 = solve(io.b_vel @ r - model.damping @ u0)
    u2 = solve(-(model.damping @ u1) - model.mass @ u0)
    y0 = io.out_disp[0] @ u0 + io.d_disp[0] @ r
    y1 = io.out_disp[0] @ u1 + io.out_vel[0] @ u0 + io.e[0] @ r
    y2 = io.out_disp[0] @ u2 + io.out_vel[0] @ u1
    return y0, y1, y2


@dataclass(frozen=True)
class TireLowFrequency:
    """The ring tire seen from the rim below its first mode: K_dyn ≈ k + iωc - ω²m."""

    stiffness_n_per_m: float  # static vertical stiffness (matches the model's K_v)
    damping_n_s_per_m: float  # equivalent viscous damping, the low-frequency limit
    rim_side_mass_kg: float  # tire mass that moves with the rim, road held still


def tire_low_frequency(model) -> TireLowFrequency:
    """Stiffness, damping and rim-side mass of the ring tire from its low-frequency dynamic
    stiffness K_dyn(ω) = -H_rim(ω) (road held still).

    The damping is the limit Im K_dyn/ω as ω → 0. With the model's stiffness-proportional
    material damping it stays close to that up to wheel hop (the demo records how close, and
    docs/vehicle_demo.md quotes it); the spring-damper reference uses this value.
    """
    y0, y1, y2 = _low_frequency_series(model)
    # K_dyn = -H_rim = -y0 - iω y1 + ω² y2 = k + iωc - ω²m
    return TireLowFrequency(float(-y0.real), float(-y1.real), float(-y2.real))


def tire_rim_side_mass_kg(model) -> float:
    return tire_low_frequency(model).rim_side_mass_kg


# -- the quarter car on a two-port -----------------------------------------------------------

@dataclass(frozen=True, eq=False)
class RideResponse:
    """Road-to-ride FRFs of the quarter car on one tire model (see :data:`RIDE_OUTPUTS`)."""

    label: str
    freqs_hz: np.ndarray
    responses: dict  # name -> (nf,) complex

    def __getitem__(self, name: str) -> np.ndarray:
        return self.responses[name]


def ride_response(params: QuarterCarParameters, tire: TireTwoPort) -> RideResponse:
    """Solve the quarter car on a tire two-port for a unit road height, frequency by frequency.

    Body: (S - m_b ω²) Z_b = S Z_w with S = k_s + iω c_s; wheel:
    [S - m_w ω² - H_rim - S²/(S - m_b ω²)] Z_w = H_road Z_r.
    """
    omega = 2 * np.pi * tire.freqs_hz
    w2 = omega**2
    s = params.suspension_stiffness_n_per_m + 1j * omega * params.suspension_damping_n_s_per_m
    body_over_wheel = s / (s - params.body_mass_kg * w2)
    wheel_dyn = s - params.wheel_mass_kg * w2 - tire.rim[0] - s * body_over_wheel
    z_w = tire.road[0] / wheel_dyn
    z_b = body_over_wheel * z_w
    responses = {
        "body_acc": -w2 * z_b,
        "wheel_acc": -w2 * z_w,
        "rim_load": tire.rim[0] * z_w + tire.road[0],
        "contact_force": tire.rim[2] * z_w + tire.road[2],
    }
    return RideResponse(f"quarter car on {tire.label}", tire.freqs_hz, responses)


@dataclass(frozen=True)
class CoupledMode:
    frequency_hz: float  # undamped natural frequency |λ|/2π
    damping_ratio: float  # -Re λ / |λ|
    wheel_share: float  # |z_w| relative to |z_b| + |z_w| in the eigenvector


def coupled_modes(params: QuarterCarParameters, model) -> list[CoupledMode]:
    """Poles of the quarter car coupled to the full ring tire, ascending frequency.

    The tire's first-order model ẋ = A x + B r (r[0] = z_w, road held) is closed with the
    wheel through its rim force C x + D z_w + E ż_w: one dense eigenproblem of 4N + 4 states.
    """
    from tire_fmu.core.io_model import build_io_model

    io = build_io_model(model)
    a_t = io.a.toarray()
    n = a_t.shape[0]
    a_q, b_q = state_space(params)
    a = np.zeros((n + 4, n + 4))
    a[:n, :n] = a_t
    a[:n, n + 2] = io.b[:, 0]  # z_w drives the tire
    a[n:, n:] = a_q
    a[n:, :n] = np.outer(b_q, io.c[0])  # rim force from the tire state
    a[n + 3, n + 2] += io.d[0, 0] / params.wheel_mass_kg
    a[n + 3, n + 3] += io.e[0, 0] / params.wheel_mass_kg
    values, vectors = np.linalg.eig(a)
    keep = values.imag > 0
    values, vectors = values[keep], vectors[:, keep]
    body, wheel = np.abs(vectors[n]), np.abs(vectors[n + 2])
    share = wheel / np.maximum(body + wheel, np.finfo(float).tiny)
    order = np.argsort(np.abs(values))
    return [CoupledMode(float(abs(values[i]) / (2 * np.pi)),
                        float(-values[i].real / abs(values[i])), float(share[i]))
            for i in order]


@dataclass(frozen=True)
class QuarterCarModes:
    """Body bounce and wheel hop: analytic (massless tire and with the tire's rim-side mass)
    and the poles of the car on the full ring model."""

    massless: AnalyticFrequencies
    with_tire_mass: AnalyticFrequencies
    body_bounce: CoupledMode
    wheel_hop: CoupledMode


def quarter_car_modes(params: QuarterCarParameters, model) -> QuarterCarModes:
    low = tire_low_frequency(model)
    massless = analytic_frequencies(params, low.stiffness_n_per_m)
    massive = analytic_frequencies(params, low.stiffness_n_per_m, low.rim_side_mass_kg)
    modes = coupled_modes(params, model)
    # body bounce: the lowest mode; wheel hop: the mode nearest the analytic value among those
    # where the wheel moves more than the body
    body = min(modes, key=lambda m: abs(m.frequency_hz - massive.body_bounce_hz))
    wheel_like = [m for m in modes if m.wheel_share > 0.5] or modes
    wheel = min(wheel_like, key=lambda m: abs(m.frequency_hz - massive.wheel_hop_hz))
    return QuarterCarModes(massless, massive, body, wheel)
