/* numerics.c: complex arithmetic, dense eigenproblems, small dense solves, brentq, repr. */
#include <stdarg.h>
#include <stdio.h>
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

/* -- dense eigenproblems ---------------------------------------------------------------------- */

cx cx_sqrt(cx z)
{
    double size = cx_abs(z), t;
    if (size == 0.0) return cx_make(0.0, z.im);
    if (size > 1e300) {  /* size + |re| would overflow: the root of z / 4, doubled */
        cx half = cx_sqrt(cx_scale(z, 0.25));
        return cx_scale(half, 2.0);
    }
    t = sqrt(0.5 * (size + fabs(z.re)));
    if (z.re >= 0.0) return cx_make(t, z.im / (2.0 * t));
    return cx_make(fabs(z.im) / (2.0 * t), z.im < 0.0 ? -t : t);
}

static double cabs1(cx z) { return fabs(z.re) + fabs(z.im); }

#define E(m, r, c) (m)[(r) * EIG_MAX_N + (c)]

/* zgebal's scaling (LAPACK 3.5 on): A := D^-1 A D, D = diag(scale) of powers of 2 that make
 * each row's and column's 2-norms comparable; exact, so only the rounding of later steps
 * changes */
static void balance(cx* a, int n, double* scale)
{
    const double radix = 2.0, factor = 0.95;
    const double sfmin1 = DBL_MIN / DBL_EPSILON, sfmax1 = 1.0 / sfmin1;
    const double sfmin2 = sfmin1 * radix, sfmax2 = 1.0 / sfmin2;
    int i, j, noconv = 1, sweeps = 0;
    for (i = 0; i < n; i++) scale[i] = 1.0;
    while (noconv && sweeps++ < 1000) {
        noconv = 0;
        for (i = 0; i < n; i++) {
            double c = 0.0, r = 0.0, ca = 0.0, ra = 0.0, g, f, s;
            for (j = 0; j < n; j++) {
                c = hypot(c, cx_abs(E(a, j, i)));
                r = hypot(r, cx_abs(E(a, i, j)));
                if (cx_abs(E(a, j, i)) > ca) ca = cx_abs(E(a, j, i));
                if (cx_abs(E(a, i, j)) > ra) ra = cx_abs(E(a, i, j));
            }
            if (c == 0.0 || r == 0.0) continue;
            g = r / radix;
            f = 1.0;
            s = c + r;
            while (c < g && fmax(f, fmax(c, ca)) < sfmax2 && fmin(r, fmin(g, ra)) > sfmin2) {
                f *= radix;
                c *= radix;
                ca *= radix;
                r /= radix;
                g /= radix;
                ra /= radix;
            }
            g = c / radix;
            while (g >= r && fmax(r, ra) < sfmax2 &&
                   fmin(fmin(f, c), fmin(g, ca)) > sfmin2) {
                f /= radix;
                c /= radix;
                g /= radix;
                ca /= radix;
                r *= radix;
                ra *= radix;
            }
            if (c + r >= factor * s) continue;
            if (f < 1.0 && scale[i] < 1.0 && f * scale[i] <= sfmin1) continue;
            if (f > 1.0 && scale[i] > 1.0 && scale[i] >= sfmax1 / f) continue;
            scale[i] *= f;
            noconv = 1;
            for (j = 0; j < n; j++) E(a, i, j) = cx_scale(E(a, i, j), 1.0 / f);
            for (j = 0; j < n; j++) E(a, j, i) = cx_scale(E(a, j, i), f);
        }
    }
}

/* H := Q^H A Q upper Hessenberg by Householder reflections P = I - tau u u^H (Hermitian,
 * unitary), Q their product */
static void hessenberg(cx* h, int n, cx* q)
{
    cx u[EIG_MAX_N];
    int i, j, r;
    for (i = 0; i < n; i++) {
        for (j = 0; j < n; j++) E(q, i, j) = cx_make(i == j ? 1.0 : 0.0, 0.0);
    }
    for (j = 0; j + 2 < n; j++) {
        double norm = 0.0, a0, tau;
        cx phase;
        for (r = j + 1; r < n; r++) norm = hypot(norm, cx_abs(E(h, r, j)));
        if (norm == 0.0) continue;
        a0 = cx_abs(E(h, j + 1, j));
        phase = a0 > 0.0 ? cx_make(E(h, j + 1, j).re / a0, E(h, j + 1, j).im / a0)
                         : cx_make(1.0, 0.0);
        /* u = (x + phase |x| e1) / |x|: P x = -phase |x| e1 and tau = 2 / |u|^2 */
        for (r = j + 1; r < n; r++) u[r] = cx_scale(E(h, r, j), 1.0 / norm);
        u[j + 1] = cx_add(u[j + 1], phase);
        tau = 1.0 / (1.0 + a0 / norm);
        for (i = j + 1; i < n; i++) {  /* from the left: rows j+1.., columns j+1.. */
            cx sum = cx_make(0.0, 0.0);
            for (r = j + 1; r < n; r++) sum = cx_add(sum, cx_mul(cx_conj(u[r]), E(h, r, i)));
            sum = cx_scale(sum, tau);
            for (r = j + 1; r < n; r++) E(h, r, i) = cx_sub(E(h, r, i), cx_mul(u[r], sum));
        }
        for (i = 0; i < n; i++) {  /* from the right: every row, columns j+1.. */
            cx sum = cx_make(0.0, 0.0), sum_q = cx_make(0.0, 0.0);
            for (r = j + 1; r < n; r++) {
                sum = cx_add(sum, cx_mul(E(h, i, r), u[r]));
                sum_q = cx_add(sum_q, cx_mul(E(q, i, r), u[r]));
            }
            sum = cx_scale(sum, tau);
            sum_q = cx_scale(sum_q, tau);
            for (r = j + 1; r < n; r++) {
                E(h, i, r) = cx_sub(E(h, i, r), cx_mul(sum, cx_conj(u[r])));
                E(q, i, r) = cx_sub(E(q, i, r), cx_mul(sum_q, cx_conj(u[r])));
            }
        }
        E(h, j + 1, j) = cx_scale(phase, -norm);
        for (r = j + 2; r < n; r++) E(h, r, j) = cx_make(0.0, 0.0);
    }
}

/* the rotation G = [c s; -conj(s) c] (c real) with G [f; g] = [r; 0] (zlartg) */
static void givens(cx f, cx g, double* c, cx* s, cx* r)
{
    double af = cx_abs(f), ag = cx_abs(g), norm;
    cx phase;
    if (ag == 0.0) {
        *c = 1.0;
        *s = cx_make(0.0, 0.0);
        *r = f;
        return;
    }
    if (af == 0.0) {
        *c = 0.0;
        *s = cx_make(g.re / ag, -g.im / ag);
        *r = cx_make(ag, 0.0);
        return;
    }
    norm = hypot(af, ag);
    phase = cx_make(f.re / af, f.im / af);
    *c = af / norm;
    *s = cx_mul(phase, cx_make(g.re / norm, -g.im / norm));
    *r = cx_scale(phase, norm);
}

/* the rotation on rows k, k+1 (columns from..n-1) and, as G^H, on columns k, k+1 of h (rows
 * 0..last) and of z (every row) */
static void rotate(cx* h, cx* z, int n, int k, int from, int last, double c, cx s)
{
    int j;
    for (j = from; j < n; j++) {
        cx a = E(h, k, j), b = E(h, k + 1, j);
        E(h, k, j) = cx_add(cx_scale(a, c), cx_mul(s, b));
        E(h, k + 1, j) = cx_sub(cx_scale(b, c), cx_mul(cx_conj(s), a));
    }
    for (j = 0; j <= last; j++) {
        cx a = E(h, j, k), b = E(h, j, k + 1);
        E(h, j, k) = cx_add(cx_scale(a, c), cx_mul(cx_conj(s), b));
        E(h, j, k + 1) = cx_sub(cx_scale(b, c), cx_mul(s, a));
    }
    for (j = 0; j < n; j++) {
        cx a = E(z, j, k), b = E(z, j, k + 1);
        E(z, j, k) = cx_add(cx_scale(a, c), cx_mul(cx_conj(s), b));
        E(z, j, k + 1) = cx_sub(cx_scale(b, c), cx_mul(s, a));
    }
}

/* is h(k, k-1) negligible? zlahqr's test: against its neighbours (Ahues and Kressner's
 * conservative criterion), or below the underflow guard */
static int negligible(const cx* h, int n, int k, double ulp, double smlnum)
{
    double sub = cabs1(E(h, k, k - 1)), tst, ab, ba, aa, bb, s;
    if (sub <= smlnum) return 1;
    tst = cabs1(E(h, k - 1, k - 1)) + cabs1(E(h, k, k));
    if (tst == 0.0) {
        if (k - 2 >= 0) tst += cabs1(E(h, k - 1, k - 2));
        if (k + 1 < n) tst += cabs1(E(h, k + 1, k));
    }
    if (!(sub <= ulp * tst)) return 0;
    ab = fmax(sub, cabs1(E(h, k - 1, k)));
    ba = fmin(sub, cabs1(E(h, k - 1, k)));
    aa = fmax(cabs1(E(h, k, k)), cabs1(cx_sub(E(h, k - 1, k - 1), E(h, k, k))));
    bb = fmin(cabs1(E(h, k, k)), cabs1(cx_sub(E(h, k - 1, k - 1), E(h, k, k))));
    s = aa + ab;
    return ba * (ab / s) <= fmax(smlnum, ulp * (bb * (aa / s)));
}

/* the eigenvalue of the trailing 2x2 block [a b; c d] closer to d (zlahqr's form) */
static cx wilkinson_shift(cx a, cx b, cx c, cx d)
{
    cx u = cx_mul(cx_sqrt(b), cx_sqrt(c)), x, y;
    double s = cabs1(u), sx;
    if (s == 0.0) return d;
    x = cx_scale(cx_sub(a, d), 0.5);
    sx = cabs1(x);
    s = fmax(s, sx);
    {
        cx xs = cx_scale(x, 1.0 / s), us = cx_scale(u, 1.0 / s);
        y = cx_scale(cx_sqrt(cx_add(cx_mul(xs, xs), cx_mul(us, us))), s);
    }
    if (sx > 0.0 && (x.re / sx) * y.re + (x.im / sx) * y.im < 0.0) y = cx_scale(y, -1.0);
    return cx_sub(d, cx_mul(u, cx_div(u, cx_add(x, y))));
}

/* The Schur form: h (upper Hessenberg) := Z^H h Z upper triangular, z := z Z (zlahqr with
 * Givens rotations for its reflections). 0, or -2 without convergence. */
static int schur(cx* h, cx* z, int n)
{
    const double ulp = DBL_EPSILON, smlnum = DBL_MIN * ((double)n / ulp), dat1 = 0.75;
    const int kexsh = 10, itmax = 30 * (n > 10 ? n : 10);
    int i = n - 1, kdefl = 0;
    while (i >= 0) {
        int l = 0, its, converged = 0;
        for (its = 0; its <= itmax; its++) {
            int k;
            cx t, x, y;
            for (k = i; k > l; k--) {
                if (negligible(h, n, k, ulp, smlnum)) break;
            }
            l = k;
            if (l > 0) E(h, l, l - 1) = cx_make(0.0, 0.0);
            if (l >= i) {
                converged = 1;
                break;
            }
            kdefl++;
            if (kdefl % (2 * kexsh) == 0) {
                t = cx_add(E(h, i, i), cx_make(dat1 * cx_abs(E(h, i, i - 1)), 0.0));
            } else if (kdefl % kexsh == 0) {
                t = cx_add(E(h, l, l), cx_make(dat1 * cx_abs(E(h, l + 1, l)), 0.0));
            } else {
                t = wilkinson_shift(E(h, i - 1, i - 1), E(h, i - 1, i), E(h, i, i - 1),
                                    E(h, i, i));
            }
            /* one implicit single-shift QR sweep over rows and columns l..i */
            x = cx_sub(E(h, l, l), t);
            y = E(h, l + 1, l);
            for (k = l; k < i; k++) {
                double c;
                cx s, r;
                if (k > l) {
                    x = E(h, k, k - 1);
                    y = E(h, k + 1, k - 1);
                }
                givens(x, y, &c, &s, &r);
                if (k > l) {
                    E(h, k, k - 1) = r;
                    E(h, k + 1, k - 1) = cx_make(0.0, 0.0);
                }
                rotate(h, z, n, k, k, k + 2 < i ? k + 2 : i, c, s);
            }
        }
        if (!converged) return -2;
        kdefl = 0;
        i = l - 1;
    }
    return 0;
}

/* column k of v: the eigenvector of the upper triangular t for t(k, k), through z */
static void schur_vector(const cx* t, const cx* z, int n, int k, double tnorm, cx* v)
{
    const double ulp = DBL_EPSILON, smlnum = DBL_MIN * ((double)n / ulp);
    const double limit = DBL_MAX / (4.0 * n * fmax(1.0, tnorm));
    cx x[EIG_MAX_N], lam = E(t, k, k);
    double smin = fmax(ulp * cabs1(lam), smlnum);
    int j, r;
    x[k] = cx_make(1.0, 0.0);
    for (r = 0; r < k; r++) x[r] = cx_scale(E(t, r, k), -1.0);
    for (j = k - 1; j >= 0; j--) {
        cx d = cx_sub(E(t, j, j), lam);
        double num = cabs1(x[j]), den;
        if (cabs1(d) < smin) d = cx_make(smin, 0.0);
        den = cabs1(d);
        if (den < 1.0 && num > den * limit) {
            double f = 0.5 * den * limit / num;
            for (r = 0; r <= k; r++) x[r] = cx_scale(x[r], f);
        }
        x[j] = cx_div(x[j], d);
        if (cabs1(x[j]) > limit) {
            double f = 0.5 * limit / cabs1(x[j]);
            for (r = 0; r <= k; r++) x[r] = cx_scale(x[r], f);
        }
        for (r = 0; r < j; r++) x[r] = cx_sub(x[r], cx_mul(E(t, r, j), x[j]));
    }
    for (r = 0; r < n; r++) {
        cx sum = cx_make(0.0, 0.0);
        for (j = 0; j <= k; j++) sum = cx_add(sum, cx_mul(E(z, r, j), x[j]));
        v[r] = sum;
    }
}

/* v / |v|_2, computed without overflow */
static void unit_vector(cx* v, int n)
{
    double big = 0.0, norm = 0.0;
    int r;
    for (r = 0; r < n; r++) big = fmax(big, cabs1(v[r]));
    if (!(big > 0.0)) return;
    for (r = 0; r < n; r++) v[r] = cx_scale(v[r], 1.0 / big);
    for (r = 0; r < n; r++) norm = hypot(norm, cx_abs(v[r]));
    for (r = 0; r < n; r++) v[r] = cx_scale(v[r], 1.0 / norm);
}

/* v (stride apart) scaled to unit 2-norm and by the phase that makes its pivot, the first
 * component within a relative tie of the largest magnitude, real and positive */
static void canonical_vector(cx* v, int n, int stride, double tie)
{
    double big = 0.0, norm = 0.0, size;
    int r, pivot = 0;
    cx p, factor;
    for (r = 0; r < n; r++) big = fmax(big, cx_abs(v[r * stride]));
    if (!(big > 0.0)) return;
    for (r = 0; r < n; r++) {
        if (cx_abs(v[r * stride]) >= (1.0 - tie) * big) {
            pivot = r;
            break;
        }
    }
    for (r = 0; r < n; r++) norm = hypot(norm, cx_abs(v[r * stride]));
    p = v[pivot * stride];
    size = cx_abs(p);
    factor = cx_scale(cx_conj(p), 1.0 / (size * norm));
    for (r = 0; r < n; r++) v[r * stride] = cx_mul(v[r * stride], factor);
    v[pivot * stride] = cx_make(size / norm, 0.0);
}

/* a real matrix's spectrum: match each eigenvalue with the conjugate of another or itself,
 * closest first, and give the pairs and the real ones their exact structure */
static void real_structure(cx* values, cx* vectors, int n)
{
    int partner[EIG_MAX_N], i, j, r;
    for (i = 0; i < n; i++) partner[i] = -1;
    for (;;) {
        double best = HUGE_VAL;
        int bi = -1, bj = -1;
        for (i = 0; i < n; i++) {
            if (partner[i] >= 0) continue;
            for (j = i; j < n; j++) {
                double gap;
                if (partner[j] >= 0) continue;
                gap = cx_abs(cx_sub(values[i], cx_conj(values[j])));
                if (gap < best) {
                    best = gap;
                    bi = i;
                    bj = j;
                }
            }
        }
        if (bi < 0) break;
        partner[bi] = bj;
        partner[bj] = bi;
    }
    for (i = 0; i < n; i++) {
        j = partner[i];
        if (j == i) {
            values[i].im = 0.0;
            canonical_vector(&vectors[i], n, n, 0.0);
            for (r = 0; r < n; r++) vectors[r * n + i].im = 0.0;
        } else if (j > i) {
            cx mean = cx_scale(cx_add(values[i], cx_conj(values[j])), 0.5);
            int up = mean.im >= 0.0 ? i : j, down = up == i ? j : i;
            if (mean.im < 0.0) mean = cx_conj(mean);
            values[up] = mean;
            values[down] = cx_conj(mean);
            for (r = 0; r < n; r++) vectors[r * n + down] = cx_conj(vectors[r * n + up]);
        }
    }
}

int cx_eig(const cx* a, int n, int real, cx* values, cx* vectors)
{
    cx h[EIG_MAX_N * EIG_MAX_N], z[EIG_MAX_N * EIG_MAX_N], v[EIG_MAX_N];
    double scale[EIG_MAX_N], tnorm = 0.0, big = 0.0;
    int i, j, status, exponent = 0;
    if (n < 1 || n > EIG_MAX_N) return -1;
    for (i = 0; i < n; i++) {
        for (j = 0; j < n; j++) {
            cx x = a[i * n + j];
            if (real) x.im = 0.0;
            if (!(isfinite(x.re) && isfinite(x.im))) return -1;
            E(h, i, j) = x;
            big = fmax(big, cabs1(x));
        }
    }
    /* entries of order 1, by a power of 2 (exact), as zgeev scales a matrix outside the
     * safe range: the deflation's underflow guard and the norms then work at any scale */
    if (big > 0.0) {
        (void)frexp(big, &exponent);
        for (i = 0; i < n; i++) {
            for (j = 0; j < n; j++) {
                E(h, i, j) = cx_make(ldexp(E(h, i, j).re, -exponent),
                                     ldexp(E(h, i, j).im, -exponent));
            }
        }
    }
    balance(h, n, scale);
    hessenberg(h, n, z);
    status = schur(h, z, n);
    if (status != 0) return status;
    for (i = 0; i < n; i++) {
        for (j = i; j < n; j++) tnorm = fmax(tnorm, cabs1(E(h, i, j)));
    }
    for (j = 0; j < n; j++) {
        values[j] = cx_make(ldexp(E(h, j, j).re, exponent), ldexp(E(h, j, j).im, exponent));
        schur_vector(h, z, n, j, tnorm, v);
        unit_vector(v, n);  /* before the balancing's scales, which could overflow it */
        for (i = 0; i < n; i++) v[i] = cx_scale(v[i], scale[i]);
        unit_vector(v, n);
        for (i = 0; i < n; i++) vectors[i * n + j] = v[i];
    }
    if (real) real_structure(values, vectors, n);
    return 0;
}

#undef E

/* the canonical order: a before b (canonical_modes) */
static int mode_before(cx a, cx b, double tie)
{
    double scale = tie * fmax(cx_abs(a), cx_abs(b));
    if (fabs(a.im - b.im) > scale) return a.im < b.im;
    if (fabs(a.re - b.re) > scale) return a.re < b.re;
    return 0;
}

void canonical_modes(int n, cx* values, cx* vectors, double tie)
{
    cx column[EIG_MAX_N];
    int i, j, r;
    for (j = 0; j < n; j++) canonical_vector(&vectors[j], n, n, tie);
    for (i = 1; i < n; i++) {  /* insertion sort: stable */
        cx value = values[i];
        for (r = 0; r < n; r++) column[r] = vectors[r * n + i];
        for (j = i; j > 0 && mode_before(value, values[j - 1], tie); j--) {
            values[j] = values[j - 1];
            for (r = 0; r < n; r++) vectors[r * n + j] = vectors[r * n + j - 1];
        }
        values[j] = value;
        for (r = 0; r < n; r++) vectors[r * n + j] = column[r];
    }
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

int say_why(char* why, size_t size, int status, const char* format, ...)
{
    if (why != NULL && size > 0) {
        va_list args;
        va_start(args, format);
        vsnprintf(why, size, format, args);
        va_end(args);
    }
    return status;
}

/* the clock (core/clock.py) */
double clock_resolved_until(double h)
{
    int exponent;
    frexp(h, &exponent);
    return ldexp(1.0, exponent + 52);
}

int clock_resolves(double time, double h) { return fabs(time) + h < clock_resolved_until(h); }
