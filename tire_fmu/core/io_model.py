"""The tire at an operating point as a linear input/output system.

Inputs are deviations from static equilibrium: rim vertical displacement and velocity, road
height and velocity. The road enters per contact point, each point seeing the road under its
own arc, i.e. the height at the front of the contact zone averaged over the window of time in
which that stretch of road passed the front (all at once at V = 0, a shaker plate; see
:mod:`.contact`), so the internal input vector is r = [z_rim, z_1, ..., z_p].

With rim-relative internal forces and the linearised contact gap
p_j = w_j + (z_j - z_rim)/cos θ_j the model is

    M ü + D u̇ + K u = B_z r + B_v ṙ,

with B_z = [K_s T - K_c (cos - sec), -K_c sec_j], B_v likewise with D_s and C_c. The velocity
forcing is removed from the state equation by the momentum-like state x = [u, M u̇ - B_v r]:

    ẋ₁ = M⁻¹ x₂ + M⁻¹ B_v r
    ẋ₂ = -K x₁ - D M⁻¹ x₂ + (B_z - D M⁻¹ B_v) r,

which is exact and leaves the input velocity only in a direct feedthrough of the outputs
(a damper between rim and tire passes rim velocity straight to the rim force):

    y = C x + D_r r + E ṙ.

Outputs (dynamic parts; the static values are the patch's, ContactPatch.static_outputs):
rim_Fz and rim_Fx, the force of the tire on the rim; contact_Fz, the road's force on the tire
(positive pushing up); deflection, the radial compression of the tread at the patch centre
relative to the rim.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from .contact import RoadWindows
from .model import TireModel

if TYPE_CHECKING:
    import scipy.sparse as sp

OUTPUTS = ("rim_Fz", "rim_Fx", "contact_Fz", "deflection")
OUTPUT_UNITS = {"rim_Fz": "N", "rim_Fx": "N", "contact_Fz": "N", "deflection": "m",
                "contact_length": "m"}
PHYSICAL_INPUTS = ("rim", "road")


@dataclass(frozen=True, eq=False)
class InputOutputModel:
    """Full (unreduced) first-order model ẋ = A x + B r, y = C x + D r + E ṙ, sparse."""

    model: TireModel
    a: sp.csr_matrix
    b: np.ndarray  # (n_states, n_inputs)
    c: np.ndarray  # (n_outputs, n_states)
    d: np.ndarray  # (n_outputs, n_inputs)
    e: np.ndarray  # (n_outputs, n_inputs), on input velocities
    road_windows: RoadWindows  # per road input: the window of road it averages
    # second-order pieces, for frequency responses and static solves
    b_disp: np.ndarray
    b_vel: np.ndarray
    out_disp: np.ndarray  # outputs from u
    out_vel: np.ndarray  # outputs from u̇
    d_disp: np.ndarray  # outputs from r with u̇ kept apart (the static feedthrough)

    output_names: tuple[str, ...] = OUTPUTS

    @property
    def n_states(self) -> int:
        return self.a.shape[0]

    @property
    def n_inputs(self) -> int:
        return self.b.shape[1]

    @cached_property
    def input_names(self) -> tuple[str, ...]:
        w = self.road_windows
        return ("rim_z",) + tuple(f"road_z(t - [{a:.6g}, {b:.6g}] s)"
                                  for a, b in zip(w.early_s, w.late_s))

    def physical_input(self, name: str, omega) -> np.ndarray:
        """Internal inputs r(ω) (n_inputs, n_freqs) for a unit harmonic of a physical input."""
        return physical_input(name, self.road_windows, omega)

    def static_gain(self) -> np.ndarray:
        """DC gain from r to y (E ṙ vanishes at DC): y = C x_static + D r."""
        import scipy.sparse.linalg as spla

        u = spla.splu(self.model.stiffness.tocsc()).solve(self.b_disp)
        return self.out_disp @ u + self.d_disp

    def frequency_response(self, name: str, freqs_hz) -> np.ndarray:
        """Exact FRF (n_outputs, n_freqs) of the full model for a physical input, second-order
        form: (K - ω²M + iωD) U = (B_z + iωB_v) r, Y = (C_u + iωC_v) U + (D_u + iωE) r."""
        import scipy.sparse.linalg as spla

        omega = 2 * np.pi * np.asarray(freqs_hz, dtype=float)
        r_all = self.physical_input(name, omega)
        m, d, k = self.model.mass, self.model.damping, self.model.stiffness
        out = np.empty((len(self.output_names), omega.size), dtype=complex)
        for i, (w, r) in enumerate(zip(omega, r_all.T)):
            dyn = (k - w * w * m + 1j * w * d).tocsc()
            u = spla.spsolve(dyn, (self.b_disp + 1j * w * self.b_vel) @ r)
            out[:, i] = (self.out_disp + 1j * w * self.out_vel) @ u + \
                (self.d_disp + 1j * w * self.e) @ r
        return out


def physical_input(name: str, windows: RoadWindows, omega) -> np.ndarray:
    """Internal inputs r(ω) for a unit harmonic rim displacement or road height (measured at
    the front of the contact zone)."""
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    r = np.zeros((1 + windows.early_s.size, omega.size), dtype=complex)
    if name == "rim":
        r[0] = 1.0
    elif name == "road":
        r[1:] = windows.frequency_response(omega)
    else:
        raise ValueError(f"input = {name!r}: must be one of {PHYSICAL_INPUTS}")
    return r


def build_io_model(model: TireModel) -> InputOutputModel:
    """Inputs, outputs and the momentum-form state space of a tire model."""
    import scipy.sparse as sp  # here, so that the FMU can read this module's names cheaply

    n = model.n_dof
    t, s = model.translation, model.horizontal
    k_s, d_s = model.structure.stiffness, model.structure.damping
    patch, zone = model.patch, model.patch.zone
    points = patch.contact_points  # the contact points with a spring
    interp = zone.interpolation[points]  # (points, zone nodes)
    k_pt = patch.point_stiffness_n_per_m[points]
    c_pt = patch.point_damping_n_s_per_m[points]
    cos, sec = zone.force_cos[points], zone.point_sec[points]
    early, late = patch.road.early_s[points], patch.road.late_s[points]
    # Points that see the same stretch of road at the same time share one input (at rest: the
    # whole footprint, a shaker plate), which keeps the input vector, and a step, small.
    keys = np.round(np.column_stack([early, late]), 15)
    unique, group = np.unique(keys, axis=0, return_inverse=True)
    group = np.asarray(group).reshape(-1)
    windows = RoadWindows(unique[:, 0].copy(), unique[:, 1].copy(), patch.road.front_m)
    n_road = unique.shape[0]

    def on_nodes(per_point: np.ndarray, per_input: bool) -> np.ndarray:
        """(n, inputs): per-point forces on the zone nodes' tread DOFs through Iᵀ (the virtual
        work of the interpolation), summed per road group."""
        columns = group if per_input else np.zeros_like(group)
        per_group = np.zeros((n_road if per_input else 1, zone.n_nodes))
        np.add.at(per_group, columns, per_point[:, None] * interp)
        out = np.zeros((n, per_group.shape[0]))
        out[zone.nodes] = per_group.T
        return out

    # contact force on the nodes: -Iᵀ(k p + c ṗ), p = (I u) + (I cos θ - sec θ_p) z_rim
    # + sec θ_p z_road,p (the I u part sits in the model's contact stiffness)
    b_disp = np.column_stack([k_s @ t - on_nodes(k_pt * (cos - sec), False)[:, 0],
                              -on_nodes(k_pt * sec, True)])
    b_vel = np.column_stack([d_s @ t - on_nodes(c_pt * (cos - sec), False)[:, 0],
                             -on_nodes(c_pt * sec, True)])
    n_in = b_disp.shape[1]

    # Outputs. Internal force on the rim: T/S·[D_s(u̇ - T ż_rim) + K_s(u - T z_rim)].
    out_disp = np.zeros((4, n))
    out_vel = np.zeros((4, n))
    d_disp = np.zeros((4, n_in))  # feedthrough of r
    e_vel = np.zeros((4, n_in))  # feedthrough of ṙ
    for row, pattern in ((0, t), (1, s)):
        out_disp[row] = k_s.T @ pattern
        out_vel[row] = d_s.T @ pattern
        d_disp[row, 0] = -pattern @ (k_s @ t)
        e_vel[row, 0] = -pattern @ (d_s @ t)
    # Road on tire, vertical: Σ (I cos θ)_p (k p + c ṗ) over the contact points.
    out_disp[2, zone.nodes] = (cos * k_pt) @ interp
    out_vel[2, zone.nodes] = (cos * c_pt) @ interp
    d_disp[2, 0] = np.sum(cos * k_pt * (cos - sec))
    e_vel[2, 0] = np.sum(cos * c_pt * (cos - sec))
    np.add.at(d_disp[2], 1 + group, cos * k_pt * sec)
    np.add.at(e_vel[2], 1 + group, cos * c_pt * sec)
    # Compression of the tread at the patch centre relative to the rim: -(u_r0 - T_0 z_rim).
    out_disp[3, 0] = -1.0
    d_disp[3, 0] = t[0]

    m_inv = 1.0 / model.mass.diagonal()
    m_inv_diag = sp.diags(m_inv)
    a = sp.bmat(
        [[None, m_inv_diag], [-model.stiffness, -(model.damping @ m_inv_diag)]], format="csr"
    )
    m_inv_bv = b_vel * m_inv[:, None]
    b = np.vstack([m_inv_bv, b_disp - model.damping @ m_inv_bv])
    # y = out_disp u + out_vel u̇ + d_disp r + e ṙ with u̇ = M⁻¹(x₂ + B_v r)
    c = np.hstack([out_disp, out_vel * m_inv[None, :]])
    d = d_disp + out_vel @ m_inv_bv
    return InputOutputModel(
        model=model,
        a=a,
        b=b,
        c=c,
        d=d,
        e=e_vel,
        road_windows=windows,
        b_disp=b_disp,
        b_vel=b_vel,
        out_disp=out_disp,
        out_vel=out_vel,
        d_disp=d_disp,
    )
