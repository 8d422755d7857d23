/* kernel.c: stepping a step contract with the unilateral contact (kernel.h).
 *
 * The ring is linear and stepped exactly in its free modal basis with the rim motion and the
 * contact forces ramped over each substep; the end-of-substep contact forces solve the law with
 * the substep's own interface flexibility W (a primal-dual active-set iteration warm-started
 * from the last set, projected Gauss-Seidel if it cycles). The ring is read and loaded at the
 * zone nodes through the orders: the DFT of the node forces at the N/2 + 1 orders feeds each
 * mode, the modes of one order sum before the inverse DFT at the zone nodes, so a substep costs
 * O(K + N Z) and no mode x node table is ever formed. Contact points read the zone nodes
 * through their interpolation weights and give their forces back with the same weights. */
#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "kernel.h"
#include "road_samples.h"
#include "spec.h"

/* The points' interface is I W I^T of the zone nodes' W (I: the points' interpolation, P x Z,
 * S nonzero entries a row), so it is kept and applied in node space: O(P S + Z^2) a product
 * where the P x P matrix cost O(P^2). With S = U I^T (U = diag(k) I W_w + diag(c) I W_r), an
 * active set's block inverts through Z x Z (Woodbury): (I - U_A I_A^T)^-1
 * = I + U_A (I_Z - I_A^T U_A)^-1 I_A^T, the same nonzero spectrum, O(a S Z + Z^3) to make.
 * Only the nodes T the active points read have rows of I_A^T U_A, and I_A^T sigma_A lives on
 * them, so the Z x Z solve is its T x T block (the others' rows are the identity's). */
typedef struct {
    char* pattern;     /* P */
    int size;          /* T: the zone nodes the active points read */
    int singular;      /* the block is singular: its forces are kept zero */
    int* nodes;        /* T of them */
    double* inverse;   /* G = (I_T - (I_A^T U_A)_TT)^-1, T x T */
} KernelSolve;

#define SOLVE_CACHE 32  /* per interface; the inverse is recomputed identically when evicted */

typedef struct {
    double h;         /* the substep */
    double h_comm;    /* the communication step it belongs to */
    int n_sub;
    cx* decay;        /* K */
    cx* beta_c;       /* K: h (phi1 - phi2) beta, on the DFT of the forces at t */
    cx* beta_d;       /* K: h phi2 beta, on the DFT of the forces at t + h */
    cx* fused;        /* K: decay beta_d + beta_c: a pending end-force ramp into the next */
    cx* rim_z;        /* per rim mode: h phi1 b_rim */
    cx* rim_vz;       /* per rim mode: h^2 phi2 b_rim */
    double* w;        /* 2 Z x Z: W_w then W_r, the zone nodes' [p; p'] per unit end node force */
    double* s_diag;   /* P: S[j, j], the diagonal of the points' S = diag(k) W_p + diag(c) W_r */
    double* out_f;    /* 3 x P: ring outputs per unit end force */
    double* pen_const;  /* P: pen_static - W_p f_static */
    double* rate_const; /* P: -W_r f_static */
    KernelSolve* solves;
    int n_solves, next_solve;
} Interface;

struct TireKernel {
    Memory mem;
    /* the contract */
    int n_elements, n_orders, K, Z, P, S, half, linear, rows, cols;
    double substep_s, speed, static_deflection, min_step, substep_work;
    int centre;
    int32_t* order_start;
    cx *lam, *beta, *gamma, *eta;
    int n_rim;         /* modes with a rim coupling */
    int* rim_mode;     /* their indices */
    cx *b_rim, *c_rim; /* per rim mode: input of rim_z, rows rim_Fz and rim_Fx (2 n_rim) */
    double *d, *e;     /* rows x cols */
    int* support;      /* P x S, zone indices */
    double* weight;    /* P x S */
    double *cos, *sec, *x_road, *k, *c, *f_static, *pen_static;
    char* static_active;
    double static_ring[3];
    Windows windows;
    double *x_lo, *x_hi; /* P: each point's window of road, x from the wheel centre (m) */
    /* the road by position (kernel_set_road): its samples, read in place, and whether the
     * kernel reads the road so (else by time, through road) */
    int road_on;
    const double *road_s, *road_z, *road_at;
    int road_n;
    int road_guess;  /* where the last read's search ended (only speeds the next one up) */
    /* derived */
    double* cos_nm;    /* cos and sin of n m dtheta: [m * n_orders + n], m = 0 .. 2 half */
    double* sin_nm;
    double* pen_rim;   /* P: how the rim's position moves each point's penetration */
    double* rate_rim;  /* P: how the rim's rate moves its rate */
    int truncated;     /* d or e reach the zone forces: the forces couple at an instant */
    /* the state; its clock is the time since start_time (core/clock.py) */
    double start_time;
    double elapsed;    /* the road history's time */
    double carry;      /* the compensation of elapsed's sum */
    cx* q;
    double* df;        /* P: force deviation from static at time */
    char* active;
    double* penetration;
    double* rate;
    double seen_z, seen_vz;
    /* the rim's rate given at the last communication point, its last change over the step it
     * was made in and that step's length (0: none yet): the extension's history (host_inputs) */
    double given_vz, change, h_change;
    /* the road by position: the wheel centre's position along the road where the road was
     * read last (that of seen_heights) and the rate it was read at; the position's rate given
     * at the last communication point and its last change (over the same step as the rim's) */
    double seen_x, seen_vx, given_vx, change_vx;
    double* seen_heights;
    double* seen_slopes;
    double ring_out[3];
    double last_step;  /* the communication step whose end start() re-solves */
    int has_last;
    Interface* last;
    double outputs[KERNEL_N_OUTPUTS];
    RoadReader road;
    long solver_fallbacks;
    int fallback_only;  /* tests: every solve by the Gauss-Seidel fallback */
    /* derived, rebuilt on demand */
    Interface* kernels;
    int n_kernels, next_kernel;
    Interface instant;  /* a truncated ring couples the forces at an instant */
    int has_instant;
    cx* dft;            /* n_orders: DFT of the node forces of df (valid when dft_ok) */
    int dft_ok;
    /* the last substep's end-force ramp, not yet added to q: the modal state is
     * q + last->beta_d * dft (added in the next substep's pass over the modes) */
    int pending;
    /* scratch */
    double* work;
    int* iwork;
    char* cwork;
    cx* orders_a;
    cx* orders_b;
    double* heights;   /* P */
    double* slopes;
    double* node_a;    /* Z */
    double* node_b;    /* Z */
    double* node_c;    /* 4 Z: the node-space products of the contact solve */
};

#define D_AT(kn, row, col) (kn)->d[(size_t)(row) * (size_t)(kn)->cols + (size_t)(col)]
#define E_AT(kn, row, col) (kn)->e[(size_t)(row) * (size_t)(kn)->cols + (size_t)(col)]

/* -- points <-> zone nodes ----------------------------------------------------------------------- */

/* y_p = sum_s weight[p, s] x[support[p, s]] */
static void to_points(const TireKernel* kn, const double* node, double* point)
{
    int p, s, S = kn->S;
    for (p = 0; p < kn->P; p++) {
        double sum = 0.0;
        for (s = 0; s < S; s++) sum += kn->weight[p * S + s] * node[kn->support[p * S + s]];
        point[p] = sum;
    }
}

/* x_j = sum of weight[p, s] y_p over the points reading node j (the virtual work) */
static void to_nodes(const TireKernel* kn, const double* point, double* node)
{
    int p, s, S = kn->S;
    memset(node, 0, sizeof(double) * (size_t)kn->Z);
    for (p = 0; p < kn->P; p++) {
        if (point[p] == 0.0) continue;
        for (s = 0; s < S; s++) node[kn->support[p * S + s]] += kn->weight[p * S + s] * point[p];
    }
}

/* -- the orders <-> zone transforms ------------------------------------------------------------ */

/* F_n = sum_j e^{-i n theta_j} x_j for n = 0 .. N/2 */
static void zone_dft(const TireKernel* kn, const double* x, cx* out)
{
    int n_orders = kn->n_orders, half = kn->half, m, n;
    const double* centre = x + half;
    for (n = 0; n < n_orders; n++) out[n] = cx_make(centre[0], 0.0);
    for (m = 1; m <= half; m++) {
        double even = centre[m] + centre[-m], odd = centre[m] - centre[-m];
        const double* c = kn->cos_nm + (size_t)m * n_orders;
        const double* s = kn->sin_nm + (size_t)m * n_orders;
        if (even == 0.0 && odd == 0.0) continue;  /* nodes off the road push nothing */
        for (n = 0; n < n_orders; n++) {
            out[n].re += c[n] * even;
            out[n].im -= s[n] * odd;
        }
    }
}

/* y_j = sum_n Re(a_n e^{i n theta_j}) at the zone nodes */
static void zone_idft(const TireKernel* kn, const cx* a, double* y)
{
    int n_orders = kn->n_orders, half = kn->half, m, n;
    double* centre = y + half;
    for (m = 0; m <= half; m++) {
        const double* c = kn->cos_nm + (size_t)m * n_orders;
        const double* s = kn->sin_nm + (size_t)m * n_orders;
        double even = 0.0, odd = 0.0, even2 = 0.0, odd2 = 0.0;
        for (n = 0; n + 1 < n_orders; n += 2) {  /* two sums each: independent chains */
            even += a[n].re * c[n];
            odd += a[n].im * s[n];
            even2 += a[n + 1].re * c[n + 1];
            odd2 += a[n + 1].im * s[n + 1];
        }
        if (n < n_orders) {
            even += a[n].re * c[n];
            odd += a[n].im * s[n];
        }
        even += even2;
        odd += odd2;
        centre[m] = even - odd;
        centre[-m] = even + odd;
    }
}

/* T(delta) = sum_n Re(s_n e^{i n delta dtheta}), delta = -2 half .. 2 half */
static void toeplitz(const TireKernel* kn, const cx* s, double* out)
{
    int n_orders = kn->n_orders, half = kn->half, m, n;
    for (m = 0; m <= 2 * half; m++) {
        const double* c = kn->cos_nm + (size_t)m * n_orders;
        const double* si = kn->sin_nm + (size_t)m * n_orders;
        double even = 0.0, odd = 0.0;
        for (n = 0; n < n_orders; n++) {
            even += s[n].re * c[n];
            odd += s[n].im * si[n];
        }
        out[2 * half + m] = even - odd;
        out[2 * half - m] = even + odd;
    }
}

/* -- interfaces ---------------------------------------------------------------------------------- */

static void interface_free(Interface* k, const Memory* mem)
{
    int i;
    mem_free(mem, k->decay);
    mem_free(mem, k->beta_c);
    mem_free(mem, k->beta_d);
    mem_free(mem, k->fused);
    mem_free(mem, k->rim_z);
    mem_free(mem, k->rim_vz);
    mem_free(mem, k->w);
    mem_free(mem, k->s_diag);
    mem_free(mem, k->out_f);
    mem_free(mem, k->pen_const);
    mem_free(mem, k->rate_const);
    if (k->solves != NULL) {
        for (i = 0; i < k->n_solves; i++) {
            mem_free(mem, k->solves[i].pattern);
            mem_free(mem, k->solves[i].inverse);
            mem_free(mem, k->solves[i].nodes);
        }
        mem_free(mem, k->solves);
    }
    memset(k, 0, sizeof *k);
}

static int interface_alloc(Interface* k, const Memory* mem, int P, int Z)
{
    k->w = (double*)mem_alloc(mem, (size_t)(2 * Z) * (size_t)Z, sizeof(double));
    k->s_diag = (double*)mem_alloc(mem, (size_t)P, sizeof(double));
    k->out_f = (double*)mem_alloc(mem, (size_t)(3 * P), sizeof(double));
    k->pen_const = (double*)mem_alloc(mem, (size_t)P, sizeof(double));
    k->rate_const = (double*)mem_alloc(mem, (size_t)P, sizeof(double));
    k->solves = (KernelSolve*)mem_alloc(mem, SOLVE_CACHE, sizeof(KernelSolve));
    return (k->w && k->s_diag && k->out_f && k->pen_const && k->rate_const && k->solves) ? 0 : -1;
}

/* y_p = sum_s weight[p, s] x[support[p, s]] at one point */
static double point_read(const TireKernel* kn, int p, const double* node)
{
    int s, S = kn->S;
    double sum = 0.0;
    for (s = 0; s < S; s++) sum += kn->weight[p * S + s] * node[kn->support[p * S + s]];
    return sum;
}

/* out = W g for a Z x Z block W */
static void node_product(int Z, const double* w, const double* g, double* out)
{
    int i, l;
    for (i = 0; i < Z; i++) {
        const double* row = w + (size_t)i * Z;
        double sum = 0.0;
        for (l = 0; l < Z; l++) sum += row[l] * g[l];
        out[i] = sum;
    }
}

/* out = W g for g nonzero at nodes[0 .. n) only (values there: g[t], packed) */
static void node_product_at(int Z, const double* w, const int* nodes, const double* g, int n,
                            double* out)
{
    int i, t;
    for (i = 0; i < Z; i++) {
        const double* row = w + (size_t)i * Z;
        double sum = 0.0;
        for (t = 0; t < n; t++) sum += row[nodes[t]] * g[t];
        out[i] = sum;
    }
}

/* the interface from the node flexibilities (Z x Z) and the ring outputs per unit node force
 * (3 x Z): the node blocks kept, what the points need of them once (S's diagonal for the
 * fallback, the static forces' share, the outputs per unit point force) */
static void interface_rows(const TireKernel* kn, Interface* k, const double* w_w,
                           const double* w_r, const double* out_nodes)
{
    int P = kn->P, S = kn->S, Z = kn->Z, i, s, t, r;
    double* g = kn->node_c;
    double* uw = g + Z;
    double* ur = uw + Z;
    memcpy(k->w, w_w, sizeof(double) * (size_t)Z * (size_t)Z);
    memcpy(k->w + (size_t)Z * Z, w_r, sizeof(double) * (size_t)Z * (size_t)Z);
    for (i = 0; i < P; i++) {
        double wp = 0.0, wr = 0.0;
        for (s = 0; s < S; s++) {
            int a = kn->support[i * S + s];
            double wa = kn->weight[i * S + s];
            for (t = 0; t < S; t++) {
                int b = kn->support[i * S + t];
                double wb = wa * kn->weight[i * S + t];
                wp += wb * w_w[a * Z + b];
                wr += wb * w_r[a * Z + b];
            }
        }
        k->s_diag[i] = kn->k[i] * wp + kn->c[i] * wr;
    }
    to_nodes(kn, kn->f_static, g);
    node_product(Z, w_w, g, uw);
    node_product(Z, w_r, g, ur);
    for (i = 0; i < P; i++) {
        k->pen_const[i] = kn->pen_static[i] - point_read(kn, i, uw);
        k->rate_const[i] = -point_read(kn, i, ur);
    }
    for (r = 0; r < 3; r++) {
        for (i = 0; i < P; i++) k->out_f[r * P + i] = point_read(kn, i, out_nodes + r * Z);
    }
}

/* scratch for making an interface: tw, tr (4 half + 1 each), w_w, w_r (Z x Z), out (3 x Z) */
static size_t make_work(int Z, int half) { return (size_t)(2 * (4 * half + 1) + 2 * Z * Z + 3 * Z); }

static int make_interface(TireKernel* kn, Interface* k, double h)
{
    const Memory* mem = &kn->mem;
    int K = kn->K, Z = kn->Z, half = kn->half, n, j, l, i, r;
    cx* u = kn->orders_a;
    cx* v = kn->orders_b;
    double* tw = kn->work;
    double* tr = tw + (4 * half + 1);
    double* w_w = tr + (4 * half + 1);
    double* w_r = w_w + Z * Z;
    double* out = w_r + Z * Z;
    memset(k, 0, sizeof *k);
    k->h = h;
    k->decay = (cx*)mem_alloc(mem, (size_t)K, sizeof(cx));
    k->beta_c = (cx*)mem_alloc(mem, (size_t)K, sizeof(cx));
    k->beta_d = (cx*)mem_alloc(mem, (size_t)K, sizeof(cx));
    k->fused = (cx*)mem_alloc(mem, (size_t)K, sizeof(cx));
    k->rim_z = (cx*)mem_alloc(mem, (size_t)kn->n_rim, sizeof(cx));
    k->rim_vz = (cx*)mem_alloc(mem, (size_t)kn->n_rim, sizeof(cx));
    if (!k->decay || !k->beta_c || !k->beta_d || !k->fused || !k->rim_z || !k->rim_vz ||
        interface_alloc(k, mem, kn->P, kn->Z) != 0) {
        interface_free(k, mem);
        return -1;
    }
    for (n = 0; n < kn->n_orders; n++) {
        int q;
        u[n] = cx_make(0.0, 0.0);
        v[n] = cx_make(0.0, 0.0);
        for (q = kn->order_start[n]; q < kn->order_start[n + 1]; q++) {
            cx z = cx_scale(kn->lam[q], h), phi1, phi2, hphi2;
            phi_functions(z, SPEC_SERIES_LIMIT, &phi1, &phi2);
            k->decay[q] = cx_exp(z);
            hphi2 = cx_scale(phi2, h);
            k->beta_c[q] = cx_mul(cx_scale(cx_sub(phi1, phi2), h), kn->beta[q]);
            k->beta_d[q] = cx_mul(hphi2, kn->beta[q]);
            k->fused[q] = cx_add(cx_mul(k->decay[q], k->beta_d[q]), k->beta_c[q]);
            u[n] = cx_add(u[n], cx_mul(kn->gamma[q], k->beta_d[q]));
            v[n] = cx_add(v[n], cx_mul(kn->eta[q], k->beta_d[q]));
        }
    }
    for (r = 0; r < kn->n_rim; r++) {
        cx z = cx_scale(kn->lam[kn->rim_mode[r]], h), phi1, phi2;
        phi_functions(z, SPEC_SERIES_LIMIT, &phi1, &phi2);
        k->rim_z[r] = cx_mul(cx_scale(phi1, h), kn->b_rim[r]);
        k->rim_vz[r] = cx_mul(cx_scale(phi2, h * h), kn->b_rim[r]);
    }
    /* W = Re(C g_f) + D_f + E_f / h per unit end node force */
    toeplitz(kn, u, tw);
    toeplitz(kn, v, tr);
    for (i = 0; i < Z; i++) {
        for (l = 0; l < Z; l++) {
            w_w[i * Z + l] = tw[(i - l) + 2 * half] + D_AT(kn, 3 + i, 1 + l)
                             + E_AT(kn, 3 + i, 1 + l) / h;
            w_r[i * Z + l] = tr[(i - l) + 2 * half] + D_AT(kn, 3 + Z + i, 1 + l)
                             + E_AT(kn, 3 + Z + i, 1 + l) / h;
        }
    }
    for (l = 0; l < Z; l++) {
        double rows[2] = {0.0, 0.0};
        int m = l - half, idx = m < 0 ? -m : m;
        /* e^{-i theta_l}: conj of order 1's phase at the node */
        cx p = cx_make(kn->cos_nm[(size_t)idx * kn->n_orders + 1],
                       (m < 0 ? 1.0 : -1.0) * kn->sin_nm[(size_t)idx * kn->n_orders + 1]);
        for (r = 0; r < kn->n_rim; r++) {
            cx b = cx_mul(k->beta_d[kn->rim_mode[r]], p);
            rows[0] += cx_mul(kn->c_rim[2 * r], b).re;
            rows[1] += cx_mul(kn->c_rim[2 * r + 1], b).re;
        }
        for (j = 0; j < 2; j++) out[j * Z + l] = rows[j] + D_AT(kn, j, 1 + l)
                                                 + E_AT(kn, j, 1 + l) / h;
        out[2 * Z + l] = -tw[(0 - (l - half)) + 2 * half] + D_AT(kn, 2, 1 + l)
                         + E_AT(kn, 2, 1 + l) / h;
    }
    interface_rows(kn, k, w_w, w_r, out);
    return 0;
}

static int instant_interface(TireKernel* kn, Interface* k)
{
    int Z = kn->Z, i, l;
    double* w_w = kn->work;
    double* w_r = w_w + Z * Z;
    double* out = w_r + Z * Z;
    memset(k, 0, sizeof *k);
    if (interface_alloc(k, &kn->mem, kn->P, kn->Z) != 0) {
        interface_free(k, &kn->mem);
        return -1;
    }
    for (i = 0; i < Z; i++) {
        for (l = 0; l < Z; l++) {
            w_w[i * Z + l] = D_AT(kn, 3 + i, 1 + l);
            w_r[i * Z + l] = D_AT(kn, 3 + Z + i, 1 + l);
        }
    }
    for (l = 0; l < Z; l++) {
        for (i = 0; i < 3; i++) out[i * Z + l] = D_AT(kn, i, 1 + l);
    }
    interface_rows(kn, k, w_w, w_r, out);
    return 0;
}

/* the communication step h: its substep interface, from the cache (a step within rounding of
 * a cached one is that step) or made; NULL when out of memory */
static Interface* step_interface(TireKernel* kn, double h)
{
    int i, slot;
    /* only the step itself: a host's h jittered by its clock's rounding (far from t = 0 a few
     * distinct values) gets coefficients of its own, so the tire integrates exactly the time
     * the host's clock moved and a run reads the same from any start time */
    for (i = 0; i < kn->n_kernels; i++) {
        if (kn->kernels[i].h_comm == h) return &kn->kernels[i];
    }
    {
        Interface made;
        int n_sub = (int)ceil(h / kn->substep_s * (1 - SPEC_SUBSTEP_SLACK));
        if (n_sub < 1) n_sub = 1;
        if (make_interface(kn, &made, h / n_sub) != 0) return NULL;
        made.h_comm = h;
        made.n_sub = n_sub;
        if (kn->n_kernels < SPEC_KERNEL_CACHE_SIZE) {
            slot = kn->n_kernels++;
        } else {
            slot = kn->next_kernel;  /* the oldest, unless the last step's end needs it */
            if (&kn->kernels[slot] == kn->last) slot = (slot + 1) % SPEC_KERNEL_CACHE_SIZE;
            kn->next_kernel = (slot + 1) % SPEC_KERNEL_CACHE_SIZE;
            interface_free(&kn->kernels[slot], &kn->mem);
        }
        kn->kernels[slot] = made;
        return &kn->kernels[slot];
    }
}

/* -- the contact solve ---------------------------------------------------------------------- */

/* scratch of the solve: [0, SOLVE_BLOCK) for a Z x Z block and its inversion (or the
 * fallback's previous forces), then combined (3P) */
#define SOLVE_BLOCK(kn)                                                                        \
    ((size_t)(2 * (kn)->Z * (kn)->Z + (kn)->Z) > (size_t)(kn)->P                               \
         ? (size_t)(2 * (kn)->Z * (kn)->Z + (kn)->Z)                                           \
         : (size_t)(kn)->P)
#define SOLVE_WORK(kn) (SOLVE_BLOCK(kn) + (size_t)(3 * (kn)->P))
#define SOLVE_COMBINED(kn) ((kn)->work + SOLVE_BLOCK(kn))

/* f_A = (I - S_AA)^-1 sigma0_A into f (zeros elsewhere), through node space:
 * f_A = sigma0_A + U_A G I_A^T sigma0_A with G the pattern's, made once and cached; -1 out
 * of memory */
static int active_solve(TireKernel* kn, Interface* k, const char* active, const double* sigma0,
                        double* f)
{
    int P = kn->P, Z = kn->Z, S = kn->S, a = 0, i, j, e, s;
    int* index = kn->iwork;
    const double* w_w = k->w;
    const double* w_r = k->w + (size_t)Z * Z;
    double* g = kn->node_c;
    double* y = g + Z;
    double* uw = y + Z;
    double* ur = uw + Z;
    KernelSolve* entry = NULL;
    for (i = 0; i < P; i++) {
        f[i] = 0.0;
        if (active[i]) index[a++] = i;
    }
    if (a == 0) return 0;
    for (e = 0; e < k->n_solves; e++) {
        if (memcmp(k->solves[e].pattern, active, (size_t)P) == 0) {
            entry = &k->solves[e];
            break;
        }
    }
    if (entry == NULL) {
        double* block = kn->work;
        double* scratch;
        int* pivot = kn->iwork + 3 * P;
        int* nodes = pivot + Z;
        int* position = nodes + Z;  /* a node's place in T, or -1 */
        int t = 0, l;
        for (l = 0; l < Z; l++) position[l] = -1;
        for (e = 0; e < a; e++) {
            for (s = 0; s < S; s++) {
                int node = kn->support[index[e] * S + s];
                if (position[node] < 0) {
                    position[node] = t;
                    nodes[t++] = node;
                }
            }
        }
        scratch = block + t * t;
        if (k->n_solves < SOLVE_CACHE) {
            entry = &k->solves[k->n_solves++];
        } else {
            entry = &k->solves[k->next_solve];
            k->next_solve = (k->next_solve + 1) % SOLVE_CACHE;
            mem_free(&kn->mem, entry->pattern);
            mem_free(&kn->mem, entry->inverse);
            mem_free(&kn->mem, entry->nodes);
        }
        entry->pattern = (char*)mem_alloc(&kn->mem, (size_t)P, 1);
        entry->inverse = (double*)mem_alloc(&kn->mem, (size_t)(t * t), sizeof(double));
        entry->nodes = (int*)mem_alloc(&kn->mem, (size_t)t, sizeof(int));
        entry->size = t;
        entry->singular = 0;
        if (!entry->pattern || !entry->inverse || !entry->nodes) {
            mem_free(&kn->mem, entry->pattern);
            mem_free(&kn->mem, entry->inverse);
            mem_free(&kn->mem, entry->nodes);
            entry->pattern = NULL;
            entry->inverse = NULL;
            entry->nodes = NULL;
            k->n_solves--;
            return -1;
        }
        memcpy(entry->pattern, active, (size_t)P);
        memcpy(entry->nodes, nodes, sizeof(int) * (size_t)t);
        /* block = I_T - sum over active p of (I_p^T U_p)_TT, U_p = k_p I_p W_w + c_p I_p W_r */
        for (i = 0; i < t * t; i++) block[i] = 0.0;
        for (i = 0; i < t; i++) block[i * t + i] = 1.0;
        for (e = 0; e < a; e++) {
            int p = index[e];
            double* u = uw;  /* U_p on T, t */
            for (l = 0; l < t; l++) u[l] = 0.0;
            for (s = 0; s < S; s++) {
                const double* rw = w_w + (size_t)kn->support[p * S + s] * Z;
                const double* rr = w_r + (size_t)kn->support[p * S + s] * Z;
                double kw = kn->k[p] * kn->weight[p * S + s];
                double cw = kn->c[p] * kn->weight[p * S + s];
                for (l = 0; l < t; l++) u[l] += kw * rw[nodes[l]] + cw * rr[nodes[l]];
            }
            for (s = 0; s < S; s++) {
                double* row = block + (size_t)position[kn->support[p * S + s]] * t;
                double wt = kn->weight[p * S + s];
                for (l = 0; l < t; l++) row[l] -= wt * u[l];
            }
        }
        if (invert(block, t, entry->inverse, scratch, pivot) != 0) {
            /* a singular block: keep the entry usable (zero forces) rather than fail the step */
            entry->singular = 1;
        }
    }
    if (entry->singular) return 0;
    {
        int t = entry->size, l;
        int* position = kn->iwork + 3 * P + 2 * Z;
        for (l = 0; l < t; l++) position[entry->nodes[l]] = l;
        for (l = 0; l < t; l++) g[l] = 0.0;
        for (e = 0; e < a; e++) {
            int p = index[e];
            for (s = 0; s < S; s++) {
                g[position[kn->support[p * S + s]]] += kn->weight[p * S + s] * sigma0[p];
            }
        }
        for (j = 0; j < t; j++) {
            const double* row = entry->inverse + (size_t)j * t;
            double sum = 0.0;
            for (l = 0; l < t; l++) sum += row[l] * g[l];
            y[j] = sum;
        }
        node_product_at(Z, w_w, entry->nodes, y, t, uw);
        node_product_at(Z, w_r, entry->nodes, y, t, ur);
    }
    for (e = 0; e < a; e++) {
        int p = index[e];
        f[p] = sigma0[p] + kn->k[p] * point_read(kn, p, uw) + kn->c[p] * point_read(kn, p, ur);
    }
    return 0;
}

/* rows [first, last) of combined = base + M f in node space: g = I^T f over the nonzero
 * entries of f (the contact forces are zero off the few pushing points), W_w g and W_r g,
 * read at the points; combined may be base */
static void combine(const TireKernel* kn, const Interface* k, const double* base,
                    const double* f, double* combined, int first, int last)
{
    int P = kn->P, Z = kn->Z, S = kn->S, r, l, any = 0;
    double* g = kn->node_c;
    double* uw = g + Z;
    double* ur = uw + Z;
    for (l = 0; l < P && !any; l++) any = f[l] != 0.0;
    if (!any) {
        if (combined != base) {
            memcpy(combined + first, base + first, sizeof(double) * (size_t)(last - first));
        }
        return;
    }
    to_nodes(kn, f, g);
    {
        int* nodes = kn->iwork + 3 * P + Z;
        double* packed = ur + Z;
        int n = 0;
        for (l = 0; l < Z; l++) {
            if (g[l] != 0.0) {
                nodes[n] = l;
                packed[n++] = g[l];
            }
        }
        if (first < 2 * P) node_product_at(Z, k->w, nodes, packed, n, uw);
        if (first < P || last > 2 * P) {
            node_product_at(Z, k->w + (size_t)Z * Z, nodes, packed, n, ur);
        }
    }
    /* each point's reads once for the rows asked (the S row needs both) */
    for (r = 0; r < P; r++) {
        int want_s = first <= r && r < last, want_p = first <= P + r && P + r < last,
            want_r = first <= 2 * P + r && 2 * P + r < last;
        double wp = 0.0, wr = 0.0;
        if (want_s || (want_p && want_r)) {
            const int* support = kn->support + r * S;
            const double* weight = kn->weight + r * S;
            int t;
            for (t = 0; t < S; t++) {  /* both reads share the supports' loads */
                wp += weight[t] * uw[support[t]];
                wr += weight[t] * ur[support[t]];
            }
        } else if (want_p) {
            wp = point_read(kn, r, uw);
        } else if (want_r) {
            wr = point_read(kn, r, ur);
        }
        if (want_s) combined[r] = base[r] + kn->k[r] * wp + kn->c[r] * wr;
        if (want_p) combined[P + r] = base[P + r] + wp;
        if (want_r) combined[2 * P + r] = base[2 * P + r] + wr;
    }
}

/* projected Gauss-Seidel in node space: g = I^T f kept current as each f_j changes, the
 * rows of point j read through its S supports (O(S Z) a point) */
static void fallback(TireKernel* kn, const Interface* k, const double* base, double* f)
{
    int P = kn->P, Z = kn->Z, S = kn->S, sweep, j, l, s;
    const double* w_w = k->w;
    const double* w_r = k->w + (size_t)Z * Z;
    double* previous = kn->work;
    double* g = kn->node_c;
    kn->solver_fallbacks++;
    for (j = 0; j < P; j++) {
        double total = kn->f_static[j] + kn->df[j];
        f[j] = total > 0.0 ? total : 0.0;
    }
    to_nodes(kn, f, g);
    for (sweep = 0; sweep < SPEC_PGS_SWEEPS; sweep++) {
        double change = 0.0, biggest = 0.0;
        memcpy(previous, f, sizeof(double) * (size_t)P);
        for (j = 0; j < P; j++) {
            double wp = 0.0, wr = 0.0, pen, rest, now;
            for (s = 0; s < S; s++) {
                const double* rw = w_w + (size_t)kn->support[j * S + s] * Z;
                const double* rr = w_r + (size_t)kn->support[j * S + s] * Z;
                double sw = 0.0, sr = 0.0;
                for (l = 0; l < Z; l++) {
                    sw += rw[l] * g[l];
                    sr += rr[l] * g[l];
                }
                wp += kn->weight[j * S + s] * sw;
                wr += kn->weight[j * S + s] * sr;
            }
            pen = base[P + j] + wp;
            rest = base[j] + kn->k[j] * wp + kn->c[j] * wr - k->s_diag[j] * f[j];
            now = pen > 0.0 ? fmax(0.0, rest / (1.0 - k->s_diag[j])) : 0.0;
            if (now != f[j]) {
                for (s = 0; s < S; s++) {
                    g[kn->support[j * S + s]] += kn->weight[j * S + s] * (now - f[j]);
                }
                f[j] = now;
            }
        }
        for (j = 0; j < P; j++) {
            if (fabs(f[j] - previous[j]) > change) change = fabs(f[j] - previous[j]);
            if (fabs(f[j]) > biggest) biggest = fabs(f[j]);
        }
        if (change <= SPEC_PGS_TOLERANCE * fmax(1.0, biggest)) break;
    }
    for (j = 0; j < P; j++) kn->active[j] = (char)(f[j] > 0.0);
}

/* total forces with [sigma; p; p'] = base + M f and the law (or two-sided springs on the
 * static footprint for the linear law); combined (3P) receives base + M f */
static int solve(TireKernel* kn, Interface* k, const double* base, double* f, double* combined)
{
    int P = kn->P, iteration, j, limit = SPEC_ACTIVE_SET_PER_NODE * P + SPEC_ACTIVE_SET_EXTRA;
    char* active = kn->cwork;
    if (kn->linear) {
        if (active_solve(kn, k, kn->static_active, base, f) != 0) return -1;
        combine(kn, k, base, f, combined, 0, 3 * P);
        return 0;
    }
    memcpy(active, kn->active, (size_t)P);
    if (kn->fallback_only) limit = 0;
    for (iteration = 0; iteration < limit; iteration++) {
        int same = 1;
        if (active_solve(kn, k, active, base, f) != 0) return -1;
        /* all three rows at once: S's rows read W_r g already, so the rates cost P S more */
        combine(kn, k, base, f, combined, 0, 3 * P);
        for (j = 0; j < P; j++) {
            char now = (char)(combined[P + j] > 0.0 && combined[j] > 0.0);
            if (now != active[j]) same = 0;
            active[j] = now;
        }
        if (same) {
            memcpy(kn->active, active, (size_t)P);
            for (j = 0; j < P; j++) f[j] = fmax(f[j], 0.0);
            return 0;
        }
    }
    fallback(kn, k, base, f);
    combine(kn, k, base, f, combined, 0, 3 * P);
    return 0;
}

/* -- stepping ------------------------------------------------------------------------------- */

/* q += beta_d DFT(change) for point force changes; with the DFT of df known (ok) it is kept
 * current; returns ok */
static int add_dft_change(TireKernel* kn, const Interface* k, const double* change, int ok)
{
    cx* F = kn->orders_a;
    int n, q;
    to_nodes(kn, change, kn->node_a);
    zone_dft(kn, kn->node_a, F);
    for (n = 0; n < kn->n_orders; n++) {
        for (q = kn->order_start[n]; q < kn->order_start[n + 1]; q++) {
            kn->q[q] = cx_add(kn->q[q], cx_mul(k->beta_d[q], F[n]));
        }
        if (ok) kn->dft[n] = cx_add(kn->dft[n], F[n]);
    }
    return ok;
}

/* the step's arrays, after the solve's scratch */
#define STEP_WORK(kn) ((kn)->work + SOLVE_WORK(kn))

/* forces at time for the inputs given at time: the last substep's end solved again with the
 * inputs given now (the penetrations move with the inputs' change, geometry at an instant,
 * and with the end forces through the step's own flexibility) */
static int start(TireKernel* kn, double z, double vz, const double* heights,
                 const double* slopes)
{
    int P = kn->P, j, i;
    double dz = z - kn->seen_z, dvz = vz - kn->seen_vz;
    double* base = STEP_WORK(kn);  /* 3P */
    double* f = base + 3 * P;
    double* change = f + P;
    double* pen = change + P;
    double* rate = pen + P;
    Interface* k = NULL;
    int dft_ok = kn->dft_ok;
    for (j = 0; j < P; j++) {
        pen[j] = kn->penetration[j] + kn->pen_rim[j] * dz
                 + kn->sec[j] * (heights[j] - kn->seen_heights[j]);
        rate[j] = kn->rate[j] + kn->rate_rim[j] * dvz
                  + kn->sec[j] * (slopes[j] - kn->seen_slopes[j]);
    }
    for (i = 0; i < 3; i++) kn->ring_out[i] += D_AT(kn, i, 0) * dz + E_AT(kn, i, 0) * dvz;
    if (kn->has_last) k = kn->last;
    else if (!kn->linear && kn->has_instant) k = &kn->instant;
    if (k != NULL) {
        double* combined = SOLVE_COMBINED(kn);  /* the solve's own, free after it */
        for (j = 0; j < P; j++) {
            change[j] = kn->f_static[j] + kn->df[j];  /* f_old for now */
            base[j] = kn->k[j] * pen[j] + kn->c[j] * rate[j];
            base[P + j] = pen[j];
            base[2 * P + j] = rate[j];
        }
        {
            double* minus = combined;  /* base - M f_old = (base + M (-f_old)) */
            for (j = 0; j < P; j++) minus[j] = -change[j];
            combine(kn, k, base, minus, base, 0, 3 * P);
        }
        if (solve(kn, k, base, f, combined) != 0) return -1;
        for (j = 0; j < P; j++) change[j] = f[j] - change[j];
        if (kn->has_last) {
            if (kn->pending) {
                /* q + beta_d DFT(df) stays the state: the change enters through the DFT */
                cx* F = kn->orders_a;
                int n;
                to_nodes(kn, change, kn->node_a);
                zone_dft(kn, kn->node_a, F);
                for (n = 0; n < kn->n_orders; n++) kn->dft[n] = cx_add(kn->dft[n], F[n]);
            } else {
                dft_ok = add_dft_change(kn, k, change, dft_ok);
            }
        }
        for (i = 0; i < 3; i++) {
            double sum = 0.0;
            for (j = 0; j < P; j++) sum += k->out_f[i * P + j] * change[j];
            kn->ring_out[i] += sum;
        }
        for (j = 0; j < P; j++) {
            pen[j] = combined[P + j];
            rate[j] = combined[2 * P + j];
        }
    } else if (kn->linear) {
        for (j = 0; j < P; j++) {
            f[j] = kn->static_active[j]
                       ? kn->f_static[j] + kn->k[j] * (pen[j] - kn->pen_static[j])
                             + kn->c[j] * rate[j]
                       : 0.0;
        }
    } else {
        for (j = 0; j < P; j++) {  /* the law at an instant */
            double push = kn->k[j] * pen[j] + kn->c[j] * rate[j];
            f[j] = pen[j] > 0.0 ? fmax(push, 0.0) : 0.0;
            kn->active[j] = (char)(f[j] > 0.0);
        }
    }
    for (j = 0; j < P; j++) {
        kn->df[j] = f[j] - kn->f_static[j];
        kn->penetration[j] = pen[j];
        kn->rate[j] = rate[j];
        kn->seen_heights[j] = heights[j];
        kn->seen_slopes[j] = slopes[j];
    }
    kn->seen_z = z;
    kn->seen_vz = vz;
    kn->dft_ok = kn->pending || (k != NULL && kn->has_last && dft_ok);
    return 0;
}

/* one substep of length k->h with the rim at z moving at vz (on its chord) and at vz_end at
 * its end; the road under the points at its end in kn->heights and kn->slopes (their rates) */
static int substep(TireKernel* kn, Interface* k, double z, double vz, double vz_end)
{
    int P = kn->P, Z = kn->Z, n, q, j, i, l, rows = kn->rows;
    double h = k->h;
    double* base = STEP_WORK(kn);
    double* f = base + 3 * P;
    double* df_end = f + P;
    double* y = df_end + P;          /* ring rows at the nodes: rows */
    double* w_pt = y + rows;         /* P */
    double* r_pt = w_pt + P;         /* P */
    double* combined = SOLVE_COMBINED(kn);
    cx* A = kn->orders_a;
    cx* B = kn->orders_b;
    cx* F = kn->dft;
    double rim[2] = {0.0, 0.0}, deflection = 0.0;
    if (!kn->dft_ok) {
        to_nodes(kn, kn->df, kn->node_a);
        zone_dft(kn, kn->node_a, F);
        kn->dft_ok = 1;
    }
    /* the free response at t + h: decay, the rim's ramp, the forces at t held to their ramp */
    if (kn->pending && kn->last != k) {  /* another interface's ramp: add it first */
        for (n = 0; n < kn->n_orders; n++) {
            for (q = kn->order_start[n]; q < kn->order_start[n + 1]; q++) {
                kn->q[q] = cx_add(kn->q[q], cx_mul(kn->last->beta_d[q], F[n]));
            }
        }
        kn->pending = 0;
    }
    {
        /* one pass: the last ramp (pending) and this one's start forces held to their ramp,
         * decayed, then read at the zone through the orders */
        const cx* into = kn->pending ? k->fused : k->beta_c;
        for (n = 0; n < kn->n_orders; n++) {
            double ar = 0.0, ai = 0.0, br = 0.0, bi = 0.0, fr = F[n].re, fi = F[n].im;
            for (q = kn->order_start[n]; q < kn->order_start[n + 1]; q++) {
                const cx d = k->decay[q], c = into[q], x = kn->q[q];
                const cx g = kn->gamma[q], e = kn->eta[q];
                double vr = d.re * x.re - d.im * x.im + c.re * fr - c.im * fi;
                double vi = d.re * x.im + d.im * x.re + c.re * fi + c.im * fr;
                kn->q[q].re = vr;
                kn->q[q].im = vi;
                ar += g.re * vr - g.im * vi;
                ai += g.re * vi + g.im * vr;
                br += e.re * vr - e.im * vi;
                bi += e.re * vi + e.im * vr;
            }
            A[n] = cx_make(ar, ai);
            B[n] = cx_make(br, bi);
            deflection -= ar;
        }
    }
    for (i = 0; i < kn->n_rim; i++) {
        int m = kn->rim_mode[i], o = 0;
        cx add = cx_add(cx_scale(k->rim_z[i], z), cx_scale(k->rim_vz[i], vz));
        kn->q[m] = cx_add(kn->q[m], add);
        /* its share of its order's sums */
        while (kn->order_start[o + 1] <= m) o++;
        A[o] = cx_add(A[o], cx_mul(kn->gamma[m], add));
        B[o] = cx_add(B[o], cx_mul(kn->eta[m], add));
        deflection -= cx_mul(kn->gamma[m], add).re;
    }
    for (i = 0; i < kn->n_rim; i++) {
        int m = kn->rim_mode[i];
        rim[0] += cx_mul(kn->c_rim[2 * i], kn->q[m]).re;
        rim[1] += cx_mul(kn->c_rim[2 * i + 1], kn->q[m]).re;
    }
    zone_idft(kn, A, y + 3);
    zone_idft(kn, B, y + 3 + Z);
    y[0] = rim[0];
    y[1] = rim[1];
    y[2] = deflection;
    /* direct terms: D r(t + h) + E r' with r = [z + h vz, forces held]; on the forces only
     * when the truncation reaches them */
    for (i = 0; i < rows; i++) {
        y[i] += D_AT(kn, i, 0) * (z + h * vz) + E_AT(kn, i, 0) * vz_end;
    }
    if (kn->truncated) {
        double* node_df = kn->node_b;
        to_nodes(kn, kn->df, node_df);
        for (i = 0; i < rows; i++) {
            double sum = 0.0;
            for (l = 0; l < Z; l++) sum += E_AT(kn, i, 1 + l) * node_df[l];
            y[i] -= sum / h;
        }
    }
    to_points(kn, y + 3, w_pt);
    to_points(kn, y + 3 + Z, r_pt);
    /* the interface at t + h for zero total end forces: [sigma0; p0; p0'] */
    for (j = 0; j < P; j++) {
        double sec = kn->sec[j];
        double p = w_pt[j] - sec * (z + h * vz) + sec * kn->heights[j] + k->pen_const[j];
        double r = r_pt[j] - sec * vz_end + sec * kn->slopes[j] + k->rate_const[j];
        base[j] = kn->k[j] * p + kn->c[j] * r;
        base[P + j] = p;
        base[2 * P + j] = r;
    }
    if (solve(kn, k, base, f, combined) != 0) return -1;
    for (j = 0; j < P; j++) df_end[j] = f[j] - kn->f_static[j];
    /* the end forces' ramp into the modes: pending until the next pass */
    to_nodes(kn, df_end, kn->node_a);
    zone_dft(kn, kn->node_a, F);
    kn->pending = 1;
    for (i = 0; i < 3; i++) {
        double sum = 0.0;
        for (j = 0; j < P; j++) sum += k->out_f[i * P + j] * df_end[j];
        kn->ring_out[i] = y[i] + sum;
    }
    for (j = 0; j < P; j++) {
        kn->df[j] = df_end[j];
        kn->penetration[j] = combined[P + j];
        kn->rate[j] = combined[2 * P + j];
        kn->seen_heights[j] = kn->heights[j];
        kn->seen_slopes[j] = kn->slopes[j];
    }
    kn->seen_z = z + h * vz;
    kn->seen_vz = vz_end;
    kn->last = k;
    kn->dft_ok = 1;  /* F holds the DFT of df */
    return 0;
}

/* -- outputs ---------------------------------------------------------------------------------- */

/* front and rear edge (road x) where the penetration, interpolated linearly between the
 * outermost pushing point and its neighbour outside, crosses zero (contact._edges) */
static double crossing(const double* x, const double* pen, int inner, int outer, int n)
{
    double p_in, p_out, share;
    if (outer < 0 || outer >= n) return x[inner];
    p_in = pen[inner];
    p_out = pen[outer];
    /* a neighbour that penetrates without pushing puts the edge at the neighbour, a point
     * that pushes from above the road (the linear law's two-sided spring) at itself: the
     * footprint is never shorter than its pushing points' span (contact._edges) */
    share = p_in > fmax(p_out, 0.0) ? fmin(p_in / (p_in - p_out), 1.0) : 0.0;
    return x[inner] + share * (x[outer] - x[inner]);
}

static double contact_length(const TireKernel* kn)
{
    int P = kn->P, first = -1, last = -1, j;
    for (j = 0; j < P; j++) {
        if (kn->f_static[j] + kn->df[j] > 0.0) {
            if (first < 0) first = j;
            last = j;
        }
    }
    if (first < 0) return 0.0;
    return crossing(kn->x_road, kn->penetration, first, first - 1, P)
           - crossing(kn->x_road, kn->penetration, last, last + 1, P);
}

static void update_outputs(TireKernel* kn)
{
    int P = kn->P, j;
    double contact = 0.0;
    for (j = 0; j < P; j++) contact += kn->cos[j] * (kn->f_static[j] + kn->df[j]);
    kn->outputs[0] = kn->static_ring[0] + kn->ring_out[0];
    kn->outputs[1] = kn->static_ring[1] + kn->ring_out[1];
    kn->outputs[2] = contact;
    /* the rim's lowering at the contact centre: the static one, the road's rise under the
     * centre point, less the rim's (core: ContactSimulator.deflection) */
    kn->outputs[3] = kn->static_deflection + kn->seen_heights[kn->centre] - kn->seen_z;
    kn->outputs[4] = contact_length(kn);
    kn->outputs[5] = kn->static_ring[2] + kn->ring_out[2];
}

void kernel_outputs(const TireKernel* kn, double outputs[KERNEL_N_OUTPUTS])
{
    memcpy(outputs, kn->outputs, sizeof kn->outputs);
}

int kernel_in_contact(const TireKernel* kn) { return kn->outputs[2] > 0.0; }

int kernel_at_zone_edge(const TireKernel* kn)
{
    int P = kn->P;
    return kn->df[0] > -kn->f_static[0] || kn->df[P - 1] > -kn->f_static[P - 1];
}

double kernel_time(const TireKernel* kn) { return kn->start_time + kn->elapsed; }

double kernel_start_time(const TireKernel* kn) { return kn->start_time; }

double kernel_elapsed(const TireKernel* kn) { return kn->elapsed; }

double kernel_min_step(const TireKernel* kn) { return kn->min_step; }

double kernel_horizon(const TireKernel* kn) { return kn->windows.horizon; }

long kernel_solver_fallbacks(const TireKernel* kn) { return kn->solver_fallbacks; }
void kernel_set_fallback_only(TireKernel* kn, int on) { kn->fallback_only = on != 0; }

int kernel_cached_steps(const TireKernel* kn) { return kn->n_kernels; }

int kernel_delay_line_on(const TireKernel* kn) { return kn->road.line_on; }

void kernel_forces(const TireKernel* kn, double* forces)
{
    int j;
    for (j = 0; j < kn->P; j++) forces[j] = kn->f_static[j] + kn->df[j];
}

/* why a step is refused (kernel.h's bits); at: a step with the road by position, whose
 * inputs are rim_z, rim_vz, x, vx */
static int step_problems(const TireKernel* kn, double h, const double inputs[KERNEL_N_INPUTS],
                         int at)
{
    int problems = 0, i;
    if (!(h > 0.0 && h <= DBL_MAX)) {
        problems |= KERNEL_BAD_H;  /* also nan */
    } else if (h < kn->min_step) {
        problems |= KERNEL_SHORT_H;
    } else if (!clock_resolves(kn->start_time + kn->elapsed, h)) {
        problems |= KERNEL_UNRESOLVED_H;
    } else if (ceil(h / kn->substep_s * (1 - SPEC_SUBSTEP_SLACK)) * kn->substep_work >
               SPEC_MAX_STEP_WORK) {
        problems |= KERNEL_LONG_H;
    }
    for (i = 0; i < KERNEL_N_INPUTS; i++) {
        double limit = i % 2 ? SPEC_MAX_VELOCITY_M_S
                             : (at && i == KERNEL_INPUT_X ? SPEC_MAX_ROAD_POSITION_M
                                                          : SPEC_MAX_DISPLACEMENT_M);
        if (!(fabs(inputs[i]) <= limit)) problems |= KERNEL_BAD_INPUT << i;
    }
    if (at != kn->road_on) problems |= KERNEL_OTHER_ROAD;
    return problems;
}

int kernel_step_problems(const TireKernel* kn, double h, const double inputs[KERNEL_N_INPUTS])
{
    return step_problems(kn, h, inputs, 0);
}

int kernel_step_at_problems(const TireKernel* kn, double h,
                            const double inputs[KERNEL_N_INPUTS])
{
    return step_problems(kn, h, inputs, 1);
}

static void fill_report(const TireKernel* kn, double report[KERNEL_REPORT])
{
    if (report == NULL) return;
    memcpy(report, kn->outputs, sizeof kn->outputs);
    report[KERNEL_REPORT_TIME] = kn->start_time + kn->elapsed;
    report[KERNEL_REPORT_ZONE_EDGE] = kernel_at_zone_edge(kn) ? 1.0 : 0.0;
}

/* core/host_inputs.py's rate_changes: the acceleration and jerk at the communication point
 * from the rate's last two changes (zero without the history) */
static void rate_changes(double rate, double rate_before, double h_before, double change_before,
                         double h_change_before, double* acceleration, double* jerk)
{
    double change;
    *acceleration = *jerk = 0.0;
    if (!(h_before > 0.0)) return;
    change = (rate - rate_before) / h_before;
    *acceleration = change;
    if (!(h_change_before > 0.0)) return;
    *jerk = (change - change_before) / (0.5 * (h_before + h_change_before));
    *acceleration = change + 0.5 * h_before * *jerk;
}

/* input_path's position and rate at tau into the step */
static double path_position(double value, double rate, double acceleration, double jerk,
                            double tau)
{
    return value + tau * (rate + tau * (0.5 * acceleration + tau * jerk / 6.0));
}

static double path_rate(double rate, double acceleration, double jerk, double tau)
{
    return rate + tau * (acceleration + 0.5 * tau * jerk);
}

/* core/host_inputs.py's on_grid: h as the whole number of grid steps it is to within the
 * resolution of the host's clock at time, else h */
static double on_grid(double h, double grid, double time)
{
    double count = nearbyint(h / grid), at = fabs(time) + h;
    double slack = fmin(fmax(1e-9 * h, 2.0 * (nextafter(at, INFINITY) - at)),
                        0.25 * grid);
    return count >= 1.0 && fabs(count * grid - h) <= slack ? count * grid : h;
}

/* the road by position under the points with the wheel centre at x moving at vx along it,
 * into kn->heights and kn->slopes (core/obstacles.py's sampled_window_reads) */
static void read_road_at(TireKernel* kn, double x, double vx)
{
    road_samples_window_reads(kn->road_s, kn->road_z, kn->road_at, kn->road_n, kn->x_lo,
                              kn->x_hi, kn->P, x, vx, kn->heights, kn->slopes, &kn->road_guess);
    kn->seen_x = x;
    kn->seen_vx = vx;
}

/* one communication step of h with the road by time (at = 0: inputs rim_z, rim_vz, road_z,
 * road_vz) or by position (at = 1: rim_z, rim_vz, x, vx) */
static int advance(TireKernel* kn, double h, const double inputs[KERNEL_N_INPUTS], int at,
                   double report[KERNEL_REPORT])
{
    Interface* k;
    int i, j;
    double h_before, accel, jerk, accel_x = 0.0, jerk_x = 0.0, z0, z1;
    if (step_problems(kn, h, inputs, at) != 0) return KERNEL_REFUSED;
    /* a host's h that is a whole number of substeps to its clock's resolution is that number:
     * the tire's clock stays on its grid from any start time */
    h = on_grid(h, kn->substep_s, kn->start_time + kn->elapsed);
    k = step_interface(kn, h);
    if (k == NULL) return KERNEL_NO_MEMORY;
    /* the inputs extended over the step (core/host_inputs.py) */
    h_before = kn->has_last ? kn->last_step : 0.0;
    rate_changes(inputs[1], kn->given_vz, h_before, kn->change, kn->h_change, &accel, &jerk);
    if (at) {
        rate_changes(inputs[3], kn->given_vx, h_before, kn->change_vx, kn->h_change, &accel_x,
                     &jerk_x);
        read_road_at(kn, inputs[2], inputs[3]);
    } else if (road_read(&kn->road, &kn->mem, kn->elapsed, inputs[2], inputs[3], h,
                         kn->heights, kn->slopes) != 0) {
        return KERNEL_NO_MEMORY;
    }
    z0 = inputs[0];
    z1 = path_position(inputs[0], inputs[1], accel, jerk, k->h);
    if (start(kn, z0, inputs[1], kn->heights, kn->slopes) != 0) return KERNEL_NO_MEMORY;
    for (i = 0; i < k->n_sub; i++) {
        double tau = (i + 1) * k->h;
        if (i > 0) {
            z0 = z1;
            z1 = path_position(inputs[0], inputs[1], accel, jerk, tau);
        }
        if (at) {
            /* the road at the substep's end, the wheel centre there on its path along the
             * road moving at the path's rate: the road resolved at each substep's travel */
            read_road_at(kn, path_position(inputs[2], inputs[3], accel_x, jerk_x, tau),
                         path_rate(inputs[3], accel_x, jerk_x, tau));
        } else {
            /* the road ramps on at its rate from the communication point */
            for (j = 0; j < kn->P; j++) kn->heights[j] += k->h * kn->slopes[j];
        }
        /* the ring integrated on the chord; the rate at the substep's end in the direct terms
         * and the penetrations' rates */
        if (substep(kn, k, z0, (z1 - z0) / k->h, path_rate(inputs[1], accel, jerk, tau)) != 0)
            return KERNEL_NO_MEMORY;
    }
    kn->change = h_before > 0.0 ? (inputs[1] - kn->given_vz) / h_before : 0.0;
    kn->given_vz = inputs[1];
    if (at) {
        kn->change_vx = h_before > 0.0 ? (inputs[3] - kn->given_vx) / h_before : 0.0;
        kn->given_vx = inputs[3];
    }
    kn->h_change = h_before;
    {   /* elapsed += h, compensated (core/clock.py: advance) */
        double y = h - kn->carry, total = kn->elapsed + y;
        kn->carry = (total - kn->elapsed) - y;
        kn->elapsed = total;
    }
    kn->last_step = h;
    kn->has_last = 1;
    update_outputs(kn);
    fill_report(kn, report);
    return KERNEL_OK;
}

int kernel_step(TireKernel* kn, double h, const double inputs[KERNEL_N_INPUTS],
                double report[KERNEL_REPORT])
{
    return advance(kn, h, inputs, 0, report);
}

int kernel_step_at(TireKernel* kn, double h, const double inputs[KERNEL_N_INPUTS],
                   double report[KERNEL_REPORT])
{
    return advance(kn, h, inputs, 1, report);
}

/* the outputs at kernel_time for inputs given there, the road by time or by position (at) */
static int outputs_for(TireKernel* kn, const double inputs[KERNEL_N_INPUTS], int at,
                       double report[KERNEL_REPORT])
{
    double h = kn->has_last ? kn->last_step : NAN;
    if ((step_problems(kn, 1.0, inputs, at) &
         ~(KERNEL_SHORT_H | KERNEL_UNRESOLVED_H | KERNEL_LONG_H)) != 0) {
        return KERNEL_REFUSED;  /* the inputs alone are checked: there is no step */
    }
    if (at) {
        read_road_at(kn, inputs[2], inputs[3]);
    } else if (road_read(&kn->road, &kn->mem, kn->elapsed, inputs[2], inputs[3], h,
                         kn->heights, kn->slopes) != 0) {
        return KERNEL_NO_MEMORY;
    }
    if (start(kn, inputs[0], inputs[1], kn->heights, kn->slopes) != 0) return KERNEL_NO_MEMORY;
    update_outputs(kn);
    fill_report(kn, report);
    return KERNEL_OK;
}

int kernel_outputs_with(TireKernel* kn, const double inputs[KERNEL_N_INPUTS],
                        double report[KERNEL_REPORT])
{
    return outputs_for(kn, inputs, 0, report);
}

int kernel_outputs_at(TireKernel* kn, const double inputs[KERNEL_N_INPUTS],
                      double report[KERNEL_REPORT])
{
    return outputs_for(kn, inputs, 1, report);
}

int kernel_set_road(TireKernel* kn, const double* s, const double* z, const double* at, int n,
                    char* why, size_t why_size)
{
    char text[256] = "", a[40], b[40];
    int i;
    if (n < 0 || (n > 0 && (s == NULL || z == NULL || at == NULL))) {
        snprintf(text, sizeof text, "the road's samples: %d of them, or an array missing (a "
                 "count >= 0 and three arrays of it)", n);
    } else if (!kn->road_on && kn->has_last) {
        snprintf(text, sizeof text, "this kernel has read the road by time: a road by "
                 "position is set before its first step or after a reset");
    }
    for (i = 0; i < n && text[0] == '\0'; i++) {
        if (!(fabs(s[i]) <= DBL_MAX) || (i > 0 && !(s[i] > s[i - 1]))) {
            py_repr(s[i], a, sizeof a);
            py_repr(i > 0 ? s[i - 1] : -INFINITY, b, sizeof b);
            snprintf(text, sizeof text, "the road's sample %d is at %s m, after %s m: its "
                     "positions must be finite and increase", i, a, b);
        } else if (!(fabs(z[i]) <= SPEC_MAX_STATE_DISPLACEMENT_M) || !(fabs(at[i]) <= DBL_MAX)) {
            py_repr(z[i], a, sizeof a);
            py_repr(at[i], b, sizeof b);
            snprintf(text, sizeof text, "the road's sample %d has the height %s m and the "
                     "integral %s m^2: a height is finite and within %g m", i, a, b,
                     SPEC_MAX_STATE_DISPLACEMENT_M);
        }
    }
    if (why != NULL && why_size > 0) snprintf(why, why_size, "%s", text);
    if (text[0] != '\0') return KERNEL_REFUSED;
    kn->road_on = 1;
    kn->road_s = s;
    kn->road_z = z;
    kn->road_at = at;
    kn->road_n = n;
    kn->road_guess = n / 2;
    return KERNEL_OK;
}

int kernel_road_on(const TireKernel* kn) { return kn->road_on; }

double kernel_road_position(const TireKernel* kn) { return kn->seen_x; }

/* q with the pending ramp added (the state the reference kernel holds) */
static void settle(TireKernel* kn)
{
    int n, q;
    if (!kn->pending) return;
    for (n = 0; n < kn->n_orders; n++) {
        for (q = kn->order_start[n]; q < kn->order_start[n + 1]; q++) {
            kn->q[q] = cx_add(kn->q[q], cx_mul(kn->last->beta_d[q], kn->dft[n]));
        }
    }
    kn->pending = 0;
}

void kernel_reset(TireKernel* kn, double start_time)
{
    int P = kn->P, K = kn->K, j;
    kn->start_time = start_time;
    kn->elapsed = 0.0;
    kn->carry = 0.0;
    for (j = 0; j < K; j++) kn->q[j] = cx_make(0.0, 0.0);
    for (j = 0; j < P; j++) {
        kn->df[j] = 0.0;
        kn->active[j] = kn->static_active[j];
        kn->penetration[j] = kn->pen_static[j];
        kn->rate[j] = 0.0;
        kn->seen_heights[j] = 0.0;
        kn->seen_slopes[j] = 0.0;
    }
    kn->seen_z = kn->seen_vz = 0.0;
    kn->given_vz = kn->change = kn->h_change = 0.0;
    kn->seen_x = kn->seen_vx = kn->given_vx = kn->change_vx = 0.0;
    kn->ring_out[0] = kn->ring_out[1] = kn->ring_out[2] = 0.0;
    kn->last = NULL;
    kn->has_last = 0;
    kn->last_step = 0.0;
    kn->dft_ok = 0;
    kn->pending = 0;
    road_reset(&kn->road, &kn->mem);
    kn->road.origin = start_time;
    update_outputs(kn);
}

/* -- making a kernel from a contract ---------------------------------------------------------- */

static int layout_problem(const TireContract* c, char* why, size_t why_size)
{
    int j, p, s;
    if (c->version != TIRE_CONTRACT_VERSION) {
        snprintf(why, why_size, "the contract is of version %u, this kernel reads %u",
                 c->version, TIRE_CONTRACT_VERSION);
        return 1;
    }
    if (c->n_elements < 1 || c->n_orders != c->n_elements / 2 + 1 || c->n_modes < 0 ||
        c->n_zone < 1 || c->n_zone % 2 != 1 || c->n_points < 1 || c->n_support < 1 ||
        c->n_ring_rows != 3 + 2 * c->n_zone || c->n_ring_cols != 1 + c->n_zone ||
        !(c->substep_s > 0.0) || c->centre_point < 0 || c->centre_point >= c->n_points ||
        c->substep_work < 1) {
        snprintf(why, why_size, "the contract's sizes are inconsistent");
        return 1;
    }
    if (c->order_start[0] != 0 || c->order_start[c->n_orders] != c->n_modes) {
        snprintf(why, why_size, "order_start must run from 0 to n_modes");
        return 1;
    }
    for (j = 0; j < c->n_orders; j++) {
        if (c->order_start[j + 1] < c->order_start[j]) {
            snprintf(why, why_size, "order_start must not decrease");
            return 1;
        }
    }
    for (j = 0; j < c->n_zone; j++) {
        if (c->zone_offset[j] != j - c->n_zone / 2) {
            snprintf(why, why_size, "the zone must be the nodes -half .. half about the centre");
            return 1;
        }
    }
    for (p = 0; p < c->n_points; p++) {
        for (s = 0; s < c->n_support; s++) {
            int node = c->point_support[p * c->n_support + s];
            if (node < 0 || node >= c->n_zone) {
                snprintf(why, why_size, "point %d reads zone node %d, of %d", p, node,
                         c->n_zone);
                return 1;
            }
        }
    }
    return 0;
}

/* a copy of count elements of size bytes each, in *to; nonzero when out of memory */
static int copy_out(const Memory* mem, void** to, const void* from, size_t count, size_t size)
{
    *to = mem_alloc(mem, count, size);
    if (*to == NULL) return 1;
    if (count) memcpy(*to, from, count * size);
    return 0;
}

#define COPY(field, from, count) \
    copy_out(mem, (void**)&kn->field, c->from, (size_t)(count), sizeof *kn->field)

void kernel_destroy(TireKernel* kn)
{
    Memory mem;
    int i;
    if (kn == NULL) return;
    mem = kn->mem;
    if (kn->kernels != NULL) {
        for (i = 0; i < kn->n_kernels; i++) interface_free(&kn->kernels[i], &mem);
    }
    if (kn->has_instant) interface_free(&kn->instant, &mem);
    road_free(&kn->road, &mem);
    mem_free(&mem, kn->windows.early);
    mem_free(&mem, kn->windows.late);
    mem_free(&mem, kn->order_start);
    mem_free(&mem, kn->lam);
    mem_free(&mem, kn->beta);
    mem_free(&mem, kn->gamma);
    mem_free(&mem, kn->eta);
    mem_free(&mem, kn->rim_mode);
    mem_free(&mem, kn->b_rim);
    mem_free(&mem, kn->c_rim);
    mem_free(&mem, kn->d);
    mem_free(&mem, kn->e);
    mem_free(&mem, kn->support);
    mem_free(&mem, kn->weight);
    mem_free(&mem, kn->cos);
    mem_free(&mem, kn->sec);
    mem_free(&mem, kn->x_road);
    mem_free(&mem, kn->x_lo);
    mem_free(&mem, kn->x_hi);
    mem_free(&mem, kn->k);
    mem_free(&mem, kn->c);
    mem_free(&mem, kn->f_static);
    mem_free(&mem, kn->pen_static);
    mem_free(&mem, kn->static_active);
    mem_free(&mem, kn->cos_nm);
    mem_free(&mem, kn->sin_nm);
    mem_free(&mem, kn->pen_rim);
    mem_free(&mem, kn->rate_rim);
    mem_free(&mem, kn->q);
    mem_free(&mem, kn->df);
    mem_free(&mem, kn->active);
    mem_free(&mem, kn->penetration);
    mem_free(&mem, kn->rate);
    mem_free(&mem, kn->seen_heights);
    mem_free(&mem, kn->seen_slopes);
    mem_free(&mem, kn->kernels);
    mem_free(&mem, kn->dft);
    mem_free(&mem, kn->work);
    mem_free(&mem, kn->iwork);
    mem_free(&mem, kn->node_c);
    mem_free(&mem, kn->cwork);
    mem_free(&mem, kn->orders_a);
    mem_free(&mem, kn->orders_b);
    mem_free(&mem, kn->heights);
    mem_free(&mem, kn->slopes);
    mem_free(&mem, kn->node_a);
    mem_free(&mem, kn->node_b);
    mem_free(&mem, kn);
}

int kernel_create(const TireContract* c, const Memory* mem, double start_time,
                  TireKernel** out, char* why, size_t why_size)
{
    TireKernel* kn;
    int K, Z, P, S, j, n, r, i;
    size_t work;
    *out = NULL;
    if (layout_problem(c, why, why_size)) return KERNEL_BAD_CONTRACT;
    kn = (TireKernel*)mem_alloc(mem, 1, sizeof(TireKernel));
    if (kn == NULL) return KERNEL_NO_MEMORY;
    memset(kn, 0, sizeof *kn);
    kn->mem = *mem;
    mem = &kn->mem;
    kn->n_elements = c->n_elements;
    kn->n_orders = c->n_orders;
    kn->K = K = c->n_modes;
    kn->Z = Z = c->n_zone;
    kn->P = P = c->n_points;
    kn->S = S = c->n_support;
    kn->half = Z / 2;
    kn->linear = c->linear;
    kn->rows = c->n_ring_rows;
    kn->cols = c->n_ring_cols;
    kn->substep_s = c->substep_s;
    kn->speed = c->speed_m_s;
    kn->static_deflection = c->static_deflection_m;
    kn->min_step = c->min_step_s;
    kn->centre = c->centre_point;
    kn->substep_work = c->substep_work;
    for (j = 0; j < 3; j++) kn->static_ring[j] = c->static_ring_out[j];
    if (COPY(order_start, order_start, kn->n_orders + 1) || COPY(lam, lam, K) ||
        COPY(beta, beta, K) || COPY(gamma, gamma, K) || COPY(eta, eta, K) ||
        COPY(d, d, kn->rows * kn->cols) || COPY(e, e, kn->rows * kn->cols) ||
        COPY(weight, point_weight, P * S) || COPY(cos, point_cos, P) ||
        COPY(sec, point_sec, P) || COPY(x_road, point_x_road, P) ||
        COPY(x_lo, window_lo_m, P) || COPY(x_hi, window_hi_m, P) ||
        COPY(k, point_stiffness, P) || COPY(c, point_damping, P) ||
        COPY(f_static, f_static, P) || COPY(pen_static, pen_static, P)) {
        goto memory;
    }
    kn->support = (int*)mem_alloc(mem, (size_t)(P * S), sizeof(int));
    if (kn->support == NULL) goto memory;
    for (j = 0; j < P * S; j++) kn->support[j] = c->point_support[j];
    /* the rim's modes: those with a rim coupling (order 1 by the contract's convention) */
    kn->rim_mode = (int*)mem_alloc(mem, (size_t)K, sizeof(int));
    kn->b_rim = (cx*)mem_alloc(mem, (size_t)K, sizeof(cx));
    kn->c_rim = (cx*)mem_alloc(mem, (size_t)(2 * K), sizeof(cx));
    if (!kn->rim_mode || !kn->b_rim || !kn->c_rim) goto memory;
    for (j = 0; j < K; j++) {
        cx b = c->b_rim[j], fz = c->c_rim[j], fx = c->c_rim[K + j];
        if (b.re != 0.0 || b.im != 0.0 || fz.re != 0.0 || fz.im != 0.0 || fx.re != 0.0 ||
            fx.im != 0.0) {
            kn->rim_mode[kn->n_rim] = j;
            kn->b_rim[kn->n_rim] = b;
            kn->c_rim[2 * kn->n_rim] = fz;
            kn->c_rim[2 * kn->n_rim + 1] = fx;
            kn->n_rim++;
        }
    }
    kn->static_active = (char*)mem_alloc(mem, (size_t)P, 1);
    if (kn->static_active == NULL) goto memory;
    for (j = 0; j < P; j++) kn->static_active[j] = (char)(kn->f_static[j] > 0.0);
    /* the road windows */
    kn->windows.early = (double*)mem_alloc(mem, (size_t)P, sizeof(double));
    kn->windows.late = (double*)mem_alloc(mem, (size_t)P, sizeof(double));
    if (!kn->windows.early || !kn->windows.late) goto memory;
    for (j = 0; j < P; j++) {
        kn->windows.early[j] = c->window_early_s[j];
        kn->windows.late[j] = c->window_late_s[j];
        if (kn->windows.late[j] > kn->windows.horizon) kn->windows.horizon = kn->windows.late[j];
        if (kn->windows.late[j] > 0.0) kn->windows.delayed = 1;
    }
    /* the phases e^{i n m dtheta}, m = 0 .. 2 half, from the table of e^{2 pi i k / N} */
    kn->cos_nm = (double*)mem_alloc(mem, (size_t)((2 * kn->half + 1) * kn->n_orders),
                                    sizeof(double));
    kn->sin_nm = (double*)mem_alloc(mem, (size_t)((2 * kn->half + 1) * kn->n_orders),
                                    sizeof(double));
    if (!kn->cos_nm || !kn->sin_nm) goto memory;
    for (j = 0; j <= 2 * kn->half; j++) {
        for (n = 0; n < kn->n_orders; n++) {
            long index = ((long)n * (long)j) % kn->n_elements;
            double angle = 2.0 * 3.14159265358979323846 * (double)index / kn->n_elements;
            double co = cos(angle), si = sin(angle);
            if (index == 0) si = 0.0;
            if (2 * index == kn->n_elements) {  /* e^{i pi}: exactly real */
                co = -1.0;
                si = 0.0;
            }
            kn->cos_nm[(size_t)j * kn->n_orders + n] = co;
            kn->sin_nm[(size_t)j * kn->n_orders + n] = si;
        }
    }
    /* how the rim's own motion moves the points' penetrations and rates at an instant */
    kn->pen_rim = (double*)mem_alloc(mem, (size_t)P, sizeof(double));
    kn->rate_rim = (double*)mem_alloc(mem, (size_t)P, sizeof(double));
    if (!kn->pen_rim || !kn->rate_rim) goto memory;
    for (j = 0; j < P; j++) {
        double pd = 0.0, pe = 0.0;
        for (i = 0; i < S; i++) {
            int node = kn->support[j * S + i];
            pd += kn->weight[j * S + i] * D_AT(kn, 3 + node, 0);
            pe += kn->weight[j * S + i] * E_AT(kn, 3 + Z + node, 0);
        }
        kn->pen_rim[j] = pd - kn->sec[j];
        kn->rate_rim[j] = pe - kn->sec[j];
    }
    for (r = 0; r < kn->rows && !kn->truncated; r++) {
        for (j = 1; j < kn->cols; j++) {
            if (D_AT(kn, r, j) != 0.0 || E_AT(kn, r, j) != 0.0) {
                kn->truncated = 1;
                break;
            }
        }
    }
    /* the state and scratch */
    work = SOLVE_WORK(kn) + (size_t)(3 * P + 3 * P + kn->rows + 2 * P);
    if (make_work(Z, kn->half) > work) work = make_work(Z, kn->half);
#define ALLOC(field, count, type) \
    (kn->field = (type*)mem_alloc(mem, (size_t)(count), sizeof(type))) == NULL
    if (ALLOC(q, K, cx) || ALLOC(df, P, double) || ALLOC(active, P, char) ||
        ALLOC(penetration, P, double) || ALLOC(rate, P, double) ||
        ALLOC(seen_heights, P, double) || ALLOC(seen_slopes, P, double) ||
        ALLOC(kernels, SPEC_KERNEL_CACHE_SIZE, Interface) || ALLOC(dft, kn->n_orders, cx) ||
        ALLOC(work, work, double) || ALLOC(iwork, 3 * P + 3 * Z, int) || ALLOC(cwork, 2 * P, char) ||
        ALLOC(orders_a, kn->n_orders, cx) || ALLOC(orders_b, kn->n_orders, cx) ||
        ALLOC(heights, P, double) || ALLOC(slopes, P, double) || ALLOC(node_a, Z, double) ||
        ALLOC(node_b, Z, double) || ALLOC(node_c, 4 * Z, double)) {
        goto memory;
    }
#undef ALLOC
    if (kn->truncated) {
        if (instant_interface(kn, &kn->instant) != 0) goto memory;
        kn->has_instant = 1;
    }
    if (road_init(&kn->road, mem, &kn->windows, P) != 0) goto memory;
    kernel_reset(kn, start_time);
    *out = kn;
    return KERNEL_OK;
memory:
    kernel_destroy(kn);
    snprintf(why, why_size, "out of memory making the step kernel (%d modes, %d points)", K, P);
    return KERNEL_NO_MEMORY;
}
#undef COPY

/* -- the kernel's state -------------------------------------------------------------------------
 * int32: K, P, history length, has_last; then doubles: start time, elapsed time, its carry,
 * last step, seen z and z', ring_out (3), outputs (6), the rim's rate given last, its last
 * change and that change's step, the road by position's seen x and x' (where the road was read
 * last), the x rate given last and its last change (all 0 with the road by time), q (2K), df,
 * penetration, rate, seen
 * heights, seen slopes (P each), history t, z, v; then the active flags (P bytes). All
 * little-endian as x86-64 and arm64 write them; the numpy kernel writes the same bytes. */

#define STATE_INTS 4
#define STATE_HEAD 22

static const char* const OUTPUT_NAMES[KERNEL_N_OUTPUTS] = {
    "rim_Fz", "rim_Fx", "contact_Fz", "deflection", "contact_length", "tread_deflection"};

static size_t doubles_for(int K, int P, int history)
{
    return (size_t)(STATE_HEAD + 2 * K + 5 * P + 3 * history);
}

size_t kernel_state_size(const TireKernel* kn)
{
    int history = road_history_length(&kn->road);
    return STATE_INTS * 4 + doubles_for(kn->K, kn->P, history) * 8 + (size_t)kn->P;
}

static void put_int(unsigned char** out, int value)
{
    int32_t v = (int32_t)value;
    memcpy(*out, &v, 4);
    *out += 4;
}

static void put_doubles(unsigned char** out, const double* values, int count)
{
    memcpy(*out, values, sizeof(double) * (size_t)count);
    *out += sizeof(double) * (size_t)count;
}

void kernel_state_write(TireKernel* kn, unsigned char* out)
{
    int K = kn->K, P = kn->P, history = road_history_length(&kn->road);
    double head[STATE_HEAD];
    /* what the state holds is what the kernel continues from: the modal state with its
     * pending ramp added, the forces' DFT computed again and the road's delay line rebuilt
     * from its history, as a restore does, so a restored run is the same run, bit for bit */
    settle(kn);
    kn->dft_ok = 0;
    road_rebuild(&kn->road, &kn->mem);
    put_int(&out, K);
    put_int(&out, P);
    put_int(&out, history);
    put_int(&out, kn->has_last);
    head[0] = kn->start_time;
    head[1] = kn->elapsed;
    head[2] = kn->carry;
    head[3] = kn->has_last ? kn->last_step : 0.0;
    head[4] = kn->seen_z;
    head[5] = kn->seen_vz;
    memcpy(head + 6, kn->ring_out, sizeof(double) * 3);
    memcpy(head + 9, kn->outputs, sizeof(double) * KERNEL_N_OUTPUTS);
    head[15] = kn->given_vz;
    head[16] = kn->change;
    head[17] = kn->h_change;
    head[18] = kn->seen_x;
    head[19] = kn->seen_vx;
    head[20] = kn->given_vx;
    head[21] = kn->change_vx;
    put_doubles(&out, head, STATE_HEAD);
    put_doubles(&out, (const double*)kn->q, 2 * K);
    put_doubles(&out, kn->df, P);
    put_doubles(&out, kn->penetration, P);
    put_doubles(&out, kn->rate, P);
    put_doubles(&out, kn->seen_heights, P);
    put_doubles(&out, kn->seen_slopes, P);
    road_history(&kn->road, (double*)out, (double*)out + history, (double*)out + 2 * history);
    out += sizeof(double) * (size_t)(3 * history);
    memcpy(out, kn->active, (size_t)P);
}

static int get_int(const unsigned char* in, int index)
{
    int32_t v;
    memcpy(&v, in + 4 * index, 4);
    return (int)v;
}

/* double number index of the state's doubles (they may be unaligned in the bytes) */
static double get_double(const unsigned char* in, size_t index)
{
    double v;
    memcpy(&v, in + STATE_INTS * 4 + 8 * index, 8);
    return v;
}

double kernel_state_time(const unsigned char* in) { return get_double(in, 0) + get_double(in, 1); }

double kernel_state_start(const unsigned char* in) { return get_double(in, 0); }

void kernel_state_outputs(const unsigned char* in, double outputs[KERNEL_N_OUTPUTS])
{
    int i;
    for (i = 0; i < KERNEL_N_OUTPUTS; i++) outputs[i] = get_double(in, 9 + (size_t)i);
}

/* the problems found so far, "; " between them (as the core joins them) */
static void add_why(char* why, size_t why_size, const char* text)
{
    size_t used = strlen(why);
    if (used + 2 >= why_size) return;
    snprintf(why + used, why_size - used, "%s%s", used ? "; " : "", text);
}

static double largest_abs(const unsigned char* in, size_t first, int count)
{
    double big = 0.0;
    int i;
    for (i = 0; i < count; i++) big = fmax(big, fabs(get_double(in, first + (size_t)i)));
    return big;
}


/* the road history as the reader keeps it (core: kernel_numpy.history_problems) */
static void history_problems(const TireKernel* kn, const unsigned char* in, size_t t0,
                             int history, double now, double last, int has_last, char* why,
                             size_t why_size)
{
    const Windows* w = &kn->windows;
    double slack = SPEC_SAME_POINT_EPS * (fabs(now) + w->horizon + 1.0), newest, earliest;
    char text[512];
    int i, increasing = 1;
    if (kn->road_on) {
        if (history > 0) {
            snprintf(text, sizeof text, "its road history holds %d samples, but this kernel "
                     "reads the road by position and keeps none", history);
            add_why(why, why_size, text);
        }
        return;
    }
    if (!w->delayed) {
        if (history > 0) {
            snprintf(text, sizeof text, "its road history holds %d samples, but at rest the "
                     "whole zone reads the road at the instant and keeps none", history);
            add_why(why, why_size, text);
        }
        return;
    }
    if (history > SPEC_MAX_HISTORY_SAMPLES) {
        snprintf(text, sizeof text, "its road history holds %d samples; the FMU keeps at most "
                 "%d (one a step, over at most %d steps)", history, SPEC_MAX_HISTORY_SAMPLES,
                 SPEC_MAX_DELAY_STEPS);
        add_why(why, why_size, text);
        return;
    }
    for (i = 1; i < history; i++) {
        if (!(get_double(in, t0 + (size_t)i) > get_double(in, t0 + (size_t)i - 1))) increasing = 0;
    }
    if (!increasing) add_why(why, why_size, "its road history times do not increase");
    if (history > 0) {
        newest = get_double(in, t0 + (size_t)history - 1);
        earliest = now - (has_last ? last : 0.0);
        if (!(earliest - slack <= newest && newest <= now + slack)) {
            char a[40], b[40], c[40];
            py_repr(newest, a, sizeof a);
            py_repr(now, b, sizeof b);
            py_repr(has_last ? last : NAN, c, sizeof c);
            snprintf(text, sizeof text, "its newest road sample is at %s s, but the state is at "
                     "%s s after a step of %s s: the road is sampled at each step's start", a, b,
                     c);
            add_why(why, why_size, text);
        }
        if (get_double(in, t0) < -slack) {
            char a[40];
            py_repr(get_double(in, t0), a, sizeof a);
            snprintf(text, sizeof text, "its road history starts at %s s, before the start", a);
            add_why(why, why_size, text);
        }
        if (history > 1 && get_double(in, t0 + 1) < newest - w->horizon - slack) {
            snprintf(text, sizeof text, "its road history reaches back %.6g s from its newest "
                     "sample, beyond the %.6g s the contact zone reads (older samples are "
                     "dropped)", newest - get_double(in, t0 + 1), w->horizon);
            add_why(why, why_size, text);
        }
    } else if (has_last) {
        add_why(why, why_size, "its road history is empty, but a step was taken (each step "
                "samples the road at its start)");
    }
    if (!(largest_abs(in, t0 + (size_t)history, history) <= SPEC_MAX_DISPLACEMENT_M &&
          largest_abs(in, t0 + 2 * (size_t)history, history) <= SPEC_MAX_VELOCITY_M_S)) {
        snprintf(text, sizeof text, "its road samples go beyond the inputs' limits (%g m, %g "
                 "m/s)", SPEC_MAX_DISPLACEMENT_M, SPEC_MAX_VELOCITY_M_S);
        add_why(why, why_size, text);
    }
}

/* the road by position's part of the head: where the road was read, within what a host gives;
 * none with the road by time (core: kernel_numpy._position_problems) */
static void position_problems(const TireKernel* kn, const unsigned char* in, char* why,
                              size_t why_size)
{
    double x = get_double(in, 18), vx = get_double(in, 19), given = get_double(in, 20);
    double change = get_double(in, 21);
    char text[512], a[40], b[40], c[40];
    py_repr(x, a, sizeof a);
    py_repr(vx, b, sizeof b);
    py_repr(given, c, sizeof c);
    if (kn->road_on) {
        if (!(fabs(x) <= SPEC_MAX_ROAD_POSITION_M && fabs(vx) <= SPEC_MAX_VELOCITY_M_S &&
              fabs(given) <= SPEC_MAX_VELOCITY_M_S)) {
            snprintf(text, sizeof text, "the position along the road it read the road at, %s "
                     "m, its rate there, %s m/s, or the rate given last, %s m/s, is beyond what "
                     "a host gives (%g m, %g m/s)", a, b, c, SPEC_MAX_ROAD_POSITION_M,
                     SPEC_MAX_VELOCITY_M_S);
            add_why(why, why_size, text);
        }
    } else if (x != 0.0 || vx != 0.0 || given != 0.0 || change != 0.0) {
        snprintf(text, sizeof text, "it holds a position along the road (%s m) or its rates "
                 "(%s m/s, given %s m/s), but this kernel reads the road by time", a, b, c);
        add_why(why, why_size, text);
    }
}

/* what the state holds against what a state of this tire means: a clock a run reaches, a road
 * history as the reader keeps it, forces that do not pull, displacements and rates within the
 * spec's bounds, and outputs that are the ones its own values give */
static void meaning_problems(const TireKernel* kn, const unsigned char* in, char* why,
                             size_t why_size)
{
    int K = kn->K, P = kn->P, history = get_int(in, 2), has_last = get_int(in, 3), n, q, j, i;
    size_t o_q = STATE_HEAD, o_df = o_q + 2 * (size_t)K, o_pen = o_df + (size_t)P;
    size_t o_rate = o_pen + (size_t)P, o_heights = o_rate + (size_t)P;
    size_t o_slopes = o_heights + (size_t)P, o_t = o_slopes + (size_t)P;
    double start = get_double(in, 0), elapsed = get_double(in, 1), carry = get_double(in, 2);
    double last = get_double(in, 3), time = start + elapsed;
    double length = SPEC_MAX_STATE_DISPLACEMENT_M, rate = SPEC_MAX_STATE_VELOCITY_M_S;
    double reach = 0.0, speed = 0.0, total_bound = 0.0, contact = 0.0, scale = 0.0;
    int pulls = 0, exceeds = 0;
    char text[512], a[40], b[40];
    if (!(elapsed >= 0.0 && fabs(carry) <= nextafter(elapsed, INFINITY) - elapsed)) {
        py_repr(elapsed, a, sizeof a);
        py_repr(carry, b, sizeof b);
        snprintf(text, sizeof text, "its clock reads %s s since the start with a carry of %s s: "
                 "a run's clock is >= 0, and its carry below one rounding of it", a, b);
        add_why(why, why_size, text);
    }
    if (has_last != (elapsed != 0.0)) {
        py_repr(elapsed, a, sizeof a);
        py_repr(has_last ? last : NAN, b, sizeof b);
        snprintf(text, sizeof text, "its clock reads %s s since the start and its last step is "
                 "%s s: only steps advance the clock", a, b);
        add_why(why, why_size, text);
    } else if (has_last && !(last <= SPEC_MAX_STEP_S)) {
        py_repr(last, a, sizeof a);
        snprintf(text, sizeof text, "its last step is %s s; the FMU takes at most %g s", a,
                 SPEC_MAX_STEP_S);
        add_why(why, why_size, text);
    } else if (has_last && !clock_resolves(time - last, last)) {
        py_repr(last, a, sizeof a);
        py_repr(time, b, sizeof b);
        snprintf(text, sizeof text, "its last step of %s s ends at t = %s s, where the clock "
                 "does not resolve it", a, b);
        add_why(why, why_size, text);
    }
    history_problems(kn, in, o_t, history, elapsed, last, has_last, why, why_size);
    position_problems(kn, in, why, why_size);
    for (j = 0; j < P; j++) {
        double f = kn->f_static[j] + get_double(in, o_df + (size_t)j);
        double bound = kn->f_static[j] + kn->k[j] * (length + fabs(kn->pen_static[j]))
                       + kn->c[j] * rate;
        if (!kn->linear && f < 0.0) pulls = 1;
        if (!(fabs(f) <= bound)) exceeds = 1;
        total_bound += bound;
        contact += kn->cos[j] * f;
        scale += fabs(f) + fabs(kn->f_static[j]);
    }
    if (pulls) add_why(why, why_size, "its contact forces pull on the tread (the unilateral "
                       "contact only pushes)");
    if (exceeds) {
        snprintf(text, sizeof text, "its contact forces exceed what the zone springs give "
                 "at %g m and %g m/s", length, rate);
        add_why(why, why_size, text);
    }
    for (n = 0; n < kn->n_orders; n++) {
        for (q = kn->order_start[n]; q < kn->order_start[n + 1]; q++) {
            double size = hypot(get_double(in, o_q + 2 * (size_t)q),
                                get_double(in, o_q + 2 * (size_t)q + 1));
            reach = fmax(reach, size * cx_abs(kn->gamma[q]));
            speed = fmax(speed, size * cx_abs(kn->eta[q]));
        }
    }
    {
        const char* whats[7] = {"the tread's excursion at the zone nodes from a mode",
                                "the tread's rate at the zone nodes from a mode",
                                "its penetrations", "its penetration rates",
                                "the rim and road positions it saw", "the road rates it saw",
                                "the tread deflection it holds"};
        const char* units[7] = {"m", "m/s", "m", "m/s", "m", "m/s", "m"};
        double found[7], bound;
        found[0] = reach;
        found[1] = speed;
        found[2] = largest_abs(in, o_pen, P);
        found[3] = largest_abs(in, o_rate, P);
        found[4] = fmax(fabs(get_double(in, 4)), largest_abs(in, o_heights, P));
        found[5] = largest_abs(in, o_slopes, P);
        found[6] = fabs(get_double(in, 8));
        for (i = 0; i < 7; i++) {
            bound = units[i][1] == '/' ? rate : length;
            if (!(found[i] <= bound)) {
                snprintf(text, sizeof text, "%s reach %.3g %s, beyond the %g %s a state may hold",
                         whats[i], found[i], units[i], bound, units[i]);
                add_why(why, why_size, text);
            }
        }
    }
    if (!(fabs(get_double(in, 5)) <= SPEC_MAX_VELOCITY_M_S)) {
        py_repr(get_double(in, 5), a, sizeof a);
        snprintf(text, sizeof text, "the rim velocity it saw, %s m/s, is beyond the input limit "
                 "%g m/s", a, SPEC_MAX_VELOCITY_M_S);
        add_why(why, why_size, text);
    }
    if (!(fabs(get_double(in, 15)) <= SPEC_MAX_VELOCITY_M_S && 0.0 <= get_double(in, 17) &&
          get_double(in, 17) <= SPEC_MAX_STEP_S)) {
        py_repr(get_double(in, 15), a, sizeof a);
        py_repr(get_double(in, 17), b, sizeof b);
        snprintf(text, sizeof text, "the rim velocity given last, %s m/s, or the step of its "
                 "last change, %s s, is beyond what a host gives", a, b);
        add_why(why, why_size, text);
    }
    if (!(fabs(get_double(in, 6)) <= total_bound && fabs(get_double(in, 7)) <= total_bound)) {
        snprintf(text, sizeof text, "its rim forces exceed what the zone springs give at %g "
                 "m and %g m/s", length, rate);
        add_why(why, why_size, text);
    }
    if (why[0] != '\0') return;
    {   /* its outputs, the ones its own values give (contact force and footprint to
         * rounding: they are sums the state does not fix the order of) */
        double expected[KERNEL_N_OUTPUTS], tolerance[KERNEL_N_OUTPUTS] = {0.0};
        int first = -1, end = -1;
        for (j = 0; j < P; j++) {
            if (kn->f_static[j] + get_double(in, o_df + (size_t)j) > 0.0) {
                if (first < 0) first = j;
                end = j;
            }
        }
        expected[0] = kn->static_ring[0] + get_double(in, 6);
        expected[1] = kn->static_ring[1] + get_double(in, 7);
        expected[2] = contact;
        tolerance[2] = 1e-9 * scale;
        expected[3] = kn->static_deflection + get_double(in, o_heights + (size_t)kn->centre)
                      - get_double(in, 4);
        expected[4] = 0.0;
        if (first >= 0) {
            double* pen = kn->work;
            for (j = 0; j < P; j++) pen[j] = get_double(in, o_pen + (size_t)j);
            expected[4] = crossing(kn->x_road, pen, first, first - 1, P)
                          - crossing(kn->x_road, pen, end, end + 1, P);
        }
        tolerance[4] = 1e-9 * (kn->x_road[0] - kn->x_road[P - 1]);
        expected[5] = kn->static_ring[2] + get_double(in, 8);
        text[0] = '\0';
        for (i = 0; i < KERNEL_N_OUTPUTS; i++) {
            double given = get_double(in, 9 + (size_t)i);
            if (!(fabs(given - expected[i]) <= tolerance[i])) {
                size_t used = strlen(text);
                py_repr(given, a, sizeof a);
                py_repr(expected[i], b, sizeof b);
                snprintf(text + used, sizeof text - used, "%s%s = %s, but the state gives %s",
                         used ? "; " : "its outputs are not the ones it gives: ",
                         OUTPUT_NAMES[i], a, b);
            }
        }
        if (text[0] != '\0') add_why(why, why_size, text);
    }
}

int kernel_state_check(const TireKernel* kn, const unsigned char* in, size_t size, char* why,
                       size_t why_size)
{
    int K, P, history, i;
    size_t count, expected;
    why[0] = '\0';
    if (size < STATE_INTS * 4) {
        snprintf(why, why_size, "its model part is %lu bytes, shorter than its header",
                 (unsigned long)size);
        return KERNEL_BAD_CONTRACT;
    }
    K = get_int(in, 0);
    P = get_int(in, 1);
    history = get_int(in, 2);
    if (K != kn->K || P != kn->P) {
        snprintf(why, why_size, "state of another model (build both with the same parameters): it holds "
                 "%d modes and %d contact points, this model %d and %d", K, P, kn->K, kn->P);
        return KERNEL_BAD_CONTRACT;
    }
    if (history < 0 || history > (int)((size - STATE_INTS * 4) / 24)) {
        snprintf(why, why_size, "its road history length %d is impossible", history);
        return KERNEL_BAD_CONTRACT;
    }
    expected = STATE_INTS * 4 + doubles_for(K, P, history) * 8 + (size_t)P;
    if (size != expected) {
        snprintf(why, why_size, "its model part is %lu bytes, expected %lu",
                 (unsigned long)size, (unsigned long)expected);
        return KERNEL_BAD_CONTRACT;
    }
    if (get_int(in, 3) != 0 && get_int(in, 3) != 1) {
        snprintf(why, why_size, "its has-last flag is %d, not 0 or 1", get_int(in, 3));
        return KERNEL_BAD_CONTRACT;
    }
    count = doubles_for(K, P, history);
    for (i = 0; i < (int)count; i++) {
        if (!isfinite(get_double(in, (size_t)i))) {
            snprintf(why, why_size, "value %d of its model part is not finite", i);
            return KERNEL_BAD_CONTRACT;
        }
    }
    if (get_int(in, 3) && !(get_double(in, 3) > 0.0)) {
        snprintf(why, why_size, "its last step is %g s, not > 0", get_double(in, 3));
        return KERNEL_BAD_CONTRACT;
    }
    for (i = 0; i < P; i++) {
        if (in[size - (size_t)P + (size_t)i] > 1) {
            snprintf(why, why_size, "its contact flags are not 0 or 1");
            return KERNEL_BAD_CONTRACT;
        }
    }
    meaning_problems(kn, in, why, why_size);
    return why[0] == '\0' ? KERNEL_OK : KERNEL_BAD_CONTRACT;
}

int kernel_state_apply(TireKernel* kn, const unsigned char* in)
{
    int K = get_int(in, 0), P = get_int(in, 1), history = get_int(in, 2), i, status = KERNEL_OK;
    const unsigned char* p = in + STATE_INTS * 4;
    double head[STATE_HEAD];
    double* scratch;
    memcpy(head, p, sizeof head);
    p += sizeof head;
    kn->has_last = get_int(in, 3);
    kn->start_time = head[0];
    kn->elapsed = head[1];
    kn->carry = head[2];
    kn->last_step = head[3];
    kn->seen_z = head[4];
    kn->seen_vz = head[5];
    memcpy(kn->ring_out, head + 6, sizeof(double) * 3);
    memcpy(kn->outputs, head + 9, sizeof(double) * KERNEL_N_OUTPUTS);
    kn->given_vz = head[15];
    kn->change = head[16];
    kn->h_change = head[17];
    kn->seen_x = head[18];
    kn->seen_vx = head[19];
    kn->given_vx = head[20];
    kn->change_vx = head[21];
    memcpy(kn->q, p, sizeof(double) * (size_t)(2 * K));
    p += sizeof(double) * (size_t)(2 * K);
#define TAKE(field)                                        \
    memcpy(kn->field, p, sizeof(double) * (size_t)P);      \
    p += sizeof(double) * (size_t)P
    TAKE(df);
    TAKE(penetration);
    TAKE(rate);
    TAKE(seen_heights);
    TAKE(seen_slopes);
#undef TAKE
    /* the history arrays may be unaligned in the bytes: copy them out first */
    scratch = (double*)mem_alloc(&kn->mem, (size_t)(3 * history), sizeof(double));
    if (scratch == NULL) return KERNEL_NO_MEMORY;
    memcpy(scratch, p, sizeof(double) * (size_t)(3 * history));
    kn->road.origin = kn->start_time;
    if (road_set_history(&kn->road, &kn->mem, scratch, scratch + history,
                         scratch + 2 * history, history) != 0) {
        status = KERNEL_NO_MEMORY;
    }
    mem_free(&kn->mem, scratch);
    p += sizeof(double) * (size_t)(3 * history);
    for (i = 0; i < P; i++) kn->active[i] = (char)p[i];
    kn->dft_ok = 0;
    kn->pending = 0;
    kn->last = NULL;
    if (kn->has_last) {
        kn->last = step_interface(kn, kn->last_step);
        if (kn->last == NULL) status = KERNEL_NO_MEMORY;
    }
    return status;
}

TireKernel* kernel_new(const TireContract* contract, double start_time, char* why,
                       size_t why_size)
{
    TireKernel* kernel = NULL;
    kernel_create(contract, mem_default(), start_time, &kernel, why, why_size);
    return kernel;
}
