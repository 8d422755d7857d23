/* inplane_step.h: one trapezoidal step of the in-plane tire on the road (inplane_step.c), and
 * the host road's window reads.
 *
 * What the step reads (InPlaneStep: the matrices the simulator, or inplane_model.c, built at
 * the current spin) and the state it steps (InPlaneState); inplane_step.c says what each is. */
#ifndef TIRE_INPLANE_STEP_H
#define TIRE_INPLANE_STEP_H

#include <stddef.h>

typedef struct {
    int ny, np, free_spin, max_passes, settle_passes;
    double h, mu, spin, dspin, dshare;
    const double *m, *c, *a0_inv, *yn, *yx, *wnn, *wnx, *kg, *kgn, *kgx, *gain, *carry;
    const double *jn, *jxw, *jl, *rim_inertia, *c1, *k1s, *k2, *kh;
    const double *kn, *cn, *kx, *cx, *pen0, *sec, *s0;
    /* the carry's stencils (carry_stencil: base, 4 weights per point), the step's shift in
     * spacings and the least entering fraction (entering_fractions, carry_edges) */
    const int* carry_base;
    const double* carry_weights;
    double carry_shift, min_entering;
    /* a driven wheel (the host gives its spin): the turn psi, the last coordinate, is psi_new
     * at the step's end, and a0_psi (ny) is the step matrix's column of it (a0_inv's row and
     * column of psi zero); unread for free and held wheels */
    int driven;
    double psi_new;
    const double* a0_psi;
} InPlaneStep;

typedef struct {
    double *y, *yd, *ydd, *e, *slip_sign, *f_n;
    int *contact, *stick;
} InPlaneState;

/* Workspace doubles and ints inplane_step needs for ny coordinates and np points. */
size_t inplane_work_doubles(int ny, int np);
size_t inplane_work_ints(int np);

/* One step from s to out (may not alias): 0, or 1 when the sets did not settle in
 * max_passes, 2 when a point solve was singular. height and rate: the road under each point
 * (the rim's z taken off), rim_old and rim: the rim's (x, vx, ax, z, vz, az) at the step's
 * start and end. */
int inplane_step(const InPlaneStep* d, const InPlaneState* s, InPlaneState* out,
                 const double* height, const double* rate, double torque,
                 const double* rim_old, const double* rim, double* work, int* iwork);

/* The host road's window reads (host_road_window_reads) are road_samples.h's. */
#include "road_samples.h"

#endif
