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

/* Roots s of det(M s^2 + D s + K) = 0 for a 2-DOF order: m diagonal, d and k 2x2 (row major).
 * real_system: the coefficients are real; roots that are real to rounding come out exactly
 * real. Returns 0, or -1 when the iteration does not converge. */
int order_roots(const double m[2], const cx d[4], const cx k[4], int real_system, cx roots[4]);

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

#endif
