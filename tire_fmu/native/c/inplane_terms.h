/* inplane_terms.h: the in-plane step's spin terms on its coordinates, in C.
 *
 * The middle of tire_fmu/core/inplane_contact.py's InPlaneSimulator._build: from the ring
 * (inplane_ring.c, rim free, hysteresis off) at spins 0, 1 and 2 rad/s and its hysteretic
 * stiffness, the polynomial in the spin W the step follows (C = c0 + W c1, K = k0 + W k1 +
 * W^2 k2, plus kh at its share of W: quadratic_in_spin in core/inplane.py), the mass, the
 * rim's inertia and the rim's rows of the tire's forces, on the step's coordinates y = [ring
 * rim-relative, psi with the wheel free], reduced on a Ritz basis when one is given. What
 * inplane_build.c reads next. Row-major doubles, memory from the caller. */
#ifndef TIRE_INPLANE_TERMS_H
#define TIRE_INPLANE_TERMS_H

#include <stddef.h>

#include "inplane_ring.h"

enum {
    INPLANE_TERMS_OK = 0,
    /* 1..5: inplane_ring_check's (elements, fields, data) */
    INPLANE_TERMS_BAD_WHEEL = 6,  /* free_spin not 0 or 1 */
    INPLANE_TERMS_BAD_BASIS = 7,  /* n_basis out of range, or a basis entry not finite */
    INPLANE_TERMS_NULL = 8
};

/* What it writes, named as the simulator's (ny the coordinates, n_dof the ring's with the
 * rim's x, z, psi: inplane_ring_n_dof(.., 1)). ny x ny: m, c0, c1, k0, k1, k2, kh (the
 * simulator's _m and _spin_terms); n_dof x ny: to_abs (the ring's absolute DOFs of the
 * coordinates, the rim's x, z held); ny x 2: rim_inertia (to_abs^T M P, P the rigid x and z);
 * 3 x n_dof: the rim's rows rim_k0, rim_k1, rim_k2, rim_kh, rim_c0, rim_c1, rim_m (the tire's
 * mass rows without the wheel's own); 3 x 2: rim_m_translation = rim_m P (_rim_rows). */
typedef struct {
    double *m, *c0, *c1, *k0, *k1, *k2, *kh, *to_abs, *rim_inertia;
    double *rim_k0, *rim_k1, *rim_k2, *rim_kh, *rim_c0, *rim_c1, *rim_m, *rim_m_translation;
} InPlaneTermsOutput;

/* The coordinates: n_basis (or every ring DOF, n_fields N, with basis NULL) and psi with the
 * wheel free; 0 for sizes out of range. */
size_t inplane_terms_ny(int n_elements, int n_fields, int free_spin, int n_basis);

/* Doubles of scratch inplane_terms_build needs; 0 for sizes out of range. */
size_t inplane_terms_work_doubles(int n_elements, int n_fields, int free_spin, int n_basis);

/* Fill out for the ring of data (n_elements, n_fields as inplane_ring.h), the wheel free
 * (free_spin 1: psi the last coordinate) or held (0), on basis (n_fields N x n_basis, the
 * ring's rim-relative DOFs; the simulator appends psi to it with the wheel free, and so does
 * this) or, with basis NULL and n_basis 0, every ring DOF. work holds
 * inplane_terms_work_doubles. On a problem returns its status, with why (why_size > 0) a
 * sentence naming the parameter, its value and what is allowed, and writes nothing of out. */
int inplane_terms_build(const InPlaneRingData* data, int n_elements, int n_fields, int free_spin,
                        const double* basis, int n_basis, InPlaneTermsOutput* out, double* work,
                        char* why, size_t why_size);

#endif
