/* inplane_ritz.c: the Ritz basis of the reduced in-plane step (see inplane_ritz.h).
 *
 * At rest with the rim held the ring is rotationally symmetric: every field block of M and K
 * is circulant, so the Fourier orders decouple. In the real Fourier coordinates (per field the
 * orthonormal cos and sin waves of each order n = 0 .. N/2, one wave at n = 0 and N/2) M and K
 * are block diagonal with blocks of 2 n_fields (n_fields at 0 and N/2), read off the blocks'
 * first columns in O(N^2) in all. Per order:
 *
 * - modes: the Hermitian n_fields x n_fields problem K(n) x = lambda M(n) x (Cholesky of M(n),
 *   complex Jacobi); each x gives the pair Re, Im of x e^{i n theta}, kept together when its one
 *   frequency is <= f_max_hz (orders 0 and N/2 give one real mode), M-normalised as eigh's;
 * - static shapes: K(n)^-1 of the unit load at node 0, refined twice from the residual of the
 *   dense K computed in double-double (Dekker's product, Knuth's sum): K(n) read off the first
 *   columns loses digits to the stencils' cancellation at low orders (the bending stencil's
 *   sum is of order dtheta^4 of its terms), so a shape from K(n) alone carries errors of
 *   eps cond(K); refined it solves the given K to rounding. A load at node j is that shape
 *   turned by j nodes (a phase per order), scaled to max |.| = 1 as the Python scales it.
 *
 * Orthonormalisation, with orth(rcond)'s rank: A = [modes, statics] and orth keeps the left
 * singular vectors of A with singular values above rcond s_max. With U D V^T the per-order SVD
 * of the modes, X = U^T S and Z = S - U X = Q R (Householder), A's singular values are those of
 * T = [[D, X], [0, R]]. By Haynsworth's inertia additivity, for mu = (rcond s_max)^2 below
 * min D^2, the number of singular values of T below rcond s_max is exactly the number of
 * singular values of R L^-T below it, L L^T = I + X^T (D^2 - mu)^-1 X, and the directions
 * orth drops are those left singular vectors (Q times them, to O(mu / D^2)). So every mode is
 * kept, and the statics' remainder Q is cut by a one-sided Jacobi SVD of the small
 * (2 n_zone)^2 matrix R L^-T: orth's rank decision without the SVD of the n_dof x columns A
 * (s_max comes from power iteration on T^T T). Gram-Schmidt alone could not say whether a
 * remainder is below rcond s_max, since its diagonal only bounds the singular values. */
#include "inplane_ritz.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "numerics.h"

#define PI 3.14159265358979323846
#define MAX_FIELDS 4
#define JACOBI_SWEEPS 60
#define POWER_STEPS 2000

static int valid_shape(int n, int nf, int nz)
{
    return n >= 8 && n <= 1600 && nf >= 2 && nf <= MAX_FIELDS && nz >= 0 && nz <= n;
}

/* per-order layout in the Fourier coordinates */
typedef struct {
    int n, nf, nz, p, n_dof, n_orders;
    const double *cosT, *sinT; /* cos, sin of 2 pi m / N (then the versines) */
} Grid;

/* the table index of (m + order) 2 pi / N, without a division in the inner loops */
static int next_angle(int m, int order, int n)
{
    m += order;
    return m >= n ? m - n : m;
}

static int single(const Grid* g, int order) { return order == 0 || 2 * order == g->n; }
static int order_size(const Grid* g, int order) { return single(g, order) ? g->nf : 2 * g->nf; }
static int order_offset(const Grid* g, int order)
{
    return order == 0 ? 0 : g->nf * (2 * order - 1);
}
/* the weight of an orthonormal wave: sqrt(2/N), sqrt(1/N) for the single ones */
static double wave_weight(const Grid* g, int order)
{
    return sqrt((single(g, order) ? 1.0 : 2.0) / g->n);
}

size_t inplane_ritz_work_doubles(int n_elements, int n_fields, int n_zone)
{
    if (!valid_shape(n_elements, n_fields, n_zone))
        return 0;
    size_t n = (size_t)n_elements, nf = (size_t)n_fields, nd = nf * n, p = 2 * (size_t)n_zone;
    size_t orders = n / 2 + 1;
    return 3 * n                  /* tables */
           + 2 * nf * nf * n      /* first columns of M and K */
           + orders * 4 * nf      /* node 0's static coordinates, w and v loads */
           + orders * 2 * nf * nf /* K(n)'s Cholesky factors (complex) */
           + orders               /* modes kept per order */
           + 2 * nf * nd + nd     /* mode directions U and D */
           + 3 * nd * p           /* S (then Z), X, Q */
           + 4 * p * p + p        /* R, L, W, V; Householder scalars */
           + 8 * nd + 2 * p;      /* power iteration; the statics' scratch when p < 4 */
}

/* ----- small dense tools ----- */

/* Hermitian Cholesky a = L L^H in place (lower triangle, n <= MAX_FIELDS); -1 if not definite */
static int cx_cholesky(cx* a, int n)
{
    for (int j = 0; j < n; ++j) {
        double d = a[j * n + j].re;
        for (int k = 0; k < j; ++k)
            d -= a[j * n + k].re * a[j * n + k].re + a[j * n + k].im * a[j * n + k].im;
        if (!(d > 0.0))
            return -1;
        double l = sqrt(d);
        a[j * n + j] = cx_make(l, 0.0);
        for (int i = j + 1; i < n; ++i) {
            cx s = a[i * n + j];
            for (int k = 0; k < j; ++k)
                s = cx_sub(s, cx_mul(a[i * n + k], cx_conj(a[j * n + k])));
            a[i * n + j] = cx_scale(s, 1.0 / l);
        }
    }
    return 0;
}

/* x <- L^-1 x, then with adjoint x <- L^-H x */
static void cx_lower_solve(const cx* l, int n, cx* x)
{
    for (int i = 0; i < n; ++i) {
        cx s = x[i];
        for (int k = 0; k < i; ++k)
            s = cx_sub(s, cx_mul(l[i * n + k], x[k]));
        x[i] = cx_scale(s, 1.0 / l[i * n + i].re);
    }
}
static void cx_adjoint_solve(const cx* l, int n, cx* x)
{
    for (int i = n - 1; i >= 0; --i) {
        cx s = x[i];
        for (int k = i + 1; k < n; ++k)
            s = cx_sub(s, cx_mul(cx_conj(l[k * n + i]), x[k]));
        x[i] = cx_scale(s, 1.0 / l[i * n + i].re);
    }
}

/* Hermitian a (n x n, n <= 8) = V diag(values) V^H by cyclic complex Jacobi; a is destroyed.
 * A real symmetric a stays real (every rotation's phase is +-1). */
static void cx_jacobi(cx* a, int n, double* values, cx* v)
{
    for (int i = 0; i < n * n; ++i)
        v[i] = cx_make(i % (n + 1) == 0 ? 1.0 : 0.0, 0.0);
    for (int sweep = 0; sweep < JACOBI_SWEEPS; ++sweep) {
        int rotated = 0;
        for (int p = 0; p < n - 1; ++p)
            for (int q = p + 1; q < n; ++q) {
                double g = cx_abs(a[p * n + q]);
                double app = a[p * n + p].re, aqq = a[q * n + q].re;
                if (!(g > 1e-18 * sqrt(fabs(app * aqq))) || g == 0.0)
                    continue;
                rotated = 1;
                cx phase = cx_scale(a[p * n + q], 1.0 / g); /* a_pq = g e^{i phi} */
                double tau = (aqq - app) / (2.0 * g);
                double t = (tau >= 0.0 ? 1.0 : -1.0) / (fabs(tau) + sqrt(1.0 + tau * tau));
                double c = 1.0 / sqrt(1.0 + t * t), s = t * c;
                /* J = diag(1, e^{-i phi}) on (p, q) times the real rotation [[c, s], [-s, c]] */
                cx jpp = cx_make(c, 0.0), jpq = cx_make(s, 0.0);
                cx jqp = cx_scale(cx_conj(phase), -s), jqq = cx_scale(cx_conj(phase), c);
                for (int k = 0; k < n; ++k) { /* a <- a J, v <- v J */
                    cx akp = a[k * n + p], akq = a[k * n + q];
                    a[k * n + p] = cx_add(cx_mul(akp, jpp), cx_mul(akq, jqp));
                    a[k * n + q] = cx_add(cx_mul(akp, jpq), cx_mul(akq, jqq));
                    cx vkp = v[k * n + p], vkq = v[k * n + q];
                    v[k * n + p] = cx_add(cx_mul(vkp, jpp), cx_mul(vkq, jqp));
                    v[k * n + q] = cx_add(cx_mul(vkp, jpq), cx_mul(vkq, jqq));
                }
                for (int k = 0; k < n; ++k) { /* a <- J^H a */
                    cx apk = a[p * n + k], aqk = a[q * n + k];
                    a[p * n + k] = cx_add(cx_mul(cx_conj(jpp), apk), cx_mul(cx_conj(jqp), aqk));
                    a[q * n + k] = cx_add(cx_mul(cx_conj(jpq), apk), cx_mul(cx_conj(jqq), aqk));
                }
                a[p * n + q] = a[q * n + p] = cx_make(0.0, 0.0);
                a[p * n + p].im = a[q * n + q].im = 0.0;
            }
        if (!rotated)
            break;
    }
    for (int i = 0; i < n; ++i)
        values[i] = a[i * n + i].re;
}

/* real Cholesky a = L L^T in place (row major, lower triangle); -1 if not definite */
static int cholesky(double* a, int n)
{
    for (int j = 0; j < n; ++j) {
        double d = a[(size_t)j * n + j];
        for (int k = 0; k < j; ++k)
            d -= a[(size_t)j * n + k] * a[(size_t)j * n + k];
        if (!(d > 0.0))
            return -1;
        double l = sqrt(d);
        a[(size_t)j * n + j] = l;
        for (int i = j + 1; i < n; ++i) {
            double s = a[(size_t)i * n + j];
            for (int k = 0; k < j; ++k)
                s -= a[(size_t)i * n + k] * a[(size_t)j * n + k];
            a[(size_t)i * n + j] = s / l;
        }
    }
    return 0;
}

/* One-sided (Hestenes) Jacobi on the columns of w (n x n, row major): on return w's columns
 * are mutually orthogonal, w_in V = w_out; sigma the column norms. */
static void hestenes(double* w, int n, double* sigma)
{
    for (int sweep = 0; sweep < JACOBI_SWEEPS; ++sweep) {
        int rotated = 0;
        for (int p = 0; p < n - 1; ++p)
            for (int q = p + 1; q < n; ++q) {
                double alpha = 0.0, beta = 0.0, gamma = 0.0;
                for (int k = 0; k < n; ++k) {
                    double a = w[(size_t)k * n + p], b = w[(size_t)k * n + q];
                    alpha += a * a;
                    beta += b * b;
                    gamma += a * b;
                }
                if (!(fabs(gamma) > 1e-15 * sqrt(alpha * beta)))
                    continue;
                rotated = 1;
                double zeta = (beta - alpha) / (2.0 * gamma);
                double t = (zeta >= 0.0 ? 1.0 : -1.0) / (fabs(zeta) + sqrt(1.0 + zeta * zeta));
                double c = 1.0 / sqrt(1.0 + t * t), s = c * t;
                for (int k = 0; k < n; ++k) {
                    double a = w[(size_t)k * n + p], b = w[(size_t)k * n + q];
                    w[(size_t)k * n + p] = c * a - s * b;
                    w[(size_t)k * n + q] = s * a + c * b;
                }
            }
        if (!rotated)
            break;
    }
    for (int j = 0; j < n; ++j) {
        double s = 0.0;
        for (int k = 0; k < n; ++k)
            s += w[(size_t)k * n + j] * w[(size_t)k * n + j];
        sigma[j] = sqrt(s);
    }
}

/* ----- the ring's Fourier blocks ----- */

void inplane_fourier_tables(int n_elements, double* tables)
{
    int n = n_elements;
    double *cos_table = tables, *sin_table = tables + n, *versine = tables + 2 * (size_t)n;
    for (int m = 0; m < n; ++m) {
        /* exact zeros at the quarter turns, so orders 0 and N/2 stay real */
        double angle = 2.0 * PI * m / n, half = sin(PI * m / n);
        cos_table[m] = 4 * m == n || 4 * m == 3 * n ? 0.0 : cos(angle);
        sin_table[m] = 2 * m == n || m == 0 ? 0.0 : sin(angle);
        versine[m] = 2.0 * half * half;
    }
}

void inplane_fourier_columns(const double* m, int n_elements, int n_fields, double* col)
{
    int n = n_elements, nf = n_fields;
    size_t nd = (size_t)nf * n;
    for (int a = 0; a < nf; ++a)
        for (int b = 0; b < nf; ++b)
            for (int k = 0; k < n; ++k) {
                size_t r = (size_t)a * n + k, c = (size_t)b * n;
                col[((size_t)a * nf + b) * n + k] = 0.5 * (m[r * nd + c] + m[c * nd + r]);
            }
}

void inplane_fourier_block(const double* col, int n_elements, int n_fields, int order,
                           const double* tables, cx* out)
{
    int n = n_elements, nf = n_fields, real = order == 0 || 2 * order == n;
    const double *sin_table = tables + n, *versine = tables + 2 * (size_t)n;
    for (int a = 0; a < nf; ++a)
        for (int b = 0; b < nf; ++b) {
            const double* c = col + ((size_t)a * nf + b) * n;
            /* sum c_k cos = sum c_k - sum c_k versine: the stencils' columns nearly sum to zero
             * (a rigid motion), so the sum is compensated (Neumaier) and the cosines' rounding,
             * of order eps |c_k| near 1, is left out of the rest */
            double sum = 0.0, carry = 0.0, turned = 0.0, im = 0.0;
            for (int k = 0, m = 0; k < n; ++k, m = next_angle(m, order, n)) {
                double t = sum + c[k];
                carry += fabs(sum) >= fabs(c[k]) ? (sum - t) + c[k] : (c[k] - t) + sum;
                sum = t;
                turned += c[k] * versine[m];
                im -= c[k] * sin_table[m];
            }
            out[a * nf + b] = cx_make((sum + carry) - turned, real ? 0.0 : im);
        }
    for (int a = 0; a < nf; ++a) /* exactly Hermitian */
        for (int b = a; b < nf; ++b) {
            cx u = out[a * nf + b], l = cx_conj(out[b * nf + a]);
            cx mean = cx_scale(cx_add(u, l), 0.5);
            out[a * nf + b] = mean;
            out[b * nf + a] = cx_conj(mean);
        }
}

/* M(n) or K(n) (nf x nf, Hermitian) from the blocks' first columns */
static void order_block(const Grid* g, const double* col, int order, cx* out)
{
    inplane_fourier_block(col, g->n, g->nf, order, g->cosT, out);
}

/* the real-space vector (field-major, nf N) of Fourier coordinates c (n_dof) */
static void to_real(const Grid* g, const double* c, double* out)
{
    int n = g->n, nf = g->nf;
    memset(out, 0, (size_t)g->n_dof * sizeof *out);
    for (int order = 0; order < g->n_orders; ++order) {
        const double* block = c + order_offset(g, order);
        double weight = wave_weight(g, order);
        int pair = !single(g, order);
        for (int a = 0; a < nf; ++a) {
            double cs = weight * block[a], sn = pair ? weight * block[nf + a] : 0.0;
            if (cs == 0.0 && sn == 0.0)
                continue;
            double* line = out + (size_t)a * n;
            for (int i = 0, m = 0; i < n; ++i, m = next_angle(m, order, n))
                line[i] += cs * g->cosT[m] + sn * g->sinT[m];
        }
    }
}

/* the Fourier coordinates of a real-space vector (to_real's inverse: the waves are
 * orthonormal) */
static void from_real(const Grid* g, const double* x, double* c)
{
    int n = g->n, nf = g->nf;
    for (int order = 0; order < g->n_orders; ++order) {
        double* block = c + order_offset(g, order);
        double weight = wave_weight(g, order);
        int pair = !single(g, order);
        for (int a = 0; a < nf; ++a) {
            const double* line = x + (size_t)a * n;
            double cs = 0.0, sn = 0.0;
            for (int i = 0, m = 0; i < n; ++i, m = next_angle(m, order, n)) {
                cs += line[i] * g->cosT[m];
                sn += line[i] * g->sinT[m];
            }
            block[a] = weight * cs;
            if (pair)
                block[nf + a] = weight * sn;
        }
    }
}

/* c <- K^-1 c order by order, K(n) = L L^H in chol: a pair's (alpha, beta) is the complex
 * alpha - i beta */
static void solve_orders(const Grid* g, const double* chol, double* c)
{
    int nf = g->nf;
    for (int order = 0; order < g->n_orders; ++order) {
        const cx* l = (const cx*)(const void*)(chol + (size_t)order * 2 * nf * nf);
        double* block = c + order_offset(g, order);
        int pair = !single(g, order);
        cx y[MAX_FIELDS];
        for (int a = 0; a < nf; ++a)
            y[a] = cx_make(block[a], pair ? -block[nf + a] : 0.0);
        cx_lower_solve(l, nf, y);
        cx_adjoint_solve(l, nf, y);
        for (int a = 0; a < nf; ++a) {
            block[a] = y[a].re;
            if (pair)
                block[nf + a] = -y[a].im;
        }
    }
}

/* Knuth's two-sum and Dekker's two-product: a sum and a product with their rounding errors */
static void two_sum(double a, double b, double* s, double* e)
{
    double t = a + b, v = t - a;
    *s = t;
    *e = (a - (t - v)) + (b - v);
}
static void split(double a, double* hi, double* lo)
{
    double t = 134217729.0 * a; /* 2^27 + 1 */
    *hi = t - (t - a);
    *lo = a - *hi;
}
static void two_product(double a, double b, double* p, double* e)
{
    double ah, al, bh, bl;
    *p = a * b;
    split(a, &ah, &al);
    split(b, &bh, &bl);
    *e = ((ah * bh - *p) + ah * bl + al * bh) + al * bl;
}

/* r_f = e_{unit_f} - K_sym x_f for the two shapes f in double-double, rounded (K_sym =
 * (K + K^T)/2 as the Python forms it, its zeros skipped); K is read in tiles so that K^T's
 * entries come from the cache; hi, lo: 2 nd doubles each */
#define TILE 32
static void residuals(const double* k, int nd, const int* unit, const double* x, double* r,
                      double* hi, double* lo)
{
    for (int f = 0; f < 2; ++f)
        for (int i = 0; i < nd; ++i) {
            hi[f * nd + i] = i == unit[f] ? 1.0 : 0.0;
            lo[f * nd + i] = 0.0;
        }
    for (int i0 = 0; i0 < nd; i0 += TILE)
        for (int j0 = 0; j0 < nd; j0 += TILE) {
            int i1 = i0 + TILE < nd ? i0 + TILE : nd, j1 = j0 + TILE < nd ? j0 + TILE : nd;
            for (int i = i0; i < i1; ++i) {
                const double* row = k + (size_t)i * nd;
                for (int j = j0; j < j1; ++j) {
                    double kij = row[j], kji = k[(size_t)j * nd + i];
                    if (kij == 0.0 && kji == 0.0)
                        continue;
                    double entry = -0.5 * (kij + kji);
                    for (int f = 0; f < 2; ++f) {
                        double p, pe, t, te;
                        two_product(entry, x[(size_t)f * nd + j], &p, &pe);
                        two_sum(hi[f * nd + i], p, &t, &te);
                        hi[f * nd + i] = t;
                        lo[f * nd + i] += te + pe;
                    }
                }
            }
        }
    for (int i = 0; i < 2 * nd; ++i)
        r[i] = hi[i] + lo[i];
}

/* s <- s minus its components along the modes' directions U, order by order */
static void project_out_modes(const Grid* g, const double* kept, const double* U, double* s)
{
    for (int order = 0; order < g->n_orders; ++order) {
        int d = order_size(g, order), k = (int)kept[order], off = order_offset(g, order);
        const double* u = U + (size_t)off * 2 * g->nf;
        for (int i = 0; i < k; ++i) {
            double dot = 0.0;
            for (int r = 0; r < d; ++r)
                dot += u[(size_t)i * d + r] * s[off + r];
            for (int r = 0; r < d; ++r)
                s[off + r] -= dot * u[(size_t)i * d + r];
        }
    }
}

static const char* matrix_name(int which) { return which ? "stiffness" : "mass"; }

/* symmetric circulant field blocks, to tolerance; their symmetric first columns into col */
static int read_blocks(const Grid* g, const double* m, int which, double* col, char* why,
                       size_t size)
{
    int n = g->n, nf = g->nf;
    size_t nd = (size_t)g->n_dof;
    double top = 0.0;
    for (size_t i = 0; i < nd * nd; ++i) {
        if (!isfinite(m[i]))
            return say_why(why, size, INPLANE_RITZ_BAD_MATRIX,
                       "%s[%zu, %zu] = %g: allowed a finite number", matrix_name(which),
                       i / nd, i % nd, m[i]);
        if (fabs(m[i]) > top)
            top = fabs(m[i]);
    }
    if (!(top > 0.0))
        return say_why(why, size, INPLANE_RITZ_BAD_MATRIX, "%s = 0: allowed a definite matrix",
                   matrix_name(which));
    double tol = INPLANE_RITZ_CIRCULANT_TOLERANCE * top;
    for (int a = 0; a < nf; ++a)
        for (int b = 0; b < nf; ++b)
            for (int i = 0; i < n; ++i)
                for (int j = 0, lag = i; j < n; ++j, lag = lag == 0 ? n - 1 : lag - 1) {
                    size_t r = (size_t)a * n + i, c = (size_t)b * n + j;
                    size_t r0 = (size_t)a * n + lag, c0 = (size_t)b * n;
                    double here = m[r * nd + c], first = m[r0 * nd + c0], mirror = m[c * nd + r];
                    if (fabs(here - first) > tol || fabs(here - mirror) > tol)
                        return say_why(why, size, INPLANE_RITZ_BAD_MATRIX,
                                   "%s[%zu, %zu] = %.17g: allowed symmetric circulant field "
                                   "blocks (within %g of the largest entry: %.17g at [%zu, "
                                   "%zu], %.17g at [%zu, %zu]): the ring at rest with the rim "
                                   "held", matrix_name(which), r, c, here,
                                   INPLANE_RITZ_CIRCULANT_TOLERANCE, first, r0, c0, mirror, c,
                                   r);
                }
    inplane_fourier_columns(m, n, nf, col);
    return INPLANE_RITZ_OK;
}

int inplane_ritz_build(const double* mass, const double* stiffness, int n_elements,
                       int n_fields, const int* zone_nodes, int n_zone, double f_max_hz,
                       int max_columns, double* basis, int* n_columns, double* work,
                       char* why, size_t why_size)
{
    if (n_elements < 8 || n_elements > 1600)
        return say_why(why, why_size, INPLANE_RITZ_BAD_SHAPE,
                   "n_elements = %d: allowed an integer in [8, 1600]", n_elements);
    if (n_fields < 2 || n_fields > MAX_FIELDS)
        return say_why(why, why_size, INPLANE_RITZ_BAD_SHAPE,
                   "n_fields = %d: allowed 2 (massless sidewall), 3 (tied) or 4 (lumped)",
                   n_fields);
    if (n_zone < 0 || n_zone > n_elements)
        return say_why(why, why_size, INPLANE_RITZ_BAD_SHAPE,
                   "n_zone = %d: allowed an integer in [0, n_elements = %d]", n_zone,
                   n_elements);
    if (!(isfinite(f_max_hz) && f_max_hz >= INPLANE_RITZ_MIN_F_MAX_HZ
          && f_max_hz <= INPLANE_RITZ_MAX_F_MAX_HZ))
        return say_why(why, why_size, INPLANE_RITZ_BAD_F_MAX,
                   "f_max_hz = %g Hz: allowed a finite number in [%g, %g] Hz", f_max_hz,
                   INPLANE_RITZ_MIN_F_MAX_HZ, INPLANE_RITZ_MAX_F_MAX_HZ);
    if (max_columns < 0)
        return say_why(why, why_size, INPLANE_RITZ_BAD_SHAPE,
                   "max_columns = %d: allowed an integer >= 0", max_columns);
    if (mass == NULL || stiffness == NULL || basis == NULL || n_columns == NULL || work == NULL
        || (n_zone > 0 && zone_nodes == NULL))
        return say_why(why, why_size, INPLANE_RITZ_NULL,
                   "a matrix, the zone nodes, the basis, n_columns or the scratch is missing");
    for (int i = 0; i < n_zone; ++i)
        if (zone_nodes[i] < 0 || zone_nodes[i] >= n_elements)
            return say_why(why, why_size, INPLANE_RITZ_BAD_ZONE,
                       "zone_nodes[%d] = %d: allowed a node in [0, %d]", i, zone_nodes[i],
                       n_elements - 1);

    Grid g;
    g.n = n_elements;
    g.nf = n_fields;
    g.nz = n_zone;
    g.p = 2 * n_zone;
    g.n_dof = n_fields * n_elements;
    g.n_orders = n_elements / 2 + 1;
    int n = g.n, nf = g.nf, p = g.p, nd = g.n_dof;
    size_t ndz = (size_t)nd;

    double* cosT = work;
    double* sinT = cosT + n;
    double* colM = sinT + 2 * (size_t)n; /* and the versines */
    double* colK = colM + (size_t)nf * nf * n;
    double* c0 = colK + (size_t)nf * nf * n;         /* 2 columns of nd coordinates */
    double* chol = c0 + (size_t)g.n_orders * 4 * nf; /* per order nf^2 complex */
    double* kept = chol + (size_t)g.n_orders * 2 * nf * nf; /* modes per order */
    double* U = kept + g.n_orders;                    /* per order d x k, column major */
    double* D = U + 2 * (size_t)nf * ndz;
    double* S = D + ndz;                              /* column c at S + c nd */
    double* X = S + ndz * p;                          /* r_m x p, row major */
    double* Q = X + ndz * p;                          /* column c at Q + c nd */
    double* R = Q + ndz * p;
    double* L = R + (size_t)p * p;
    double* W = L + (size_t)p * p;
    double* V = W + (size_t)p * p;
    double* tau = V + (size_t)p * p;
    double* v1 = tau + p; /* 8 nd + 2 p from here */
    double* y1 = v1 + ndz;
    double* v2 = y1 + ndz;
    double* y2 = v2 + p;
    g.cosT = cosT;
    g.sinT = sinT;
    inplane_fourier_tables(n, cosT);

    int status = read_blocks(&g, mass, 0, colM, why, why_size);
    if (!status)
        status = read_blocks(&g, stiffness, 1, colK, why, why_size);
    if (status)
        return status;

    /* ----- per order: modes and the static responses ----- */
    double lambda_max = pow(2.0 * PI * f_max_hz, 2.0);
    int r_m = 0;
    for (int order = 0; order < g.n_orders; ++order) {
        cx mh[MAX_FIELDS * MAX_FIELDS], kh[MAX_FIELDS * MAX_FIELDS], a[MAX_FIELDS * MAX_FIELDS];
        cx vec[MAX_FIELDS * MAX_FIELDS];
        double values[MAX_FIELDS];
        order_block(&g, colM, order, mh);
        order_block(&g, colK, order, kh);
        memcpy(a, kh, sizeof kh);
        if (cx_cholesky(mh, nf))
            return say_why(why, why_size, INPLANE_RITZ_BAD_MATRIX,
                       "mass: allowed a positive definite matrix (not so in order %d)", order);
        if (cx_cholesky(kh, nf)) /* the rim is held: K is definite */
            return say_why(why, why_size, INPLANE_RITZ_BAD_MATRIX,
                       "stiffness: allowed a positive definite matrix, the rim held (not so in "
                       "order %d)", order);
        memcpy(chol + (size_t)order * 2 * nf * nf, kh, (size_t)nf * nf * sizeof *kh);
        /* L^-1 K L^-H, column by column then row by row */
        for (int j = 0; j < nf; ++j) {
            cx column[MAX_FIELDS];
            for (int i = 0; i < nf; ++i)
                column[i] = a[i * nf + j];
            cx_lower_solve(mh, nf, column);
            for (int i = 0; i < nf; ++i)
                a[i * nf + j] = column[i];
        }
        for (int i = 0; i < nf; ++i) {
            cx row[MAX_FIELDS];
            for (int j = 0; j < nf; ++j)
                row[j] = cx_conj(a[i * nf + j]);
            cx_lower_solve(mh, nf, row);
            for (int j = 0; j < nf; ++j)
                a[i * nf + j] = cx_conj(row[j]);
        }
        for (int i = 0; i < nf; ++i) /* exactly Hermitian */
            for (int j = i; j < nf; ++j) {
                cx mean = cx_scale(cx_add(a[i * nf + j], cx_conj(a[j * nf + i])), 0.5);
                a[i * nf + j] = mean;
                a[j * nf + i] = cx_conj(mean);
            }
        cx_jacobi(a, nf, values, vec);
        /* the modes kept, as Phi's columns in this order's coordinates (d x k) */
        int d = order_size(&g, order), k = 0;
        double* phi = U + (size_t)order_offset(&g, order) * 2 * nf;
        for (int e = 0; e < nf; ++e) {
            /* one frequency per pair: both kept or both dropped */
            if (!(values[e] <= lambda_max))
                continue;
            cx x[MAX_FIELDS];
            for (int i = 0; i < nf; ++i)
                x[i] = vec[i * nf + e];
            cx_adjoint_solve(mh, nf, x); /* x^H M(n) x = 1 */
            if (single(&g, order)) {
                double norm = 0.0;
                for (int i = 0; i < nf; ++i)
                    norm += x[i].re * x[i].re + x[i].im * x[i].im;
                double re = 0.0;
                for (int i = 0; i < nf; ++i)
                    re += x[i].re * x[i].re;
                /* real to rounding up to a phase (+-1, +-i: the rotations of a real matrix);
                 * the larger part, scaled back to M-norm 1 */
                int imaginary = re < 0.5 * norm;
                double fix = sqrt(norm / (imaginary ? norm - re : re));
                for (int i = 0; i < nf; ++i)
                    phi[(size_t)k * d + i] = (imaginary ? x[i].im : x[i].re) * fix;
                k += 1;
            } else {
                for (int i = 0; i < nf; ++i) {
                    phi[(size_t)k * d + i] = x[i].re;
                    phi[(size_t)k * d + nf + i] = -x[i].im;
                    phi[(size_t)(k + 1) * d + i] = x[i].im;
                    phi[(size_t)(k + 1) * d + nf + i] = x[i].re;
                }
                k += 2;
            }
        }
        kept[order] = k;
        r_m += k;
    }

    /* ----- per order: Phi = U diag(D) V^T (U orthonormal, d x k), from Phi^T Phi ----- */
    {
        int row = 0;
        for (int order = 0; order < g.n_orders; ++order) {
            int d = order_size(&g, order), k = (int)kept[order];
            double* phi = U + (size_t)order_offset(&g, order) * 2 * nf;
            if (k == 0)
                continue;
            cx gram[8 * 8], vec[8 * 8];
            double values[8], out[8 * 8];
            for (int i = 0; i < k; ++i)
                for (int j = 0; j < k; ++j) {
                    double s = 0.0;
                    for (int r = 0; r < d; ++r)
                        s += phi[(size_t)i * d + r] * phi[(size_t)j * d + r];
                    gram[i * k + j] = cx_make(s, 0.0);
                }
            cx_jacobi(gram, k, values, vec);
            for (int j = 0; j < k; ++j) {
                double sigma = sqrt(values[j]);
                for (int r = 0; r < d; ++r) {
                    double s = 0.0;
                    for (int i = 0; i < k; ++i)
                        s += phi[(size_t)i * d + r] * vec[i * k + j].re;
                    out[j * d + r] = s / sigma;
                }
                D[row + j] = sigma;
            }
            /* modified Gram-Schmidt once more: U orthonormal to rounding */
            for (int j = 0; j < k; ++j) {
                double* u = out + j * d;
                for (int i = 0; i < j; ++i) {
                    double s = 0.0;
                    for (int r = 0; r < d; ++r)
                        s += out[i * d + r] * u[r];
                    for (int r = 0; r < d; ++r)
                        u[r] -= s * out[i * d + r];
                }
                double s = 0.0;
                for (int r = 0; r < d; ++r)
                    s += u[r] * u[r];
                s = sqrt(s);
                for (int r = 0; r < d; ++r)
                    u[r] /= s;
            }
            memcpy(phi, out, (size_t)k * d * sizeof *out);
            row += k;
        }
    }

    /* ----- node 0's static shapes, refined; the zone's turned and scaled ----- */
    double scale[2];
    {
        /* scratch before S and X are filled: S holds the shapes and the residuals when it
         * has the room (p >= 4), else the power iteration's room */
        double *x = S, *r = S + 2 * ndz, *hi = X, *lo = X + 2 * ndz;
        if (p < 4)
            x = v1, r = v1 + 2 * ndz, hi = v1 + 4 * ndz, lo = v1 + 6 * ndz;
        int unit[2] = {0, n};
        memset(c0, 0, 2 * ndz * sizeof *c0);
        for (int f = 0; f < 2; ++f) { /* e_f's coordinates */
            double* rc = r + (size_t)f * ndz;
            memset(rc, 0, ndz * sizeof *rc);
            for (int order = 0; order < g.n_orders; ++order)
                rc[order_offset(&g, order) + f] = wave_weight(&g, order);
        }
        for (int pass = 0; pass < 3; ++pass) {
            for (int f = 0; f < 2; ++f) {
                double *c = c0 + (size_t)f * ndz, *rc = r + (size_t)f * ndz;
                if (pass > 0)
                    from_real(&g, r + (size_t)f * ndz, hi); /* hi: scratch here */
                if (pass > 0)
                    memcpy(rc, hi, ndz * sizeof *rc);
                solve_orders(&g, chol, rc);
                for (int i = 0; i < nd; ++i)
                    c[i] += rc[i];
                to_real(&g, c, x + (size_t)f * ndz);
            }
            if (pass < 2)
                residuals(stiffness, nd, unit, x, r, hi, lo);
        }
        for (int f = 0; f < 2; ++f) {
            double top = 0.0;
            for (int i = 0; i < nd; ++i)
                if (fabs(x[(size_t)f * ndz + i]) > top)
                    top = fabs(x[(size_t)f * ndz + i]);
            scale[f] = 1.0 / top;
        }
    }
    for (int z = 0; z < n_zone; ++z)
        for (int f = 0; f < 2; ++f) {
            double* out = S + (size_t)(2 * z + f) * ndz;
            const double* c = c0 + (size_t)f * ndz;
            int j = zone_nodes[z];
            for (int order = 0; order < g.n_orders; ++order) {
                int off = order_offset(&g, order), m = (int)(((long)order * j) % n);
                double cs = g.cosT[m], sn = g.sinT[m];
                for (int a = 0; a < nf; ++a) {
                    if (single(&g, order)) {
                        out[off + a] = scale[f] * cs * c[off + a];
                        continue;
                    }
                    /* (alpha - i beta) e^{-i n theta_j}, back to (Re, -Im) */
                    double alpha = c[off + a], beta = c[off + nf + a];
                    out[off + a] = scale[f] * (alpha * cs - beta * sn);
                    out[off + nf + a] = scale[f] * (beta * cs + alpha * sn);
                }
            }
        }

    /* ----- X = U^T S, Z = S - U X, twice ----- */
    memset(X, 0, (size_t)r_m * p * sizeof *X);
    for (int pass = 0; pass < 2; ++pass) {
        int row = 0;
        for (int order = 0; order < g.n_orders; ++order) {
            int d = order_size(&g, order), k = (int)kept[order], off = order_offset(&g, order);
            const double* u = U + (size_t)off * 2 * nf;
            for (int i = 0; i < k; ++i)
                for (int c = 0; c < p; ++c) {
                    double* s = S + (size_t)c * ndz + off;
                    double dot = 0.0;
                    for (int r = 0; r < d; ++r)
                        dot += u[(size_t)i * d + r] * s[r];
                    for (int r = 0; r < d; ++r)
                        s[r] -= dot * u[(size_t)i * d + r];
                    X[(size_t)(row + i) * p + c] += dot;
                }
            row += k;
        }
    }

    /* ----- Z = Q R by Householder (Z's columns in S hold the reflectors) ----- */
    memset(R, 0, (size_t)p * p * sizeof *R);
    for (int c = 0; c < p; ++c) {
        double* z = S + (size_t)c * ndz;
        double norm = 0.0;
        for (int r = c; r < nd; ++r)
            norm += z[r] * z[r];
        norm = sqrt(norm);
        double alpha = z[c] > 0.0 ? -norm : norm;
        /* v = z - alpha e_c, stored over z[c:]; tau = 2 / v^T v */
        z[c] -= alpha;
        double vv = 0.0;
        for (int r = c; r < nd; ++r)
            vv += z[r] * z[r];
        tau[c] = vv > 0.0 ? 2.0 / vv : 0.0;
        for (int e = c + 1; e < p; ++e) {
            double* y = S + (size_t)e * ndz;
            double dot = 0.0;
            for (int r = c; r < nd; ++r)
                dot += z[r] * y[r];
            dot *= tau[c];
            for (int r = c; r < nd; ++r)
                y[r] -= dot * z[r];
        }
        for (int i = 0; i < c; ++i)
            R[(size_t)i * p + c] = z[i];
        R[(size_t)c * p + c] = alpha;
    }
    for (int c = 0; c < p; ++c) { /* Q's columns: the reflectors applied to e_c */
        double* q = Q + (size_t)c * ndz;
        memset(q, 0, ndz * sizeof *q);
        q[c] = 1.0;
        for (int h = c; h >= 0; --h) {
            const double* v = S + (size_t)h * ndz;
            double dot = 0.0;
            for (int r = h; r < nd; ++r)
                dot += v[r] * q[r];
            dot *= tau[h];
            for (int r = h; r < nd; ++r)
                q[r] -= dot * v[r];
        }
    }

    /* ----- s_max by power iteration on T^T T, T = [[D, X], [0, R]] ----- */
    double s_max2 = 0.0;
    for (int i = 0; i < r_m; ++i)
        v1[i] = 1.0;
    for (int c = 0; c < p; ++c)
        v2[c] = 1.0;
    for (int step = 0; step < POWER_STEPS && r_m + p > 0; ++step) {
        double norm = 0.0;
        for (int i = 0; i < r_m; ++i)
            norm += v1[i] * v1[i];
        for (int c = 0; c < p; ++c)
            norm += v2[c] * v2[c];
        norm = sqrt(norm);
        for (int i = 0; i < r_m; ++i)
            v1[i] /= norm;
        for (int c = 0; c < p; ++c)
            v2[c] /= norm;
        /* y = T v */
        for (int i = 0; i < r_m; ++i) {
            double s = D[i] * v1[i];
            for (int c = 0; c < p; ++c)
                s += X[(size_t)i * p + c] * v2[c];
            y1[i] = s;
        }
        for (int i = 0; i < p; ++i) {
            double s = 0.0;
            for (int c = i; c < p; ++c)
                s += R[(size_t)i * p + c] * v2[c];
            y2[i] = s;
        }
        double rayleigh = 0.0;
        for (int i = 0; i < r_m; ++i)
            rayleigh += y1[i] * y1[i];
        for (int i = 0; i < p; ++i)
            rayleigh += y2[i] * y2[i];
        /* v = T^T y */
        for (int i = 0; i < r_m; ++i)
            v1[i] = D[i] * y1[i];
        for (int c = 0; c < p; ++c) {
            double s = 0.0;
            for (int i = 0; i < r_m; ++i)
                s += X[(size_t)i * p + c] * y1[i];
            for (int i = 0; i <= c; ++i)
                s += R[(size_t)i * p + c] * y2[i];
            v2[c] = s;
        }
        int settled = rayleigh <= s_max2 * (1.0 + 1e-13);
        if (rayleigh > s_max2)
            s_max2 = rayleigh;
        if (settled && step > 10)
            break;
    }
    double threshold = INPLANE_RITZ_RCOND * sqrt(s_max2), mu = threshold * threshold;
    for (int i = 0; i < r_m; ++i)
        if (!(D[i] > 2.0 * threshold))
            return say_why(why, why_size, INPLANE_RITZ_BAD_MATRIX,
                       "mass: allowed masses within 1e20 of each other (a mode's norm %g is "
                       "below %g times the basis's largest singular value)", D[i],
                       2.0 * INPLANE_RITZ_RCOND);

    /* ----- the statics' remainder cut at orth's rank: W = R L^-T ----- */
    int kept_static = 0;
    if (p > 0) {
        memset(L, 0, (size_t)p * p * sizeof *L);
        for (int a = 0; a < p; ++a)
            L[(size_t)a * p + a] = 1.0;
        for (int i = 0; i < r_m; ++i) {
            const double* xi = X + (size_t)i * p;
            double weight = 1.0 / (D[i] * D[i] - mu);
            for (int a = 0; a < p; ++a) {
                double xa = weight * xi[a];
                double* line = L + (size_t)a * p;
                for (int b = 0; b <= a; ++b)
                    line[b] += xa * xi[b];
            }
        }
        for (int a = 0; a < p; ++a)
            for (int b = 0; b < a; ++b)
                L[(size_t)b * p + a] = L[(size_t)a * p + b];
        if (cholesky(L, p))
            return say_why(why, why_size, INPLANE_RITZ_BAD_MATRIX,
                       "stiffness: allowed a ring whose static shapes are finite");
        for (int i = 0; i < p; ++i) { /* row i of W: L w = row i of R */
            double* w = W + (size_t)i * p;
            for (int j = 0; j < p; ++j) {
                double s = R[(size_t)i * p + j];
                for (int k = 0; k < j; ++k)
                    s -= L[(size_t)j * p + k] * w[k];
                w[j] = s / L[(size_t)j * p + j];
            }
        }
        hestenes(W, p, V);
        /* the kept left singular vectors, then Q times them, into S's columns */
        for (int j = 0; j < p; ++j) {
            if (!(V[j] > threshold))
                continue;
            double* out = S + (size_t)kept_static * ndz;
            memset(out, 0, ndz * sizeof *out);
            for (int i = 0; i < p; ++i) {
                double u = W[(size_t)i * p + j] / V[j];
                const double* q = Q + (size_t)i * ndz;
                for (int r = 0; r < nd; ++r)
                    out[r] += u * q[r];
            }
            kept_static += 1;
        }
        /* the remainder orthogonal to the modes and to itself to rounding: its left vectors
         * near the threshold carry rounding of order eps s_max / s, and Householder's Q is
         * orthogonal to the modes only where Z has rank. Gram-Schmidt, once more where a
         * projection took away more than half the norm ("twice is enough") */
        for (int c = 0; c < kept_static; ++c) {
            double* s = S + (size_t)c * ndz;
            for (int pass = 0; pass < 2; ++pass) {
                project_out_modes(&g, kept, U, s);
                for (int e = 0; e < c; ++e) {
                    const double* t = S + (size_t)e * ndz;
                    double dot = 0.0;
                    for (int r = 0; r < nd; ++r)
                        dot += t[r] * s[r];
                    for (int r = 0; r < nd; ++r)
                        s[r] -= dot * t[r];
                }
                double norm = 0.0;
                for (int r = 0; r < nd; ++r)
                    norm += s[r] * s[r];
                norm = sqrt(norm);
                for (int r = 0; r < nd; ++r)
                    s[r] /= norm;
                if (norm > 0.5)
                    break;
            }
        }
    }

    int total = r_m + kept_static;
    if (total > max_columns)
        return say_why(why, why_size, INPLANE_RITZ_TOO_MANY,
                   "max_columns = %d: allowed at least the basis's %d columns (%d modes up to "
                   "%g Hz and %d static shapes)", max_columns, total, r_m, f_max_hz,
                   kept_static);

    /* ----- to real space ----- */
    int column = 0;
    for (int order = 0; order < g.n_orders; ++order) {
        int d = order_size(&g, order), k = (int)kept[order], off = order_offset(&g, order);
        const double* u = U + (size_t)off * 2 * nf;
        double weight = wave_weight(&g, order);
        for (int i = 0; i < k; ++i, ++column) {
            double* out = basis + (size_t)column * ndz;
            for (int a = 0; a < nf; ++a) {
                double cs = weight * u[(size_t)i * d + a];
                double sn = single(&g, order) ? 0.0 : weight * u[(size_t)i * d + nf + a];
                for (int j = 0, m = 0; j < n; ++j, m = next_angle(m, order, n))
                    out[(size_t)a * n + j] = cs * g.cosT[m] + sn * g.sinT[m];
            }
        }
    }
    for (int c = 0; c < kept_static; ++c, ++column)
        to_real(&g, S + (size_t)c * ndz, basis + (size_t)column * ndz);
    *n_columns = total;
    return INPLANE_RITZ_OK;
}
