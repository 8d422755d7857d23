"""What one communication step may be: the limits both FMUs and the step kernels enforce.

Written once here; the FMUs' spec (``fmu/spec.py`` -> ``spec.h``) carries them to the C.
"""

#: The longest communication step (s). The contact is solved in sub-steps of at most
#: contact_dynamics.MAX_SUBSTEP_S (0.1 ms), so this is 10^4 of them (a fraction of a second of
#: work); 1e6 s, the former limit, meant 10^10 sub-steps and hung the host (found by fuzzing).
MAX_STEP_S = 1.0
#: At speed the FMU keeps the road's history back to the patch's last node, one sample per
#: step, and reads it through a delay line of that many steps: at most this many.
MAX_DELAY_STEPS = 100_000
#: The most road samples the FMU ever holds: a delay line of MAX_DELAY_STEPS + 2 (the older
#: sample of the last window end and the newest), or as many recorded one a step over the
#: same reach, and the current point's; a state holding more is none of the FMU's.
MAX_HISTORY_SAMPLES = MAX_DELAY_STEPS + 3

#: Largest input magnitudes a step accepts (m, m/s): far beyond any tire's travel, but
#: finite enough that no product inside a step can overflow.
MAX_DISPLACEMENT_M = 10.0
MAX_VELOCITY_M_S = 1000.0
#: The largest position along the road a step accepts and a state holds (m), the wheel
#: centre's when the road is read by position: the road files' own limit on distances
#: (road_files.MAX_ABS_DISTANCE_M), 10 000 km, where a double still resolves 2e-9 m.
MAX_ROAD_POSITION_M = 1.0e7
#: The largest height above the road's datum a wheel-centre input takes (m): any road on Earth.
MAX_ROAD_HEIGHT_M = 1.0e4
#: The largest torque on the wheel an FMU takes (N m): ten times a truck wheel's brake.
MAX_TORQUE_N_M = 3.0e5
#: Largest displacement and rate a state may hold (m, m/s): the tread's excursion at the zone
#: nodes from any one mode, penetrations, the rim and road it saw. A step of an FMU moves the
#: rim and road at most MAX_DISPLACEMENT_M + MAX_VELOCITY_M_S x 1 s = 1010 m from equilibrium;
#: these are ten times that (and the rates a thousand times the input limit), so no run within
#: the inputs' limits reaches them, while a state beyond them is no tire's (1e300 in a mode gave
#: outputs of 3e307) and a step from it could overflow.
MAX_STATE_DISPLACEMENT_M = 1e4
MAX_STATE_VELOCITY_M_S = 1e6
#: The shortest step (s) of a ring truncated with static correction. Its dropped modes enter
#: through their static compliance and a rate term E ṙ, which a step of h weighs as E/h: the
#: shorter the step, the more the rate term outweighs the compliance, until the step's contact
#: problem loses its unique solution (from 6e-6 s down, the longest of 40 random tires around
#: GL073A at up to 15 m/s; 1e-6 s at N = 100, 10 m/s, f_max = 150 Hz) and, below 1e-300 s, E/h
#: overflows (found by fuzzing both FMUs). The ring with every mode, or without the static
#: correction, has no rate term and steps any h.
MIN_CORRECTED_STEP_S = 1e-5
#: The refusal of a shorter step: h (repr) and the bound.
SHORT_STEP_TEMPLATE = ("step size h = %s s: must be at least %g s for a ring truncated with "
                       "static correction (the dropped modes' rate term grows as 1/h); keep "
                       "every mode, or turn the static correction off, to step shorter")

#: The work of one internal sub-step of the kernel, in units of about one multiply-add of the
#: zone transforms. Each term of substep_work is one loop of kernel.c's substep and its
#: contact solve (one active-set pass, the kernel both FMUs step with), per item of the loop:
#: its multiply-adds where arithmetic bounds it (the transforms, the node-space products), its
#: measured cost beside the transforms' where memory and bookkeeping do (the modes, the points,
#: the rate term); benchmarks/bench_step_work.py --fit measures them. This is the fixed part:
#: the rim's couplings, the direct terms of the rim's motion, the calls.
SUBSTEP_WORK_BASE = 1000
#: Per mode kept: the one pass over the modes (decay, the held forces' ramp, the readout
#: through gamma and eta: four complex products, streamed from five arrays).
SUBSTEP_WORK_PER_MODE = 12
#: Per order and zone node pair (n_orders x (n_zone // 2 + 1)): the two inverse DFTs that read
#: the ring at the zone nodes and the DFT of the end forces, two multiply-adds each.
SUBSTEP_WORK_PER_ORDER_NODE = 6
#: Per point and support node: reading the tread at the points (twice), spreading the end
#: forces back to the nodes, and in the contact solve's pass the same both ways again.
SUBSTEP_WORK_PER_SUPPORT = 16
#: Per contact point: its penetration and rate, the law, the outputs' three rows, its state.
SUBSTEP_WORK_PER_POINT = 32
#: Per zone node pair (n_zone^2): the node-space contact solve, W_w and W_r applied to the
#: forces on the nodes the pushing points load and the active set's block (O(Z^2) where the
#: points' dense solve cost O(P^2)).
SUBSTEP_WORK_PER_NODE_PAIR = 2
#: Per entry of the direct rate term on the held forces (a ring truncated with static
#: correction only: 3 + 2 n_zone rows x n_zone): one multiply-add that streams E from memory,
#: measured at about four of the transforms'.
SUBSTEP_WORK_PER_RATE_ENTRY = 4
#: The most work one communication step may take (units): at most about 0.7 s of CPU on the
#: machine the weights were measured on (0.2-0.75 ns a unit over bench_step_work.py's sweeps,
#: the active set's churn making the spread), about a second on one somewhat slower. A tire
#: whose millisecond would take more (a stiff contact on a light tread, sub-stepped at
#: 1/sqrt(k_cw/rhoA), on a fine mesh) is refused when it is built, and a longer step than the
#: tire allows when it is taken, so no host waits minutes on one call.
MAX_STEP_WORK = 1_000_000_000
#: The longest interval a tire must step within MAX_STEP_WORK (s).
WORK_INTERVAL_S = 1e-3


def substep_work(n_modes: int, n_orders: int, n_zone: int, n_points: int, n_support: int,
                 truncated: bool) -> int:
    """The work of one sub-step (units, SUBSTEP_WORK_BASE): the same sum in both builders
    (contract_pack.c's contract_substep_work). ``truncated``: a ring truncated with static
    correction, whose sub-step also reads the held forces through the direct rate term."""
    return (SUBSTEP_WORK_BASE + SUBSTEP_WORK_PER_MODE * n_modes
            + SUBSTEP_WORK_PER_ORDER_NODE * n_orders * (n_zone // 2 + 1)
            + SUBSTEP_WORK_PER_SUPPORT * n_points * n_support
            + SUBSTEP_WORK_PER_POINT * n_points
            + SUBSTEP_WORK_PER_NODE_PAIR * n_zone * n_zone
            + (SUBSTEP_WORK_PER_RATE_ENTRY * (3 + 2 * n_zone) * n_zone if truncated else 0))


#: How a step that would take more than MAX_STEP_WORK is refused: h (repr), the sub-steps it
#: needs, the sub-step (s), the work of each, the limit, the longest step allowed (s).
LONG_STEP_TEMPLATE = ("step size h = %s s: would take %d sub-steps of %.3g s at %d units of "
                      "work each, more than the %d a step may take (about 1 s of CPU); take "
                      "steps of at most %.3g s with this tire and mesh")
#: How a tire whose millisecond would take more is refused (the k_cw problem's allowed text):
#: the largest k_cw, rhoA, n_elements, the sub-steps a millisecond takes at the given k_cw and
#: the work of each, the limit.
STIFF_CONTACT_ALLOWED = ("at most %.3g N/m^2 with rhoA = %g kg/m on this mesh (n_elements = "
                         "%d)")
STIFF_CONTACT_REASON = ("the contact is sub-stepped at 1/sqrt(k_cw/rhoA): a millisecond would "
                        "take %d sub-steps of %d units of work each, more than the %d a step "
                        "may take (about 1 s of CPU)")
