/* inplane_critical.c: the in-plane ring's critical speed (see inplane_critical.h).
 *
 * With damping and the hysteretic loss left out, the held ring's stiffness K(Omega) is
 * exactly quadratic in the spin and its field blocks are symmetric circulant, so each Fourier
 * order n has its own Hermitian nf x nf block K_n(Omega) = K0 + Omega K1 + Omega^2 K2, read off
 * the rings built at 0, S and 2S (S = INPLANE_CRITICAL_FIT_STEP_RAD_S, large enough that the
 * Omega^2 part is not lost beside K0's stencils) through the blocks' first columns
 * (inplane_ritz.h's Fourier tools). A zero of det K_n(Omega) is a standing wave.
 *
 * K2 may be singular (the sidewall's rows are not loaded by the spin) but K0, at rest with the
 * rim held, is definite: so the roots are taken as mu = 1/Omega of the reversed problem
 * (mu^2 K0 + mu K1 + K2) q = 0, the standard eigenproblem of the companion
 * [[0, I], [-K0^-1 K2, -K0^-1 K1]] on (q, mu q) (2 nf <= 8, cx_eig). K2's null directions are
 * roots mu = 0 (infinite spin); rounding leaves them at small finite mu, which the share rule
 * drops. |Im mu| / |mu| = |Im Omega| / |Omega|, so the Python's rule for a real Omega is the
 * same rule on mu. The kind is read from q's kinetic energy with the ring's nodal masses. */
#include "inplane_critical.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "inplane_ritz.h"
#include "numerics.h"

#define MAX_FIELDS 4

size_t inplane_critical_work_doubles(int n_elements, int n_fields)
{
    size_t nd = inplane_ring_n_dof(n_elements, n_fields, 0);
    size_t ring = inplane_ring_work_doubles(n_elements, n_fields);
    if (nd == 0 || ring == 0)
        return 0;
    size_t n = (size_t)n_elements, nf = (size_t)n_fields;
    return 3 * nd * nd + ring /* mass, stiffness, damping; the ring's scratch */
           + 3 * nf * nf * n  /* K's first columns at the three spins */
           + 3 * n;           /* tables */
}

static double frobenius(const cx* a, int n)
{
    double s = 0.0;
    for (int i = 0; i < n * n; ++i)
        s += a[i].re * a[i].re + a[i].im * a[i].im;
    return sqrt(s);
}

int inplane_critical_speed(const InPlaneRingData* data, int n_elements, int n_fields,
                           double* spin_rad_s, double* speed_m_s, int* order, int* branch,
                           double* work, char* why, size_t why_size)
{
    int status = inplane_ring_check(data, n_elements, n_fields, 0.0, why, why_size);
    if (status)
        return status;
    if (spin_rad_s == NULL || speed_m_s == NULL || order == NULL || branch == NULL
        || work == NULL)
        return say_why(why, why_size, INPLANE_RING_NULL,
                   "an output (spin, speed, order, branch) or the scratch memory is missing");

    int n = n_elements, nf = n_fields;
    size_t nd = (size_t)nf * n;
    double* mass = work;
    double* stiffness = mass + nd * nd;
    double* damping = stiffness + nd * nd;
    double* ring_work = damping + nd * nd;
    double* col = ring_work + inplane_ring_work_doubles(n, nf); /* 3 spins */
    double* tables = col + 3 * (size_t)nf * nf * n;

    InPlaneRingData undamped = *data;
    undamped.alpha = 0.0;
    undamped.beta = 0.0;
    const double step = INPLANE_CRITICAL_FIT_STEP_RAD_S;
    double masses[MAX_FIELDS];
    for (int s = 0; s < 3; ++s) {
        status = inplane_ring_build(&undamped, n, nf, s * step, 0, 0, mass, stiffness, damping,
                                    NULL, ring_work, why, why_size);
        if (status)
            return status;
        inplane_fourier_columns(stiffness, n, nf, col + (size_t)s * nf * nf * n);
        if (s == 0)
            for (int f = 0; f < nf; ++f) /* per field, node 0: the mass is diagonal, held */
                masses[f] = mass[((size_t)f * n) * nd + (size_t)f * n];
    }
    inplane_fourier_tables(n, tables);

    double best = HUGE_VAL;
    int best_order = -1, best_branch = INPLANE_CRITICAL_NONE;
    for (int o = 0; o <= n / 2; ++o) {
        cx k0[MAX_FIELDS * MAX_FIELDS], k1[MAX_FIELDS * MAX_FIELDS], k2[MAX_FIELDS * MAX_FIELDS];
        cx ka[MAX_FIELDS * MAX_FIELDS], kb[MAX_FIELDS * MAX_FIELDS];
        cx inv[MAX_FIELDS * MAX_FIELDS];
        cx a[4 * MAX_FIELDS * MAX_FIELDS], vectors[4 * MAX_FIELDS * MAX_FIELDS];
        cx mu[2 * MAX_FIELDS];
        size_t block = (size_t)nf * nf * n;
        inplane_fourier_block(col, n, nf, o, tables, k0);
        inplane_fourier_block(col + block, n, nf, o, tables, ka);
        inplane_fourier_block(col + 2 * block, n, nf, o, tables, kb);
        /* core/inplane.py's quadratic_in_spin, the same operations */
        for (int i = 0; i < nf * nf; ++i) {
            double f2 = 0.5 / (step * step), f1 = 1.0 / step;
            k2[i] = cx_scale(cx_add(cx_sub(kb[i], cx_scale(ka[i], 2.0)), k0[i]), f2);
            k1[i] = cx_sub(cx_scale(cx_sub(ka[i], k0[i]), f1), cx_scale(k2[i], step));
        }
        memcpy(inv, k0, sizeof k0);
        if (cx_invert(inv, nf))
            return say_why(why, why_size, INPLANE_CRITICAL_SINGULAR,
                       "stiffness at rest, rim held: allowed a definite matrix (singular in "
                       "order %d)", o);
        int m = 2 * nf;
        for (int i = 0; i < m * m; ++i)
            a[i] = cx_make(0.0, 0.0);
        for (int i = 0; i < nf; ++i) {
            a[i * m + nf + i] = cx_make(1.0, 0.0);
            for (int j = 0; j < nf; ++j) {
                cx s2 = cx_make(0.0, 0.0), s1 = cx_make(0.0, 0.0);
                for (int k = 0; k < nf; ++k) {
                    s2 = cx_add(s2, cx_mul(inv[i * nf + k], k2[k * nf + j]));
                    s1 = cx_add(s1, cx_mul(inv[i * nf + k], k1[k * nf + j]));
                }
                a[(nf + i) * m + j] = cx_scale(s2, -1.0);
                a[(nf + i) * m + nf + j] = cx_scale(s1, -1.0);
            }
        }
        int real = o == 0 || 2 * o == n; /* real blocks: cx_eig keeps a real matrix's pairs */
        int eig = cx_eig(a, m, real, mu, vectors);
        if (eig)
            return say_why(why, why_size, INPLANE_CRITICAL_NO_CONVERGENCE,
                       "order %d: the eigenvalues of its %d x %d companion did not converge "
                       "(cx_eig status %d)", o, m, m, eig);
        double k0_norm = frobenius(k0, nf);
        double zero = INPLANE_CRITICAL_INFINITE_SHARE * sqrt(frobenius(k2, nf) / k0_norm);
        for (int e = 0; e < m; ++e) {
            double size = cx_abs(mu[e]);
            if (!(mu[e].re > 0.0 && size > zero
                  && fabs(mu[e].im) <= INPLANE_CRITICAL_REAL_TOLERANCE * size))
                continue;
            double spin = mu[e].re / (mu[e].re * mu[e].re + mu[e].im * mu[e].im); /* Re 1/mu */
            if (!(spin < best))
                continue;
            double total = 0.0, tangential = 0.0;
            for (int f = 0; f < nf; ++f) {
                cx q = vectors[f * m + e];
                double energy = masses[f] * (q.re * q.re + q.im * q.im);
                total += energy;
                if (f == 1 || f == 3) /* v, and v_s of the lumped sidewall */
                    tangential += energy;
            }
            best = spin;
            best_order = o;
            best_branch = tangential > 0.5 * total ? INPLANE_CRITICAL_TANGENTIAL
                                                   : INPLANE_CRITICAL_RADIAL;
        }
    }
    *spin_rad_s = best;
    *speed_m_s = best * data->R;
    *order = best_order;
    *branch = best_branch;
    return INPLANE_CRITICAL_OK;
}
