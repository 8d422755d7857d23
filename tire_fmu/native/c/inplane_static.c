/* inplane_static.c: the in-plane tire's static footprint (see inplane_static.h).
 *
 * A pass's matrix is K plus a low-rank term from the points in contact, so each pass is
 * solved by the Woodbury identity on K's one factor (Cholesky's; numerics.c's LU for a K
 * that is not symmetric definite):
 *     (K + Jn_A^T D Jn_A)^-1 r = u - Z_A (I + D W_AA)^-1 D Jn_A u,   u = K^-1 r,
 * with Z's columns z_i = K^-1 Jn_i^T and W = Jn Z, made for a point the first time it is in
 * contact and kept for every later pass and deflection (the secant's trials share them).
 * A pass then costs a small LU of the set's size instead of the core's LU of the
 * coordinates'. Its rounding is not the core's np.linalg.solve's: the solve is refined from
 * residuals summed in long double on the full system (once, before the set is judged; once
 * more on the last pass) until it is the system's solution to its last digits, which the
 * core's is to about cond(A) eps (where long double is double, as with MSVC, the refinement
 * still leaves a backward-stable solve of the core's accuracy). The set's rules are the core's:
 * a point in contact stays while its force kn pen is positive, one off the road joins when
 * its pen is. */
#include "inplane_static.h"

#include <math.h>
#include <string.h>

#include "numerics.h"

/* K counts as symmetric (for Cholesky's factor) when its halves differ by at most this share
 * of its largest entry: the Ritz products' rounding, far below any physical asymmetry. */
#define SYMMETRIC 1e-12

size_t inplane_static_work_doubles(int n_coords, int n_points)
{
    if (n_coords < 1 || n_points < 1)
        return 0;
    size_t nc = (size_t)n_coords, p = (size_t)n_points;
    return nc * nc + p * nc /* K's LU, the points' z */
           + 2 * p * p      /* W, the set's matrix (then its LU) */
           + 4 * nc         /* y, b, a residual, u */
           + 4 * p;         /* pen0, the pushes (two parts), the set's small vector */
}

size_t inplane_static_work_ints(int n_coords, int n_points)
{
    if (n_coords < 1 || n_points < 1)
        return 0;
    return (size_t)n_coords + 6 * (size_t)n_points; /* K's pivots; the set's pivots, its list,
                                                      z made, two sets */
}

/* a . b in four sums (for the pipeline: the kernel's -O2 does not vectorise). */
static double dot(const double* a, const double* b, int n)
{
    double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
    int k;
    for (k = 0; k + 3 < n; k += 4) {
        s0 += a[k] * b[k];
        s1 += a[k + 1] * b[k + 1];
        s2 += a[k + 2] * b[k + 2];
        s3 += a[k + 3] * b[k + 3];
    }
    for (; k < n; k++)
        s0 += a[k] * b[k];
    return (s0 + s1) + (s2 + s3);
}

/* Cholesky's L of a symmetric definite a (row major, its lower triangle read, L written
 * over it) by rows, each entry a dot product of two rows' beginnings; -1 at a pivot not
 * above 0. */
static int cholesky_factor(double* a, int n)
{
    int i, j;
    for (i = 0; i < n; i++) {
        double* ri = a + (size_t)i * n;
        for (j = 0; j <= i; j++) {
            const double* rj = a + (size_t)j * n;
            double sum = ri[j] - dot(ri, rj, j);
            if (i == j) {
                if (!(sum > 0.0) || !isfinite(sum))
                    return -1;
                ri[i] = sqrt(sum);
            } else {
                ri[j] = sum / rj[j];
            }
        }
    }
    return 0;
}

/* x = (L L^T)^-1 x, L from cholesky_factor. */
static void cholesky_solve(const double* l, int n, double* x)
{
    int i, k;
    for (i = 0; i < n; i++) {
        const double* ri = l + (size_t)i * n;
        x[i] = (x[i] - dot(ri, x, i)) / ri[i];
    }
    for (i = n - 1; i >= 0; i--) {
        double sum = x[i] / l[(size_t)i * n + i];
        x[i] = sum;
        for (k = 0; k < i; k++)
            x[k] -= l[(size_t)i * n + k] * sum;
    }
}

typedef struct {
    double *k_lu, *z, *w, *s, *y, *b, *residual, *u, *pen0, *push, *small;
    int *k_pivot, *s_pivot, *list, *have_z, *active, *fresh;
    int count;    /* points in the set (list) */
    int cholesky; /* k_lu holds K's Cholesky factor (else its LU) */
} Scratch;

static void lay_out(const InPlaneStaticData* d, double* work, int* iwork, Scratch* sc)
{
    size_t nc = (size_t)d->n_coords, p = (size_t)d->n_points;
    sc->k_lu = work;
    sc->z = sc->k_lu + nc * nc;
    sc->w = sc->z + p * nc;
    sc->s = sc->w + p * p;
    sc->y = sc->s + p * p;
    sc->b = sc->y + nc;
    sc->residual = sc->b + nc;
    sc->u = sc->residual + nc;
    sc->pen0 = sc->u + nc;
    sc->push = sc->pen0 + p;
    sc->small = sc->push + 2 * p;
    sc->k_pivot = iwork;
    sc->s_pivot = sc->k_pivot + nc;
    sc->list = sc->s_pivot + p;
    sc->have_z = sc->list + p;
    sc->active = sc->have_z + p;
    sc->fresh = sc->active + p;
    sc->count = 0;
}

static int all_finite(const double* x, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++)
        if (!isfinite(x[i]))
            return 0;
    return 1;
}

static int check_data(const InPlaneStaticData* d, const void* work, const void* iwork, char* why,
                      size_t size)
{
    if (d == NULL)
        return say_why(why, size, INPLANE_STATIC_NULL, "no footprint data given");
    if (d->n_coords < 1)
        return say_why(why, size, INPLANE_STATIC_BAD_SIZE,
                       "n_coords = %d: allowed an integer of at least 1", d->n_coords);
    if (d->n_points < 1)
        return say_why(why, size, INPLANE_STATIC_BAD_SIZE,
                       "n_points = %d: allowed an integer of at least 1", d->n_points);
    if (d->max_passes < 1)
        return say_why(why, size, INPLANE_STATIC_BAD_SIZE,
                       "max_passes = %d: allowed an integer of at least 1", d->max_passes);
    if (d->stiffness == NULL || d->jn == NULL || d->kn == NULL || d->sec == NULL
        || d->rim_fz_row == NULL || work == NULL || iwork == NULL)
        return say_why(why, size, INPLANE_STATIC_NULL,
                       "an input (stiffness, jn, kn, sec, rim_fz_row) or the scratch memory is "
                       "missing");
    if (!(isfinite(d->radius_m) && d->radius_m > 0.0))
        return say_why(why, size, INPLANE_STATIC_BAD_DATA,
                       "radius_m = %g m: allowed a finite number above 0 m", d->radius_m);
    {
        size_t nc = (size_t)d->n_coords, p = (size_t)d->n_points;
        const char* name = NULL;
        if (!all_finite(d->stiffness, nc * nc))
            name = "stiffness";
        else if (!all_finite(d->jn, p * nc))
            name = "jn";
        else if (!all_finite(d->kn, p))
            name = "kn";
        else if (!all_finite(d->sec, p))
            name = "sec";
        else if (!all_finite(d->rim_fz_row, nc))
            name = "rim_fz_row";
        if (name != NULL)
            return say_why(why, size, INPLANE_STATIC_BAD_DATA,
                           "%s has a non-finite entry: allowed finite numbers only", name);
    }
    return INPLANE_STATIC_OK;
}

static int check_deflection(const InPlaneStaticData* d, double deflection_m, char* why,
                            size_t size)
{
    if (!(isfinite(deflection_m) && deflection_m >= 0.0 && deflection_m < d->radius_m))
        return say_why(why, size, INPLANE_STATIC_BAD_DEFLECTION,
                       "deflection_m = %g m: allowed a finite number in [0, %g) m (below the "
                       "tread radius R)",
                       deflection_m, d->radius_m);
    return INPLANE_STATIC_OK;
}

/* K's factor, no point's z made yet: Cholesky's where K is symmetric and definite (at rest
 * with the rim held it is, to the Ritz products' rounding, which the refinement's residual on
 * the whole K takes out), else the LU. */
static int prepare(const InPlaneStaticData* d, Scratch* sc, char* why, size_t size)
{
    int nc = d->n_coords, i, j;
    size_t nn = (size_t)nc * (size_t)nc;
    double big = 0.0, skew = 0.0;
    for (i = 0; i < nc; i++)
        for (j = 0; j <= i; j++) {
            double upper = d->stiffness[(size_t)j * nc + i];
            double lower = d->stiffness[(size_t)i * nc + j];
            if (fabs(lower) > big)
                big = fabs(lower);
            if (fabs(upper - lower) > skew)
                skew = fabs(upper - lower);
        }
    for (i = 0; i < d->n_points; i++)
        sc->have_z[i] = 0;
    memcpy(sc->k_lu, d->stiffness, sizeof(double) * nn);
    sc->cholesky = skew <= SYMMETRIC * big && cholesky_factor(sc->k_lu, nc) == 0;
    if (sc->cholesky)
        return INPLANE_STATIC_OK;
    memcpy(sc->k_lu, d->stiffness, sizeof(double) * nn);
    if (lu_factor(sc->k_lu, nc, sc->k_pivot) != 0)
        return say_why(why, size, INPLANE_STATIC_SINGULAR,
                       "stiffness is singular: allowed a stiffness definite with the rim held");
    return INPLANE_STATIC_OK;
}

static void k_solve(const InPlaneStaticData* d, const Scratch* sc, double* x)
{
    if (sc->cholesky)
        cholesky_solve(sc->k_lu, d->n_coords, x);
    else
        lu_solve(sc->k_lu, d->n_coords, sc->k_pivot, x);
}

/* z_i = K^-1 Jn_i^T and W's column i, the first time point i is in the set. */
static void need_z(const InPlaneStaticData* d, Scratch* sc, int i)
{
    int nc = d->n_coords, p = d->n_points, j;
    double* z = sc->z + (size_t)i * nc;
    if (sc->have_z[i])
        return;
    memcpy(z, d->jn + (size_t)i * nc, sizeof(double) * (size_t)nc);
    k_solve(d, sc, z);
    for (j = 0; j < p; j++)
        sc->w[(size_t)j * p + i] = dot(d->jn + (size_t)j * nc, z, nc);
    sc->have_z[i] = 1;
}

/* The set's list and the LU of I + D W_AA; -1 when that is singular. */
static int factor_set(const InPlaneStaticData* d, Scratch* sc)
{
    int p = d->n_points, m = 0, a, c;
    for (a = 0; a < p; a++)
        if (sc->active[a]) {
            need_z(d, sc, a);
            sc->list[m++] = a;
        }
    sc->count = m;
    for (a = 0; a < m; a++) {
        int i = sc->list[a];
        for (c = 0; c < m; c++)
            sc->s[(size_t)a * m + c] = (a == c ? 1.0 : 0.0)
                                       + d->kn[i] * sc->w[(size_t)i * p + sc->list[c]];
    }
    return m ? lu_factor(sc->s, m, sc->s_pivot) : 0;
}

/* x = (K + Jn_A^T D Jn_A)^-1 r by the Woodbury identity (r and x may be the same). */
static void solve_set(const InPlaneStaticData* d, Scratch* sc, const double* r, double* x)
{
    int nc = d->n_coords, m = sc->count, a, k;
    double* u = sc->u;
    memcpy(u, r, sizeof(double) * (size_t)nc);
    k_solve(d, sc, u);
    for (a = 0; a < m; a++) {
        int i = sc->list[a];
        sc->small[a] = d->kn[i] * dot(d->jn + (size_t)i * nc, u, nc);
    }
    if (m)
        lu_solve(sc->s, m, sc->s_pivot, sc->small);
    for (k = 0; k < nc; k++)
        x[k] = u[k];
    for (a = 0; a < m; a++) {
        const double* z = sc->z + (size_t)sc->list[a] * nc;
        double h = sc->small[a];
        for (k = 0; k < nc; k++)
            x[k] -= h * z[k];
    }
}

/* One step of iterative refinement: y += A^-1 (b - A y), the residual summed in long double
 * from K and the active rows of Jn; push holds each active point's kn (Jn y)_i as a long
 * double's high and low parts. */
static void refine(const InPlaneStaticData* d, Scratch* sc)
{
    int nc = d->n_coords, p = d->n_points, i, j;
    double *y = sc->y, *push = sc->push, *residual = sc->residual;
    for (i = 0; i < p; i++) {
        const double* row = d->jn + (size_t)i * nc;
        long double along = 0.0L;
        if (!sc->active[i])
            continue;
        for (j = 0; j < nc; j++)
            along += (long double)row[j] * y[j];
        along *= d->kn[i];
        push[2 * i] = (double)along;
        push[2 * i + 1] = (double)(along - push[2 * i]);
    }
    for (j = 0; j < nc; j++) {
        const double* row = d->stiffness + (size_t)j * nc;
        long double sum = sc->b[j];
        for (i = 0; i < nc; i++)
            sum -= (long double)row[i] * y[i];
        for (i = 0; i < p; i++) {
            double jn = d->jn[(size_t)i * nc + j];
            if (sc->active[i] && jn != 0.0)
                sum -= (long double)jn * ((long double)push[2 * i] + push[2 * i + 1]);
        }
        residual[j] = (double)sum;
    }
    solve_set(d, sc, residual, residual);
    for (j = 0; j < nc; j++)
        y[j] += residual[j];
}

/* The state at a checked deflection, K prepared: y into sc->y, the set into sc->active;
 * passes into *passes. */
static int solve_state(const InPlaneStaticData* d, double deflection_m, Scratch* sc,
                       int* passes, char* why, size_t size)
{
    int nc = d->n_coords, p = d->n_points;
    double r = d->radius_m;
    int i, j, pass;

    for (i = 0; i < p; i++) {
        sc->pen0[i] = r - (r - deflection_m) * d->sec[i];
        sc->active[i] = sc->pen0[i] > 0.0;
    }
    for (pass = 1; pass <= d->max_passes; pass++) {
        int same = 1;
        for (j = 0; j < nc; j++)
            sc->b[j] = 0.0;
        for (i = 0; i < p; i++) {
            const double* row = d->jn + (size_t)i * nc;
            double push = d->kn[i] * sc->pen0[i];
            if (!sc->active[i])
                continue;
            for (j = 0; j < nc; j++)
                sc->b[j] -= row[j] * push;
        }
        if (factor_set(d, sc) != 0)
            return say_why(why, size, INPLANE_STATIC_SINGULAR,
                           "the static footprint's matrix at deflection_m = %g m is singular "
                           "(pass %d): allowed a stiffness definite on the set in contact",
                           deflection_m, pass);
        solve_set(d, sc, sc->b, sc->y);
        refine(d, sc);
        for (i = 0; i < p; i++) {
            double pen = dot(d->jn + (size_t)i * nc, sc->y, nc) + sc->pen0[i];
            sc->fresh[i] = sc->active[i] ? d->kn[i] * pen > 0.0 : pen > 0.0;
            if (sc->fresh[i] != sc->active[i])
                same = 0;
        }
        if (same) {
            refine(d, sc);
            *passes = pass;
            return INPLANE_STATIC_OK;
        }
        memcpy(sc->active, sc->fresh, sizeof(int) * (size_t)p);
    }
    return say_why(why, size, INPLANE_STATIC_UNSETTLED,
                   "the static footprint did not settle (deflection_m = %g m, max_passes = %d)",
                   deflection_m, d->max_passes);
}

static double load_of(const InPlaneStaticData* d, const double* y)
{
    double sum = 0.0;
    int j;
    for (j = 0; j < d->n_coords; j++)
        sum += d->rim_fz_row[j] * y[j];
    return -sum;
}

int inplane_static_state(const InPlaneStaticData* data, double deflection_m, double* y,
                         int* active, double* load_n, int* passes, double* work, int* iwork,
                         char* why, size_t why_size)
{
    Scratch sc;
    int taken, status = check_data(data, work, iwork, why, why_size);
    if (status)
        return status;
    status = check_deflection(data, deflection_m, why, why_size);
    if (status)
        return status;
    lay_out(data, work, iwork, &sc);
    status = prepare(data, &sc, why, why_size);
    if (status == INPLANE_STATIC_OK)
        status = solve_state(data, deflection_m, &sc, &taken, why, why_size);
    if (status)
        return status;
    if (y != NULL)
        memcpy(y, sc.y, sizeof(double) * (size_t)data->n_coords);
    if (active != NULL)
        memcpy(active, sc.active, sizeof(int) * (size_t)data->n_points);
    if (load_n != NULL)
        *load_n = load_of(data, sc.y);
    if (passes != NULL)
        *passes = taken;
    return INPLANE_STATIC_OK;
}

static int load_at(const InPlaneStaticData* d, double deflection_m, Scratch* sc,
                   double* load_n, char* why, size_t size)
{
    int taken, status = check_deflection(d, deflection_m, why, size);
    if (status == INPLANE_STATIC_OK)
        status = solve_state(d, deflection_m, sc, &taken, why, size);
    if (status == INPLANE_STATIC_OK)
        *load_n = load_of(d, sc->y);
    return status;
}

int inplane_deflection_for_load(const InPlaneStaticData* data, double load_n,
                                double* deflection_m, int* iterations, double* y, int* active,
                                double* work, int* iwork, char* why, size_t why_size)
{
    double lo = INPLANE_STATIC_SECANT_LO_M, hi = INPLANE_STATIC_SECANT_HI_M;
    double f_lo, f_hi, mid = NAN, f_mid;
    Scratch sc;
    int n, status = check_data(data, work, iwork, why, why_size);
    if (status)
        return status;
    if (!(isfinite(load_n) && load_n > 0.0))
        return say_why(why, why_size, INPLANE_STATIC_BAD_LOAD,
                       "load_n = %g N: allowed a finite number above 0 N", load_n);
    lay_out(data, work, iwork, &sc);
    status = prepare(data, &sc, why, why_size);
    if (status == INPLANE_STATIC_OK)
        status = load_at(data, lo, &sc, &f_lo, why, why_size);
    if (status == INPLANE_STATIC_OK)
        status = load_at(data, hi, &sc, &f_hi, why, why_size);
    if (status)
        return status;
    for (n = 1; n <= INPLANE_STATIC_SECANT_ITERATIONS; n++) {
        if (f_hi == f_lo)
            return say_why(why, why_size, INPLANE_STATIC_FLAT_SECANT,
                           "the load is the same (%g N) at deflections %g m and %g m: the "
                           "secant for load_n = %g N has no next deflection",
                           f_hi, lo, hi, load_n);
        mid = hi - (f_hi - load_n) * (hi - lo) / (f_hi - f_lo);
        status = load_at(data, mid, &sc, &f_mid, why, why_size);
        if (status)
            return status;
        if (fabs(f_mid - load_n) < INPLANE_STATIC_SECANT_TOLERANCE * load_n)
            break;
        lo = hi;
        f_lo = f_hi;
        hi = mid;
        f_hi = f_mid;
    }
    if (deflection_m != NULL)
        *deflection_m = mid;
    if (iterations != NULL)
        *iterations = n > INPLANE_STATIC_SECANT_ITERATIONS ? INPLANE_STATIC_SECANT_ITERATIONS : n;
    if (y != NULL)
        memcpy(y, sc.y, sizeof(double) * (size_t)data->n_coords);
    if (active != NULL)
        memcpy(active, sc.active, sizeof(int) * (size_t)data->n_points);
    return INPLANE_STATIC_OK;
}
