/* ring.c: the free rolling ring in diagonal modal form, order by order (core/free_ring.py).
 *
 * Without contact the ground-frame ring is circulant, so order n (n = 0 .. N/2) is a 2-DOF
 * system M u'' + D_n u' + K_n u = F_n. Its 4x4 momentum-form state matrix A_n
 * (free_ring.momentum_matrices) is diagonalised by the dense eigen-solver of numerics.c, its
 * modes put in the canonical normalisation and order (free_ring.order_modes), and V^-1 gives
 * the modal inputs. A zone force f_j enters every order through e^{-i n theta_j}, a zone
 * displacement reads every order through e^{i n theta_j}, the rim only orders +-1: that
 * structure is kept (no dense mode x node tables), so building costs O(N Z) and a step
 * O(K + N Z). Orders 0 < n < N/2 stand for n and -n (factor 2 in c). */
#include <stdlib.h>
#include <string.h>

#include "spec.h"
#include "tire.h"

#define PI 3.14159265358979323846

typedef struct {
    double lam2, lam4, kappa;
    int order;
} Symbols;

/* discretisation.symbols: the stencils' values on e^{i n theta}, summed as the core sums them */
static Symbols order_symbols(int n, double dtheta)
{
    Symbols s;
    double x = n * dtheta, x2 = (2.0 * n) * dtheta;
    double c1 = cos(x), c2 = cos(x2);
    s.order = n;
    s.kappa = sin(x) * (1.0 / dtheta);
    s.lam2 = -(pow(dtheta, -2) * ((c1 + -2.0) + c1));
    s.lam4 = pow(dtheta, -4) * ((((c2 + -4.0 * c1) + 6.0) + -4.0 * c1) + c2);
    return s;
}

double tire_stiffness_factor(const Tire* tire)
{
    if (tire->sidewall_pressure_exponent == 0.0) return 1.0;
    return pow(tire->inflation_pressure / tire->reference_pressure,
               tire->sidewall_pressure_exponent);
}

typedef struct {
    double k_tt, k_ss, k_ts, c_tt, c_ss, c_ts;
} OrderEntries;

/* dispersion.per_order_matrices: body-frame stiffness and material damping, per metre */
static OrderEntries per_order(const Tire* t, Symbols s, double spin)
{
    OrderEntries e;
    double factor = tire_stiffness_factor(t);
    double k_r1 = t->k_r1 * factor, k_r2 = t->k_r2 * factor, shear = t->sidewall_shear * factor;
    double pre = t->inflation_pressure * t->b * t->R;
    double centrifugal = t->rhoA * (t->R * t->R) * (spin * spin);
    double r2 = t->R * t->R;
    double bend = t->EI / (r2 * r2) * s.lam4;
    double k0_tt = bend + pre / r2 * s.lam2 + k_r1;
    double k0_ss = k_r1 + k_r2 + shear / r2 * s.lam2;
    double k0_ts = -k_r1;
    /* material damping on the lumped structure: the tie is elastic only */
    e.c_tt = t->alpha * t->rhoA + t->beta * k0_tt;
    e.c_ss = t->alpha * t->m_s + t->beta * k0_ss;
    e.c_ts = -t->beta * k_r1;
    if (t->sidewall_max_order > 0.0 && fabs((double)s.order) > t->sidewall_max_order) {
        /* dispersion.sidewall_tie: the sidewall rides on the tread above sidewall_max_order */
        double ratio = k_r1 / k0_ss;
        double p = SPEC_SIDEWALL_TIE_FACTOR * (k0_tt + k0_ss);
        k0_tt = k0_tt + p * ratio * ratio;
        k0_ss = k0_ss + p;
        k0_ts = -(p * ratio) - k_r1;
    }
    e.k_tt = k0_tt + centrifugal / r2 * s.lam2 - t->rhoA * (spin * spin);
    e.k_ss = k0_ss - t->m_s * (spin * spin);
    e.k_ts = k0_ts;
    return e;
}

/* -- the critical speed (standing_waves.py) -------------------------------------------------- */

typedef struct {
    const Tire* tire;
    int n, branch, n_elements;
    double kappa;
} MarginData;

/* lowest ground frequency of one order and branch (rad/s): analytic.two_mass_eigenvalues */
static double margin(const Tire* tire, int n, int branch, double kappa, int n_elements,
                     double spin)
{
    Symbols s = order_symbols(n, 2.0 * PI / n_elements);
    OrderEntries e = per_order(tire, s, spin);
    double quad = tire->rhoA * tire->m_s;
    double lin = e.k_tt * tire->m_s + e.k_ss * tire->rhoA;
    double konst = e.k_tt * e.k_ss - e.k_ts * e.k_ts;
    double diff = e.k_tt * tire->m_s - e.k_ss * tire->rhoA;
    double root = sqrt(diff * diff + 4.0 * quad * (e.k_ts * e.k_ts));
    double high = (lin + root) / (2.0 * quad);
    double low = konst / (quad * high);
    double value = branch == 0 ? sqrt(low) : sqrt(high);  /* nan below zero: buckled */
    return value - kappa * spin;
}

static double margin_for_root(double spin, void* data)
{
    const MarginData* m = (const MarginData*)data;
    double value = margin(m->tire, m->n, m->branch, m->kappa, m->n_elements, spin);
    return isfinite(value) ? value : -1.0;
}

double critical_speed(const Tire* tire, int n_elements)
{
    int half = n_elements / 2, i, n, branch;
    double dtheta = 2.0 * PI / n_elements;
    double stop = SPEC_MAX_SCANNED_SPEED_M_S / tire->R;
    double step = stop / (SPEC_SCAN_POINTS - 1), previous = 0.0;
    for (i = 1; i < SPEC_SCAN_POINTS; i++) {
        double spin = i == SPEC_SCAN_POINTS - 1 ? stop : i * step + 0.0;
        double best = HUGE_VAL;
        int found = 0;
        for (branch = 0; branch < 2; branch++) {
            for (n = 1; n <= half; n++) {
                double kappa = order_symbols(n, dtheta).kappa;
                double value = margin(tire, n, branch, kappa, n_elements, spin);
                if (!(value > 0.0)) {
                    MarginData data;
                    double root;
                    data.tire = tire;
                    data.n = n;
                    data.branch = branch;
                    data.n_elements = n_elements;
                    data.kappa = kappa;
                    root = brentq(margin_for_root, &data, previous, spin, SPEC_ROOT_TOLERANCE,
                                  SPEC_ROOT_TOLERANCE, 100);
                    if (root < best) best = root;
                    found = 1;
                }
            }
        }
        if (found) return best * tire->R;
        previous = spin;
    }
    return HUGE_VAL;
}

/* -- the modes ---------------------------------------------------------------------------------- */

typedef struct {
    cx lam, beta, gamma, eta, b_rim, c_rim[2];
    int order, index;
    double size;
} Mode;

static int compare_modes(const void* a, const void* b)
{
    const Mode* x = (const Mode*)a;
    const Mode* y = (const Mode*)b;
    if (x->size < y->size) return -1;
    if (x->size > y->size) return 1;
    return x->index - y->index;  /* stable, as numpy's argsort(kind="stable") */
}

static int compare_by_order(const void* a, const void* b)
{
    const Mode* x = (const Mode*)a;
    const Mode* y = (const Mode*)b;
    if (x->order != y->order) return x->order - y->order;
    return x->index - y->index;
}

typedef struct {
    cx k[4], d[4];   /* K_n and D_n, 2x2 row major */
    double weight;
    int real_system;
} Order;

static void build_order(const Tire* tire, double arc, double spin, int n, int n_elements,
                        Order* o)
{
    double dtheta = 2.0 * PI / n_elements;
    Symbols s = order_symbols(n, dtheta);
    OrderEntries e = per_order(tire, s, spin);
    double w = spin * s.kappa;
    double mass[2];
    mass[0] = arc * tire->rhoA;
    mass[1] = arc * tire->m_s;
    o->real_system = n == 0 || 2 * n == n_elements;
    o->weight = o->real_system ? 1.0 : 2.0;
    /* K_n = K* - w^2 M + i w C, D_n = C + 2 i w M (free_ring.order_matrices) */
    o->k[0] = cx_make(arc * e.k_tt - w * w * mass[0], w * (arc * e.c_tt));
    o->k[1] = cx_make(arc * e.k_ts - w * w * 0.0, w * (arc * e.c_ts));
    o->k[2] = o->k[1];
    o->k[3] = cx_make(arc * e.k_ss - w * w * mass[1], w * (arc * e.c_ss));
    o->d[0] = cx_make(arc * e.c_tt, 2.0 * w * mass[0]);
    o->d[1] = cx_make(arc * e.c_ts, 0.0);
    o->d[2] = o->d[1];
    o->d[3] = cx_make(arc * e.c_ss, 2.0 * w * mass[1]);
    if (o->real_system) {  /* n = 0 or N/2: the core takes the real system */
        int i;
        for (i = 0; i < 4; i++) {
            o->k[i].im = 0.0;
            o->d[i].im = 0.0;
        }
    }
}

static cx ones_row(const cx* a, int column) { return cx_add(a[column], a[2 + column]); }

/* A_n = [0 M^-1; -K_n -D_n M^-1] (row major) of the momentum state x = [u_n, M u_n'] and its
 * four modes, canonical (free_ring.order_modes): a real order is the real system. 0, or the
 * eigen-solver's error. */
static int order_eigen(const Order* o, const double mass[2], cx a[16], cx values[4],
                       cx vectors[16])
{
    double m_inv[2];
    int i, j, status;
    m_inv[0] = 1.0 / mass[0];
    m_inv[1] = 1.0 / mass[1];
    for (i = 0; i < 16; i++) a[i] = cx_make(0.0, 0.0);
    a[0 * 4 + 2] = cx_make(m_inv[0], 0.0);
    a[1 * 4 + 3] = cx_make(m_inv[1], 0.0);
    for (i = 0; i < 2; i++) {
        for (j = 0; j < 2; j++) {
            a[(2 + i) * 4 + j] = cx_scale(o->k[2 * i + j], -1.0);
            a[(2 + i) * 4 + 2 + j] = cx_scale(cx_scale(o->d[2 * i + j], -1.0), m_inv[j]);
        }
    }
    status = cx_eig(a, 4, o->real_system, values, vectors);
    if (status != 0) return status;
    canonical_modes(4, values, vectors, SPEC_MODE_TIE_TOLERANCE);
    return 0;
}

int ring_order_modes(const Tire* tire, int n_elements, double spin, int n, cx a[16],
                     cx values[4], cx vectors[16])
{
    double arc = tire->R * (2.0 * PI / n_elements), mass[2];
    Order o;
    mass[0] = arc * tire->rhoA;
    mass[1] = arc * tire->m_s;
    build_order(tire, arc, spin, n, n_elements, &o);
    return order_eigen(&o, mass, a, values, vectors);
}

/* The order's modes: eigenvalues, eigenvectors [u; s M u], V^-1, and what the ring needs of
 * them. Returns the number of modes written (4, or fewer for n = 0, N/2), -1 on failure. */
static int order_modes(const Order* o, const double mass[2], int n, int n_elements,
                       Mode* out, int first_index)
{
    cx a[16], values[4], v[16], vinv[16];
    int k, count = 0;
    if (order_eigen(o, mass, a, values, v) != 0) return -1;
    memcpy(vinv, v, sizeof v);
    if (cx_invert(vinv, 4) != 0) return -1;
    for (k = 0; k < 4; k++) {
        cx lam = values[k];
        double factor = 2.0;
        Mode* m;
        int row;
        if (o->real_system) {
            if (lam.im < 0.0) continue;  /* the partner of a kept mode */
            if (lam.im == 0.0) factor = 1.0;
        }
        m = &out[count++];
        memset(m, 0, sizeof *m);
        m->lam = lam;
        m->order = n;
        m->index = first_index + k;
        m->size = cx_abs(lam);
        m->beta = cx_scale(vinv[k * 4 + 2], -1.0 / n_elements);
        m->gamma = cx_scale(v[0 * 4 + k], factor);
        m->eta = cx_scale(v[2 * 4 + k], factor / mass[0]);
        if (n == 1) {
            /* rim input: B = [M^-1 b_v; b_z - D M^-1 b_v], b_z = K 1 t_in, b_v = D 1 t_in */
            cx bz[2], bv[2], b[4], tau = cx_make(-0.5 * n_elements, 0.0);
            cx sig = cx_make(0.0, -0.5 * n_elements), c_row[4];
            double t_in = -0.5;
            for (row = 0; row < 2; row++) {
                bz[row] = cx_scale(cx_add(o->k[2 * row], o->k[2 * row + 1]), t_in);
                bv[row] = cx_scale(cx_add(o->d[2 * row], o->d[2 * row + 1]), t_in);
                b[row] = cx_scale(bv[row], 1.0 / mass[row]);
            }
            for (row = 0; row < 2; row++) {
                b[2 + row] = cx_sub(bz[row], cx_add(cx_mul(o->d[2 * row], b[0]),
                                                    cx_mul(o->d[2 * row + 1], b[1])));
            }
            m->b_rim = cx_make(0.0, 0.0);
            for (row = 0; row < 4; row++) {
                m->b_rim = cx_add(m->b_rim, cx_mul(vinv[k * 4 + row], b[row]));
            }
            /* rim force rows: tau (1^T K) on u, tau (1^T D) M^-1 on the momentum */
            c_row[0] = ones_row(o->k, 0);
            c_row[1] = ones_row(o->k, 1);
            c_row[2] = cx_scale(ones_row(o->d, 0), 1.0 / mass[0]);
            c_row[3] = cx_scale(ones_row(o->d, 1), 1.0 / mass[1]);
            for (row = 0; row < 2; row++) {
                cx pattern = row == 0 ? tau : sig, sum = cx_make(0.0, 0.0);
                int i;
                for (i = 0; i < 4; i++) sum = cx_add(sum, cx_mul(c_row[i], v[i * 4 + k]));
                m->c_rim[row] = cx_scale(cx_mul(pattern, sum), factor);
            }
        }
        if (o->real_system) {  /* real eigenvalue, real eigenvector: drop rounding dust */
            if (lam.im == 0.0) {
                m->beta.im = 0.0;
                m->gamma.im = 0.0;
                m->eta.im = 0.0;
            }
        }
    }
    return count;
}

/* e^{i n m dtheta} from the table of e^{2 pi i k / N} */
static cx phase(const double* cos_table, const double* sin_table, int n, int m, int n_elements)
{
    long k = ((long)n * (long)m) % n_elements;
    if (k < 0) k += n_elements;
    return cx_make(cos_table[k], sin_table[k]);
}

/* T(delta) = sum_n Re(s_n e^{i n delta dtheta}) for delta = -2 half .. 2 half */
static void toeplitz(const cx* s, int n_orders, int half, const double* cos_table,
                     const double* sin_table, int n_elements, double* out)
{
    int delta, n;
    for (delta = -2 * half; delta <= 2 * half; delta++) {
        double sum = 0.0;
        for (n = 0; n < n_orders; n++) {
            cx p = phase(cos_table, sin_table, n, delta, n_elements);
            sum += s[n].re * p.re - s[n].im * p.im;
        }
        out[delta + 2 * half] = sum;
    }
}

void ring_free(Ring* ring, const Memory* mem)
{
    mem_free(mem, ring->order_start);
    mem_free(mem, ring->lam);
    mem_free(mem, ring->beta);
    mem_free(mem, ring->gamma);
    mem_free(mem, ring->eta);
    mem_free(mem, ring->cos_nm);
    mem_free(mem, ring->sin_nm);
    mem_free(mem, ring->d);
    mem_free(mem, ring->e);
    mem_free(mem, ring->static_gain);
    memset(ring, 0, sizeof *ring);
}

#define AT(matrix, row, col) (matrix)[(size_t)(row) * (size_t)ring->cols + (size_t)(col)]

/* contributions sum over modes of Re(-c b / lam^power) to the matrix out (rows x cols), for
 * the modes with use[k] set */
static void modal_dc(Ring* ring, const Mode* modes, int count, const char* use, int power,
                     double sign, const double* cos_table, const double* sin_table,
                     cx* per_order_w, cx* per_order_r, double* tw, double* tr, double* out)
{
    int Z = ring->n_zone, half = ring->half, k, i, j, n;
    for (n = 0; n < ring->n_orders; n++) {
        per_order_w[n] = cx_make(0.0, 0.0);
        per_order_r[n] = cx_make(0.0, 0.0);
    }
    for (k = 0; k < count; k++) {
        const Mode* m = &modes[k];
        cx inv = cx_div(cx_make(1.0, 0.0), m->lam), scale;
        if (!use[k]) continue;
        if (power == 2) inv = cx_mul(inv, inv);
        scale = cx_scale(inv, -sign);  /* -c b / lam^p */
        /* zone force columns through the orders */
        per_order_w[m->order] = cx_add(per_order_w[m->order], cx_mul(cx_mul(m->gamma, m->beta),
                                                                     scale));
        per_order_r[m->order] = cx_add(per_order_r[m->order], cx_mul(cx_mul(m->eta, m->beta),
                                                                     scale));
        if (m->order == 1) {  /* the rim column and the rim rows */
            cx b = cx_mul(m->b_rim, scale);
            AT(out, 0, 0) += cx_mul(m->c_rim[0], b).re;
            AT(out, 1, 0) += cx_mul(m->c_rim[1], b).re;
            AT(out, 2, 0) += -cx_mul(m->gamma, b).re;
            for (j = 0; j < Z; j++) {
                cx p = phase(cos_table, sin_table, 1, j - half, ring->n_elements);
                AT(out, 3 + j, 0) += cx_mul(cx_mul(m->gamma, p), b).re;
                AT(out, 3 + Z + j, 0) += cx_mul(cx_mul(m->eta, p), b).re;
            }
            for (j = 0; j < Z; j++) {
                cx p = phase(cos_table, sin_table, -1, j - half, ring->n_elements);
                cx bf = cx_mul(cx_mul(m->beta, p), scale);
                AT(out, 0, 1 + j) += cx_mul(m->c_rim[0], bf).re;
                AT(out, 1, 1 + j) += cx_mul(m->c_rim[1], bf).re;
            }
        }
    }
    toeplitz(per_order_w, ring->n_orders, half, cos_table, sin_table, ring->n_elements, tw);
    toeplitz(per_order_r, ring->n_orders, half, cos_table, sin_table, ring->n_elements, tr);
    for (j = 0; j < Z; j++) {
        AT(out, 2, 1 + j) += -tw[(0 - (j - half)) + 2 * half];
        for (i = 0; i < Z; i++) {
            AT(out, 3 + i, 1 + j) += tw[(i - j) + 2 * half];
            AT(out, 3 + Z + i, 1 + j) += tr[(i - j) + 2 * half];
        }
    }
}

int ring_build(Ring* ring, const Memory* mem, const Tire* tire, int n_elements, double spin,
               int half, const Truncation* truncation)
{
    int n_orders = n_elements / 2 + 1, Z = 2 * half + 1, rows, cols, n, k, j, i, count = 0;
    int total, kept;
    double dtheta = 2.0 * PI / n_elements, arc = tire->R * dtheta;
    double mass[2];
    Mode* modes = NULL;
    char* keep = NULL;
    char* dropped = NULL;
    double *cos_table = NULL, *sin_table = NULL, *tw = NULL, *tr = NULL, *direct_d = NULL;
    cx *acc_w = NULL, *acc_r = NULL, *g = NULL;
    Order o1;
    int status = -1;
    memset(ring, 0, sizeof *ring);
    mass[0] = arc * tire->rhoA;
    mass[1] = arc * tire->m_s;
    ring->n_elements = n_elements;
    ring->n_orders = n_orders;
    ring->n_zone = Z;
    ring->half = half;
    ring->dtheta = dtheta;
    ring->arc = arc;
    ring->spin = spin;
    ring->mass[0] = mass[0];
    ring->mass[1] = mass[1];
    ring->rows = rows = 3 + 2 * Z;
    ring->cols = cols = 1 + Z;
    modes = (Mode*)mem_alloc(mem, (size_t)(4 * n_orders), sizeof(Mode));
    keep = (char*)mem_alloc(mem, (size_t)(4 * n_orders), 1);
    dropped = (char*)mem_alloc(mem, (size_t)(4 * n_orders), 1);
    cos_table = (double*)mem_alloc(mem, (size_t)n_elements, sizeof(double));
    sin_table = (double*)mem_alloc(mem, (size_t)n_elements, sizeof(double));
    tw = (double*)mem_alloc(mem, (size_t)(4 * half + 1), sizeof(double));
    tr = (double*)mem_alloc(mem, (size_t)(4 * half + 1), sizeof(double));
    acc_w = (cx*)mem_alloc(mem, (size_t)n_orders, sizeof(cx));
    acc_r = (cx*)mem_alloc(mem, (size_t)n_orders, sizeof(cx));
    g = (cx*)mem_alloc(mem, (size_t)n_orders, sizeof(cx));
    direct_d = (double*)mem_alloc(mem, (size_t)(rows * cols), sizeof(double));
    ring->d = (double*)mem_alloc(mem, (size_t)(rows * cols), sizeof(double));
    ring->e = (double*)mem_alloc(mem, (size_t)(rows * cols), sizeof(double));
    ring->static_gain = (double*)mem_alloc(mem, (size_t)(rows * cols), sizeof(double));
    ring->order_start = (int*)mem_alloc(mem, (size_t)(n_orders + 1), sizeof(int));
    ring->cos_nm = (double*)mem_alloc(mem, (size_t)((2 * half + 1) * n_orders), sizeof(double));
    ring->sin_nm = (double*)mem_alloc(mem, (size_t)((2 * half + 1) * n_orders), sizeof(double));
    if (!modes || !keep || !dropped || !cos_table || !sin_table || !tw || !tr || !acc_w ||
        !acc_r || !g || !direct_d || !ring->d || !ring->e || !ring->static_gain ||
        !ring->order_start || !ring->cos_nm || !ring->sin_nm) {
        goto done;
    }
    for (k = 0; k < n_elements; k++) {
        double angle = 2.0 * PI * k / n_elements;
        cos_table[k] = cos(angle);
        sin_table[k] = sin(angle);
    }
    sin_table[0] = 0.0;
    if (n_elements % 2 == 0) {  /* e^{i pi m}: exactly real, as the core takes it */
        cos_table[n_elements / 2] = -1.0;
        sin_table[n_elements / 2] = 0.0;
    }
    for (j = 0; j <= 2 * half; j++) {
        for (n = 0; n < n_orders; n++) {
            cx p = phase(cos_table, sin_table, n, j, n_elements);
            ring->cos_nm[j * n_orders + n] = p.re;
            ring->sin_nm[j * n_orders + n] = p.im;
        }
    }

    /* every order: its modes and its exact static compliance g_n = (K_n^-1)_00 */
    for (n = 0; n < n_orders; n++) {
        Order o;
        cx det, inv00;
        int written;
        build_order(tire, arc, spin, n, n_elements, &o);
        if (n == 1) o1 = o;
        det = cx_sub(cx_mul(o.k[0], o.k[3]), cx_mul(o.k[1], o.k[2]));
        inv00 = cx_div(o.k[3], det);
        g[n] = cx_scale(inv00, o.weight / n_elements);
        written = order_modes(&o, mass, n, n_elements, modes + count, 4 * n);
        if (written < 0) goto done;
        count += written;
    }
    total = count;
    qsort(modes, (size_t)count, sizeof(Mode), compare_modes);

    /* truncation: |lam| <= 2 pi f_max, at most n_modes, lowest first */
    kept = 0;
    for (k = 0; k < count; k++) {
        int ok = truncation->f_max_hz > 0.0 ? modes[k].size <= 2 * PI * truncation->f_max_hz : 1;
        if (ok && truncation->n_modes > 0 && kept + 1 > truncation->n_modes) ok = 0;
        keep[k] = (char)ok;
        dropped[k] = (char)!ok;
        kept += ok;
    }

    /* exact DC gain (free_ring._Orders.static_gain) and the direct terms */
    {
        cx tau = cx_make(-0.5 * n_elements, 0.0), sig = cx_make(0.0, -0.5 * n_elements);
        cx k11 = cx_add(ones_row(o1.k, 0), ones_row(o1.k, 1));
        cx d11 = cx_add(ones_row(o1.d, 0), ones_row(o1.d, 1));
        double t_in = -0.5;
        cx bz[2], u[2], bv[2], det, kinv[4], rows_k[2];
        int r;
        double* sg = ring->static_gain;
        /* d_direct and e_direct: the rim-relative parts -T z and -T z' */
        AT(direct_d, 0, 0) = -(2.0 * cx_mul(cx_scale(tau, t_in), k11).re);
        AT(direct_d, 1, 0) = -(2.0 * cx_mul(cx_scale(sig, t_in), k11).re);
        AT(ring->e, 0, 0) = -(2.0 * cx_mul(cx_scale(tau, t_in), d11).re);
        AT(ring->e, 1, 0) = -(2.0 * cx_mul(cx_scale(sig, t_in), d11).re);
        AT(direct_d, 2, 0) = -1.0;
        for (j = 0; j < Z; j++) {
            double c = cos((j - half) * dtheta);
            AT(direct_d, 3 + j, 0) = c;
            AT(ring->e, 3 + Z + j, 0) = c;
        }
        memcpy(sg, direct_d, sizeof(double) * (size_t)(rows * cols));
        /* rim column: u_1 = K_1^-1 K_1 1 t_in through order 1 */
        det = cx_sub(cx_mul(o1.k[0], o1.k[3]), cx_mul(o1.k[1], o1.k[2]));
        kinv[0] = cx_div(o1.k[3], det);
        kinv[1] = cx_div(cx_scale(o1.k[1], -1.0), det);
        kinv[2] = cx_div(cx_scale(o1.k[2], -1.0), det);
        kinv[3] = cx_div(o1.k[0], det);
        for (r = 0; r < 2; r++) {
            bz[r] = cx_scale(cx_add(o1.k[2 * r], o1.k[2 * r + 1]), t_in);
            bv[r] = cx_scale(cx_add(o1.d[2 * r], o1.d[2 * r + 1]), t_in);
        }
        for (r = 0; r < 2; r++) {
            u[r] = cx_add(cx_mul(kinv[2 * r], bz[0]), cx_mul(kinv[2 * r + 1], bz[1]));
        }
        rows_k[0] = ones_row(o1.k, 0);
        rows_k[1] = ones_row(o1.k, 1);
        {
            cx ku = cx_add(cx_mul(rows_k[0], u[0]), cx_mul(rows_k[1], u[1]));
            AT(sg, 0, 0) += 2.0 * cx_mul(tau, ku).re;
            AT(sg, 1, 0) += 2.0 * cx_mul(sig, ku).re;
            AT(sg, 2, 0) += 2.0 * (-u[0].re);
            for (j = 0; j < Z; j++) {
                cx p = phase(cos_table, sin_table, 1, j - half, n_elements);
                AT(sg, 3 + j, 0) += 2.0 * cx_mul(p, u[0]).re;
            }
        }
        /* zone force columns: rim rows through order 1, the rest through every order */
        {
            cx ke0 = cx_add(cx_mul(rows_k[0], kinv[0]), cx_mul(rows_k[1], kinv[2]));
            for (j = 0; j < Z; j++) {
                cx p = phase(cos_table, sin_table, -1, j - half, n_elements);
                cx b = cx_scale(p, -1.0 / n_elements);
                AT(sg, 0, 1 + j) += 2.0 * cx_mul(tau, cx_mul(ke0, b)).re;
                AT(sg, 1, 1 + j) += 2.0 * cx_mul(sig, cx_mul(ke0, b)).re;
            }
        }
        toeplitz(g, n_orders, half, cos_table, sin_table, n_elements, tw);
        for (j = 0; j < Z; j++) {
            AT(sg, 2, 1 + j) += tw[(0 - (j - half)) + 2 * half];
            for (i = 0; i < Z; i++) AT(sg, 3 + i, 1 + j) += -tw[(i - j) + 2 * half];
        }
        /* the feedthrough of the rim's damper: l_v M^-1 b_v on order 1 */
        memcpy(ring->d, direct_d, sizeof(double) * (size_t)(rows * cols));
        {
            cx dv = cx_add(cx_scale(cx_mul(ones_row(o1.d, 0), bv[0]), 1.0 / mass[0]),
                           cx_scale(cx_mul(ones_row(o1.d, 1), bv[1]), 1.0 / mass[1]));
            AT(ring->d, 0, 0) += 2.0 * cx_mul(tau, dv).re;
            AT(ring->d, 1, 0) += 2.0 * cx_mul(sig, dv).re;
            for (j = 0; j < Z; j++) {
                cx p = phase(cos_table, sin_table, 1, j - half, n_elements);
                AT(ring->d, 3 + Z + j, 0) += 2.0 * cx_scale(cx_mul(p, bv[0]), 1.0 / mass[0]).re;
            }
        }
    }
    if (truncation->static_correction && kept < count) {
        /* d = exact DC - kept DC; e += the dropped modes' -c b / lam^2 */
        double* kept_dc = direct_d;
        memset(kept_dc, 0, sizeof(double) * (size_t)(rows * cols));
        modal_dc(ring, modes, count, keep, 1, 1.0, cos_table, sin_table, acc_w, acc_r, tw, tr,
                 kept_dc);
        for (k = 0; k < rows * cols; k++) ring->d[k] = ring->static_gain[k] - kept_dc[k];
        modal_dc(ring, modes, count, dropped, 2, 1.0, cos_table, sin_table, acc_w, acc_r, tw,
                 tr, ring->e);
    }
    ring->truncated = 0;
    for (i = 0; i < rows; i++) {
        for (j = 1; j < cols; j++) {
            if (AT(ring->d, i, j) != 0.0 || AT(ring->e, i, j) != 0.0) ring->truncated = 1;
        }
    }

    /* the kept modes, grouped by order */
    j = 0;
    for (k = 0; k < count; k++) {
        if (keep[k]) modes[j++] = modes[k];
    }
    qsort(modes, (size_t)kept, sizeof(Mode), compare_by_order);
    ring->total_modes = total;
    ring->n_modes = kept;
    ring->lam = (cx*)mem_alloc(mem, (size_t)kept, sizeof(cx));
    ring->beta = (cx*)mem_alloc(mem, (size_t)kept, sizeof(cx));
    ring->gamma = (cx*)mem_alloc(mem, (size_t)kept, sizeof(cx));
    ring->eta = (cx*)mem_alloc(mem, (size_t)kept, sizeof(cx));
    if (!ring->lam || !ring->beta || !ring->gamma || !ring->eta) goto done;
    ring->rim_count = 0;
    ring->first_rim = 0;
    for (n = 0; n <= n_orders; n++) ring->order_start[n] = 0;
    for (k = 0; k < kept; k++) {
        ring->lam[k] = modes[k].lam;
        ring->beta[k] = modes[k].beta;
        ring->gamma[k] = modes[k].gamma;
        ring->eta[k] = modes[k].eta;
        ring->order_start[modes[k].order + 1]++;
        if (modes[k].order == 1) {
            if (ring->rim_count == 0) ring->first_rim = k;
            ring->b_rim[ring->rim_count] = modes[k].b_rim;
            ring->c_rim[0][ring->rim_count] = modes[k].c_rim[0];
            ring->c_rim[1][ring->rim_count] = modes[k].c_rim[1];
            ring->rim_count++;
        }
    }
    for (n = 0; n < n_orders; n++) ring->order_start[n + 1] += ring->order_start[n];
    status = 0;
done:
    mem_free(mem, modes);
    mem_free(mem, keep);
    mem_free(mem, dropped);
    mem_free(mem, cos_table);
    mem_free(mem, sin_table);
    mem_free(mem, tw);
    mem_free(mem, tr);
    mem_free(mem, acc_w);
    mem_free(mem, acc_r);
    mem_free(mem, g);
    mem_free(mem, direct_d);
    if (status != 0) ring_free(ring, mem);
    return status;
}

void ring_compliance(const Ring* ring, double* compliance)
{
    int Z = ring->n_zone, i, j;
    for (i = 0; i < Z; i++) {
        for (j = 0; j < Z; j++) compliance[i * Z + j] = -AT(ring->static_gain, 3 + i, 1 + j);
    }
}
