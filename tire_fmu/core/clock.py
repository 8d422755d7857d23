"""The simulator's clock: the time since the start, kept apart from the start time.

A clock in double precision resolves less the later it reads: 1.2e-10 s at 1e6 s, 2.4e-7 s
at an epoch time (1.7e9 s), 1.2e-4 s at 1e12 s. The model is time-invariant, so what it
indexes by time (the road history under the contact zone) is indexed by the time since the
start, which a step of h advances by h to a rounding of the elapsed time however late the
start; the steps are summed with compensation (Kahan), so k steps of h read k·h to an ulp and
do not drift over millions of steps. The absolute time, start + elapsed, is only what the
host's clock shows.

A step the host's clock cannot resolve is refused: when h is less than the spacing of doubles
at t + h, consecutive communication points start + k·h round onto one double now and then
(for h = 1e-4 s from 5.5e11 s on), and where the spacing exceeds 2h (from 2.2e12 s) t + h is
t: the host's time stops.
"""

from __future__ import annotations

import math

#: How a step the clock cannot resolve is refused: h, t (as repr), the spacing of doubles
#: there, the shortest step it resolves, and the time up to which h is resolved (s). The
#: native FMU fills the same template (spec.py).
RESOLUTION_TEMPLATE = (
    "step size h = %s s at t = %s s: shorter than the resolution of the clock there (%.3g s "
    "between one double and the next), so the communication points would not advance by h; "
    "take steps of at least %.3g s, or run at times below %.4g s (a start time nearer 0)")


def resolved_until(h: float) -> float:
    """The time magnitude below which a clock of doubles resolves steps of ``h`` (s): the
    spacing of doubles is at most h below it and 2h from it on."""
    return math.ldexp(1.0, math.frexp(h)[1] + 52)


def resolves(time_s: float, h: float) -> bool:
    """Whether the step from ``time_s`` to ``time_s + h`` is at least the spacing of doubles
    at its end (False for non-finite values)."""
    return abs(time_s) + h < resolved_until(h)


def resolution_problem(time_s: float, h: float) -> str:
    """Why a step the clock does not resolve is refused (see :data:`RESOLUTION_TEMPLATE`)."""
    spacing = math.ulp(abs(time_s) + h)
    return RESOLUTION_TEMPLATE % (repr(float(h)), repr(float(time_s)), spacing, spacing,
                                  resolved_until(h))


def advance(elapsed_s: float, carry_s: float, h: float) -> tuple[float, float]:
    """``elapsed_s + h`` with Kahan compensation: the new elapsed time and what its rounding
    left out (carried into the next step)."""
    y = h - carry_s
    total = elapsed_s + y
    return total, (total - elapsed_s) - y
