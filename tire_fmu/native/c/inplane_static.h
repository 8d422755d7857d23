/* inplane_static.h: the in-plane tire's static footprint for a load, in C.
 *
 * The arithmetic of tire_fmu/core/inplane_contact.py's InPlaneSimulator.static_state,
 * static_load_n and deflection_for_load: the tire pressed onto the flat road at rest,
 * frictionless, by the active-set solve of
 *     (K + Jn_A^T diag(kn_A) Jn_A) y = -Jn_A^T diag(kn_A) pen0_A(d),
 *     pen0(d) = R - (R - d) sec(theta_p),
 * over the set A of the points that push (from the points with pen0 > 0; a point in A stays
 * while its force kn pen is positive, a point out of it joins when its pen is); the load the
 * rim carries, Fz = -(row . y) with row the rim's Fz row of K on the coordinates at rest; and
 * the deflection that carries a load, by the core's secant. */
#ifndef TIRE_INPLANE_STATIC_H
#define TIRE_INPLANE_STATIC_H

#include <stddef.h>

/* The secant of deflection_for_load: its two starting deflections (m), its tolerance on the
 * load (relative) and its most iterations. */
#define INPLANE_STATIC_SECANT_LO_M 0.005
#define INPLANE_STATIC_SECANT_HI_M 0.04
#define INPLANE_STATIC_SECANT_TOLERANCE 1e-9
#define INPLANE_STATIC_SECANT_ITERATIONS 40

/* A built simulator's footprint at rest, on its ring coordinates (n_coords of them; row
 * major): what core/inplane_contact.py's static_state reads off it. */
typedef struct {
    int n_coords;             /* ring coordinates, 1 .. */
    int n_points;             /* contact points, 1 .. */
    const double* stiffness;  /* n_coords x n_coords: K at rest */
    const double* jn;         /* n_points x n_coords: d pen / d y */
    const double* kn;         /* n_points: the points' normal stiffness (N/m) */
    const double* sec;        /* n_points: sec of the points' angles */
    const double* rim_fz_row; /* n_coords: the rim's Fz row of K (Fz = -row . y) */
    double radius_m;          /* R (m), > 0 */
    int max_passes;           /* most active-set passes (the core's MAX_SET_PASSES), 1 .. */
} InPlaneStaticData;

enum {
    INPLANE_STATIC_OK = 0,
    INPLANE_STATIC_BAD_SIZE = 1,       /* n_coords, n_points or max_passes out of range */
    INPLANE_STATIC_NULL = 2,           /* a pointer missing */
    INPLANE_STATIC_BAD_DATA = 3,       /* a non-finite entry, or R <= 0 */
    INPLANE_STATIC_BAD_DEFLECTION = 4, /* the deflection non-finite, negative or >= R */
    INPLANE_STATIC_BAD_LOAD = 5,       /* the load non-finite or <= 0 */
    INPLANE_STATIC_SINGULAR = 6,       /* K, or a pass's set matrix, is singular */
    INPLANE_STATIC_UNSETTLED = 7,      /* the set did not settle in max_passes passes */
    INPLANE_STATIC_FLAT_SECANT = 8     /* the secant's two loads equal: no next deflection */
};

/* Doubles and ints of scratch the two functions need (n_coords^2 + n_points n_coords +
 * 2 n_points^2 + 4 (n_coords + n_points), and n_coords + 6 n_points); 0 for sizes out of
 * range. */
size_t inplane_static_work_doubles(int n_coords, int n_points);
size_t inplane_static_work_ints(int n_coords, int n_points);

/* The static state at deflection_m: y (n_coords), the set (active, n_points: 1 pushing, 0
 * not), the load (N) and the passes taken. Any output may be NULL. On a problem returns its
 * status, with why (why_size > 0) a sentence naming the parameter, its value and what is
 * allowed, and writes none of the outputs. */
int inplane_static_state(const InPlaneStaticData* data, double deflection_m, double* y,
                         int* active, double* load_n, int* passes, double* work, int* iwork,
                         char* why, size_t why_size);

/* The deflection (m) that carries load_n at rest, the core's secant from 0.005 and 0.04 m to
 * 1e-9 of the load in at most 40 iterations (the last one's deflection when none meets it, as
 * the core returns); the iterations taken (each a new deflection) into *iterations, and the
 * static state and set at the deflection (inplane_static_state's, without its second solve)
 * into y and active. Any output may be NULL; on a problem as inplane_static_state. */
int inplane_deflection_for_load(const InPlaneStaticData* data, double load_n,
                                double* deflection_m, int* iterations, double* y, int* active,
                                double* work, int* iwork, char* why, size_t why_size);

#endif
