"""core/obstacles.py's PositionRoad (the host's road by position; position_road.c is its C):
the running integral stays the trapezoids' of the samples held, whatever a call replaces,
inserts and appends while its buffer grows or is compacted."""

import numpy as np

from tire_fmu.core.obstacles import PositionRoad


def test_the_running_integral_is_the_samples_trapezoids_through_growth_and_forgetting():
    """Calls that replace a held height (or insert between held samples) and append beyond
    the newest in one go, the buffer growing or compacted during the call: the integral was
    taken again from an index that had not moved with the samples (stale trapezoids)."""
    rng = np.random.default_rng(37)
    road = PositionRoad(0.3)
    newest, checked = 0.0, 0
    for _ in range(400):
        held = road.s
        positions, heights = [], []
        if held.size > 2:  # one held position given again, one between two held
            i = int(rng.integers(0, held.size - 1))
            positions += [held[i], 0.5 * (held[i] + held[i + 1])]
            heights += list(rng.normal(0.0, 1e-2, 2))
        ahead = newest + np.cumsum(rng.uniform(2e-3, 1e-2, int(rng.integers(1, 40))))
        positions += list(ahead)
        heights += list(rng.normal(0.0, 1e-2, ahead.size))
        newest = float(ahead[-1])
        road.set_samples(positions, heights)
        s, z, at = road.s, road.z, road._at
        trapezoids = np.concatenate([[0.0], np.cumsum(0.5 * np.diff(s) * (z[1:] + z[:-1]))])
        assert np.all(np.diff(s) > 0)
        assert np.allclose(at - at[0], trapezoids, rtol=0, atol=1e-15)
        checked += 1
    assert checked == 400 and road.s[-1] == newest
