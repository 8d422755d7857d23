"""The wheel centre's state and the road by position: what both tires' FMUs share.

A host gives the wheel centre's position along the road and its height above the road's datum
(ISO 8855 / TYDEX: x forward, z up) with their rates; the tires take them as deviations from
an origin fixed at their first step (the wheel's position there and the road's height under
it), so that nothing far from the road's origin enters a step's arithmetic, and read the road
by position at every contact point at their own step. A host that owns its road is asked for
heights where the tire needs them (:func:`road_queries`). What users read besides the forces
(:func:`longitudinal_slip`, :func:`effective_rolling_radius`) is defined here once.
"""

from __future__ import annotations

import math

import numpy as np

#: The speed below which the slip is taken over this one (m/s): rest has no slip.
SLIP_SPEED_FLOOR_M_S = 0.1
#: How far the radial tire's speed may stray from the one its modes were built at: a tenth
#: of it, or this (m/s) when that is less. Its ring's modes are the built speed's; the road
#: passes at the wheel's own speed (tests/test_wheel_centre.py measures what the difference
#: costs).
RADIAL_SPEED_SLACK_M_S = 0.5
RADIAL_SPEED_SLACK_FRACTION = 0.1
#: The host road's samples reach where the next step needs them when they end at most this
#: short of it (m, far below any road's resolution): the tie a step's travel that is a whole
#: number of point spacings makes is decided alike however the positions round (the native
#: FMUs' differ from the Python ones' by 1e-13 m), so both runtimes ask for the same road.
ROAD_QUERY_SLACK_M = 1e-6
#: The host's road is asked for no closer than this share of the contact points' spacing.
QUERY_FLOOR_SHARE = 0.0625


def longitudinal_slip(spin_rad_s: float, radius_m: float, speed_m_s: float) -> float:
    """(spin R - speed) / max(|speed|, SLIP_SPEED_FLOOR_M_S): negative braking, -1 locked."""
    return (spin_rad_s * radius_m - speed_m_s) / max(abs(speed_m_s), SLIP_SPEED_FLOOR_M_S)


def effective_rolling_radius(speed_m_s: float, spin_rad_s: float, radius_m: float) -> float:
    """speed / spin (m), or ``radius_m`` while the wheel barely turns (below 1e-9 rad/s)."""
    return speed_m_s / spin_rad_s if abs(spin_rad_s) > 1e-9 else radius_m


def radial_speed_range(built_m_s: float) -> tuple[float, float]:
    """The wheel speeds (m/s) the radial tire built at ``built_m_s`` takes."""
    slack = max(RADIAL_SPEED_SLACK_FRACTION * abs(built_m_s), RADIAL_SPEED_SLACK_M_S)
    return built_m_s - slack, built_m_s + slack


def road_queries(count: int, wheel_x_m: float, wheel_vx_m_s: float, step_s: float,
                 rear_m: float, front_m: float, spacing_m: float,
                 held_m: np.ndarray) -> np.ndarray:
    """Where a tire needs its host's road next (m along it), ``count`` positions: ahead of the
    newest sample held (``held_m``, increasing), spread evenly up to the contact zone's front
    (``front_m`` ahead of the wheel centre) after the wheel's travel over ``step_s`` and one
    contact point spacing (``spacing_m``) more, so that every query the host answers serves:
    at 20 m/s and a 1 ms step, 16 of them sample the road every 2 mm, finer than the contact
    points, and a cleat's edges reach the tire wherever the samples fall. Never closer than
    QUERY_FLOOR_SHARE of the spacing (a creeping wheel would fill the road's memory with
    samples no point resolves). The whole zone (``rear_m`` to ``front_m`` from the wheel
    centre) before the first samples and while the samples held already reach that far (then
    the host's road is read again under the tire: at rest, a road that moves under a still
    tire, a shaker plate)."""
    rear, front = wheel_x_m + rear_m, wheel_x_m + front_m
    reach = front + abs(wheel_vx_m_s) * step_s + spacing_m
    newest = float(held_m[-1]) if len(held_m) else -math.inf
    if newest >= reach - ROAD_QUERY_SLACK_M or not len(held_m):
        return rear + (front - rear) * np.arange(count) / (count - 1)
    gap = max(QUERY_FLOOR_SHARE * spacing_m, (reach - newest) / count)
    return newest + gap * np.arange(1, count + 1)
