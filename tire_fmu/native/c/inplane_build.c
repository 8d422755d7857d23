/* inplane_build.c: the in-plane step's matrices at a spin (inplane_build.h says what).
 *
 * Every entry-wise formula keeps the Python's order of operations (its scalars first, as numpy
 * multiplies a scalar product into an array), so those entries are the Python's to the bit;
 * the inverse and the products round in their own order. */
#include "inplane_build.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "numerics.h"
#include "spec.h"

/* A carry's departure point is refused beyond this many spacings: its base must fit an int
 * (a step moves the tread by far less than one spacing in any use). */
#define MAX_SHIFT_SPACINGS 1e6

static int say(char* why, size_t size, int status, const char* format, ...)
{
    if (why != NULL && size > 0) {
        va_list args;
        va_start(args, format);
        vsnprintf(why, size, format, args);
        va_end(args);
    }
    return status;
}

static int sizes_ok(int ny, int np)
{
    return ny >= 1 && ny <= INPLANE_BUILD_MAX_NY && np >= 2 && np <= INPLANE_BUILD_MAX_NP;
}

size_t inplane_build_work_doubles(int ny, int np)
{
    if (!sizes_ok(ny, np)) return 0;
    return (size_t)ny * (size_t)ny + (size_t)ny;
}

size_t inplane_build_work_ints(int ny)
{
    return ny >= 1 && ny <= INPLANE_BUILD_MAX_NY ? (size_t)ny : 0;
}

/* The first non-finite entry of a (rows x cols): its status and sentence, else 0. */
static int finite_entries(const char* name, const double* a, int rows, int cols, char* why,
                          size_t size)
{
    size_t i, count = (size_t)rows * (size_t)cols;
    for (i = 0; i < count; i++) {
        if (!isfinite(a[i])) {
            char text[40];
            value_text(a[i], "", text, sizeof text);
            return say(why, size, INPLANE_BUILD_BAD_INPUT,
                       "%s[%d, %d] = %s: the entries must be finite", name,
                       (int)(i / (size_t)cols), (int)(i % (size_t)cols), text);
        }
    }
    return 0;
}

/* What both parts need: the sizes, the step, the spin, the points' angles, jxw and jl. */
static int check_common(const InPlaneBuildInput* in, double spin, const void* out, char* why,
                        size_t size)
{
    char text[40];
    int status, p;
    double spacing;
    if (in == NULL || out == NULL)
        return say(why, size, INPLANE_BUILD_NULL, "the input and the output must be given");
    if (!sizes_ok(in->ny, in->np))
        return say(why, size, INPLANE_BUILD_BAD_SIZE,
                   "ny = %d, np = %d: the coordinates must number 1 to %d and the contact "
                   "points 2 to %d", in->ny, in->np, INPLANE_BUILD_MAX_NY,
                   INPLANE_BUILD_MAX_NP);
    if (!(isfinite(in->h) && in->h >= INPLANE_BUILD_MIN_STEP_S
          && in->h <= INPLANE_BUILD_MAX_STEP_S)) {
        value_text(in->h, "s", text, sizeof text);
        return say(why, size, INPLANE_BUILD_BAD_STEP, "h = %s: the step must be in [%g, %g] s",
                   text, INPLANE_BUILD_MIN_STEP_S, INPLANE_BUILD_MAX_STEP_S);
    }
    if (in->point_theta == NULL || in->jxw == NULL || in->jl == NULL)
        return say(why, size, INPLANE_BUILD_NULL, "point_theta, jxw and jl must be given");
    if ((status = finite_entries("point_theta", in->point_theta, 1, in->np, why, size)))
        return status;
    for (p = 1; p < in->np; p++) {
        if (!(in->point_theta[p] > in->point_theta[p - 1]))
            return say(why, size, INPLANE_BUILD_BAD_INPUT,
                       "point_theta[%d] = %.17g after %.17g: the points' angles must increase",
                       p, in->point_theta[p], in->point_theta[p - 1]);
    }
    spacing = (in->point_theta[in->np - 1] - in->point_theta[0]) / (in->np - 1);
    if (!(isfinite(spin) && fabs(spin) * in->h <= MAX_SHIFT_SPACINGS * spacing)) {
        value_text(spin, "rad/s", text, sizeof text);
        return say(why, size, INPLANE_BUILD_BAD_SPIN,
                   "spin_rad_s = %s: the spin must be finite and turn the tread by at most "
                   "%g point spacings a step (|spin| <= %.6g rad/s here)", text,
                   MAX_SHIFT_SPACINGS, MAX_SHIFT_SPACINGS * spacing / in->h);
    }
    if ((status = finite_entries("jxw", in->jxw, in->np, in->ny, why, size))) return status;
    return finite_entries("jl", in->jl, in->np, in->ny, why, size);
}

static int check_ring(const InPlaneBuildInput* in, double spin, const InPlaneBuildOutput* out,
                      const double* work, const int* iwork, char* why, size_t size)
{
    const char* names[] = {"m", "c0", "c1", "k0", "k1", "k2", "kh", "jn", "jnw", "kx", "cx"};
    const double* arrays[11];
    int i, status = check_common(in, spin, out, why, size);
    if (status) return status;
    arrays[0] = in->m, arrays[1] = in->c0, arrays[2] = in->c1, arrays[3] = in->k0;
    arrays[4] = in->k1, arrays[5] = in->k2, arrays[6] = in->kh, arrays[7] = in->jn;
    arrays[8] = in->jnw, arrays[9] = in->kx, arrays[10] = in->cx;
    for (i = 0; i < 11; i++) {
        int rows = i < 7 ? in->ny : (i < 9 ? in->np : 1);
        int cols = i < 7 ? in->ny : (i < 9 ? in->ny : in->np);
        if (arrays[i] == NULL)
            return say(why, size, INPLANE_BUILD_NULL, "%s must be given", names[i]);
        if ((status = finite_entries(names[i], arrays[i], rows, cols, why, size)))
            return status;
    }
    if (in->hysteretic && !(isfinite(in->radius_m) && in->radius_m > 0.0)) {
        char text[40];
        value_text(in->radius_m, "m", text, sizeof text);
        return say(why, size, INPLANE_BUILD_BAD_INPUT,
                   "radius_m = %s: a hysteretic tire's radius must be finite and positive",
                   text);
    }
    if (work == NULL || iwork == NULL || out->c == NULL || out->k == NULL || out->c1 == NULL
        || out->k1s == NULL || out->k2 == NULL || out->kh == NULL || out->a0_inv == NULL
        || out->yn == NULL || out->yx == NULL || out->wnn == NULL || out->wnx == NULL
        || out->kg_a == NULL || out->kg_b == NULL || out->kgn_a == NULL || out->kgn_b == NULL
        || out->kgx_a == NULL || out->kgx_b == NULL)
        return say(why, size, INPLANE_BUILD_NULL,
                   "the scratch and every output of the ring's part must be given");
    return 0;
}

/* core/inplane.py's hysteresis_share */
static double share_at(double spin_rad_s, double radius_m)
{
    double full = SPEC_HYSTERESIS_FULL_SPEED_M_S / radius_m;
    double share = spin_rad_s / full;
    return share > 1.0 ? 1.0 : (share < -1.0 ? -1.0 : share);
}

/* out (rows x cols) = a (rows x inner) b (inner x cols) */
static void product(const double* a, const double* b, int rows, int inner, int cols,
                    double* out)
{
    int i, k, j;
    for (i = 0; i < rows; i++) {
        double* row = out + (size_t)i * cols;
        for (j = 0; j < cols; j++) row[j] = 0.0;
        for (k = 0; k < inner; k++) {
            double aik = a[(size_t)i * inner + k];
            const double* bk = b + (size_t)k * cols;
            if (aik == 0.0) continue;
            for (j = 0; j < cols; j++) row[j] += aik * bk[j];
        }
    }
}

/* out (rows x cols) = a (rows x inner) b^T, b (cols x inner) */
static void product_t(const double* a, const double* b, int rows, int inner, int cols,
                      double* out)
{
    int i, k, j;
    for (i = 0; i < rows; i++) {
        const double* ai = a + (size_t)i * inner;
        for (j = 0; j < cols; j++) {
            const double* bj = b + (size_t)j * inner;
            double sum = 0.0;
            for (k = 0; k < inner; k++) sum += ai[k] * bj[k];
            out[(size_t)i * cols + j] = sum;
        }
    }
}

int inplane_build_ring(const InPlaneBuildInput* in, double spin_rad_s, InPlaneBuildOutput* out,
                       double* work, int* iwork, char* why, size_t why_size)
{
    int status = check_ring(in, spin_rad_s, out, work, iwork, why, why_size);
    int ny, np, i, j, p;
    size_t n2, e;
    double o = spin_rad_s, h, share, s_m, s_c, two_o, half_h, two_h;
    double* column;
    if (status) return status;
    ny = in->ny, np = in->np, h = in->h;
    n2 = (size_t)ny * (size_t)ny;
    column = work + n2;
    share = in->hysteretic ? share_at(o, in->radius_m) : 0.0;
    s_m = 4.0 / (h * h), s_c = 2.0 / h, two_o = 2.0 * o;
    /* a0 first, into the scratch: nothing is written until it factors */
    for (e = 0; e < n2; e++) {
        double c = in->c0[e] + o * in->c1[e];
        double k = in->k0[e] + o * in->k1[e] + (o * o) * in->k2[e];
        if (share != 0.0) k = k + share * in->kh[e];
        work[e] = s_m * in->m[e] + s_c * c + k;
    }
    if (lu_factor(work, ny, iwork) != 0)
        return say(why, why_size, INPLANE_BUILD_SINGULAR,
                   "spin_rad_s = %.17g: 4/h^2 M + 2/h C + K is singular at this spin (h = "
                   "%.17g s)", o, h);
    for (e = 0; e < n2; e++) {
        out->c[e] = in->c0[e] + o * in->c1[e];
        out->k[e] = in->k0[e] + o * in->k1[e] + (o * o) * in->k2[e];
        if (share != 0.0) out->k[e] = out->k[e] + share * in->kh[e];
        out->c1[e] = in->c1[e];
        out->k1s[e] = in->k1[e] + two_o * in->k2[e];
        out->k2[e] = in->k2[e];
        out->kh[e] = in->kh[e];
    }
    for (j = 0; j < ny; j++) {
        for (i = 0; i < ny; i++) column[i] = i == j ? 1.0 : 0.0;
        lu_solve(work, ny, iwork, column);
        for (i = 0; i < ny; i++) out->a0_inv[(size_t)i * ny + j] = column[i];
    }
    out->ring_spin = o;
    out->ring_share = share;
    product_t(out->a0_inv, in->jnw, ny, ny, np, out->yn);
    product_t(out->a0_inv, in->jxw, ny, ny, np, out->yx);
    product(in->jn, out->yn, np, ny, np, out->wnn);
    product(in->jn, out->yx, np, ny, np, out->wnx);
    half_h = 0.5 * h, two_h = 2.0 / h;
    for (p = 0; p < np; p++) {
        double kx = in->kx[p], cx = in->cx[p];
        for (j = 0; j < ny; j++) {
            size_t at = (size_t)p * ny + j;
            out->kg_a[at] = kx * in->jxw[at] + cx * (two_h * in->jxw[at]);
            out->kg_b[at] = kx * (half_h * in->jl[at]) + cx * in->jl[at];
        }
    }
    product(out->kg_a, out->yn, np, ny, np, out->kgn_a);
    product(out->kg_b, out->yn, np, ny, np, out->kgn_b);
    product(out->kg_a, out->yx, np, ny, np, out->kgx_a);
    product(out->kg_b, out->yx, np, ny, np, out->kgx_b);
    return INPLANE_BUILD_OK;
}

int inplane_build_tread(const InPlaneBuildInput* in, double spin_rad_s, InPlaneBuildOutput* out,
                        char* why, size_t why_size)
{
    int status = check_common(in, spin_rad_s, out, why, why_size);
    int ny, np, p, k;
    size_t e, count;
    double o = spin_rad_s, h, gain_scale, shift, spacing, theta0;
    if (status) return status;
    if (out->kg_a == NULL || out->kg_b == NULL || out->kgn_a == NULL || out->kgn_b == NULL
        || out->kgx_a == NULL || out->kgx_b == NULL || out->gain == NULL || out->kg == NULL
        || out->kgn == NULL || out->kgx == NULL || out->carry == NULL
        || out->carry_weights == NULL || out->carry_base == NULL)
        return say(why, why_size, INPLANE_BUILD_NULL,
                   "the ring's kg parts and every output of the tread's part must be given");
    ny = in->ny, np = in->np, h = in->h;
    gain_scale = 0.5 * h * o;
    count = (size_t)np * (size_t)ny;
    for (e = 0; e < count; e++) {
        out->gain[e] = in->jxw[e] + gain_scale * in->jl[e];
        out->kg[e] = out->kg_b[e] * o + out->kg_a[e];
    }
    count = (size_t)np * (size_t)np;
    for (e = 0; e < count; e++) {
        out->kgn[e] = out->kgn_b[e] * o + out->kgn_a[e];
        out->kgx[e] = out->kgx_b[e] * o + out->kgx_a[e];
        out->carry[e] = 0.0;
    }
    /* carry_stencil and carry_matrix: cubic Lagrange weights on points base - 1 .. base + 2
     * at each departure point theta_p - W h (contact.lagrange_weights) */
    shift = o * h;
    theta0 = in->point_theta[0];
    spacing = (in->point_theta[np - 1] - theta0) / (np - 1);
    for (p = 0; p < np; p++) {
        double position = (in->point_theta[p] - shift - theta0) / spacing;
        double floor_position = floor(position), s = position - floor_position;
        int base = (int)floor_position;
        double* w = out->carry_weights + (size_t)p * 4;
        w[0] = -s * (s - 1) * (s - 2) / 6;
        w[1] = (s + 1) * (s - 1) * (s - 2) / 2;
        w[2] = -(s + 1) * s * (s - 2) / 2;
        w[3] = (s + 1) * s * (s - 1) / 6;
        out->carry_base[p] = base;
        for (k = 0; k < 4; k++) {
            int column = base - 1 + k;
            if (column >= 0 && column < np) out->carry[(size_t)p * np + column] = w[k];
        }
    }
    out->carry_shift = o * h * (np - 1) / (in->point_theta[np - 1] - theta0);
    out->spin_now = o;
    return INPLANE_BUILD_OK;
}

int inplane_build(const InPlaneBuildInput* in, double spin_rad_s, InPlaneBuildOutput* out,
                  double* work, int* iwork, char* why, size_t why_size)
{
    /* the tread's checks first, so that a refusal leaves the ring's part unwritten too */
    int status = check_common(in, spin_rad_s, out, why, why_size);
    if (status) return status;
    if (out->gain == NULL || out->kg == NULL || out->kgn == NULL || out->kgx == NULL
        || out->carry == NULL || out->carry_weights == NULL || out->carry_base == NULL)
        return say(why, why_size, INPLANE_BUILD_NULL,
                   "every output of the tread's part must be given");
    status = inplane_build_ring(in, spin_rad_s, out, work, iwork, why, why_size);
    if (status) return status;
    return inplane_build_tread(in, spin_rad_s, out, why, why_size);
}
