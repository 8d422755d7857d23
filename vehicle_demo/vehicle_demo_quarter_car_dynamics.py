"""Quarter-car equations of motion, numpy only: shared by the references (quarter_car.py) and
the QuarterCar FMU's slave, which ships this module in its resources/ (hence the distinctive
name: pythonfmu FMUs in one process share ``sys.modules``)."""

import numpy as np


def two_mass_state_space(body_mass_kg: float, wheel_mass_kg: float,
                         suspension_stiffness_n_per_m: float,
                         suspension_damping_n_s_per_m: float) -> tuple[np.ndarray, np.ndarray]:
    """(A, B) of x = [z_b, ż_b, z_w, ż_w] with input ΔF_rim (N) on the wheel."""
    m_b, m_w = body_mass_kg, wheel_mass_kg
    k, c = suspension_stiffness_n_per_m, suspension_damping_n_s_per_m
    a = np.array([
        [0.0, 1.0, 0.0, 0.0],
        [-k / m_b, -c / m_b, k / m_b, c / m_b],
        [0.0, 0.0, 0.0, 1.0],
        [k / m_w, c / m_w, -k / m_w, -c / m_w],
    ])
    b = np.array([0.0, 0.0, 0.0, 1.0 / m_w])
    return a, b
