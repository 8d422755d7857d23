/* numerics.h: the small numerical tools of the tire model. Complex numbers are a struct (not
 * C99 _Complex) so that the sources also build with MSVC. */
#ifndef TIRE_NUMERICS_H
#define TIRE_NUMERICS_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

typedef struct {
    double re, im;
} cx;

static inline cx cx_make(double re, double im)
{
    cx z;
    z.re = re;
    z.im = im;
    return z;
}
static inline cx cx_add(cx a, cx b) { return cx_make(a.re + b.re, a.im + b.im); }
static inline cx cx_sub(cx a, cx b) { return cx_make(a.re - b.re, a.im - b.im); }
static inline cx cx_mul(cx a, cx b)
{
    return cx_make(a.re * b.re - a.im * b.im, a.re * b.im + a.im * b.re);
}
static inline cx cx_scale(cx a, double s) { return cx_make(a.re * s, a.im * s); }
static inline cx cx_conj(cx a) { return cx_make(a.re, -a.im); }
static inline double cx_abs(cx a) { return hypot(a.re, a.im); }
cx cx_div(cx a, cx b);
cx cx_exp(cx z);
cx cx_expm1(cx z);

/* phi1(z) = (e^z - 1)/z and phi2(z) = (e^z - 1 - z)/z^2 (series below |z| = limit) */
void phi_functions(cx z, double series_limit, cx* phi1, cx* phi2);

cx cx_sqrt(cx z); /* the principal square root */

/* Eigenvalues and right eigenvectors of a dense n x n complex matrix a (row major, 1 <= n <=
 * EIG_MAX_N), the steps of LAPACK's zgeev: scaling by a power of 2 to entries of order 1,
 * balancing by powers of 2 (zgebal's scaling, without its permutations), Householder reduction to upper Hessenberg form, complex single-shift QR
 * with Wilkinson shifts and exceptional shifts (after 10 and 20 iterations without a
 * deflation) to the Schur form T = Z^H A Z, eigenvectors of T by back-substitution (ztrevc's,
 * a diagonal within ulp |lambda| of zero moved there, scaled against overflow), then through Z
 * and the balancing. vectors: n x n row major, column k the eigenvector of values[k] with unit
 * 2-norm. real: a is real (its imaginary parts are not read) and the result keeps a real
 * matrix's structure, as LAPACK's dgeev returns it: each eigenvalue is matched with the
 * conjugate of another (pairs) or of itself (real) by the closest match first; a pair is made
 * exactly conjugate, values and vectors, from its member with Im > 0, a real eigenvalue gets
 * Im = 0 and a real eigenvector. Returns 0; -1 for n out of range or a non-finite entry; -2
 * when the QR iteration does not converge (more than 30 max(10, n) sweeps for one eigenvalue).
 * No order is promised: canonical_modes gives one. */
#define EIG_MAX_N 16
int cx_eig(const cx* a, int n, int real, cx* values, cx* vectors);

/* The canonical normalisation and order of the modes (values[k], column k of the n x n row
 * major vectors), in place: the rule of tire_fmu.core.modal_form.canonical_modes, with its
 * tolerance tie (spec.h: SPEC_MODE_TIE_TOLERANCE). */
void canonical_modes(int n, cx* values, cx* vectors, double tie);

/* Dense complex n x n inverse by Gauss-Jordan with partial pivoting, in place (n <= 8).
 * Returns 0, or -1 for a singular matrix. */
int cx_invert(cx* a, int n);

/* Real n x n LU with partial pivoting (row major, in place) and solves with it. */
int lu_factor(double* a, int n, int* pivot);
void lu_solve(const double* lu, int n, const int* pivot, double* b);
/* The inverse of a (n x n, row major) into inverse; work holds n*n + n doubles. */
int invert(const double* a, int n, double* inverse, double* work, int* pivot);

/* scipy.optimize.brentq (scipy/optimize/Zeros/brentq.c), the same steps. */
typedef double (*scalar_function)(double x, void* data);
double brentq(scalar_function f, void* data, double xa, double xb, double xtol, double rtol,
              int iterations);

/* x as Python's repr() writes it (the shortest text that reads back to x). */
void py_repr(double x, char* text, size_t size);
/* a value as the core's messages show it (parameters.value_text): %g when that reads back
 * exactly, else the shortest repr; then the unit, for a finite value */
void value_text(double x, const char* unit, char* text, size_t size);

/* 64-bit FNV-1a over bytes, continuing from hash (start with FNV_OFFSET). */
#define FNV_OFFSET UINT64_C(14695981039346656037)
uint64_t fnv1a(uint64_t hash, const unsigned char* bytes, size_t count);

/* A builder's refusal: the sentence (printf's format) into why, at most size bytes (nothing
 * when why is NULL), and status returned, so that `return say_why(why, size, 3, ...)` refuses
 * in one line. */
int say_why(char* why, size_t size, int status, const char* format, ...);
/* The clock (core/clock.py): whether a clock of doubles resolves the step h from time, and
 * up to which time it does. */
int clock_resolves(double time, double h);
double clock_resolved_until(double h);

#endif
