"""The Ritz basis of the reduced in-plane step: core/inplane_contact.py's ritz_basis (numpy and
scipy: the ring's dense matrices, eigh, a dense solve, orth) beside native/c/inplane_ritz.c
(order by order from the held ring's circulant blocks), at N = 100 and 400, the simulator's
contact zone (default length and spacing) and f_max = 300 Hz (the host's default), for the
default tire (tied tangential sidewall), the lumped one and the massless one.

The C's time is given whole (the C ring's M and K built by inplane_ring.c, then the basis) and
for the basis alone (from matrices already built). Cases alternate round by round, so load on
the shared machine hits them alike; figures are medians over the rounds. Each run also prints
how far apart the two spans are (largest principal angle) and their ranks.

    python benchmarks/bench_inplane_ritz.py [--rounds 5] [--n 100 400] [--f-max 300]
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402
import scipy.linalg  # noqa: E402

from benchmarks.record import sidewall_tires, timed  # noqa: E402
from tire_fmu.core.contact import contact_zone  # noqa: E402
from tire_fmu.core.discretisation import Grid  # noqa: E402
from tire_fmu.core.inplane_contact import ritz_basis  # noqa: E402
from tire_fmu.native.inplane_ring import c_inplane_ring, n_fields  # noqa: E402
from tire_fmu.native.inplane_ritz import c_ritz_basis, c_ritz_basis_of  # noqa: E402
from tire_fmu.native.kernel import load_library  # noqa: E402

TIRES = sidewall_tires()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--n", type=int, nargs="+", default=[100, 400])
    parser.add_argument("--f-max", type=float, default=300.0)
    args = parser.parse_args()
    library = load_library()  # compiled (or read from the cache) before any timing
    print(f"f_max = {args.f_max:g} Hz, the simulator's contact zone, medians of {args.rounds} "
          "rounds (s)")
    print(f"{'tire':9s} {'N':>4s} {'zone':>4s} {'rank':>5s} {'Python':>8s} {'C whole':>8s} "
          f"{'C basis':>8s} {'ratio':>6s} {'angle':>9s}")
    for n in args.n:
        for name, model in TIRES.items():
            t = model.tire
            zone = contact_zone(Grid(n, t.R), t.k_cw, t.beta).nodes
            ring = c_inplane_ring(model, n, library=library)
            mass, stiffness = ring.mass, ring.stiffness
            times = {"python": [], "whole": [], "basis": []}
            for _ in range(args.rounds):
                seconds, python = timed(ritz_basis, model, n, zone, args.f_max)
                times["python"].append(seconds)
                seconds, built = timed(c_ritz_basis, model, n, zone, args.f_max, library)
                times["whole"].append(seconds)
                seconds, _ = timed(c_ritz_basis_of, mass, stiffness, n, n_fields(model), zone,
                                    args.f_max, library)
                times["basis"].append(seconds)
            median = {key: statistics.median(values) for key, values in times.items()}
            angle = (scipy.linalg.subspace_angles(python, built).max()
                     if python.shape == built.shape else np.nan)
            print(f"{name:9s} {n:4d} {zone.size:4d} {built.shape[1]:5d} "
                  f"{median['python']:8.4f} {median['whole']:8.4f} {median['basis']:8.4f} "
                  f"{median['python'] / median['whole']:6.1f} {angle:9.2e}"
                  + ("" if python.shape == built.shape else
                     f"  (ranks differ: Python {python.shape[1]})"))


if __name__ == "__main__":
    main()
