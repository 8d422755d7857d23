/* inplane_model.h: the reduced in-plane step's whole set-up in one C call.
 *
 * What tests/test_inplane_c_assembly.py's CAssembled assembles from the bricks in Python, done
 * in C: the zone's nodes (contact.c) -> the Ritz basis of the held ring at rest
 * (inplane_ring.c, inplane_ritz.c) -> the spin terms on the step's coordinates
 * (inplane_terms.c) -> the points at deflection 0 (inplane_points.c) -> the deflection for the
 * load at rest (inplane_static.c) -> the points at that deflection, speed and spin -> the step's
 * matrices at the spin, the ring's and the tread's (inplane_build.c). The model owns every
 * array (memory from the caller's Memory, calloc and free for NULL); inplane_step.c steps with
 * them, and inplane_build_ring / inplane_build_tread rebuild them in place as the spin moves
 * (on build_in, into build). */
#ifndef TIRE_INPLANE_MODEL_H
#define TIRE_INPLANE_MODEL_H

#include <stddef.h>

#include "inplane_build.h"
#include "inplane_points.h"
#include "inplane_ring.h"
#include "inplane_terms.h"
#include "tire.h"

/* The active-set passes the static footprint may take (core/inplane_contact.py's
 * MAX_SET_PASSES). */
#define INPLANE_MODEL_MAX_SET_PASSES 50

typedef struct {
    InPlaneRingData tire;   /* the ring's data, as inplane_ring.h */
    double k_cw;            /* the tread's radial contact stiffness per metre (N/m^2): not
                               the ring's, so not in its data */
    int n_elements;         /* N, as inplane_ring.h */
    int n_fields;           /* the sidewall model, as inplane_ring.h */
    int wheel_free;         /* 1: the wheel's turn psi is a coordinate; 0: held */
    double f_max_hz;        /* the basis's highest mode (Hz), as inplane_ritz.h */
    double zone_length_m;   /* the contact zone's length (m), as inplane_points.h */
    double point_spacing_m; /* the points' largest spacing (m), as inplane_points.h */
    double load_n;          /* the load the deflection carries at rest (N), > 0 */
    double speed_m_s;       /* the road's speed against the axle (m/s) */
    double spin_rad_s;      /* the wheel's spin the step is built at (rad/s) */
    double step_s;          /* the step h (s), as inplane_build.h */
    int driven;             /* 1: the wheel's turn (wheel_free 1) is a host's, given
                               (inplane_build.h's driven); 0: free or held */
} InPlaneModelInput;

/* Sizes: n_dof = n_fields N (the ring's rim-relative DOFs), n_basis the Ritz columns r,
 * ny = r + wheel_free the step's coordinates, np the contact points, n_zone the zone nodes.
 * Row major. */
typedef struct {
    int n_elements, n_fields, wheel_free, n_dof, n_basis, ny, np, n_zone;
    int* zone_nodes;       /* n_zone ring node indices */
    double* basis;         /* (n_dof + wheel_free) x ny: the Ritz basis, psi appended free */
    InPlaneTermsOutput terms; /* as inplane_terms.h, on basis (to_abs (n_dof + 3) x ny) */
    double deflection_m;   /* carrying load_n at rest */
    int secant_iterations;
    double* static_y;      /* n_basis: the static state at rest at the deflection */
    double* rim_fz_row;    /* n_basis: the rim's Fz row of K at rest (Fz = -row . y) */
    InPlanePoints points;  /* at the deflection, speed and spin (np points) */
    double* point_theta;   /* np: the points' angles (contact.c's zone) */
    InPlaneBuildInput build_in; /* the build's input, into the arrays above */
    InPlaneBuildOutput build;   /* the step's matrices at spin_rad_s */
    const Memory* mem;     /* what the arrays came from (inplane_model_free returns them) */
} InPlaneModel;

enum {
    INPLANE_MODEL_OK = 0,
    INPLANE_MODEL_NULL = 1,       /* in, out or a field missing */
    INPLANE_MODEL_NO_MEMORY = 2,
    INPLANE_MODEL_RING = 3,       /* inplane_ring_build refused (why: its sentence) */
    INPLANE_MODEL_RITZ = 4,       /* inplane_ritz_build refused */
    INPLANE_MODEL_TERMS = 5,      /* inplane_terms_build refused */
    INPLANE_MODEL_POINTS = 6,     /* inplane_points_count / _build refused */
    INPLANE_MODEL_STATIC = 7,     /* inplane_deflection_for_load refused */
    INPLANE_MODEL_BUILD = 8       /* inplane_build refused */
};

/* Build out from in (mem NULL: calloc and free). On a problem returns its status, with why
 * (size > 0) the refusing brick's sentence (naming the parameter, its value and what is
 * allowed) after the brick's name, and leaves out empty (everything freed, all zero). */
int inplane_model_build(const InPlaneModelInput* in, InPlaneModel* out, const Memory* mem,
                        char* why, size_t size);

/* Return every array of a model (built, refused or zeroed) and zero it. */
void inplane_model_free(InPlaneModel* model);

#endif
