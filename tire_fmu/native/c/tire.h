/* tire.h: the tire model's parts, each the C of one module of tire_fmu.core:
 *   ring.c       free_ring.py, dispersion.py, standing_waves.py (the free ring, order by order)
 *   contact.c    contact.py (zone, contact points, static footprint by active-set continuation,
 *                road windows)
 *   road.c       road.py (the road under each node: history and delay line)
 *   kernel.c     kernel_numpy.py (the step, for either builder's contract: kernel.h)
 * Everything an instance needs is in its structs: no global mutable state. */
#ifndef TIRE_H
#define TIRE_H

#include <stddef.h>

#include "numerics.h"

/* the host's memory functions (FMI 2.0: calloc-like allocate, free) */
typedef struct {
    void* (*allocate)(size_t count, size_t size);
    void (*release)(void* pointer);
} Memory;

void* mem_alloc(const Memory* mem, size_t count, size_t size);
void mem_free(const Memory* mem, void* pointer);
const Memory* mem_default(void); /* calloc and free */

/* -- tire data and operating point ---------------------------------------------------------- */
typedef struct {
    double R, b, inflation_pressure, rhoA, m_s, k_r1, k_r2, EI, k_cw, alpha, beta;
    double sidewall_shear, sidewall_max_order, sidewall_pressure_exponent, reference_pressure;
} Tire;

double tire_stiffness_factor(const Tire* tire);  /* the pressure law's (p0/p_ref)^e */

/* -- the free ring (ring.c) ------------------------------------------------------------------ */
typedef struct {
    int n_elements, n_orders; /* orders n = 0 .. N/2 */
    int n_zone, half;         /* zone nodes m = -half .. half (offsets from the centre) */
    double dtheta, arc, spin;
    double mass[2];           /* node masses: tread, sidewall */
    int total_modes, n_modes; /* before and after truncation */
    /* kept modes, grouped by order: modes order_start[n] .. order_start[n + 1] - 1 */
    int* order_start;
    cx* lam;                  /* eigenvalue */
    cx* beta;                 /* b on zone force j = beta * e^{-i n theta_j} */
    cx* gamma;                /* c on w_j = gamma * e^{i n theta_j}; deflection -gamma */
    cx* eta;                  /* c on the rate of w_j = eta * e^{i n theta_j} */
    cx b_rim[4], c_rim[2][4]; /* order 1 only: b on rim_z, c of rim_Fz and rim_Fx */
    int first_rim;            /* index of the first order-1 mode, count rim_count */
    int rim_count;
    /* cos and sin of n * m * dtheta: trig[m * n_orders + n], m = 0 .. 2 half */
    double* cos_nm;
    double* sin_nm;
    /* direct terms and exact DC gain: rows rim_Fz, rim_Fx, deflection, w (Z), rate of w (Z);
     * columns rim_z, zone forces (Z); row major */
    int rows, cols;
    double* d;
    double* e;
    double* static_gain;
    int truncated;            /* d or e reach the zone forces: the forces couple at an instant */
} Ring;

typedef struct {
    double f_max_hz; /* 0: no cut */
    int n_modes;     /* 0: no limit */
    int static_correction;
} Truncation;

int ring_build(Ring* ring, const Memory* mem, const Tire* tire, int n_elements, double spin,
               int half, const Truncation* truncation);
void ring_free(Ring* ring, const Memory* mem);
/* order n's momentum-form state matrix A_n (4x4 row major) and its four modes as ring_build
 * takes them (canonical: free_ring.order_modes; eigenvectors are the columns of vectors):
 * tests/test_native_eig.py compares them with the core's. 0, or the eigen-solver's error. */
int ring_order_modes(const Tire* tire, int n_elements, double spin, int n, cx a[16],
                     cx values[4], cx vectors[16]);
/* G (Z x Z, m/N) from the static gain: w = -G f for zone forces f pushing inwards */
void ring_compliance(const Ring* ring, double* compliance);
/* the lowest speed at which a ground-frame frequency of the undeformed mesh reaches zero */
double critical_speed(const Tire* tire, int n_elements);

/* -- the contact zone, its contact points and the static footprint (contact.c) ------------ */
/* The zone nodes are the ring nodes the contact points read (offsets -half .. half); the
 * carrying nodes -carry .. carry are those whose unloaded ray meets the road within the zone
 * length. Each carrying node carries per_node contact points (odd; 1 reproduces the node
 * model: a point on each node, weight 1), each reading the ring at n_support zone nodes by
 * cubic Lagrange interpolation (4 nodes; 1 for per_node = 1), front (theta < 0) to rear. */
typedef struct {
    int n_zone, half, centre;  /* zone nodes; centre = the zone index of node 0 */
    int carry, per_node;       /* carrying nodes -carry .. carry, points per node m */
    int n_points, n_support, centre_point;
    double radius, dtheta;
    double* theta;     /* Z node angles */
    double* cos;       /* Z */
    double* sin;       /* Z */
    int* support;      /* P x S zone indices */
    double* weight;    /* P x S */
    double* point_theta; /* P: the point's ray angle */
    double* ray_cos;   /* P: cos of it (its gap to a flat road) */
    double* sec;       /* P: 1 / ray_cos */
    double* load_cos;  /* P: sum of weight x cos(theta_node): its force's vertical share */
    double* load_sin;  /* P: the same with sin: its force's fore-aft share */
    double stiffness;  /* k_p = k_cw a / m, the same for every point */
    double damping;    /* c_p = beta k_p */
} Zone;

int zone_half_count(double radius, int n_elements, double zone_length);
/* the smallest odd m with node_arc / m <= spacing (1 + SPEC_POINT_SPACING_SLACK) */
int points_per_node(double node_arc, double spacing);
/* 0, or -1 out of memory (nothing allocated then) */
int zone_build(Zone* zone, const Memory* mem, int n_elements, double radius, double k_cw,
               double beta, int carry, int per_node);
void zone_free(Zone* zone, const Memory* mem);

typedef struct {
    double deflection, load, length, front, rear, tangent;
    double* forces;      /* P */
    double* penetration; /* P */
    char* active;        /* P */
    double* x;           /* P: where each point's ray meets the road */
    double* node_w;      /* Z: the zone nodes' compression G I^T f (m) */
    int touches_edge;
} Footprint;

/* The continuation in the zone nodes' space: on a segment with active set A the node
 * compressions y = y0 + y1 d solve (I + G M_A) y = G b_A, M_A = sum_A k w w^T, b_A = sum_A k r w
 * (Woodbury: a Z x Z system however many points push), and every point's penetration is
 * r - I y, its force k times that where it pushes. */
typedef struct {
    int count, capacity;
    double* start;    /* deflection where each segment starts */
    char* active;     /* count x P */
    double* y0;       /* count x Z: node compressions y = y0 + y1 d */
    double* y1;
    double* w0;       /* load = w0 + w1 d */
    double* w1;
    double max_deflection;
} FootprintPath;

/* 0, or -1 (out of memory), or -2 (the continuation did not terminate) */
int footprint_path(FootprintPath* path, const Memory* mem, const Zone* zone,
                   const double* compliance, double max_deflection);
void footprint_path_free(FootprintPath* path, const Memory* mem);
int footprint_alloc(Footprint* fp, const Memory* mem, const Zone* zone);
void footprint_free(Footprint* fp, const Memory* mem);
void footprint_at_deflection(const FootprintPath* path, const Zone* zone, double deflection,
                             Footprint* out);
int footprint_at_load(const FootprintPath* path, const Zone* zone, double load,
                      Footprint* out); /* -1 beyond the path */
void max_credible_load(const FootprintPath* path, const Zone* zone, double max_length,
                       Footprint* out);
/* front and rear edge (road x) of the footprint */
void footprint_edges(const double* x, const double* penetration, const char* active, int n,
                     double* front, double* rear);

typedef struct {
    double* early; /* P: delays of each point's window ends from the zone front (s) */
    double* late;
    double front, horizon;
    int delayed;
} Windows;

/* each point's window is the road its sub-arc [theta_p -+ dtheta / 2m] covers */
int windows_build(Windows* w, const Memory* mem, const Zone* zone, double deflection,
                  double speed);
void windows_free(Windows* w, const Memory* mem);

/* -- the road under each node (road.c) ------------------------------------------------------- */
typedef struct {
    int size, count, start;
    double h, newest_time;
    int* index;      /* 2Z ends x 5: buffer positions relative to the newest sample's row */
    double* combine; /* 2Z ends x 5 weights on the mean (rows 0..Z-1), 2Z x 5 on the slope */
    double* buffer;  /* 6 size: [z, v h, C] twice */
} DelayLine;

typedef struct {
    const Windows* windows;
    int n;
    /* times are since origin (the simulator's start); only the same-step tolerances use
     * origin + now, the host's absolute clock (road.py) */
    double origin;
    /* the recorded history (used while no delay line runs) */
    int length, capacity;
    double* t;
    double* z;
    double* v;
    double* work;  /* capacity: cumulative integrals */
    DelayLine line;
    int line_on;
    double line_h;
    int uniform_run; /* -1: not known */
} RoadReader;

int road_init(RoadReader* road, const Memory* mem, const Windows* windows, int n);
void road_free(RoadReader* road, const Memory* mem);
void road_reset(RoadReader* road, const Memory* mem);
/* record the sample of now and write the road under each node; -1 out of memory */
int road_read(RoadReader* road, const Memory* mem, double now, double z, double vz, double h,
              double* heights, double* slopes);
/* the history as samples (t, z, v), oldest first; count samples */
int road_history_length(const RoadReader* road);
void road_history(const RoadReader* road, double* t, double* z, double* v);
/* drop the delay line, keep the history (what a restore of the history leaves) */
void road_rebuild(RoadReader* road, const Memory* mem);
int road_set_history(RoadReader* road, const Memory* mem, const double* t, const double* z,
                     const double* v, int count);

#endif
