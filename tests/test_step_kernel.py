"""The contact simulator's fast paths against the plain formulas they replace: the road
delay line against the history search and against exact window averages, restored states,
and the step-size jitter hosts produce."""

import re

import numpy as np
import pytest

from tire_fmu.core import OperatingPoint, TireParameters
from tire_fmu.core.contact import RoadWindows
from tire_fmu.core.contact_dynamics import (
    MIN_CORRECTED_STEP_S,
    ContactSimulator,
    ContactState,
    StepError,
    build_contact_model,
)
from tire_fmu.core.free_ring import RingTruncation
from tire_fmu.core.road import window_reads


@pytest.fixture(scope="module")
def models():
    return {speed: build_contact_model(TireParameters(),
                                       OperatingPoint(n_elements=40, speed_m_s=speed))
            for speed in (0.0, 15.0)}


def _road(t):
    w = 2 * np.pi * 30
    return 1e-3 * np.sin(w * t), 1e-3 * w * np.cos(w * t)


def test_window_reads_are_exact_averages_of_the_interpolant():
    """A cubic road is its own Hermite interpolant: each window's mean and end-to-end slope
    come out exactly, over any number of samples, with level road before the first."""
    def profile(t):
        return 1e-3 * (1 + t - 2 * t**2 + 3 * t**3), 1e-3 * (1 - 4 * t + 9 * t**2)

    t = np.linspace(0.0, 0.5, 37)
    z, v = profile(t)
    windows = RoadWindows(np.array([0.0, 0.013, 0.1, 0.45]), np.array([0.01, 0.05, 0.31, 0.6]),
                          0.3)
    heights, slopes = window_reads(t, z, v, 0.5, windows)
    for k, (a, b) in enumerate(zip(0.5 - windows.late_s, 0.5 - windows.early_s)):
        fine = np.linspace(a, b, 20001)
        inside = np.where(fine < 0, profile(0.0)[0], profile(np.maximum(fine, 0))[0])
        mean = np.trapezoid(inside, fine) / (b - a)
        ends = [profile(max(x, 0.0))[0] for x in (a, b)]
        assert heights[k] == pytest.approx(mean, rel=1e-7)
        assert slopes[k] == pytest.approx((ends[1] - ends[0]) / (b - a), rel=1e-12)


def test_the_compiled_kernels_delay_line_reads_the_road_as_the_history_search(models):
    """road.c switches to a delay line once the steps have had one size for the windows'
    whole reach, and back to the history when h changes; the numpy kernel always searches the
    history. The two read the same road: the outputs agree throughout, at 15 m/s over a road
    of 30 Hz, with the step changing twice."""
    model = models[15.0]
    line, search = (ContactSimulator(model, backend=b) for b in ("compiled", "numpy"))
    steps = [1e-4] * 650 + [2e-4] * 350 + [1e-4] * 700
    t, used = 0.0, []
    for h in steps:
        a = line.step(h, 0.0, 0.0, *_road(t))
        b = search.step(h, 0.0, 0.0, *_road(t))
        np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-9 * model.patch.load_n)
        used.append(line.kernel.delay_line_on)
        t += h
    # on after a full reach of uniform steps, off when h changes, on again later
    assert used[640] and not used[660] and used[990] and not used[1010] and used[-1]


@pytest.mark.parametrize("steps_before", [10, 700])
def test_restoring_a_state_takes_the_same_path_bit_for_bit(models, steps_before):
    """Before the delay line starts and after it: a restored state, also in a fresh
    simulator, reproduces the steps exactly."""
    sim = ContactSimulator(models[15.0])
    for i in range(steps_before):
        sim.step(1e-4, 0.0, 0.0, *_road(i * 1e-4))
    saved = sim.get_state().to_bytes()
    future = [_road((steps_before + j) * 1e-4) for j in range(30)]
    first = [sim.step(1e-4, 0.0, 0.0, *road) for road in future]
    for target in (sim, ContactSimulator(models[15.0])):
        target.set_state(ContactState.from_bytes(saved))
        assert [target.step(1e-4, 0.0, 0.0, *road).tolist() for road in future] == \
            [y.tolist() for y in first]


def test_step_size_jitter_of_a_host_is_integrated_as_it_is(models):
    """fmpy steps by differences of communication points, h jitters in the last bits: each
    distinct h (a handful) gets coefficients of its own, so the tire integrates the time the
    host's clock moved, and gives the outputs of the clean step."""
    model = models[15.0]
    fixed, jittered = ContactSimulator(model), ContactSimulator(model)
    h, start = 1e-4, 7.0
    fixed.reset(start)
    jittered.reset(start)
    for n in range(900):
        inputs = (0.0, 0.0, *_road(n * h))
        a = fixed.step(h, *inputs)
        t, t_next = start + n * h, start + (n + 1) * h
        assert abs(jittered.time - t) <= 1e-14  # its own clock sums the host's steps
        b = jittered.step(t_next - t, *inputs)
        np.testing.assert_allclose(b, a, rtol=1e-9, atol=1e-9 * model.patch.load_n)
    assert 1 <= jittered.kernel.cached_steps <= 4  # the distinct differences of points


def test_inputs_out_of_range_are_refused_by_name_and_change_nothing(models):
    sim = ContactSimulator(models[0.0])
    sim.step(1e-4, 1e-3, 0.0, 0.0, 0.0)
    before = sim.get_state().to_bytes()
    with pytest.raises(StepError, match=r"rim_z = 1e\+308 m: must be in \[-10, 10\] m; "
                       r"road_z = 1e\+308 m"):
        sim.step(1e-4, 1e308, 0.0, 1e308, 0.0)  # finite, but a product would overflow
    with pytest.raises(StepError, match="road_vz = inf m/s"):
        sim.step(1e-4, 0.0, 0.0, 0.0, np.inf)
    with pytest.raises(StepError, match=r"step size h = nan s"):
        sim.step(float("nan"), 0.0, 0.0, 0.0, 0.0)
    assert sim.get_state().to_bytes() == before


def test_a_ring_truncated_to_no_modes_steps_in_both_kernels_alike():
    """f_max below the lowest mode keeps none of them (a quasi-static ring): the former fast
    step's products on the empty modal state were refused by BLAS (the fuzz found it through
    the Python FMU after 11 steps). Both kernels step it, to the same outputs."""
    model = build_contact_model(TireParameters(), OperatingPoint(n_elements=16),
                                RingTruncation(f_max_hz=1e-3))
    assert model.ring.n_modes == 0
    t = 1e-4 * np.arange(60)
    w = 2 * np.pi * 20
    inputs = np.column_stack([1e-4 * np.sin(w * t), 1e-4 * w * np.cos(w * t), 0 * t, 0 * t])

    def run(backend):
        sim = ContactSimulator(model, backend=backend)
        rows = []
        for values in inputs:
            rows.append(sim.outputs_with(*values))
            rows.append(sim.step_values(1e-4, *values))
        return np.array(rows)

    compiled, reference = run("compiled"), run("numpy")
    assert np.all(np.isfinite(compiled)) and np.all(compiled[:, 2] > 0)
    np.testing.assert_allclose(compiled, reference, rtol=1e-9, atol=1e-9 * model.patch.load_n)


def test_a_ring_truncated_with_static_correction_refuses_the_steps_its_rate_term_breaks():
    """The dropped modes enter with a rate term E that a step weighs as E/h. Below
    MIN_CORRECTED_STEP_S the step's contact problem loses its unique solution at speed (I - S
    on the zone stops being positive definite), and at h = 5e-324 s E/h overflowed into
    non-finite outputs (the fuzz found it in both FMUs). Such steps are refused naming h and
    change nothing; the full ring, and one without the correction, have no rate term and
    step any h the clock resolves (at rest: at speed the road's delay line bounds h from
    below)."""
    op = OperatingPoint(n_elements=100, speed_m_s=10.0)
    model = build_contact_model(TireParameters(), op, RingTruncation(f_max_hz=150.0))
    sim = ContactSimulator(model)
    reference = ContactSimulator(model, backend="numpy").kernel

    def well_posed(h):
        s = reference.interface(h)[1].m[:sim.n_zone]
        a = np.eye(sim.n_zone) - s
        return np.linalg.eigvalsh(a + a.T).min() > 0

    assert well_posed(MIN_CORRECTED_STEP_S) and not well_posed(MIN_CORRECTED_STEP_S / 10)
    sim.step(1e-4, 1e-3, 0.0, 0.0, 0.0)
    before = sim.get_state().to_bytes()
    for h in (5e-324, 1e-9, MIN_CORRECTED_STEP_S / 2):
        with pytest.raises(StepError, match=rf"^step size h = {re.escape(repr(h))} s: must be "
                           r"at least 1e-05 s for a ring truncated with static correction"):
            sim.step(h, 1e-3, 0.0, 0.0, 0.0)
    assert sim.get_state().to_bytes() == before
    assert np.all(np.isfinite(sim.step(MIN_CORRECTED_STEP_S, 1e-3, 0.0, 0.0, 0.0)))
    for truncation in (None, RingTruncation(f_max_hz=150.0, static_correction=False)):
        other = ContactSimulator(build_contact_model(TireParameters(),
                                                     OperatingPoint(n_elements=100), truncation))
        other.step(1e-4, 1e-3, 0.0, 0.0, 0.0)
        # the shortest step the clock resolves at t = 1e-4 s (shorter ones it refuses)
        assert np.all(np.isfinite(other.step(1e-15, 1e-3, 0.0, 0.0, 0.0)))


def test_the_node_space_interface_is_the_points_matrix_written_out(models):
    """The kernels apply M = [S; W_p; W_r] through the zone nodes (I W Iᵀ) and solve an active
    set's block through the nodes it reads (Woodbury): on a tire rolling over a road at the
    default spacing (more points than zone nodes), base + M f, (I - S_AA)⁻¹ σ_A and the
    projected Gauss-Seidel fallback are what the dense points' matrix gives, the fallback
    the same forces as the active-set iteration."""
    model = models[15.0]
    sim = ContactSimulator(model, backend="numpy")
    kernel = sim.kernel
    for i in range(300):  # the road reaches the footprint after 20 ms; the rim pressed down
        sim.step(1e-4, -2e-3, 0.0, *_road(i * 1e-4))
    interface = kernel.last
    p, z = kernel.contract.n_points, kernel.contract.n_zone
    assert p > 2 * z
    m = interface.m
    rng = np.random.default_rng(7)
    f = np.where(rng.random(p) < 0.4, rng.normal(size=p), 0.0) * model.patch.load_n / p
    base = rng.normal(size=3 * p)
    np.testing.assert_allclose(interface.combine(base, f), base + m @ f, rtol=0,
                               atol=1e-12 * np.abs(base + m @ f).max())
    for share in (0.1, 0.5, 1.0):
        active = rng.random(p) < share
        sigma = rng.normal(size=p)
        expected = np.zeros(p)
        expected[active] = np.linalg.solve(np.eye(active.sum()) - m[:p][np.ix_(active, active)],
                                           sigma[active])
        np.testing.assert_allclose(interface.active_forces(active, sigma), expected, rtol=0,
                                   atol=1e-10 * np.abs(expected).max())
    np.testing.assert_allclose(interface.s_diag, np.diag(m[:p]), rtol=1e-12)
    # the end of the last substep again: a well-posed contact problem, both solvers' forces
    f_now = kernel.forces
    pen, rate = kernel.penetration, kernel.rate
    base = interface.combine(np.concatenate([kernel.k * pen + kernel.c * rate, pen, rate]),
                             -f_now)
    f_active, _ = kernel._solve(interface, base)
    assert np.count_nonzero(f_active) > z
    kernel.df = np.zeros(p)  # Gauss-Seidel from the static forces, not from the answer
    f_pgs = kernel._fallback(interface, base)
    assert np.abs(kernel.f_static - f_active).max() > 1e-3 * np.abs(f_active).max()
    np.testing.assert_allclose(f_pgs, f_active, rtol=0, atol=1e-9 * model.patch.load_n)
    np.testing.assert_allclose(f_active, f_now, rtol=0, atol=1e-9 * model.patch.load_n)


def test_the_gauss_seidel_fallback_of_both_kernels_gives_the_active_sets_forces(models):
    """The projected Gauss-Seidel fallback, run for every solve, in the C kernel and in
    numpy: over a rolling run on a 30 Hz road, with the rim lifted clear and landing, both
    give the active set's outputs to the fallback's tolerance, and the two fallbacks agree.
    (Left to itself the active set settles in almost every solve: a landing is where it
    cycles and falls back.)"""
    model = models[15.0]
    sims = {name: ContactSimulator(model, backend=backend) for name, backend in
            [("active set", "compiled"), ("C fallback", "compiled"),
             ("numpy fallback", "numpy")]}
    for name in ("C fallback", "numpy fallback"):
        sims[name].kernel.set_fallback_only(True)
    load = model.patch.load_n
    t, worst, lifted = 0.0, {"C fallback": 0.0, "numpy fallback": 0.0}, False
    for i in range(600):
        rim = 0.06 * np.sin(np.pi * (i - 250) / 100) if 250 <= i < 350 else 0.0
        out = {name: np.asarray(sim.step(1e-4, rim, 0.0, *_road(t)))
               for name, sim in sims.items()}
        lifted |= out["active set"][2] == 0.0
        for name in worst:
            worst[name] = max(worst[name], float(np.max(np.abs(out[name]
                                                               - out["active set"]))))
        assert np.max(np.abs(out["C fallback"] - out["numpy fallback"])) < 1e-9 * load
        t += 1e-4
    assert lifted  # the footprint emptied and filled again
    assert sims["active set"].kernel.solver_fallbacks < 0.02 * 600
    assert sims["C fallback"].kernel.solver_fallbacks > 600
    assert sims["numpy fallback"].kernel.solver_fallbacks > 600
    assert max(worst.values()) < 1e-8 * load
