/* inplane_build.h: the in-plane step's matrices at a spin, in C.
 *
 * The arithmetic of tire_fmu/core/inplane_contact.py's InPlaneSimulator._set_ring_spin and
 * _set_tread_spin: from the spin's polynomial terms on the step's coordinates (C = c0 + W c1,
 * K = k0 + W k1 + W^2 k2, plus the hysteretic kh at its share of W), the mass, the contact
 * points' Jacobians and the tread's springs, the matrices inplane_step.c steps with. The ring's
 * part costs an inverse of the coordinates' size (LU with partial pivoting); the tread's part is
 * points-sized and follows the spin between ring builds. Row-major doubles, memory from the
 * caller; each entry is computed in the Python's order of operations, the products and the
 * inverse in their own (so they agree to rounding, not bit for bit). */
#ifndef TIRE_INPLANE_BUILD_H
#define TIRE_INPLANE_BUILD_H

#include <stddef.h>

enum {
    INPLANE_BUILD_OK = 0,
    INPLANE_BUILD_BAD_SIZE = 1,   /* ny or np out of range */
    INPLANE_BUILD_BAD_STEP = 2,   /* h not in [INPLANE_BUILD_MIN_STEP_S, ..._MAX_STEP_S] */
    INPLANE_BUILD_BAD_SPIN = 3,   /* a spin not finite */
    INPLANE_BUILD_BAD_INPUT = 4,  /* a non-finite entry, or the points' angles not increasing */
    INPLANE_BUILD_SINGULAR = 5,   /* 4/h^2 M + 2/h C + K singular */
    INPLANE_BUILD_NULL = 6
};

/* The ranges: the step's InPlaneSimulator's; the sizes so that every product fits in size_t
 * and int on any platform the FMU builds for. */
#define INPLANE_BUILD_MIN_STEP_S 1e-7
#define INPLANE_BUILD_MAX_STEP_S 1e-2
#define INPLANE_BUILD_MAX_NY 8192
#define INPLANE_BUILD_MAX_NP 4096

/* What the build reads (the simulator's _build prepares it): ny coordinates, np contact
 * points. ny x ny: m and the spin's terms; np x ny: jn, jnw, jxw, jl; np: kx, cx and the
 * points' angles point_theta (increasing, equally spaced: the carry's grid). hysteretic: the
 * tire has a hysteretic loss (loss_factor != 0), its share then hysteresis_share(W, radius_m)
 * as core/inplane.py's (SPEC_HYSTERESIS_FULL_SPEED_M_S). */
typedef struct {
    int ny, np, hysteretic;
    double h, radius_m;
    const double *m, *c0, *c1, *k0, *k1, *k2, *kh;
    const double *jn, *jnw, *jxw, *jl;
    const double *kx, *cx, *point_theta;
} InPlaneBuildInput;

/* What it writes, named as the simulator's attributes. The ring's part (inplane_build_ring):
 * ny x ny: c, k (with the share's kh), c1, k1s = k1 + 2 W k2, k2, kh, a0_inv (the inverse of
 * a0 = 4/h^2 M + 2/h C + K); ny x np: yn = a0_inv jnw^T, yx = a0_inv jxw^T; np x np:
 * wnn = jn yn, wnx = jn yx; np x ny: kg_a = kx jxw + cx (2/h) jxw, kg_b = kx (h/2) jl + cx jl
 * (the simulator's _kg_parts); np x np: kgn_a, kgn_b = kg_. yn and kgx_a, kgx_b = kg_. yx;
 * ring_spin and ring_share. The tread's part (inplane_build_tread, from the ring's kg_, kgn_
 * and kgx_ parts): np x ny: gain = jxw + (h/2) W jl, kg = kg_a + W kg_b; np x np: kgn, kgx
 * likewise; carry (np x np, core's carry_matrix), carry_base (np), carry_weights (np x 4)
 * (carry_stencil) and carry_shift = W h / spacing; spin_now. */
typedef struct {
    double *c, *k, *c1, *k1s, *k2, *kh, *a0_inv, *yn, *yx, *wnn, *wnx;
    double *kg_a, *kg_b, *kgn_a, *kgn_b, *kgx_a, *kgx_b;
    double ring_spin, ring_share;
    double *gain, *kg, *kgn, *kgx, *carry, *carry_weights;
    int* carry_base;
    double carry_shift, spin_now;
} InPlaneBuildOutput;

/* Scratch of inplane_build_ring (and inplane_build): ny^2 + ny np doubles (the LU, a
 * transposed Jacobian) and ny ints (the pivots); 0 for sizes out of range. */
size_t inplane_build_work_doubles(int ny, int np);
size_t inplane_build_work_ints(int ny);

/* The ring's part at spin_rad_s. On a problem returns its status, with why (why_size > 0) a
 * sentence naming the parameter, its value and what is allowed, and writes nothing of out. */
int inplane_build_ring(const InPlaneBuildInput* in, double spin_rad_s, InPlaneBuildOutput* out,
                       double* work, int* iwork, char* why, size_t why_size);

/* The tread's part at spin_rad_s, from the ring's kg_, kgn_ and kgx_ parts in out (built at
 * any spin). Refuses as inplane_build_ring does. */
int inplane_build_tread(const InPlaneBuildInput* in, double spin_rad_s, InPlaneBuildOutput* out,
                        char* why, size_t why_size);

/* core/inplane.py's hysteresis_share: the hysteretic loss's share at this spin, in [-1, 1]
 * (linear up to SPEC_HYSTERESIS_FULL_SPEED_M_S of the tread, of the sign of the rolling). */
double inplane_hysteresis_share(double spin_rad_s, double radius_m);

/* Both at one spin: the simulator's _set_spin. */
int inplane_build(const InPlaneBuildInput* in, double spin_rad_s, InPlaneBuildOutput* out,
                  double* work, int* iwork, char* why, size_t why_size);

#endif
