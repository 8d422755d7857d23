/* numerics.c: complex arithmetic, the per-order quartic, small dense solves, brentq, repr. */
#include "numerics.h"

#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

cx cx_div(cx a, cx b)
{
    /* Smith's algorithm, as numpy divides */
    if (fabs(b.re) >= fabs(b.im)) {
        double r = b.im / b.re, den = b.re + b.im * r;
        return cx_make((a.re + a.im * r) / den, (a.im - a.re * r) / den);
    } else {
        double r = b.re / b.im, den = b.re * r + b.im;
        return cx_make((a.re * r + a.im) / den, (a.im * r - a.re) / den);
    }
}

cx cx_exp(cx z)
{
    double e = exp(z.re);
    return cx_make(e * cos(z.im), e * sin(z.im));
}

cx cx_expm1(cx z)
{
    /* e^x cos y - 1 = expm1(x) cos y - 2 sin^2(y/2): no cancellation for small z */
    double half = sin(0.5 * z.im);
    return cx_make(expm1(z.re) * cos(z.im) - 2.0 * half * half, exp(z.re) * sin(z.im));
}

void phi_functions(cx z, double series_limit, cx* phi1, cx* phi2)
{
    if (cx_abs(z) < series_limit) {
        cx z2 = cx_mul(z, z), z3 = cx_mul(z2, z);
        *phi1 = cx_make(1.0 + z.re / 2 + z2.re / 6 + z3.re / 24, z.im / 2 + z2.im / 6 + z3.im / 24);
        *phi2 = cx_make(0.5 + z.re / 6 + z2.re / 24 + z3.re / 120,
                        z.im / 6 + z2.im / 24 + z3.im / 120);
    } else {
        cx em1 = cx_expm1(z);
        *phi1 = cx_div(em1, z);
        *phi2 = cx_div(cx_sub(em1, z), cx_mul(z, z));
    }
}

/* -- the per-order quartic ------------------------------------------------------------------- */

static void det_q(const double m[2], const cx d[4], const cx k[4], cx s, cx* value, cx* slope)
{
    cx s2 = cx_mul(s, s);
    cx q11 = cx_add(cx_add(cx_scale(s2, m[0]), cx_mul(d[0], s)), k[0]);
    cx q22 = cx_add(cx_add(cx_scale(s2, m[1]), cx_mul(d[3], s)), k[3]);
    cx q12 = cx_add(cx_mul(d[1], s), k[1]);
    cx q21 = cx_add(cx_mul(d[2], s), k[2]);
    cx p11 = cx_add(cx_scale(s, 2.0 * m[0]), d[0]);
    cx p22 = cx_add(cx_scale(s, 2.0 * m[1]), d[3]);
    *value = cx_sub(cx_mul(q11, q22), cx_mul(q12, q21));
    *slope = cx_sub(cx_add(cx_mul(p11, q22), cx_mul(q11, p22)),
                    cx_add(cx_mul(d[1], q21), cx_mul(q12, d[2])));
}

static cx poly(const cx* c, int degree, cx x, cx* slope)
{
    cx value = c[degree], d = cx_make(0.0, 0.0);
    int i;
    for (i = degree - 1; i >= 0; i--) {
        d = cx_add(cx_mul(d, x), value);
        value = cx_add(cx_mul(value, x), c[i]);
    }
    *slope = d;
    return value;
}

int order_roots(const double m[2], const cx d[4], const cx k[4], int real_system, cx roots[4])
{
    cx a[5], b[5], x[4];
    double scale, size;
    int i, j, iteration, converged = 0;
    a[4] = cx_make(m[0] * m[1], 0.0);
    a[3] = cx_add(cx_scale(d[3], m[0]), cx_scale(d[0], m[1]));
    a[2] = cx_sub(cx_add(cx_add(cx_scale(k[3], m[0]), cx_scale(k[0], m[1])), cx_mul(d[0], d[3])),
                  cx_mul(d[1], d[2]));
    a[1] = cx_sub(cx_add(cx_mul(d[0], k[3]), cx_mul(d[3], k[0])),
                  cx_add(cx_mul(d[1], k[2]), cx_mul(d[2], k[1])));
    a[0] = cx_sub(cx_mul(k[0], k[3]), cx_mul(k[1], k[2]));
    /* s = scale x makes the polynomial monic with |b0| = 1, roots near the unit circle */
    size = cx_abs(a[0]) / cx_abs(a[4]);
    scale = size > 0.0 ? pow(size, 0.25) : 1.0;
    for (i = 0; i <= 4; i++) {
        b[i] = cx_scale(cx_div(a[i], a[4]), pow(scale, i - 4));
    }
    for (i = 0; i < 4; i++) {  /* Aberth-Ehrlich from points spread around the unit circle */
        double angle = 2.0 * 3.14159265358979323846 * i / 4 + 0.4;
        x[i] = cx_make(cos(angle), sin(angle));
    }
    for (iteration = 0; iteration < 500 && !converged; iteration++) {
        converged = 1;
        for (i = 0; i < 4; i++) {
            cx slope, value = poly(b, 4, x[i], &slope), ratio, sum = cx_make(0.0, 0.0), w;
            if (value.re == 0.0 && value.im == 0.0) continue;
            ratio = cx_div(value, slope);
            for (j = 0; j < 4; j++) {
                if (j != i) sum = cx_add(sum, cx_div(cx_make(1.0, 0.0), cx_sub(x[i], x[j])));
            }
            w = cx_div(ratio, cx_sub(cx_make(1.0, 0.0), cx_mul(ratio, sum)));
            x[i] = cx_sub(x[i], w);
            if (!(cx_abs(w) <= 1e-13 * cx_abs(x[i]))) converged = 0;
        }
    }
    /* a polynomial whose rounding floor stops the corrections above that still has its roots
     * to working accuracy: the Newton steps on the determinant below settle them */
    converged = 1;
    for (i = 0; i < 4; i++) {
        if (!(isfinite(x[i].re) && isfinite(x[i].im))) converged = 0;
    }
    for (i = 0; i < 4; i++) {
        cx s = cx_scale(x[i], scale);
        if (real_system && fabs(s.im) <= 1e-8 * cx_abs(s)) s.im = 0.0;
        for (j = 0; j < 3; j++) {  /* Newton on the determinant itself: its own residual */
            cx value, slope;
            det_q(m, d, k, s, &value, &slope);
            if ((value.re == 0.0 && value.im == 0.0) || (slope.re == 0.0 && slope.im == 0.0)) {
                break;
            }
            s = cx_sub(s, cx_div(value, slope));
        }
        if (!(isfinite(s.re) && isfinite(s.im))) return -1;
        {   /* a root: det Q(s) vanishes against the size of its two products */
            cx s2 = cx_mul(s, s);
            cx q11 = cx_add(cx_add(cx_scale(s2, m[0]), cx_mul(d[0], s)), k[0]);
            cx q22 = cx_add(cx_add(cx_scale(s2, m[1]), cx_mul(d[3], s)), k[3]);
            cx q12 = cx_add(cx_mul(d[1], s), k[1]);
            cx q21 = cx_add(cx_mul(d[2], s), k[2]);
            double products = cx_abs(cx_mul(q11, q22)) + cx_abs(cx_mul(q12, q21));
            double residual = cx_abs(cx_sub(cx_mul(q11, q22), cx_mul(q12, q21)));
            if (!(residual <= 1e-8 * products)) return -1;
        }
        roots[i] = s;
    }
    return converged ? 0 : -1;
}

/* -- small dense solves ------------------------------------------------------------------------- */

int cx_invert(cx* a, int n)
{
    int perm[8], i, j, col;
    cx work[64];
    if (n > 8) return -1;
    memcpy(work, a, sizeof(cx) * (size_t)(n * n));
    for (i = 0; i < n; i++) {
        for (j = 0; j < n; j++) a[i * n + j] = cx_make(i == j ? 1.0 : 0.0, 0.0);
        perm[i] = i;
    }
    for (col = 0; col < n; col++) {
        int best = col;
        double big = cx_abs(work[col * n + col]);
        cx pivot;
        for (i = col + 1; i < n; i++) {
            double v = cx_abs(work[i * n + col]);
            if (v > big) {
                big = v;
                best = i;
            }
        }
        if (big == 0.0) return -1;
        if (best != col) {
            for (j = 0; j < n; j++) {
                cx t = work[col * n + j];
                work[col * n + j] = work[best * n + j];
                work[best * n + j] = t;
                t = a[col * n + j];
                a[col * n + j] = a[best * n + j];
                a[best * n + j] = t;
            }
        }
        pivot = work[col * n + col];
        for (j = 0; j < n; j++) {
            work[col * n + j] = cx_div(work[col * n + j], pivot);
            a[col * n + j] = cx_div(a[col * n + j], pivot);
        }
        for (i = 0; i < n; i++) {
            cx factor;
            if (i == col) continue;
            factor = work[i * n + col];
            if (factor.re == 0.0 && factor.im == 0.0) continue;
            for (j = 0; j < n; j++) {
                work[i * n + j] = cx_sub(work[i * n + j], cx_mul(factor, work[col * n + j]));
                a[i * n + j] = cx_sub(a[i * n + j], cx_mul(factor, a[col * n + j]));
            }
        }
    }
    (void)perm;
    return 0;
}

int lu_factor(double* a, int n, int* pivot)
{
    int i, j, col;
    for (col = 0; col < n; col++) {
        int best = col;
        double big = fabs(a[col * n + col]);
        for (i = col + 1; i < n; i++) {
            if (fabs(a[i * n + col]) > big) {
                big = fabs(a[i * n + col]);
                best = i;
            }
        }
        pivot[col] = best;
        if (big == 0.0 || !isfinite(big)) return -1;
        if (best != col) {
            for (j = 0; j < n; j++) {
                double t = a[col * n + j];
                a[col * n + j] = a[best * n + j];
                a[best * n + j] = t;
            }
        }
        for (i = col + 1; i < n; i++) {
            double factor = a[i * n + col] / a[col * n + col];
            a[i * n + col] = factor;
            if (factor == 0.0) continue;
            for (j = col + 1; j < n; j++) a[i * n + j] -= factor * a[col * n + j];
        }
    }
    return 0;
}

void lu_solve(const double* lu, int n, const int* pivot, double* b)
{
    int i, j;
    for (i = 0; i < n; i++) {
        if (pivot[i] != i) {
            double t = b[i];
            b[i] = b[pivot[i]];
            b[pivot[i]] = t;
        }
    }
    for (i = 0; i < n; i++) {
        double sum = b[i];
        for (j = 0; j < i; j++) sum -= lu[i * n + j] * b[j];
        b[i] = sum;
    }
    for (i = n - 1; i >= 0; i--) {
        double sum = b[i];
        for (j = i + 1; j < n; j++) sum -= lu[i * n + j] * b[j];
        b[i] = sum / lu[i * n + i];
    }
}

int invert(const double* a, int n, double* inverse, double* work, int* pivot)
{
    double* column = work + (size_t)n * (size_t)n;
    int i, j;
    memcpy(work, a, sizeof(double) * (size_t)n * (size_t)n);
    if (lu_factor(work, n, pivot) != 0) return -1;
    for (j = 0; j < n; j++) {
        for (i = 0; i < n; i++) column[i] = i == j ? 1.0 : 0.0;
        lu_solve(work, n, pivot, column);
        for (i = 0; i < n; i++) inverse[i * n + j] = column[i];
    }
    return 0;
}

/* -- brentq --------------------------------------------------------------------------------- */

double brentq(scalar_function f, void* data, double xa, double xb, double xtol, double rtol,
              int iterations)
{
    double xpre = xa, xcur = xb, xblk = 0.0, fpre, fcur, fblk = 0.0, spre = 0.0, scur = 0.0;
    double sbis, delta, stry, dpre, dblk;
    int i;
    fpre = f(xpre, data);
    fcur = f(xcur, data);
    if (fpre == 0) return xpre;
    if (fcur == 0) return xcur;
    if (signbit(fpre) == signbit(fcur)) return NAN;
    for (i = 0; i < iterations; i++) {
        if (fpre != 0 && fcur != 0 && (signbit(fpre) != signbit(fcur))) {
            xblk = xpre;
            fblk = fpre;
            spre = scur = xcur - xpre;
        }
        if (fabs(fblk) < fabs(fcur)) {
            xpre = xcur;
            xcur = xblk;
            xblk = xpre;
            fpre = fcur;
            fcur = fblk;
            fblk = fpre;
        }
        delta = (xtol + rtol * fabs(xcur)) / 2;
        sbis = (xblk - xcur) / 2;
        if (fcur == 0 || fabs(sbis) < delta) return xcur;
        if (fabs(spre) > delta && fabs(fcur) < fabs(fpre)) {
            if (xpre == xblk) {
                stry = -fcur * (xcur - xpre) / (fcur - fpre);  /* interpolate */
            } else {
                dpre = (fpre - fcur) / (xpre - xcur);  /* extrapolate */
                dblk = (fblk - fcur) / (xblk - xcur);
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre));
            }
            if (2 * fabs(stry) < fmin(fabs(spre), 3 * fabs(sbis) - delta)) {
                spre = scur;  /* good short step */
                scur = stry;
            } else {
                spre = sbis;  /* bisect */
                scur = sbis;
            }
        } else {
            spre = sbis;
            scur = sbis;
        }
        xpre = xcur;
        fpre = fcur;
        if (fabs(scur) > delta) {
            xcur += scur;
        } else {
            xcur += (sbis > 0 ? delta : -delta);
        }
        fcur = f(xcur, data);
    }
    return xcur;
}

/* -- repr --------------------------------------------------------------------------------------- */

/* the decimal of ``precision`` digits one unit in the last place from the correctly rounded
 * one that reads back as x, written as %e writes it; 0 when neither does */
static int neighbour_digits(double x, int precision, char* buffer, size_t size)
{
    char rounded[40], candidate[40];
    unsigned long long mantissa = 0, low = 1, high;
    int exponent, i, delta;
    const char* p;
    snprintf(rounded, sizeof rounded, "%.*e", precision - 1, fabs(x));
    for (p = rounded; *p && *p != 'e'; p++) {
        if (*p != '.') mantissa = mantissa * 10 + (unsigned long long)(*p - '0');
    }
    exponent = atoi(p + 1);
    for (i = 1; i < precision; i++) low *= 10;
    high = low * 10;
    for (delta = -1; delta <= 1; delta += 2) {
        unsigned long long m = delta < 0 ? mantissa - 1 : mantissa + 1;
        int e = exponent;
        char digits[24];
        if (m >= high) {
            m /= 10;
            e++;
        } else if (m < low) {
            m = high - 1;
            e--;
        }
        snprintf(digits, sizeof digits, "%llu", m);
        if (precision > 1) {
            snprintf(candidate, sizeof candidate, "%s%c.%se%+03d", x < 0 ? "-" : "", digits[0],
                     digits + 1, e);
        } else {
            snprintf(candidate, sizeof candidate, "%s%ce%+03d", x < 0 ? "-" : "", digits[0], e);
        }
        if (strtod(candidate, NULL) == x) {
            snprintf(buffer, size, "%s", candidate);
            return 1;
        }
    }
    return 0;
}

void py_repr(double x, char* text, size_t size)
{
    char buffer[40], digits[24];
    int precision, exponent = 0, n_digits = 0, point, i;
    char* out = text;
    size_t left = size;
    if (isnan(x)) {
        snprintf(text, size, "nan");
        return;
    }
    if (isinf(x)) {
        snprintf(text, size, x > 0 ? "inf" : "-inf");
        return;
    }
    if (x == 0.0) {
        snprintf(text, size, signbit(x) ? "-0.0" : "0.0");
        return;
    }
    for (precision = 1; precision <= 17; precision++) {
        snprintf(buffer, sizeof buffer, "%.*e", precision - 1, x);
        if (strtod(buffer, NULL) == x) break;
        /* the correctly rounded digits may miss x where a neighbour of the same length hits
         * it (2^-24: 16 digits round to ...062, only ...063 reads back): Python takes that */
        if (neighbour_digits(x, precision, buffer, sizeof buffer)) break;
    }
    {   /* buffer: [-]d[.ddd]e[+-]XX */
        const char* p = buffer;
        if (*p == '-') p++;
        while (*p && *p != 'e') {
            if (*p != '.') digits[n_digits++] = *p;
            p++;
        }
        if (*p == 'e') exponent = atoi(p + 1);
    }
    while (n_digits > 1 && digits[n_digits - 1] == '0') n_digits--;
    digits[n_digits] = '\0';
    point = exponent + 1;  /* Python's decpt: digits times 10^(point - n_digits) */
#define PUT(...)                                                  \
    do {                                                          \
        int written_ = snprintf(out, left, __VA_ARGS__);          \
        if (written_ < 0 || (size_t)written_ >= left) return;     \
        out += written_;                                          \
        left -= (size_t)written_;                                 \
    } while (0)
    if (x < 0) PUT("-");
    if (point > -4 && point <= 16) {
        if (point <= 0) {
            PUT("0.");
            for (i = 0; i < -point; i++) PUT("0");
            PUT("%s", digits);
        } else if (point >= n_digits) {
            PUT("%s", digits);
            for (i = n_digits; i < point; i++) PUT("0");
            PUT(".0");
        } else {
            PUT("%.*s.%s", point, digits, digits + point);
        }
    } else {
        PUT("%c", digits[0]);
        if (n_digits > 1) PUT(".%s", digits + 1);
        PUT("e%c%02d", point - 1 < 0 ? '-' : '+', abs(point - 1));
    }
#undef PUT
}

uint64_t fnv1a(uint64_t hash, const unsigned char* bytes, size_t count)
{
    size_t i;
    for (i = 0; i < count; i++) {
        hash ^= bytes[i];
        hash *= UINT64_C(1099511628211);
    }
    return hash;
}

void value_text(double x, const char* unit, char* text, size_t size)
{
    char buffer[40];
    if (!isfinite(x)) {
        py_repr(x, text, size);
        return;
    }
    snprintf(buffer, sizeof buffer, "%g", x);
    if (strtod(buffer, NULL) != x) py_repr(x, buffer, sizeof buffer);
    if (unit != NULL && unit[0] != '\0') {
        snprintf(text, size, "%s %s", buffer, unit);
    } else {
        snprintf(text, size, "%s", buffer);
    }
}
