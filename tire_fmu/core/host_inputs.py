"""How the tire meets a co-simulation master's inputs: the values a host sets before
fmi2DoStep(t, h) are those AT t (fmpy's simulate_fmu, libcosim, ecos and fmusim all set them
so), and the tire extends them over the step to t + h in one way, the same in every FMU.

- A position given with its rate (the rim's z and x, the road's height at the zone front) is
  extended on the cubic whose value and rate are the ones given and whose acceleration and jerk
  come from the rates given before (:func:`rate_changes`, :func:`input_path`): a Taylor
  expansion from t, third order in h. Holding the rate alone leaves the tire's inertia a step
  and a half behind the host's motion (forces ~1-4 % of their range off at 1 ms on a wheel
  hopping at 12-15 Hz); holding the values, several per cent more.
- An input without a rate (a torque) is held over the step, FMI's own default.
- Where the host's next values differ from where the extension ended (the motion was not the
  cubic, or the inputs are not consistent: a position step with its rate zero), the tire takes
  the host's values as they are at the new communication point: the rim jumps, the tire's own
  mass does not (its momentum carries on), so the forces stay those of the stretched tire.

A host step that is not a whole number of the tire's own step is cut into equal shorter ones
(:func:`substeps`), so any step the FMU declares it takes is taken, exactly to t + h, from any
start time.
"""

from __future__ import annotations

import math

import numpy as np

from .parameters import ParameterError, Problem

#: The shortest step the in-plane tire takes (s): a host's step below it is refused (the step's
#: matrices are built for its length, and their inverse grows as 1/h²).
MIN_STEP_S = 1e-7


def rate_changes(rates, rates_before, h_before: float, change_before,
                 h_change_before: float) -> tuple[np.ndarray, np.ndarray]:
    """(acceleration, jerk) at a communication point of inputs given with their rates, from
    the rates' last two changes: the last change over its step is the acceleration half that
    step back; the change between the two the jerk, which carries the acceleration to the
    point. Zero where there is no history yet (the first step: the host's inputs start at
    rest; the second: no jerk)."""
    rates = np.asarray(rates, dtype=float)
    if not h_before > 0.0:
        return np.zeros_like(rates), np.zeros_like(rates)
    change = (rates - np.asarray(rates_before, dtype=float)) / h_before
    if not h_change_before > 0.0:
        return change, np.zeros_like(rates)
    jerk = (change - np.asarray(change_before, dtype=float)) / (
        0.5 * (h_before + h_change_before))
    return change + 0.5 * h_before * jerk, jerk


def input_path(value: float, rate: float, acceleration: float, jerk: float = 0.0):
    """How the tire extends an input given at a communication point over the step after it:
    ``tau`` (s) into the step, (value, rate, acceleration) on the cubic with the given value
    and rate and the acceleration and jerk of :func:`rate_changes` (a Taylor expansion whose
    last two terms come from the rates the host gave before). Against the motion itself it
    errs at third order in the host's step; holding the rate alone leaves the tire's inertia a
    step and a half late, about 1 % of the forces' range on a wheel hopping at 15 Hz
    (tests/test_inplane_contact.py; benchmarks/bench_host_timing.py measures 1 ms against
    0.1 ms through the FMUs)."""

    def at(tau: float) -> tuple[float, float, float]:
        return (value + tau * (rate + tau * (0.5 * acceleration + tau * jerk / 6.0)),
                rate + tau * (acceleration + 0.5 * tau * jerk), acceleration + tau * jerk)

    return at


def on_grid(step_s: float, grid_s: float, at_time_s: float = 0.0) -> float:
    """``step_s`` as the whole number of ``grid_s`` it is to within the resolution of the
    host's clock at ``at_time_s`` (hosts pass h as the difference of two time points: at
    t = 1e9 s a step of 1e-3 s arrives up to 1.2e-7 s off), else ``step_s`` itself: a run then
    steps the same from any start time, its clock on the tire's grid."""
    count = round(step_s / grid_s)
    # the difference of two rounded time points is off by at most one spacing of doubles
    # there; never so much that another whole number of the grid would do
    slack = min(max(1e-9 * step_s, 2.0 * math.ulp(abs(at_time_s) + step_s)), 0.25 * grid_s)
    if count >= 1 and abs(count * grid_s - step_s) <= slack:
        return count * grid_s
    return step_s


def substeps(step_s: float, tire_step_s: float, at_time_s: float = 0.0) -> tuple[int, float]:
    """How the tire cuts a host's step: (count, length). Whole steps of ``tire_step_s`` when
    ``step_s`` is a whole number of them (:func:`on_grid`), else the fewest equal steps no
    longer than it, which end exactly at t + h (an input event off the tire's grid)."""
    if not (math.isfinite(step_s) and step_s >= MIN_STEP_S):
        raise ParameterError([Problem("step_s", step_s, "s", f"at least {MIN_STEP_S:g} s")])
    snapped = on_grid(step_s, tire_step_s, at_time_s)
    count = round(snapped / tire_step_s)
    if count >= 1 and snapped == count * tire_step_s:
        return count, tire_step_s
    count = math.ceil(step_s / tire_step_s)
    return count, step_s / count
