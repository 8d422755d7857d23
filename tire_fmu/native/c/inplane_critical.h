/* inplane_critical.h: the in-plane ring's critical (standing-wave) speed, in C.
 *
 * The number of tire_fmu/core/inplane_modes.py's critical_speed(model, n_elements): the
 * lowest spin at which a ground-frame frequency of the undamped ring on this mesh (rim held,
 * damping and the hysteretic loss left out) reaches zero, i.e. at which the order-n block
 * K_n(Omega) = K0 + Omega K1 + Omega^2 K2 of the stiffness turns singular, over the orders
 * n = 0 .. N/2; with the order and the standing wave's kind. inplane_critical.c says how. */
#ifndef TIRE_INPLANE_CRITICAL_H
#define TIRE_INPLANE_CRITICAL_H

#include <stddef.h>

#include "inplane_ring.h"

/* The rules of core/inplane_modes.py, with its names: the spin step of the three rings the
 * quadratic is read off (CRITICAL_FIT_STEP_RAD_S), when a root counts as real
 * (|Im| <= tolerance |root|, CRITICAL_REAL_TOLERANCE; the same for Omega and mu = 1/Omega) and
 * when as infinite (|mu| <= share sqrt(|K2| / |K0|), CRITICAL_INFINITE_SHARE). */
#define INPLANE_CRITICAL_FIT_STEP_RAD_S 64.0
#define INPLANE_CRITICAL_REAL_TOLERANCE 1e-9
#define INPLANE_CRITICAL_INFINITE_SHARE 1e-8

/* The standing wave's kind: the larger part of its kinetic energy (tangential: v and v_s). */
enum { INPLANE_CRITICAL_NONE = 0, INPLANE_CRITICAL_RADIAL = 1, INPLANE_CRITICAL_TANGENTIAL = 2 };

/* Statuses: the ring's for its input (INPLANE_RING_BAD_ELEMENTS .. INPLANE_RING_NULL), then
 * the two ways the numerics can fail. */
enum {
    INPLANE_CRITICAL_OK = 0,
    INPLANE_CRITICAL_SINGULAR = 6,      /* an order's K0 (at rest, rim held) is singular */
    INPLANE_CRITICAL_NO_CONVERGENCE = 7 /* cx_eig did not converge */
};

/* Doubles of scratch inplane_critical_speed needs (three dense rings and the ring's scratch:
 * about 3 (n_fields N)^2); 0 for a mesh or field count out of range. */
size_t inplane_critical_work_doubles(int n_elements, int n_fields);

/* The critical spin (rad/s) into *spin_rad_s, its speed spin R (m/s) into *speed_m_s, its
 * order into *order and its kind into *branch; with no real positive root in any order,
 * infinity, infinity, -1 and INPLANE_CRITICAL_NONE (the Python's inf, inf, None, None). data,
 * n_elements and n_fields as inplane_ring_build takes them (alpha, beta and loss_factor are
 * checked but not used). On a problem returns its status, with why (why_size > 0) a sentence
 * naming the parameter, its value and what is allowed, and writes none of the four. */
int inplane_critical_speed(const InPlaneRingData* data, int n_elements, int n_fields,
                           double* spin_rad_s, double* speed_m_s, int* order, int* branch,
                           double* work, char* why, size_t why_size);

#endif
