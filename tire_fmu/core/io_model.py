"""The tire at an operating point as a linear input/output system.

Inputs are deviations from static equilibrium: rim vertical displacement and velocity, road
height and velocity. The road enters per patch node, each node seeing the road height at the
leading edge delayed by its distance from it over V (all at once at V = 0, a shaker plate), so
the internal input vector is r = [z_rim, z_road(t - τ_1), ..., z_road(t - τ_p)].

With rim-relative internal forces and road-relative contact forces the model is

    M ü + D u̇ + K u = B_z r + B_v ṙ,

with B_z = [K_s T, K_c T_j], B_v = [D_s T, C_c T_j]. The velocity forcing is removed from the
state equation by the momentum-like state x = [u, M u̇ - B_v r]:

    ẋ₁ = M⁻¹ x₂ + M⁻¹ B_v r
    ẋ₂ = -K x₁ - D M⁻¹ x₂ + (B_z - D M⁻¹ B_v) r,

which is exact and leaves the input velocity only in a direct feedthrough of the outputs
(a damper between rim and tire passes rim velocity straight to the rim force):

    y = C x + D_r r + E ṙ.

Outputs (dynamic parts; static values are added by :mod:`tire_fmu.core.simulation`):
rim_Fz and rim_Fx, the force of the tire on the rim; contact_Fz, the road's force on the tire
(positive pushing up); deflection, the radial compression of the tread at the patch centre
relative to the rim.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .model import TireModel

OUTPUTS = ("rim_Fz", "rim_Fx", "contact_Fz", "deflection")
OUTPUT_UNITS = {"rim_Fz": "N", "rim_Fx": "N", "contact_Fz": "N", "deflection": "m"}
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
    input_delays_s: np.ndarray  # per internal input: 0 for the rim, τ for each road input
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
        return ("rim_z",) + tuple(f"road_z(t - {tau:.6g} s)" for tau in self.input_delays_s[1:])

    def physical_input(self, name: str, omega) -> np.ndarray:
        """Internal inputs r(ω) (n_inputs, n_freqs) for a unit harmonic of a physical input."""
        return physical_input(name, self.input_delays_s, omega)

    def static_gain(self) -> np.ndarray:
        """DC gain from r to y (E ṙ vanishes at DC): y = C x_static + D r."""
        u = spla.splu(self.model.stiffness.tocsc()).solve(self.b_disp)
        return self.out_disp @ u + self.d_disp

    def frequency_response(self, name: str, freqs_hz) -> np.ndarray:
        """Exact FRF (n_outputs, n_freqs) of the full model for a physical input, second-order
        form: (K - ω²M + iωD) U = (B_z + iωB_v) r, Y = (C_u + iωC_v) U + (D_u + iωE) r."""
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


def physical_input(name: str, delays_s: np.ndarray, omega) -> np.ndarray:
    """Internal inputs r(ω) for a unit harmonic rim displacement or road height.

    The road, measured at the leading edge, reaches patch node j after ``delays_s[j]``.
    """
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    r = np.zeros((len(delays_s), omega.size), dtype=complex)
    if name == "rim":
        r[0] = 1.0
    elif name == "road":
        r[1:] = np.exp(-1j * np.outer(delays_s[1:], omega))
    else:
        raise ValueError(f"input = {name!r}: must be one of {PHYSICAL_INPUTS}")
    return r


def build_io_model(model: TireModel) -> InputOutputModel:
    """Inputs, outputs and the momentum-form state space of a tire model."""
    n = model.n_dof
    t, s = model.translation, model.horizontal
    k_s, d_s = model.structure.stiffness, model.structure.damping
    k_c, c_c = model.contact_stiffness, model.contact_damping
    nodes = model.patch.node_indices  # tread DOFs in contact
    node_delays = model.patch.road_delays_s[nodes]
    # Nodes that see the road at the same time share one input (at rest: the whole patch,
    # a shaker plate), which keeps the input vector, and the cost of a step, small.
    delays, group = np.unique(np.round(node_delays, 15), return_inverse=True)
    grouping = sp.csr_matrix((np.ones(len(nodes)), (np.arange(len(nodes)), group)),
                             shape=(len(nodes), len(delays)))
    delays = np.r_[0.0, delays]

    def road_columns(matrix):
        # contact force per unit road rise at node j is matrix[:, j]·T_j; summed per group
        if not len(nodes):
            return np.zeros((n, 0))
        cols = matrix[:, nodes].toarray() * t[nodes][None, :]
        return np.asarray(cols @ grouping)

    b_disp = np.column_stack([k_s @ t, road_columns(k_c)])
    b_vel = np.column_stack([d_s @ t, road_columns(c_c)])
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
    # Road on tire, vertical: -Tᵀ[C_c(u̇ - T ż_road) + K_c(u - T z_road)], per road node.
    out_disp[2] = -(k_c.T @ t)
    out_vel[2] = -(c_c.T @ t)
    d_disp[2, 1:] = road_columns(k_c).T @ t
    e_vel[2, 1:] = road_columns(c_c).T @ t
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
        input_delays_s=delays,
        b_disp=b_disp,
        b_vel=b_vel,
        out_disp=out_disp,
        out_vel=out_vel,
        d_disp=d_disp,
    )
