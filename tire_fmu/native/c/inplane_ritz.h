/* inplane_ritz.h: the Ritz basis of the reduced in-plane step, in C.
 *
 * The subspace of tire_fmu/core/inplane_contact.py's ritz_basis(model, n_elements, zone_nodes,
 * f_max_hz): the undamped modes at rest of the ring with the rim held up to f_max_hz and the
 * static shapes of a unit radial (w) and tangential (v) load at each zone node, orthonormal,
 * of the rank scipy.linalg.orth(rcond=1e-10) gives the same columns (each mode M-normalised,
 * each static shape to max |.| = 1). The input is the ring's dense M and K at rest with the rim
 * held (inplane_ring_build with spin 0 and rim_free 0), whose field blocks are circulant: the
 * work is per Fourier order (inplane_ritz.c says how). Row-major doubles, memory from the
 * caller.
 *
 * f_max: a mode is kept when its lambda <= (2 pi f_max_hz)^2. A degenerate pair (the cos and
 * sin of one order) has one lambda here, so it is kept or dropped whole; the Python's eigh
 * gives the two members values that differ in the last digits and compares each
 * (sqrt(lambda) / 2 pi <= f_max), so the two can differ only for an f_max within rounding of a
 * mode's frequency (then the Python may keep one member of a pair, and the C keeps both or
 * neither). */
#ifndef TIRE_INPLANE_RITZ_H
#define TIRE_INPLANE_RITZ_H

#include <stddef.h>

#include "numerics.h"

enum {
    INPLANE_RITZ_OK = 0,
    INPLANE_RITZ_BAD_SHAPE = 1,  /* n_elements, n_fields, n_zone or max_columns */
    INPLANE_RITZ_BAD_ZONE = 2,   /* a zone node outside the mesh */
    INPLANE_RITZ_BAD_F_MAX = 3,
    INPLANE_RITZ_BAD_MATRIX = 4, /* M or K not symmetric circulant blocks, or not definite */
    INPLANE_RITZ_TOO_MANY = 5,   /* the basis has more columns than max_columns */
    INPLANE_RITZ_NULL = 6
};

/* The relative rank threshold, scipy.linalg.orth's rcond in ritz_basis. */
#define INPLANE_RITZ_RCOND 1e-10
/* How far (relative to the matrix's largest entry) M and K may be from symmetric circulant
 * field blocks. */
#define INPLANE_RITZ_CIRCULANT_TOLERANCE 1e-10
/* f_max_hz's range: InPlaneSimulator's. */
#define INPLANE_RITZ_MIN_F_MAX_HZ 1.0
#define INPLANE_RITZ_MAX_F_MAX_HZ 1e5

/* Doubles of scratch inplane_ritz_build needs; 0 for a shape out of range (n_elements in
 * [8, 1600], n_fields in [2, 4], n_zone in [0, n_elements]). */
size_t inplane_ritz_work_doubles(int n_elements, int n_fields, int n_zone);

/* The basis into basis, column k at basis[k * n_dof ...] (n_dof = n_fields n_elements; a
 * row-major max_columns x n_dof array, the basis transposed), its column count into
 * *n_columns: the modes (by Fourier order) first, then the static shapes' remainder. mass and
 * stiffness are n_dof x n_dof; zone_nodes holds n_zone node indices in [0, n_elements). On a
 * problem returns its status, with why (why_size > 0) a sentence naming the parameter, its
 * value and what is allowed, and writes neither basis nor *n_columns. */
int inplane_ritz_build(const double* mass, const double* stiffness, int n_elements,
                       int n_fields, const int* zone_nodes, int n_zone, double f_max_hz,
                       int max_columns, double* basis, int* n_columns, double* work,
                       char* why, size_t why_size);

/* ----- the held ring's Fourier orders (shared with inplane_critical.c) -----
 * A matrix of nf x nf symmetric circulant field blocks (N x N each, field-major DOFs) is
 * block diagonal on the Fourier vectors e^{i n theta_j} / sqrt(N) of each field: its order-n
 * block (nf x nf, Hermitian) is f^H A f, core/inplane_modes.py's order_matrices. */

/* cos, sin and the versine 1 - cos = 2 sin^2(pi m / N) of 2 pi m / N for m < N, into tables
 * (3 N doubles, the three one after the other); cos and sin exactly zero at the quarter turns
 * so that orders 0 and N/2 come out real. */
void inplane_fourier_tables(int n_elements, double* tables);

/* The field blocks' first columns, col[(a nf + b) N + k] = (m[aN + k, bN] + m[bN, aN + k]) / 2
 * (nf^2 N doubles), of m (nf N x nf N, row major). */
void inplane_fourier_columns(const double* m, int n_elements, int n_fields, double* col);

/* The order-n block (0 <= order <= N/2) into out (nf x nf, row major) from the first columns:
 * sum_k col[k] e^{-i n theta_k} per block (its real part as sum col - sum col versine, which
 * keeps the digits a stencil's near-zero sum cancels), made exactly Hermitian, real for orders
 * 0 and N/2. The tables are inplane_fourier_tables'. */
void inplane_fourier_block(const double* col, int n_elements, int n_fields, int order,
                           const double* tables, cx* out);

#endif
