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

static int sizes_ok(int ny, int np)
{
    return ny >= 1 && ny <= INPLANE_BUILD_MAX_NY && np >= 2 && np <= INPLANE_BUILD_MAX_NP;
}

size_t inplane_build_work_doubles(int ny, int np)
{
    if (!sizes_ok(ny, np)) return 0;
    return (size_t)ny * (size_t)ny + (size_t)ny * (size_t)np;
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
            return say_why(why, size, INPLANE_BUILD_BAD_INPUT,
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
        return say_why(why, size, INPLANE_BUILD_NULL, "the input and the output must be given");
    if (!sizes_ok(in->ny, in->np))
        return say_why(why, size, INPLANE_BUILD_BAD_SIZE,
                   "ny = %d, np = %d: the coordinates must number 1 to %d and the contact "
                   "points 2 to %d", in->ny, in->np, INPLANE_BUILD_MAX_NY,
                   INPLANE_BUILD_MAX_NP);
    if (!(isfinite(in->h) && in->h >= INPLANE_BUILD_MIN_STEP_S
          && in->h <= INPLANE_BUILD_MAX_STEP_S)) {
        value_text(in->h, "s", text, sizeof text);
        return say_why(why, size, INPLANE_BUILD_BAD_STEP, "h = %s: the step must be in [%g, %g] s",
                   text, INPLANE_BUILD_MIN_STEP_S, INPLANE_BUILD_MAX_STEP_S);
    }
    if (in->point_theta == NULL || in->jxw == NULL || in->jl == NULL)
        return say_why(why, size, INPLANE_BUILD_NULL, "point_theta, jxw and jl must be given");
    if ((status = finite_entries("point_theta", in->point_theta, 1, in->np, why, size)))
        return status;
    for (p = 1; p < in->np; p++) {
        if (!(in->point_theta[p] > in->point_theta[p - 1]))
            return say_why(why, size, INPLANE_BUILD_BAD_INPUT,
                       "point_theta[%d] = %.17g after %.17g: the points' angles must increase",
                       p, in->point_theta[p], in->point_theta[p - 1]);
    }
    spacing = (in->point_theta[in->np - 1] - in->point_theta[0]) / (in->np - 1);
    if (!(isfinite(spin) && fabs(spin) * in->h <= MAX_SHIFT_SPACINGS * spacing)) {
        value_text(spin, "rad/s", text, sizeof text);
        return say_why(why, size, INPLANE_BUILD_BAD_SPIN,
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
            return say_why(why, size, INPLANE_BUILD_NULL, "%s must be given", names[i]);
        if ((status = finite_entries(names[i], arrays[i], rows, cols, why, size)))
            return status;
    }
    if (in->hysteretic && !(isfinite(in->radius_m) && in->radius_m > 0.0)) {
        char text[40];
        value_text(in->radius_m, "m", text, sizeof text);
        return say_why(why, size, INPLANE_BUILD_BAD_INPUT,
                   "radius_m = %s: a hysteretic tire's radius must be finite and positive",
                   text);
    }
    if (work == NULL || iwork == NULL || out->c == NULL || out->k == NULL || out->c1 == NULL
        || out->k1s == NULL || out->k2 == NULL || out->kh == NULL || out->a0_inv == NULL
        || out->yn == NULL || out->yx == NULL || out->wnn == NULL || out->wnx == NULL
        || out->kg_a == NULL || out->kg_b == NULL || out->kgn_a == NULL || out->kgn_b == NULL
        || out->kgx_a == NULL || out->kgx_b == NULL)
        return say_why(why, size, INPLANE_BUILD_NULL,
                   "the scratch and every output of the ring's part must be given");
    return 0;
}

double inplane_hysteresis_share(double spin_rad_s, double radius_m)
{
    double full = SPEC_HYSTERESIS_FULL_SPEED_M_S / radius_m;
    double share = spin_rad_s / full;
    return share > 1.0 ? 1.0 : (share < -1.0 ? -1.0 : share);
}

/* c (rows x cols, row stride ldc) += sign a b, a (rows x inner, lda), b (inner x cols, ldb):
 * four rows of c and two of b at a time, so that each entry of b read serves eight products
 * (the plain loop reads one entry of b and one of c for each: memory-bound) */
static void multiply_add_tile(int rows, int inner, int cols, double sign, const double* a,
                              size_t lda, const double* b, size_t ldb, double* c, size_t ldc)
{
    int i = 0, k, j;
    for (; i + 4 <= rows; i += 4) {
        double *c0 = c + (size_t)i * ldc, *c1 = c0 + ldc, *c2 = c1 + ldc, *c3 = c2 + ldc;
        const double* ai = a + (size_t)i * lda;
        for (k = 0; k + 2 <= inner; k += 2) {
            const double *b0 = b + (size_t)k * ldb, *b1 = b0 + ldb;
            double a00 = sign * ai[k], a01 = sign * ai[k + 1];
            double a10 = sign * ai[lda + k], a11 = sign * ai[lda + k + 1];
            double a20 = sign * ai[2 * lda + k], a21 = sign * ai[2 * lda + k + 1];
            double a30 = sign * ai[3 * lda + k], a31 = sign * ai[3 * lda + k + 1];
            for (j = 0; j < cols; j++) {
                double x = b0[j], y = b1[j];
                c0[j] += a00 * x + a01 * y;
                c1[j] += a10 * x + a11 * y;
                c2[j] += a20 * x + a21 * y;
                c3[j] += a30 * x + a31 * y;
            }
        }
        for (; k < inner; k++) {
            const double* b0 = b + (size_t)k * ldb;
            double a0 = sign * ai[k], a1 = sign * ai[lda + k];
            double a2 = sign * ai[2 * lda + k], a3 = sign * ai[3 * lda + k];
            for (j = 0; j < cols; j++) {
                double x = b0[j];
                c0[j] += a0 * x;
                c1[j] += a1 * x;
                c2[j] += a2 * x;
                c3[j] += a3 * x;
            }
        }
    }
    for (; i < rows; i++) {
        double* ci = c + (size_t)i * ldc;
        for (k = 0; k < inner; k++) {
            const double* b0 = b + (size_t)k * ldb;
            double a0 = sign * a[(size_t)i * lda + k];
            for (j = 0; j < cols; j++) ci[j] += a0 * b0[j];
        }
    }
}

/* multiply_add_tile over chunks of CHUNK columns: a chunk of b's rows stays in the cache
 * while every block of four rows of c reads it (a whole row of b would be read again from
 * memory for each) */
#ifndef CHUNK
#define CHUNK 64
#endif
static void multiply_add(int rows, int inner, int cols, double sign, const double* a,
                         size_t lda, const double* b, size_t ldb, double* c, size_t ldc)
{
    int j;
    for (j = 0; j < cols; j += CHUNK)
        multiply_add_tile(rows, inner, cols - j < CHUNK ? cols - j : CHUNK, sign, a, lda,
                          b + j, ldb, c + j, ldc);
}

/* out (rows x cols) = a (rows x inner) b (inner x cols) */
static void product(const double* a, const double* b, int rows, int inner, int cols,
                    double* out)
{
    memset(out, 0, sizeof(double) * (size_t)rows * (size_t)cols);
    multiply_add(rows, inner, cols, 1.0, a, (size_t)inner, b, (size_t)cols, out,
                 (size_t)cols);
}

/* out (rows x cols) = a (rows x inner) b^T, b (cols x inner); scratch: inner x cols */
static void product_t(const double* a, const double* b, int rows, int inner, int cols,
                      double* out, double* scratch)
{
    int j, k;
    for (j = 0; j < cols; j++)
        for (k = 0; k < inner; k++) scratch[(size_t)k * cols + j] = b[(size_t)j * inner + k];
    product(a, scratch, rows, inner, cols, out);
}

/* numerics.c's lu_factor (the same partial pivoting: the largest |entry| of the column, whole
 * rows swapped; -1 for a zero or non-finite pivot) in panels of LU_PANEL columns: the rest of
 * the matrix is updated once per panel by one multiply_add, not once per column. */
#define LU_PANEL 16
static int blocked_lu(double* a, int n, int* pivot)
{
    int first, col, i, j, k;
    for (first = 0; first < n; first += LU_PANEL) {
        int last = first + LU_PANEL < n ? first + LU_PANEL : n; /* the panel: [first, last) */
        for (col = first; col < last; col++) {
            int best = col;
            double big = fabs(a[(size_t)col * n + col]);
            for (i = col + 1; i < n; i++) {
                if (fabs(a[(size_t)i * n + col]) > big) {
                    big = fabs(a[(size_t)i * n + col]);
                    best = i;
                }
            }
            pivot[col] = best;
            if (big == 0.0 || !isfinite(big)) return -1;
            if (best != col) {
                for (j = 0; j < n; j++) {
                    double t = a[(size_t)col * n + j];
                    a[(size_t)col * n + j] = a[(size_t)best * n + j];
                    a[(size_t)best * n + j] = t;
                }
            }
            for (i = col + 1; i < n; i++) {
                double* ai = a + (size_t)i * n;
                double factor = ai[col] / a[(size_t)col * n + col];
                ai[col] = factor;
                if (factor == 0.0) continue;
                for (j = col + 1; j < last; j++) ai[j] -= factor * a[(size_t)col * n + j];
            }
        }
        if (last == n) break;
        /* the panel's rows right of it: U12 = L11^-1 A12 */
        for (i = first + 1; i < last; i++) {
            double* ai = a + (size_t)i * n;
            for (k = first; k < i; k++) {
                double l = ai[k];
                const double* ak = a + (size_t)k * n;
                if (l == 0.0) continue;
                for (j = last; j < n; j++) ai[j] -= l * ak[j];
            }
        }
        multiply_add(n - last, last - first, n - last, -1.0, a + (size_t)last * n + first,
                     (size_t)n, a + (size_t)first * n + last, (size_t)n,
                     a + (size_t)last * n + last, (size_t)n);
    }
    return 0;
}

/* The inverse of the matrix blocked_lu left in lu (n x n) with its pivots, into x, CHUNK
 * columns at a time (the columns of the solves are independent, and a chunk of x stays in
 * the cache through them): L^-1, then U x = L^-1, both in blocks of four rows (the rows before
 * or after a block enter it by one multiply_add_tile), then the columns swapped back, last
 * pivot first (LAPACK's getri: P A = L U, so A^-1 = U^-1 L^-1 P). */
static void inverse_from_lu(const double* lu, int n, const int* pivot, double* x)
{
    int i, j, k, top, first, c0;
    memset(x, 0, sizeof(double) * (size_t)n * (size_t)n);
    for (c0 = 0; c0 < n; c0 += CHUNK) {
        int width = n - c0 < CHUNK ? n - c0 : CHUNK;
        double* xc = x + c0; /* the chunk's columns */
        for (i = c0; i < c0 + width; i++) xc[(size_t)i * n + (i - c0)] = 1.0;
        /* L^-1 is unit lower triangular: its rows above c0 are zero in the chunk */
        for (first = c0; first < n; first += 4) {
            int last = first + 4 < n ? first + 4 : n;
            if (first > c0)
                multiply_add_tile(last - first, first - c0, width, -1.0,
                                  lu + (size_t)first * n + c0, (size_t)n, xc + (size_t)c0 * n,
                                  (size_t)n, xc + (size_t)first * n, (size_t)n);
            for (i = first + 1; i < last; i++) {
                double* xi = xc + (size_t)i * n;
                for (k = first; k < i; k++) {
                    double l = lu[(size_t)i * n + k];
                    const double* xk = xc + (size_t)k * n;
                    for (j = 0; j < width; j++) xi[j] -= l * xk[j];
                }
            }
        }
        for (top = n; top > 0;) {
            first = top >= 4 ? top - 4 : 0;
            if (top < n)
                multiply_add_tile(top - first, n - top, width, -1.0,
                                  lu + (size_t)first * n + top, (size_t)n, xc + (size_t)top * n,
                                  (size_t)n, xc + (size_t)first * n, (size_t)n);
            for (i = top - 1; i >= first; i--) {
                double* xi = xc + (size_t)i * n;
                double d = lu[(size_t)i * n + i];
                for (k = i + 1; k < top; k++) {
                    double u = lu[(size_t)i * n + k];
                    const double* xk = xc + (size_t)k * n;
                    for (j = 0; j < width; j++) xi[j] -= u * xk[j];
                }
                for (j = 0; j < width; j++) xi[j] /= d;
            }
            top = first;
        }
    }
    for (k = n - 1; k >= 0; k--) {
        int other = pivot[k];
        if (other == k) continue;
        for (i = 0; i < n; i++) {
            double t = x[(size_t)i * n + k];
            x[(size_t)i * n + k] = x[(size_t)i * n + other];
            x[(size_t)i * n + other] = t;
        }
    }
}

int inplane_build_ring(const InPlaneBuildInput* in, double spin_rad_s, InPlaneBuildOutput* out,
                       double* work, int* iwork, char* why, size_t why_size)
{
    int status = check_ring(in, spin_rad_s, out, work, iwork, why, why_size);
    int ny, np, j, p;
    size_t n2, e;
    double o = spin_rad_s, h, share, s_m, s_c, two_o, half_h, two_h;
    double* scratch;
    if (status) return status;
    ny = in->ny, np = in->np, h = in->h;
    n2 = (size_t)ny * (size_t)ny;
    scratch = work + n2;
    share = in->hysteretic ? inplane_hysteresis_share(o, in->radius_m) : 0.0;
    s_m = 4.0 / (h * h), s_c = 2.0 / h, two_o = 2.0 * o;
    /* a0 first, into the scratch: nothing is written until it factors */
    for (e = 0; e < n2; e++) {
        double c = in->c0[e] + o * in->c1[e];
        double k = in->k0[e] + o * in->k1[e] + (o * o) * in->k2[e];
        if (share != 0.0) k = k + share * in->kh[e];
        work[e] = s_m * in->m[e] + s_c * c + k;
    }
    if (blocked_lu(work, ny, iwork) != 0)
        return say_why(why, why_size, INPLANE_BUILD_SINGULAR,
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
    inverse_from_lu(work, ny, iwork, out->a0_inv);
    out->ring_spin = o;
    out->ring_share = share;
    product_t(out->a0_inv, in->jnw, ny, ny, np, out->yn, scratch);
    product_t(out->a0_inv, in->jxw, ny, ny, np, out->yx, scratch);
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
        return say_why(why, why_size, INPLANE_BUILD_NULL,
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
        return say_why(why, why_size, INPLANE_BUILD_NULL,
                   "every output of the tread's part must be given");
    status = inplane_build_ring(in, spin_rad_s, out, work, iwork, why, why_size);
    if (status) return status;
    return inplane_build_tread(in, spin_rad_s, out, why, why_size);
}
