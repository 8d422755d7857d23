/* inplane_ring.c: the in-plane ring's M, K and C (see inplane_ring.h), in C.
 *
 * It follows tire_fmu/core/inplane.py's InPlaneRing step by step, so that the two agree to
 * rounding (tests/test_inplane_ring_c.py compares them matrix by matrix): the ring's matrices
 * are first built on the "built" fields (w, v, w_s, v_s, or w, v massless), rim-relative, then
 * taken to the DOFs by G = t tie, where t subtracts the rim's rigid patterns (relative
 * matrices) and tie hands the tied sidewall's v_s to the tread's v. G has one ring entry and
 * three rim entries per built row, so G^T B G costs O(n^2) here where the Python's dense
 * products cost O(n^3). Each scalar is formed as the Python forms it (a product's grouping,
 * pow for the powers), and each energy term is summed on its own before it is added, as the
 * Python adds whole matrices. The two terms that are dense per field are formed from their
 * per-order values: the radial tie's circulant columns (the inverse DFT the Python takes with
 * irfft, summed here in O(N^2)) and the Hilbert circulant of the hysteretic loss (its closed
 * form, -(2/N) cot(pi m/N) on odd m for even N), applied to K's few entries per row. */
#include "inplane_ring.h"
#include "numerics.h"
#include "spec.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/* math.h's M_PI is not C99; the value of Python's math.pi */
#define PI 3.14159265358979323846

typedef struct {
    size_t offset;
    const char *name, *unit;
    double low, high;
    int low_inclusive, integer;
} Range;

#define FIELD(name) offsetof(InPlaneRingData, name), #name

/* core/parameters.py's TIRE_FIELDS (for the fields the ring reads) and core/inplane.py's
 * TANGENTIAL_RANGES: a native FMU refuses what the Python refuses. m_s is checked apart: the
 * massless ring does not read it. */
static const Range RANGES[] = {
    {FIELD(R), "m", 0.1, 3.0, 0, 0},
    {FIELD(b), "m", 0.01, 2.0, 0, 0},
    {FIELD(inflation_pressure), "Pa", 0.0, 3.0e6, 1, 0},
    {FIELD(rhoA), "kg/m", 1e-6, 1.0e4, 1, 0},
    {FIELD(k_r1), "N/m^2", 0.0, 1.0e12, 0, 0},
    {FIELD(k_r2), "N/m^2", 0.0, 1.0e12, 0, 0},
    {FIELD(EI), "N*m^2", 0.0, 1.0e8, 0, 0},
    {FIELD(alpha), "1/s", 0.0, 1.0e3, 1, 0},
    {FIELD(beta), "s", 0.0, 1.0e-1, 1, 0},
    {FIELD(sidewall_pressure_exponent), "", 0.0, 3.0, 1, 0},
    {FIELD(reference_pressure), "Pa", 1e4, 3.0e6, 1, 0},
    {FIELD(sidewall_max_order), "", 0.0, 1e5, 1, 1},
    {FIELD(EA), "N", 1e3, 1e12, 1, 0},
    {FIELD(k_t1), "N/m^2", 1e2, 1e12, 1, 0},
    {FIELD(k_t2), "N/m^2", 1e2, 1e12, 1, 0},
    {FIELD(rim_radius_m), "m", 1e-3, 10.0, 1, 0},
    {FIELD(wheel_mass_kg), "kg", 1e-3, 1e5, 1, 0},
    {FIELD(wheel_inertia_kg_m2), "kg*m^2", 1e-6, 1e5, 1, 0},
    {FIELD(k_tx), "N/m^2", 0.0, 1e12, 1, 0},
    {FIELD(friction_coefficient), "", 0.0, 3.0, 1, 0},
    {FIELD(loss_factor), "", 0.0, 1.0, 1, 0},
};
static const Range M_S_RANGE = {FIELD(m_s), "kg/m", 1e-6, 1.0e4, 1, 0};

/* below core/parameters.py's MIN_LAW_PRESSURE_PA the pressure law leaves the sidewall almost
 * without stiffness */
#define MIN_LAW_PRESSURE_PA 1e4

static int range_problem(const Range* r, const InPlaneRingData* d, char* why, size_t size)
{
    double v = *(const double*)((const char*)d + r->offset);
    int below = r->low_inclusive ? v < r->low : v <= r->low;
    if (isfinite(v) && !below && v <= r->high && (!r->integer || v == floor(v)))
        return INPLANE_RING_OK;
    const char* gap = r->unit[0] ? " " : "";
    return say_why(why, size, INPLANE_RING_BAD_DATA, "%s = %g%s%s: allowed %s in %s%g, %g]%s%s",
               r->name, v, gap, r->unit, r->integer ? "an integer" : "a finite number",
               r->low_inclusive ? "[" : "(", r->low, r->high, gap, r->unit);
}

static int valid_shape(int n_elements, int n_fields)
{
    return n_elements >= INPLANE_RING_MIN_ELEMENTS && n_elements <= INPLANE_RING_MAX_ELEMENTS
           && n_fields >= INPLANE_RING_MASSLESS && n_fields <= INPLANE_RING_LUMPED;
}

size_t inplane_ring_n_dof(int n_elements, int n_fields, int rim_free)
{
    if (!valid_shape(n_elements, n_fields))
        return 0;
    return (size_t)n_fields * (size_t)n_elements + (rim_free ? 3u : 0u);
}

/* the built fields: the tied sidewall is built with its own v_s and tied afterwards */
static int built_fields(int n_fields) { return n_fields == INPLANE_RING_MASSLESS ? 2 : 4; }

size_t inplane_ring_work_doubles(int n_elements, int n_fields)
{
    if (!valid_shape(n_elements, n_fields))
        return 0;
    size_t nb = (size_t)built_fields(n_fields) * (size_t)n_elements;
    /* two built matrices (the elastic one and one being worked on), a row of it, and the
     * sidewall's L^T L (2N x 2N), the patterns, the rim rows of G and two products with them
     * (3 columns each); a cosine table, the Hilbert column and the tie's three columns (N
     * each) */
    return 2 * nb * nb + 4 * (size_t)n_elements * n_elements + nb + 4 * 3 * nb
           + 5 * (size_t)n_elements;
}

int inplane_ring_check(const InPlaneRingData* d, int n_elements, int n_fields,
                       double spin_rad_s, char* why, size_t size)
{
    if (d == NULL)
        return say_why(why, size, INPLANE_RING_NULL, "no tire data given");
    if (n_elements < INPLANE_RING_MIN_ELEMENTS || n_elements > INPLANE_RING_MAX_ELEMENTS)
        return say_why(why, size, INPLANE_RING_BAD_ELEMENTS,
                   "n_elements = %d: allowed an integer in [%d, %d] (the bending stencil needs "
                   "distinct neighbours two nodes away; larger meshes cost too much to build)",
                   n_elements, INPLANE_RING_MIN_ELEMENTS, INPLANE_RING_MAX_ELEMENTS);
    if (n_fields < INPLANE_RING_MASSLESS || n_fields > INPLANE_RING_LUMPED)
        return say_why(why, size, INPLANE_RING_BAD_FIELDS,
                   "n_fields = %d: allowed 2 (massless sidewall), 3 (tied) or 4 (lumped)",
                   n_fields);
    if (!isfinite(spin_rad_s))
        return say_why(why, size, INPLANE_RING_BAD_SPIN,
                   "spin_rad_s = %g rad/s: allowed a finite number", spin_rad_s);
    for (size_t i = 0; i < sizeof RANGES / sizeof RANGES[0]; ++i) {
        int status = range_problem(&RANGES[i], d, why, size);
        if (status)
            return status;
    }
    if (n_fields != INPLANE_RING_MASSLESS) {
        int status = range_problem(&M_S_RANGE, d, why, size);
        if (status)
            return status;
    }
    if (d->sidewall_pressure_exponent > 0.0 && d->inflation_pressure < MIN_LAW_PRESSURE_PA)
        return say_why(why, size, INPLANE_RING_BAD_DATA,
                   "inflation_pressure = %g Pa: allowed at least %g Pa, or "
                   "sidewall_pressure_exponent = 0 (with sidewall_pressure_exponent = %g the "
                   "pressure law would leave the sidewall almost without stiffness)",
                   d->inflation_pressure, MIN_LAW_PRESSURE_PA, d->sidewall_pressure_exponent);
    if (d->rim_radius_m >= d->R)
        return say_why(why, size, INPLANE_RING_BAD_DATA,
                   "rim_radius_m = %g m: allowed below the tread radius R = %g m (the sidewall "
                   "spans from the rim to the tread)",
                   d->rim_radius_m, d->R);
    return INPLANE_RING_OK;
}

/* ----- building blocks ----- */

/* One row of a stencil operator: up to six (column, coefficient) pairs. */
typedef struct {
    int n;
    int col[6];
    double c[6];
} Row;

static void row_add(Row* r, int col, double c)
{
    r->col[r->n] = col;
    r->c[r->n] = c;
    r->n++;
}

/* out += (s c)^T c over the row's pairs: one row's share of (s A)^T A, the grouping of numpy's
 * `s * A.T @ A` (the scalar scales A.T before the product). Repeated columns add up, as
 * _circulant's np.add.at does. */
static void add_gram_row(double* out, int ld, const Row* r, double s)
{
    for (int p = 0; p < r->n; ++p) {
        double left = s * r->c[p];
        double* line = out + (size_t)r->col[p] * ld;
        for (int q = 0; q < r->n; ++q)
            line[r->col[q]] += left * r->c[q];
    }
}

static void add_into(double* a, const double* b, size_t count)
{
    for (size_t i = 0; i < count; ++i)
        a[i] += b[i];
}

/* (k_r1, k_r2) at the inflation pressure: TireParameters.effective_k_r1, _r2 */
static void effective_radial(const InPlaneRingData* d, double* k_r1, double* k_r2)
{
    double factor = 1.0;
    if (d->sidewall_pressure_exponent != 0.0)
        factor = pow(d->inflation_pressure / d->reference_pressure, d->sidewall_pressure_exponent);
    *k_r1 = d->k_r1 * factor;
    *k_r2 = d->k_r2 * factor;
}

typedef struct {
    int n, nb, n_fields, rim_free, n_dof;
    double dtheta, arc, kappa1, share; /* share: the tied sidewall's r = k_t1/(k_t1 + k_t2) */
    const double* patterns;            /* nb x 3: the built fields' rigid patterns */
} Ring;

/* core/inplane.py's hysteresis_share: the loss's share at this spin, linear up to
 * HYSTERESIS_FULL_SPEED_M_S of the tread, its sign the direction of rolling */
static double hysteresis_share(double spin_rad_s, double radius_m)
{
    double full = SPEC_HYSTERESIS_FULL_SPEED_M_S / radius_m;
    double share = spin_rad_s / full;
    return share > 1.0 ? 1.0 : (share < -1.0 ? -1.0 : share);
}

static inline int wrap(int j, int n) { return j < 0 ? j + n : (j >= n ? j - n : j); }

/* _built_elastic into e (nb x nb), term by term with tmp as scratch */
static void built_elastic(const Ring* g, const InPlaneRingData* d, double* e, double* tmp)
{
    int n = g->n, nb = g->nb;
    size_t all = (size_t)nb * nb;
    double dth = g->dtheta, a = g->arc, radius = d->R;
    double inv_d2 = pow(dth, -2.0);
    memset(e, 0, all * sizeof *e);

    /* membrane: e at j+1/2 from (w, v) = avg w + fwd v */
    double s = d->EA / pow(radius, 2.0) * a;
    for (int j = 0; j < n; ++j) {
        Row r = {0};
        row_add(&r, j, 0.5);
        row_add(&r, wrap(j + 1, n), 0.5);
        row_add(&r, n + j, -1.0 / dth);
        row_add(&r, n + wrap(j + 1, n), 1.0 / dth);
        add_gram_row(e, nb, &r, s);
    }

    /* bending: kappa at j = D2 w - D1 v */
    memset(tmp, 0, all * sizeof *tmp);
    s = d->EI / pow(radius, 4.0) * a;
    for (int j = 0; j < n; ++j) {
        Row r = {0};
        row_add(&r, wrap(j - 1, n), inv_d2);
        row_add(&r, j, -2.0 * inv_d2);
        row_add(&r, wrap(j + 1, n), inv_d2);
        row_add(&r, n + wrap(j - 1, n), -(-0.5 / dth));
        row_add(&r, n + wrap(j + 1, n), -(0.5 / dth));
        add_gram_row(tmp, nb, &r, s);
    }
    add_into(e, tmp, all);

    /* pressure: tension [[F^T F, D1], [-D1, F^T F]], F the forward difference */
    memset(tmp, 0, all * sizeof *tmp);
    double pretension = d->inflation_pressure * d->b * radius;
    double tension = pretension / pow(radius, 2.0) * a;
    for (int j = 0; j < n; ++j) {
        int f0 = j, f1 = wrap(j + 1, n);
        double c0 = -1.0 / dth, c1 = 1.0 / dth;
        for (int block = 0; block < 2; ++block) {
            double* base = tmp + (size_t)block * n * nb + (size_t)block * n;
            base[(size_t)f0 * nb + f0] += c0 * c0;
            base[(size_t)f0 * nb + f1] += c0 * c1;
            base[(size_t)f1 * nb + f0] += c1 * c0;
            base[(size_t)f1 * nb + f1] += c1 * c1;
        }
    }
    for (int block = 0; block < 2; ++block)
        for (int i = 0; i < n; ++i) {
            double* line = tmp + (size_t)(block * n + i) * nb + (size_t)block * n;
            for (int j = 0; j < n; ++j)
                line[j] = tension * line[j];
        }
    for (int j = 0; j < n; ++j) {
        int back = wrap(j - 1, n), ahead = wrap(j + 1, n);
        /* tension * D1 at (w, v) and tension * (-D1) at (v, w) */
        tmp[(size_t)j * nb + n + back] += tension * (-0.5 / dth);
        tmp[(size_t)j * nb + n + ahead] += tension * (0.5 / dth);
        tmp[(size_t)(n + j) * nb + back] += tension * -(-0.5 / dth);
        tmp[(size_t)(n + j) * nb + ahead] += tension * -(0.5 / dth);
    }
    add_into(e, tmp, all);

    /* the sidewall's springs (in series when massless) */
    double k_r1, k_r2, k_t1 = d->k_t1, k_t2 = d->k_t2;
    effective_radial(d, &k_r1, &k_r2);
    if (g->n_fields == INPLANE_RING_MASSLESS) {
        double k_r = k_r1 * k_r2 / (k_r1 + k_r2), k_t = k_t1 * k_t2 / (k_t1 + k_t2);
        for (int j = 0; j < n; ++j) {
            e[(size_t)j * nb + j] += a * k_r;
            e[(size_t)(n + j) * nb + n + j] += a * k_t;
        }
        return;
    }
    for (int j = 0; j < n; ++j) {
        int w = j, v = n + j, ws = 2 * n + j, vs = 3 * n + j;
        e[(size_t)w * nb + w] += a * k_r1;
        e[(size_t)w * nb + ws] += a * -k_r1;
        e[(size_t)ws * nb + w] += a * -k_r1;
        e[(size_t)ws * nb + ws] += a * (k_r1 + k_r2);
        e[(size_t)v * nb + v] += a * k_t1;
        e[(size_t)v * nb + vs] += a * -k_t1;
        e[(size_t)vs * nb + v] += a * -k_t1;
        e[(size_t)vs * nb + vs] += a * (k_t1 + k_t2);
    }
}

/* the built mass's diagonal entry of built DOF i */
static double built_mass(const Ring* g, const InPlaneRingData* d, int i)
{
    return (i < 2 * g->n ? d->rhoA : d->m_s) * g->arc;
}

/* L = D1 + kappa1 J on one (w, v) pair: row `row` of the pair's 2N x 2N block */
static Row pair_L_row(const Ring* g, int row)
{
    int n = g->n, j = row % n;
    double dth = g->dtheta;
    Row r = {0};
    if (row < n) {
        row_add(&r, wrap(j - 1, n), -0.5 / dth);
        row_add(&r, wrap(j + 1, n), 0.5 / dth);
        row_add(&r, n + j, -g->kappa1);
    } else {
        row_add(&r, j, g->kappa1);
        row_add(&r, n + wrap(j - 1, n), -0.5 / dth);
        row_add(&r, n + wrap(j + 1, n), 0.5 / dth);
    }
    return r;
}

/* A += G^T B G (relative: G = t tie; else G = tie): B is a built matrix (nb x nb), A one on
 * the DOFs (n_dof x n_dof). rim_rows (nb x 3) receives G's rim columns, bh and htb the
 * products B H and H^T B. */
static void assemble(const Ring* g, const double* b, int relative, double* out, double* rim_rows,
                     double* bh, double* htb)
{
    int n = g->n, nb = g->nb, nd = g->n_dof, tied = g->n_fields == INPLANE_RING_TIED;
    int rim0 = g->n_fields * n;
    /* the ring column and weight of a built row: the tied v_s is r v */
#define COLUMN(i) (tied && (i) >= 3 * n ? (i) - 2 * n : (i))
#define WEIGHT(i) (tied && (i) >= 3 * n ? g->share : 1.0)
    for (int i = 0; i < nb; ++i) {
        const double* line = b + (size_t)i * nb;
        double* target = out + (size_t)COLUMN(i) * nd;
        double gi = WEIGHT(i);
        if (gi == 1.0 && !tied) {
            for (int j = 0; j < nb; ++j)
                target[j] += line[j];
        } else {
            for (int j = 0; j < nb; ++j)
                target[COLUMN(j)] += gi * line[j] * WEIGHT(j);
        }
    }
    if (!g->rim_free)
        return;
    for (int i = 0; i < nb; ++i)
        for (int k = 0; k < 3; ++k) {
            /* the tie keeps v_s,rel = r v_rel: v_s = r v + (1 - r) P_v x_rim */
            double h = tied && i >= 3 * n ? (1.0 - g->share) * g->patterns[(size_t)(i - 2 * n) * 3 + k]
                                          : 0.0;
            if (relative)
                h -= g->patterns[(size_t)i * 3 + k];
            rim_rows[(size_t)i * 3 + k] = h;
        }
    memset(bh, 0, (size_t)nb * 3 * sizeof *bh);
    memset(htb, 0, (size_t)nb * 3 * sizeof *htb);
    for (int i = 0; i < nb; ++i) {
        const double* line = b + (size_t)i * nb;
        const double* hi = rim_rows + (size_t)i * 3;
        double s0 = 0.0, s1 = 0.0, s2 = 0.0;
        for (int j = 0; j < nb; ++j) {
            const double* hj = rim_rows + (size_t)j * 3;
            double x = line[j];
            s0 += x * hj[0];
            s1 += x * hj[1];
            s2 += x * hj[2];
            htb[j] += hi[0] * x;
            htb[nb + j] += hi[1] * x;
            htb[2 * nb + j] += hi[2] * x;
        }
        bh[(size_t)i * 3] = s0;
        bh[(size_t)i * 3 + 1] = s1;
        bh[(size_t)i * 3 + 2] = s2;
    }
    for (int i = 0; i < nb; ++i) {
        double gi = WEIGHT(i);
        double* target = out + (size_t)COLUMN(i) * nd + rim0;
        for (int k = 0; k < 3; ++k)
            target[k] += gi * bh[(size_t)i * 3 + k];
    }
    for (int k = 0; k < 3; ++k) {
        double* target = out + (size_t)(rim0 + k) * nd;
        for (int j = 0; j < nb; ++j)
            target[COLUMN(j)] += htb[(size_t)k * nb + j] * WEIGHT(j);
        for (int l = 0; l < 3; ++l) {
            double s = 0.0;
            for (int i = 0; i < nb; ++i)
                s += rim_rows[(size_t)i * 3 + k] * bh[(size_t)i * 3 + l];
            target[rim0 + l] += s;
        }
    }
#undef COLUMN
#undef WEIGHT
}

/* The radial sidewall's tie above sidewall_max_order (model.sidewall_tie_matrix): the first
 * columns of its tt, ss, ts circulants (per metre), from dispersion.sidewall_tie's per-order
 * values p [[r^2, -r], [-r, 1]], p = SIDEWALL_TIE_FACTOR (k0_tt + k0_ss), r = k_r1/k0_ss, on the
 * lumped stiffness at rest (discretisation.symbols summed as the core sums them). 0 where no
 * order is tied (massless, sidewall_max_order 0 or at least N/2), else 1. */
static int tie_columns(const Ring* g, const InPlaneRingData* d, double* cosines, double* tt,
                       double* ss, double* ts)
{
    int n = g->n, half = n / 2;
    double top = d->sidewall_max_order;
    if (g->n_fields == INPLANE_RING_MASSLESS || !(top > 0.0 && top < half))
        return 0;
    double k_r1, k_r2;
    effective_radial(d, &k_r1, &k_r2);
    double dth = g->dtheta, radius = d->R;
    double pretension = d->inflation_pressure * d->b * radius;
    for (int j = 0; j < n; ++j)
        cosines[j] = cos(2.0 * PI * j / n);
    memset(tt, 0, (size_t)n * sizeof *tt);
    memset(ss, 0, (size_t)n * sizeof *ss);
    memset(ts, 0, (size_t)n * sizeof *ts);
    for (int k = 0; k <= half; ++k) {
        if (!((double)k > top))
            continue;
        double c1 = cos(k * dth), c2 = cos((2.0 * k) * dth);
        double lam2 = -(pow(dth, -2.0) * ((c1 + -2.0) + c1));
        double lam4 = pow(dth, -4.0) * ((((c2 + -4.0 * c1) + 6.0) + -4.0 * c1) + c2);
        double k0_tt = d->EI / pow(radius, 4.0) * lam4 + pretension / pow(radius, 2.0) * lam2;
        k0_tt = k0_tt + k_r1;
        double k0_ss = k_r1 + k_r2; /* + the sidewall's shear, 0 in the in-plane ring */
        double ratio = k_r1 / k0_ss;
        double p = SPEC_SIDEWALL_TIE_FACTOR * (k0_tt + k0_ss);
        double s_tt = p * ratio * ratio, s_ss = p, s_ts = -p * ratio;
        /* the inverse DFT of a real even symbol: orders k and N - k alike, N/2 once */
        double weight = (k == 0 || 2 * k == n) ? 1.0 : 2.0;
        for (int m = 0; m < n; ++m) {
            double c = weight * cosines[(k * m) % n];
            tt[m] += s_tt * c;
            ss[m] += s_ss * c;
            ts[m] += s_ts * c;
        }
    }
    for (int m = 0; m < n; ++m) {
        tt[m] *= 1.0 / n;
        ss[m] *= 1.0 / n;
        ts[m] *= 1.0 / n;
    }
    return 1;
}

/* core/inplane.py's hilbert_circulant: H[j, m] = h[(j - m) mod N], i sign(sin(n dtheta)) on
 * order n, in closed form: -(2/N) cot(pi m/N) on odd m for even N, -(1/N) cot(pi m/(2N)) on odd
 * and (1/N) tan(pi m/(2N)) on even m for odd N. Formed for m <= N/2 and mirrored (h is odd),
 * so that the angle stays away from the cotangent's pole, where pi's rounding would tell. */
static void hilbert_column(int n, double* h)
{
    h[0] = 0.0;
    for (int m = 1; m <= n / 2; ++m) {
        double v;
        if (n % 2 == 0)
            v = m % 2 ? -(2.0 / n) / tan(PI * m / n) : 0.0;
        else
            v = m % 2 ? -(1.0 / n) / tan(PI * m / (2.0 * n)) : (1.0 / n) * tan(PI * m / (2.0 * n));
        h[m] = v;
        if (n - m != m)
            h[n - m] = -v;
    }
}

/* row i of (eta K) H, H the Hilbert circulant on every built field (InPlaneRing's
 * _built_hysteretic, `eta * K @ h`): each of K's few entries in the row spreads H's row over
 * its field */
static void hysteretic_row(const Ring* g, const double* e, double eta, const double* h, int i,
                           double* out)
{
    int n = g->n, nb = g->nb;
    const double* line = e + (size_t)i * nb;
    memset(out, 0, (size_t)nb * sizeof *out);
    for (int k = 0; k < nb; ++k) {
        if (line[k] == 0.0)
            continue;
        double c = eta * line[k];
        int field = k / n, local = k - field * n;
        double* target = out + (size_t)field * n;
        for (int j = 0; j <= local; ++j) /* H[k, j] = h[(k - j) mod N] */
            target[j] += c * h[local - j];
        for (int j = local + 1; j < n; ++j)
            target[j] += c * h[local - j + n];
    }
}

int inplane_ring_build(const InPlaneRingData* d, int n_elements, int n_fields,
                       double spin_rad_s, int rim_free, int hysteresis, double* mass,
                       double* stiffness, double* damping, double* hysteretic, double* work,
                       char* why, size_t why_size)
{
    int status = inplane_ring_check(d, n_elements, n_fields, spin_rad_s, why, why_size);
    if (status)
        return status;
    if (mass == NULL || stiffness == NULL || damping == NULL || work == NULL)
        return say_why(why, why_size, INPLANE_RING_NULL, "a matrix or the scratch memory is missing");

    Ring g;
    int n = n_elements;
    g.n = n;
    g.n_fields = n_fields;
    g.nb = built_fields(n_fields) * n;
    g.rim_free = rim_free != 0;
    g.n_dof = (int)inplane_ring_n_dof(n, n_fields, g.rim_free);
    g.dtheta = 2.0 * PI / n;
    g.arc = d->R * g.dtheta;
    g.kappa1 = sin(g.dtheta) / g.dtheta;
    g.share = d->k_t1 / (d->k_t1 + d->k_t2);

    int nb = g.nb;
    size_t all = (size_t)nb * nb, dofs = (size_t)g.n_dof * g.n_dof;
    double *e = work, *w = e + all, *block = w + all, *row = block + (size_t)4 * n * n,
           *patterns = row + nb;
    double *rim_rows = patterns + 3 * (size_t)nb, *bh = rim_rows + 3 * (size_t)nb,
           *htb = bh + 3 * (size_t)nb;
    double *cosines = htb + 3 * (size_t)nb;
    double *hilbert = cosines + n, *tie_tt = hilbert + n, *tie_ss = tie_tt + n,
           *tie_ts = tie_ss + n;
    g.patterns = patterns;
    /* radial (-sin, -cos, 0) and tangential (-cos, sin, R) per (w, v) pair */
    for (int i = 0; i < nb; ++i) {
        int j = i % n, tangential = (i / n) % 2;
        double th = j * g.dtheta;
        double* p = patterns + (size_t)i * 3;
        p[0] = tangential ? -cos(th) : -sin(th);
        p[1] = tangential ? sin(th) : -cos(th);
        p[2] = tangential ? d->R : 0.0;
    }
    memset(mass, 0, dofs * sizeof *mass);
    memset(stiffness, 0, dofs * sizeof *stiffness);
    memset(damping, 0, dofs * sizeof *damping);
    if (hysteretic != NULL)
        memset(hysteretic, 0, dofs * sizeof *hysteretic);

    built_elastic(&g, d, e, w);

    /* material damping alpha M + beta K, on the rim-relative rates */
    for (int i = 0; i < nb; ++i)
        for (int j = 0; j < nb; ++j) {
            double m = i == j ? built_mass(&g, d, i) : 0.0;
            w[(size_t)i * nb + j] = d->alpha * m + d->beta * e[(size_t)i * nb + j];
        }
    assemble(&g, w, 1, damping, rim_rows, bh, htb);

    /* rolling: the circulatory Omega C D1 (D1 on each built field), row by row from C */
    double omega = spin_rad_s, dth = g.dtheta;
    for (int i = 0; i < nb; ++i) {
        double* line = w + (size_t)i * nb;
        memcpy(row, line, (size_t)nb * sizeof *row);
        for (int f = 0; f < nb / n; ++f)
            for (int q = 0; q < n; ++q) {
                /* column q of D1: +1/(2 dtheta) from row q - 1, -1/(2 dtheta) from row q + 1 */
                line[f * n + q] = omega * row[f * n + wrap(q - 1, n)] * (0.5 / dth)
                                  + omega * row[f * n + wrap(q + 1, n)] * (-0.5 / dth);
            }
    }
    /* the sidewall's net centrifugal term -m_s Omega^2 [L^T L - (R/l) E_v] */
    if (n_fields != INPLANE_RING_MASSLESS && omega != 0.0) {
        double s = pow(omega, 2.0) * d->m_s * g.arc;
        size_t side = (size_t)2 * n;
        /* L^T L - (R/l) E_v formed whole, then scaled and subtracted, as the Python does */
        memset(block, 0, (size_t)4 * n * n * sizeof *block);
        for (int r = 0; r < 2 * n; ++r) {
            Row lr = pair_L_row(&g, r);
            add_gram_row(block, 2 * n, &lr, 1.0);
        }
        double ratio = d->R / (d->R - d->rim_radius_m);
        for (int j = 0; j < n; ++j)
            block[(size_t)(n + j) * 2 * n + n + j] -= ratio;
        for (int i = 0; i < 2 * n; ++i)
            for (int j = 0; j < 2 * n; ++j)
                w[(side + i) * nb + side + j] -= s * block[(size_t)i * 2 * n + j];
    }
    add_into(w, e, all); /* w = rolling + elastic: the order of the Python's sum is immaterial */
    /* the radial tie (tread w, sidewall w_s), elastic only: no damper and no loss act on it */
    if (tie_columns(&g, d, cosines, tie_tt, tie_ss, tie_ts)) {
        size_t ws = (size_t)2 * n;
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) {
                int m = wrap(i - j, n);
                w[(size_t)i * nb + j] += tie_tt[m] * g.arc;
                w[(size_t)i * nb + ws + j] += tie_ts[m] * g.arc;
                w[(ws + i) * nb + j] += tie_ts[m] * g.arc;
                w[(ws + i) * nb + ws + j] += tie_ss[m] * g.arc;
            }
    }
    /* the hysteretic loss eta K H at its share of the spin; K the elastic one, without the tie */
    double eta = d->loss_factor;
    double share = hysteresis ? hysteresis_share(omega, d->R) : 0.0;
    if (eta != 0.0)
        hilbert_column(n, hilbert);
    if (eta != 0.0 && share != 0.0)
        for (int i = 0; i < nb; ++i) {
            double* line = w + (size_t)i * nb;
            hysteretic_row(&g, e, eta, hilbert, i, row);
            for (int j = 0; j < nb; ++j)
                line[j] += share * row[j];
        }
    assemble(&g, w, 1, stiffness, rim_rows, bh, htb);
    if (hysteretic != NULL && eta != 0.0) {
        for (int i = 0; i < nb; ++i)
            hysteretic_row(&g, e, eta, hilbert, i, w + (size_t)i * nb);
        assemble(&g, w, 1, hysteretic, rim_rows, bh, htb);
    }

    /* gyroscopic 2 Omega M L on the absolute velocities */
    memset(w, 0, all * sizeof *w);
    for (int i = 0; i < nb; ++i) {
        double m = 2.0 * omega * built_mass(&g, d, i);
        int pair = i / (2 * n);
        Row lr = pair_L_row(&g, i - pair * 2 * n);
        for (int k = 0; k < lr.n; ++k)
            w[(size_t)i * nb + pair * 2 * n + lr.col[k]] += m * lr.c[k];
    }
    assemble(&g, w, 0, damping, rim_rows, bh, htb);

    memset(w, 0, all * sizeof *w);
    for (int i = 0; i < nb; ++i)
        w[(size_t)i * nb + i] = built_mass(&g, d, i);
    assemble(&g, w, 0, mass, rim_rows, bh, htb);
    if (g.rim_free) {
        int rim0 = n_fields * n;
        double wheel[3] = {d->wheel_mass_kg, d->wheel_mass_kg, d->wheel_inertia_kg_m2};
        for (int k = 0; k < 3; ++k)
            mass[(size_t)(rim0 + k) * g.n_dof + rim0 + k] += wheel[k];
    }
    return INPLANE_RING_OK;
}
