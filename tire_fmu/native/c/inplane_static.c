/* inplane_static.c: the in-plane tire's static footprint (see inplane_static.h).
 *
 * Each pass assembles K + Jn_A^T diag(kn_A) Jn_A and solves it by LU with partial pivoting
 * (numerics.c), as the core's np.linalg.solve does; the products are taken in the core's order
 * (jn_a (kn jn_c)) so that the two differ by the solves' rounding alone. On the unreduced
 * nodal coordinates a point's row of Jn holds only its interpolation's few nodes: the
 * assembly runs over a row's nonzero entries, which on a Ritz basis are all of them. */
#include "inplane_static.h"

#include <math.h>
#include <string.h>

#include "numerics.h"

/* Refinement steps per solve: one from LU's own rounding (partial pivoting without LAPACK's
 * blocking loses about cond(A) eps) to the solution's rounding, and one to make sure. */
#define REFINEMENTS 2

size_t inplane_static_work_doubles(int n_coords, int n_points)
{
    if (n_coords < 1 || n_points < 1)
        return 0;
    size_t nc = (size_t)n_coords, p = (size_t)n_points;
    return nc * nc + 3 * nc + 3 * p; /* the pass's matrix (then its LU), y, b, a residual;
                                        pen0, the points' pushes (two parts) */
}

size_t inplane_static_work_ints(int n_coords, int n_points)
{
    if (n_coords < 1 || n_points < 1)
        return 0;
    return 2 * (size_t)n_coords + 2 * (size_t)n_points; /* pivots, a row's nonzeros, 2 sets */
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

/* One step of iterative refinement: y += A^-1 (b - A y), the residual summed in long double
 * from K and the active rows (A's LU has overwritten A); push holds 2 n_points doubles, each
 * active point's kn (Jn y)_i as a long double's high and low parts. */
static void refine(const InPlaneStaticData* d, const int* active, const double* b,
                   const double* lu, const int* pivot, double* y, double* residual,
                   double* push)
{
    int nc = d->n_coords, p = d->n_points, i, j;
    for (i = 0; i < p; i++) {
        const double* row = d->jn + (size_t)i * nc;
        long double along = 0.0L;
        if (!active[i])
            continue;
        for (j = 0; j < nc; j++)
            along += (long double)row[j] * y[j];
        along *= d->kn[i];
        push[2 * i] = (double)along;
        push[2 * i + 1] = (double)(along - push[2 * i]);
    }
    for (j = 0; j < nc; j++) {
        const double* row = d->stiffness + (size_t)j * nc;
        long double sum = b[j];
        for (i = 0; i < nc; i++)
            sum -= (long double)row[i] * y[i];
        for (i = 0; i < p; i++) {
            double jn = d->jn[(size_t)i * nc + j];
            if (active[i] && jn != 0.0)
                sum -= (long double)jn * ((long double)push[2 * i] + push[2 * i + 1]);
        }
        residual[j] = (double)sum;
    }
    lu_solve(lu, nc, pivot, residual);
    for (j = 0; j < nc; j++)
        y[j] += residual[j];
}

/* The state at a checked deflection into work's y (returned), the set into iwork's first
 * set (returned through *set); passes into *passes. */
static int solve_state(const InPlaneStaticData* d, double deflection_m, double* work, int* iwork,
                       double** y_out, int** set_out, int* passes, char* why, size_t size)
{
    int nc = d->n_coords, p = d->n_points;
    size_t nn = (size_t)nc * (size_t)nc;
    double* a = work;
    double* y = a + nn;
    double* b = y + nc;
    double* residual = b + nc;
    double* pen0 = residual + nc;
    double* push = pen0 + p;
    int* pivot = iwork;
    int* nonzero = pivot + nc;
    int* active = nonzero + nc;
    int* fresh = active + p;
    double r = d->radius_m;
    int i, j, k, pass;

    for (i = 0; i < p; i++) {
        pen0[i] = r - (r - deflection_m) * d->sec[i];
        active[i] = pen0[i] > 0.0;
    }
    for (pass = 1; pass <= d->max_passes; pass++) {
        int same = 1;
        memcpy(a, d->stiffness, sizeof(double) * nn);
        for (j = 0; j < nc; j++)
            b[j] = 0.0;
        for (i = 0; i < p; i++) {
            const double* row = d->jn + (size_t)i * nc;
            double kn = d->kn[i], push = kn * pen0[i];
            int count = 0;
            if (!active[i])
                continue;
            for (j = 0; j < nc; j++)
                if (row[j] != 0.0)
                    nonzero[count++] = j;
            for (j = 0; j < count; j++) {
                int aj = nonzero[j];
                double* arow = a + (size_t)aj * nc;
                b[aj] -= row[aj] * push;
                for (k = 0; k < count; k++) {
                    int ak = nonzero[k];
                    arow[ak] += row[aj] * (kn * row[ak]);
                }
            }
        }
        if (lu_factor(a, nc, pivot) != 0)
            return say_why(why, size, INPLANE_STATIC_SINGULAR,
                           "the static footprint's matrix at deflection_m = %g m is singular "
                           "(pass %d): allowed a stiffness definite on the set in contact",
                           deflection_m, pass);
        memcpy(y, b, sizeof(double) * (size_t)nc);
        lu_solve(a, nc, pivot, y);
        for (k = 0; k < REFINEMENTS; k++)
            refine(d, active, b, a, pivot, y, residual, push);
        for (i = 0; i < p; i++) {
            const double* row = d->jn + (size_t)i * nc;
            double pen = 0.0;
            for (j = 0; j < nc; j++)
                pen += row[j] * y[j];
            pen += pen0[i];
            fresh[i] = active[i] ? d->kn[i] * pen > 0.0 : pen > 0.0;
            if (fresh[i] != active[i])
                same = 0;
        }
        if (same) {
            *y_out = y;
            *set_out = active;
            *passes = pass;
            return INPLANE_STATIC_OK;
        }
        memcpy(active, fresh, sizeof(int) * (size_t)p);
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
    double* state;
    int* set;
    int taken, status = check_data(data, work, iwork, why, why_size);
    if (status)
        return status;
    status = check_deflection(data, deflection_m, why, why_size);
    if (status)
        return status;
    status = solve_state(data, deflection_m, work, iwork, &state, &set, &taken, why, why_size);
    if (status)
        return status;
    if (y != NULL)
        memcpy(y, state, sizeof(double) * (size_t)data->n_coords);
    if (active != NULL)
        memcpy(active, set, sizeof(int) * (size_t)data->n_points);
    if (load_n != NULL)
        *load_n = load_of(data, state);
    if (passes != NULL)
        *passes = taken;
    return INPLANE_STATIC_OK;
}

static int load_at(const InPlaneStaticData* d, double deflection_m, double* load_n,
                   double* work, int* iwork, char* why, size_t size)
{
    double* state;
    int* set;
    int taken, status = check_deflection(d, deflection_m, why, size);
    if (status)
        return status;
    status = solve_state(d, deflection_m, work, iwork, &state, &set, &taken, why, size);
    if (status)
        return status;
    *load_n = load_of(d, state);
    return INPLANE_STATIC_OK;
}

int inplane_deflection_for_load(const InPlaneStaticData* data, double load_n,
                                double* deflection_m, int* iterations, double* work,
                                int* iwork, char* why, size_t why_size)
{
    double lo = INPLANE_STATIC_SECANT_LO_M, hi = INPLANE_STATIC_SECANT_HI_M;
    double f_lo, f_hi, mid = NAN, f_mid;
    int n, status = check_data(data, work, iwork, why, why_size);
    if (status)
        return status;
    if (!(isfinite(load_n) && load_n > 0.0))
        return say_why(why, why_size, INPLANE_STATIC_BAD_LOAD,
                       "load_n = %g N: allowed a finite number above 0 N", load_n);
    status = load_at(data, lo, &f_lo, work, iwork, why, why_size);
    if (status == INPLANE_STATIC_OK)
        status = load_at(data, hi, &f_hi, work, iwork, why, why_size);
    if (status)
        return status;
    for (n = 1; n <= INPLANE_STATIC_SECANT_ITERATIONS; n++) {
        if (f_hi == f_lo)
            return say_why(why, why_size, INPLANE_STATIC_FLAT_SECANT,
                           "the load is the same (%g N) at deflections %g m and %g m: the "
                           "secant for load_n = %g N has no next deflection",
                           f_hi, lo, hi, load_n);
        mid = hi - (f_hi - load_n) * (hi - lo) / (f_hi - f_lo);
        status = load_at(data, mid, &f_mid, work, iwork, why, why_size);
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
    return INPLANE_STATIC_OK;
}
