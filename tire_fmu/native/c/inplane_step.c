/* inplane_step.c: one trapezoidal step of the in-plane tire on the road, in C.
 *
 * The same step as tire_fmu/core/inplane_contact.py's InPlaneSimulator._step and
 * _point_forces (read that for the why of each line): the Python core builds every matrix
 * (at the current spin) and keeps them; this only does the arithmetic of a step, so that the
 * Python FMU's step costs what the BLAS-sized products cost rather than numpy's per-call
 * overhead. tests/test_inplane_host.py steps both over a braking, bumpy run and compares.
 *
 * Matrices are row-major doubles: (P x ny) jn, jxw, jl, kg, gain; (ny x P) yn, yx;
 * (P x P) wnn, wnx, kgn, kgx, carry; (ny x ny) m, c, a0_inv, c1, k1s, k2; (ny x 2)
 * rim_inertia. dspin is the wheel's spin less the one the ring's step was built at: its
 * terms, dspin (c1 v + k1s y) + dspin^2 k2 y on the state predicted at the step's end, are
 * taken off the step's load (_spin_correction), with dshare kh y, the change of the
 * hysteretic loss's share (nonzero only below its full speed). */
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "inplane_step.h"

/* out = a x; four rows at a time with four partial sums each, so that the products overlap
 * (the compiler may not reorder a single sum's additions) */
static void matvec(const double* a, const double* x, int rows, int cols, double* out) {
    int i = 0;
    for (; i + 4 <= rows; i += 4) {
        const double *r0 = a + (size_t)i * cols, *r1 = r0 + cols, *r2 = r1 + cols,
                     *r3 = r2 + cols;
        double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
        for (int j = 0; j < cols; ++j) {
            double v = x[j];
            s0 += r0[j] * v;
            s1 += r1[j] * v;
            s2 += r2[j] * v;
            s3 += r3[j] * v;
        }
        out[i] = s0;
        out[i + 1] = s1;
        out[i + 2] = s2;
        out[i + 3] = s3;
    }
    for (; i < rows; ++i) {
        const double* row = a + (size_t)i * cols;
        double s = 0.0;
        for (int j = 0; j < cols; ++j) s += row[j] * x[j];
        out[i] = s;
    }
}

/* Solve a x = b in place (a: n x n, row-major, overwritten), partial pivoting; 0 on
 * success, 1 if singular. */
static int lu_solve(double* a, double* b, int n) {
    for (int k = 0; k < n; ++k) {
        int p = k;
        double big = fabs(a[(size_t)k * n + k]);
        for (int i = k + 1; i < n; ++i) {
            double v = fabs(a[(size_t)i * n + k]);
            if (v > big) { big = v; p = i; }
        }
        if (!(big > 0.0)) return 1;
        if (p != k) {
            for (int j = 0; j < n; ++j) {
                double t = a[(size_t)k * n + j];
                a[(size_t)k * n + j] = a[(size_t)p * n + j];
                a[(size_t)p * n + j] = t;
            }
            double t = b[k]; b[k] = b[p]; b[p] = t;
        }
        double pivot = a[(size_t)k * n + k];
        for (int i = k + 1; i < n; ++i) {
            double f = a[(size_t)i * n + k] / pivot;
            if (f == 0.0) continue;
            a[(size_t)i * n + k] = f;
            for (int j = k + 1; j < n; ++j) a[(size_t)i * n + j] -= f * a[(size_t)k * n + j];
            b[i] -= f * b[k];
        }
    }
    for (int i = n - 1; i >= 0; --i) {
        double s = b[i];
        for (int j = i + 1; j < n; ++j) s -= a[(size_t)i * n + j] * b[j];
        b[i] = s / a[(size_t)i * n + i];
    }
    return 0;
}

/* The points' forces for given sets (_point_forces): the point laws with y eliminated. */
static int point_forces(const InPlaneStep* d, const int* contact, const int* stick,
                        const double* sign, const double* a_n, const double* beta_n,
                        const double* n_z0, const double* t_z0, double* f_n, double* f_x,
                        int* on, double* matrix, double* rhs) {
    int p = d->np, m = 0;
    for (int i = 0; i < p; ++i) {
        f_n[i] = f_x[i] = 0.0;
        if (contact[i]) on[m++] = i;
    }
    if (m == 0) return 0;
    int n = 2 * m;
    memset(matrix, 0, sizeof(double) * (size_t)n * n);
    for (int a = 0; a < m; ++a) {
        int i = on[a];
        double* row = matrix + (size_t)a * n;
        for (int b = 0; b < m; ++b) {
            int j = on[b];
            row[b] = a_n[i] * d->wnn[(size_t)i * p + j];
            row[m + b] = -a_n[i] * d->wnx[(size_t)i * p + j];
        }
        rhs[a] = beta_n[i] + a_n[i] * n_z0[i];
        double* lower = matrix + (size_t)(m + a) * n;
        if (stick[i]) {
            for (int b = 0; b < m; ++b) {
                int j = on[b];
                lower[b] = -d->kgn[(size_t)i * p + j];
                lower[m + b] = d->kgx[(size_t)i * p + j];
            }
            rhs[m + a] = -t_z0[i];
        } else {
            lower[a] = d->mu * sign[i];
            rhs[m + a] = 0.0;
        }
    }
    for (int k = 0; k < n; ++k) matrix[(size_t)k * n + k] += 1.0;
    if (lu_solve(matrix, rhs, n)) return 1;
    for (int a = 0; a < m; ++a) {
        f_n[on[a]] = rhs[a];
        f_x[on[a]] = rhs[m + a];
    }
    return 0;
}

/* The entering fractions of the runs in contact (entering_fractions), at least the step's
 * shift: pen is the penetration at the step's start. */
static void entering_fractions(const InPlaneStep* d, const double* pen, const int* contact,
                               double* delta) {
    const int p = d->np;
    for (int j = 0; j < p; ++j) {
        delta[j] = 1.0;
        if (!contact[j] || (j > 0 && contact[j - 1])) continue;
        delta[j] = 0.5;
        if (j > 0 && pen[j - 1] <= 0.0 && pen[j] > 0.0) {
            double fraction = pen[j] / (pen[j] - pen[j - 1]);
            delta[j] = fraction > d->min_entering ? fraction : d->min_entering;
        }
    }
    for (int j = 0; j < p; ++j)
        if (delta[j] < d->carry_shift) delta[j] = d->carry_shift;
}

/* The carry's corrections at the field's ends (carry_edges), added to e_conv: ahead of each
 * run in contact the field through zero at the road's edge, behind each run of sticking
 * points the run's own slope. */
static void carry_edges(const InPlaneStep* d, const double* e, const int* contact,
                        const int* stick, const double* delta, double* e_conv) {
    const int p = d->np;
    for (int pass = 0; pass < 2; ++pass) {
        for (int first = 0; first < p; ++first) {
#define IN_RUN(i) (contact[i] && (pass == 0 || stick[i]))
            if (!IN_RUN(first) || (first > 0 && IN_RUN(first - 1))) continue;
            int last = first;
            while (last + 1 < p && IN_RUN(last + 1)) ++last;
#undef IN_RUN
            double slope = 0.0;
            if (pass == 1)
                slope = last > 0 && contact[last - 1] ? e[last] - e[last - 1]
                                                      : e[last] / delta[last];
            for (int r = first; r <= last; ++r) {
                double sum = 0.0;
                for (int k = 0; k < 4; ++k) {
                    int c = d->carry_base[r] - 1 + k;
                    double virtual_e;
                    if (pass == 0 && c < first)
                        virtual_e = (1.0 - (first - c) / delta[first]) * e[first];
                    else if (pass == 1 && c > last)
                        virtual_e = e[last] + (c - last) * slope;
                    else
                        continue;
                    double real = c >= 0 && c < p ? e[c] : 0.0;
                    sum += d->carry_weights[4 * r + k] * (virtual_e - real);
                }
                e_conv[r] += sum;
            }
            first = last;
        }
    }
}

/* Workspace doubles and ints inplane_step needs for ny coordinates and np points. */
size_t inplane_work_doubles(int ny, int np) {
    return (size_t)11 * ny + (size_t)26 * np + (size_t)4 * np * np + 16;
}

size_t inplane_work_ints(int np) { return (size_t)8 * np + 8; }

/* One step from s to out (may not alias): 0, or 1 when the sets did not settle in
 * max_passes, 2 when a point solve was singular. */
int inplane_step(const InPlaneStep* d, const InPlaneState* s, InPlaneState* out,
                 const double* height, const double* rate, double torque,
                 const double* rim_old, const double* rim, double* work, int* iwork) {
    const int ny = d->ny, p = d->np;
    const double h = d->h;
    double *r = work, *b0 = r + ny, *tmp = b0 + ny, *tmp2 = tmp + ny, *z0 = tmp2 + ny;
    double *y_new = z0 + ny, *vny = y_new + ny;
    double *s_old = vny + ny, *e_conv = s_old + p, *pen_const = e_conv + p, *a_n = pen_const + p;
    double *beta_n = a_n + p, *gamma = beta_n + p, *n_z0 = gamma + p, *t0 = n_z0 + p;
    double *t_z0 = t0 + p, *f_n = t_z0 + p, *f_x = f_n + p, *pen = f_x + p, *f_trial = pen + p;
    double *e_trial = f_trial + p, *tread = e_trial + p, *limit = tread + p, *vp = limit + p;
    double *vp2 = vp + p, *sign = vp2 + p, *new_sign = sign + p, *jy = new_sign + p;
    double *matrix = jy + p, *rhs = matrix + (size_t)4 * p * p;
    int *contact = iwork, *stick = contact + p, *new_contact = stick + p;
    int *new_stick = new_contact + p, *on = new_stick + p;

    /* the tread's slip before the step (_slip) and the elements carried back by spin h */
    matvec(d->jxw, s->yd, p, ny, s_old);
    matvec(d->jl, s->y, p, ny, vp);
    for (int i = 0; i < p; ++i) s_old[i] += d->spin * vp[i];
    matvec(d->carry, s->e, p, p, e_conv);
    for (int k = 0; k < ny; ++k) {
        r[k] = 2.0 / h * s->y[k] + s->yd[k];
        tmp[k] = 4.0 / (h * h) * s->y[k] + 4.0 / h * s->yd[k] + s->ydd[k];
    }
    matvec(d->m, tmp, ny, ny, b0);
    matvec(d->c, r, ny, ny, tmp2);
    for (int k = 0; k < ny; ++k) b0[k] += tmp2[k];
    if (d->free_spin) b0[ny - 1] += torque;
    if (d->dspin != 0.0 || d->dshare != 0.0) {
        double *v_end = rhs + 2 * p, *y_end = v_end + ny, *q = y_end + ny;
        for (int k = 0; k < ny; ++k) {
            v_end[k] = s->yd[k] + h * s->ydd[k];
            y_end[k] = s->y[k] + h * s->yd[k] + 0.5 * h * h * s->ydd[k];
        }
        matvec(d->c1, v_end, ny, ny, tmp2);
        for (int k = 0; k < ny; ++k) b0[k] -= d->dspin * tmp2[k];
        matvec(d->k1s, y_end, ny, ny, tmp2);
        matvec(d->k2, y_end, ny, ny, q);
        for (int k = 0; k < ny; ++k) b0[k] -= d->dspin * (tmp2[k] + d->dspin * q[k]);
        if (d->dshare != 0.0) {
            matvec(d->kh, y_end, ny, ny, q);
            for (int k = 0; k < ny; ++k) b0[k] -= d->dshare * q[k];
        }
    }
    if (rim[2] != 0.0 || rim[5] != 0.0)
        for (int k = 0; k < ny; ++k)
            b0[k] -= d->rim_inertia[2 * k] * rim[2] + d->rim_inertia[2 * k + 1] * rim[5];
    matvec(d->jn, r, p, ny, vp);   /* jn r */
    matvec(d->jxw, r, p, ny, vp2); /* jxw r */
    int any_contact = 0;
    for (int i = 0; i < p; ++i) {
        pen_const[i] = d->pen0[i] + height[i] * d->sec[i];
        any_contact |= s->contact[i];
    }
    if (any_contact) { /* the field's ends: the ring at the step's start on its end's road */
        double *pen_start = rhs + 2 * p + 3 * ny, *delta = pen_start + p;
        matvec(d->jn, s->y, p, ny, pen_start);
        for (int i = 0; i < p; ++i) pen_start[i] += pen_const[i];
        entering_fractions(d, pen_start, s->contact, delta);
        carry_edges(d, s->e, s->contact, s->stick, delta, e_conv);
    }
    for (int i = 0; i < p; ++i) {
        a_n[i] = d->kn[i] + 2.0 * d->cn[i] / h;
        beta_n[i] = d->kn[i] * pen_const[i] + d->cn[i] * (rate[i] * d->sec[i] - vp[i]);
        double s0_new = d->s0[i] + rim[1];
        gamma[i] = e_conv[i] + 0.5 * h * (s_old[i] - vp2[i])
                   + 0.5 * h * (d->s0[i] + rim_old[1] + s0_new);
        t0[i] = d->kx[i] * gamma[i] + d->cx[i] * (s0_new - vp2[i]);
    }
    if (d->driven) /* the given turn's column is a load; the ring's rows are solved */
        for (int k = 0; k < ny; ++k) b0[k] -= d->a0_psi[k] * d->psi_new;
    matvec(d->a0_inv, b0, ny, ny, z0);
    if (d->driven) z0[ny - 1] = d->psi_new;
    matvec(d->jn, z0, p, ny, n_z0);
    matvec(d->kg, z0, p, ny, vp);
    for (int i = 0; i < p; ++i) {
        t_z0[i] = t0[i] + vp[i];
        contact[i] = s->contact[i];
        stick[i] = s->stick[i];
        sign[i] = s->slip_sign[i];
    }
    int settled = 0;
    for (int passes = 0; passes < d->max_passes; ++passes) {
        if (point_forces(d, contact, stick, sign, a_n, beta_n, n_z0, t_z0, f_n, f_x, on,
                         matrix, rhs))
            return 2;
        /* jn y_new and kg y_new through the products the simulator built (wnn = jn yn, ...):
         * the points' forces are zero off the road, so this costs points x contact points,
         * not points x coordinates; y_new itself is formed once, after the passes */
        int m = 0;
        for (int i = 0; i < p; ++i)
            if (contact[i]) on[m++] = i;
        for (int i = 0; i < p; ++i) {
            const double *wnn = d->wnn + (size_t)i * p, *wnx = d->wnx + (size_t)i * p;
            const double *kgn = d->kgn + (size_t)i * p, *kgx = d->kgx + (size_t)i * p;
            double a = n_z0[i], b = t_z0[i];
            for (int q = 0; q < m; ++q) {
                int j = on[q];
                a += -wnn[j] * f_n[j] + wnx[j] * f_x[j];
                b += -kgn[j] * f_n[j] + kgx[j] * f_x[j];
            }
            jy[i] = a;
            vp2[i] = b - t0[i];
        }
        int same = 1;
        for (int i = 0; i < p; ++i) {
            pen[i] = pen_const[i] + jy[i];
            f_trial[i] = a_n[i] * jy[i] + beta_n[i];
            tread[i] = t0[i] + vp2[i];
            new_contact[i] = pen[i] > 0.0 && f_trial[i] > 0.0;
            limit[i] = d->mu * (f_trial[i] > 0.0 ? f_trial[i] : 0.0);
            new_stick[i] = fabs(tread[i]) <= limit[i] * (1.0 + 1e-12);
            new_sign[i] = new_stick[i] ? sign[i]
                          : (tread[i] > 0.0 ? 1.0 : (tread[i] < 0.0 ? -1.0 : 0.0));
            if (passes >= d->settle_passes) {
                new_stick[i] = new_stick[i] && (stick[i] || !contact[i]);
                new_contact[i] = new_contact[i] && contact[i];
            }
        }
        /* sets_settled: the same contact set, the same sticking among it, the sliding ones
         * sliding the same way */
        for (int i = 0; i < p && same; ++i) {
            if (new_contact[i] != contact[i]) same = 0;
            else if ((new_stick[i] || !new_contact[i]) != (stick[i] || !contact[i])) same = 0;
            else if (new_contact[i] && !new_stick[i] && new_sign[i] != sign[i]) same = 0;
        }
        if (same) { settled = 1; break; }
        for (int i = 0; i < p; ++i) {
            contact[i] = new_contact[i];
            stick[i] = new_stick[i];
            sign[i] = new_sign[i];
        }
    }
    if (!settled) return 1;
    /* y_new = z0 - Y_n f_n + Y_x f_x (the last pass's forces), and the elements' trial
     * deflection from it */
    {
        int m = 0;
        for (int i = 0; i < p; ++i)
            if (f_n[i] != 0.0 || f_x[i] != 0.0) on[m++] = i;
        for (int k = 0; k < ny; ++k) {
            const double *yn = d->yn + (size_t)k * p, *yx = d->yx + (size_t)k * p;
            double v = z0[k];
            for (int q = 0; q < m; ++q) v += -yn[on[q]] * f_n[on[q]] + yx[on[q]] * f_x[on[q]];
            y_new[k] = v;
        }
        matvec(d->gain, y_new, p, ny, vp);
        for (int i = 0; i < p; ++i) e_trial[i] = gamma[i] + vp[i];
    }
    for (int k = 0; k < ny; ++k) {
        double dy = y_new[k] - s->y[k];
        out->yd[k] = 2.0 / h * dy - s->yd[k];
        out->ydd[k] = 4.0 / (h * h) * dy - 4.0 / h * s->yd[k] - s->ydd[k];
        out->y[k] = y_new[k];
    }
    /* a driven turn's rate is the host's, linear over the step: its acceleration is that
     * line's slope (the trapezoidal recurrence would carry any change of slope on as an
     * undamped alternation of sign, and the rim's moment with it) */
    if (d->driven) out->ydd[ny - 1] = (out->yd[ny - 1] - s->yd[ny - 1]) / h;
    for (int i = 0; i < p; ++i) {
        out->contact[i] = contact[i];
        out->stick[i] = stick[i];
        out->slip_sign[i] = sign[i];
        out->f_n[i] = contact[i] ? f_trial[i] : 0.0;
        double kx = d->kx[i] > 1e-300 ? d->kx[i] : 1e-300;
        out->e[i] = contact[i] ? (stick[i] ? e_trial[i] : sign[i] * limit[i] / kx) : 0.0;
    }
    return 0;
}
