/* inplane_points.h: the in-plane simulator's contact points in C: their Jacobians on the
 * ring's coordinates and their data.
 *
 * The arithmetic of tire_fmu/core/inplane_contact.py's InPlaneSimulator._build for the points
 * (and _set_speed's s0), on the zone of contact.c's zone_build (core/contact.py's
 * contact_zone): with I the points' interpolation of the zone nodes, theta_p their angles,
 * on the unreduced coordinates y = [w (N), v (N), the sidewall's fields, psi when free]
 *     jn  = I on w                              (d pen / d y)
 *     jx  = -sin theta_p I on w, -cos theta_p I on v   (d x_p / d y)
 *     jnw = jn, jxw = jx with the psi column -R cos theta_p when the wheel is free
 *     jl  = jx[:, :2N] L,  L = [[D1, -kappa1 E], [kappa1 E, D1]] on the tread pair (w, v),
 *           D1 the central difference, kappa1 = sin(dtheta) / dtheta
 * each then times the basis (the coordinates the simulator steps: ring DOFs x r, with psi's
 * row and column when free; the identity for every DOF), and per point
 *     kn, cn (the zone's stiffness and damping), kx = k_tx arc, cx = beta kx,
 *     pen0 = R - (R - d) / cos theta_p, sec = 1 / cos theta_p, s0 = V - spin R cos theta_p. */
#ifndef TIRE_INPLANE_POINTS_H
#define TIRE_INPLANE_POINTS_H

#include <stddef.h>

#include "tire.h"

typedef struct {
    int n_elements;         /* N, 4 .. 100000 */
    int n_fields;           /* the ring's fields, w and v first: 2 .. 4 */
    int wheel_free;         /* 1: psi is a coordinate (the last row of the basis), 0: held */
    int n_coords;           /* the basis's columns r, 1 .. */
    const double* basis;    /* (n_fields N + wheel_free) x r, row major */
    double radius_m;        /* R > 0 */
    double k_cw;            /* the tread's radial stiffness per metre (N/m^2), >= 0 */
    double beta;            /* its damping's time constant (s), >= 0 */
    double k_tx;            /* the tread's fore-aft stiffness per metre (N/m^2), >= 0 */
    double zone_length_m;   /* the contact zone's length (m) */
    double point_spacing_m; /* the points' largest spacing (m) */
    double deflection_m;    /* the rim's deflection (m), in [0, R) */
    double speed_m_s;       /* the road's speed against the axle (m/s) */
    double spin_rad_s;      /* the tread's spin s0 is measured against (rad/s) */
} InPlanePointsInput;

/* Caller-owned outputs for n_points points: jn .. jl n_points x n_coords row major, the rest
 * n_points each. */
typedef struct {
    int n_points;
    double *jn, *jx, *jnw, *jxw, *jl;
    double *kn, *cn, *kx, *cx, *pen0, *sec, *s0;
} InPlanePoints;

enum {
    INPLANE_POINTS_OK = 0,
    INPLANE_POINTS_BAD_SIZE = 1,  /* n_elements, n_fields, n_coords, wheel_free or the points'
                                     count (n_points of the outputs) out of range */
    INPLANE_POINTS_NULL = 2,      /* a pointer missing */
    INPLANE_POINTS_BAD_DATA = 3,  /* a parameter non-finite or out of its range */
    INPLANE_POINTS_NO_MEMORY = 4
};

/* The number of points the input makes (checked as inplane_points_build checks it). On a
 * problem returns its status and, with why (why_size > 0), a sentence naming the parameter,
 * its value and what is allowed; *n_points is then left alone. */
int inplane_points_count(const InPlanePointsInput* in, int* n_points, char* why,
                         size_t why_size);

/* Fills out (out->n_points must be inplane_points_count's), with the zone's scratch from mem
 * (NULL: calloc and free). On a problem returns its status, with why as above, and writes
 * none of the outputs. */
int inplane_points_build(const InPlanePointsInput* in, const InPlanePoints* out,
                         const Memory* mem, char* why, size_t why_size);

#endif
