/* inplane_ring.h: the in-plane ring's mass, stiffness and damping built in C.
 *
 * The same matrices as tire_fmu/core/inplane.py's InPlaneRing(model, n_elements, spin_rad_s,
 * rim_free, hysteresis) .mass, .stiffness, .damping and .hysteretic_stiffness (read that for
 * the physics: the radial sidewall's tie above sidewall_max_order, the hysteretic loss at its
 * share of the spin), so that a native in-plane FMU can build them at initialisation without
 * Python. Row-major doubles, memory from the caller: inplane_ring_n_dof and
 * inplane_ring_work_doubles say how much. */
#ifndef TIRE_INPLANE_RING_H
#define TIRE_INPLANE_RING_H

#include <stddef.h>

/* The tire data the ring reads: TireParameters' fields, then all of TangentialParameters'
 * (k_tx and friction_coefficient are the contact's, carried so that one struct holds the
 * tangential data; the ring does not read them). SI units as in the Python. sidewall_shear is
 * not carried: InPlaneTire refuses any but 0. */
typedef struct {
    double R, b, inflation_pressure, rhoA, m_s, k_r1, k_r2, EI, alpha, beta,
        sidewall_pressure_exponent, reference_pressure, sidewall_max_order;
    double EA, k_t1, k_t2, rim_radius_m, wheel_mass_kg, wheel_inertia_kg_m2, k_tx,
        friction_coefficient, loss_factor;
} InPlaneRingData;

/* The field count says the sidewall model (InPlaneTire's sidewall_mass and
 * sidewall_tangential): 2 massless (tread w, v; m_s is not read), 3 tied (w, v, w_s), 4 lumped
 * (w, v, w_s, v_s). */
enum { INPLANE_RING_MASSLESS = 2, INPLANE_RING_TIED = 3, INPLANE_RING_LUMPED = 4 };

enum {
    INPLANE_RING_OK = 0,
    INPLANE_RING_BAD_ELEMENTS = 1,
    INPLANE_RING_BAD_FIELDS = 2,
    INPLANE_RING_BAD_DATA = 3,
    INPLANE_RING_BAD_SPIN = 4,
    INPLANE_RING_NULL = 5
};

/* Mesh limits of the Python (core/parameters.py MIN_ELEMENTS, MAX_ELEMENTS). */
#define INPLANE_RING_MIN_ELEMENTS 8
#define INPLANE_RING_MAX_ELEMENTS 1600

/* Rows (= columns) of each matrix: n_fields N, and 3 rim DOFs (x, z, psi) with the rim free;
 * 0 for a mesh or field count out of range. */
size_t inplane_ring_n_dof(int n_elements, int n_fields, int rim_free);

/* Doubles of scratch inplane_ring_build needs; 0 for a mesh or field count out of range. */
size_t inplane_ring_work_doubles(int n_elements, int n_fields);

/* INPLANE_RING_OK, or the first problem found; with why (why_size > 0) a sentence naming the
 * parameter, its value and what is allowed. */
int inplane_ring_check(const InPlaneRingData* data, int n_elements, int n_fields,
                       double spin_rad_s, char* why, size_t why_size);

/* Fill mass, stiffness, damping (each n_dof x n_dof) for spin_rad_s and rim_free (0 held,
 * else free), as InPlaneRing does; hysteresis 0 leaves the hysteretic loss out of the
 * stiffness (InPlaneRing's hysteresis=False), else the stiffness holds its share at the spin.
 * hysteretic, when not NULL, receives the loss's stiffness at full share (n_dof x n_dof, zero
 * for loss_factor = 0; it does not depend on the spin). work holds inplane_ring_work_doubles.
 * Checks first (why as inplane_ring_check) and writes nothing on a problem. */
int inplane_ring_build(const InPlaneRingData* data, int n_elements, int n_fields,
                       double spin_rad_s, int rim_free, int hysteresis, double* mass,
                       double* stiffness, double* damping, double* hysteretic, double* work,
                       char* why, size_t why_size);

#endif
