/* inplane_terms.c: the in-plane step's spin terms on its coordinates (inplane_terms.h).
 *
 * The coordinates y = [ring rim-relative, psi]: the ring's absolute DOFs are the rim-relative
 * ones plus the turn's pattern P_psi psi, the rim's x, z held (to_abs0, an identity and the
 * turn's column); reduced, y = blockdiag(B, 1) z, so to_abs = to_abs0 blockdiag(B, 1). Each
 * ring matrix A goes to the coordinates as to_abs^T A to_abs: first to_abs0 (written out: its
 * products cost n_dof^2, not n_dof^3), then the basis (dense). The ring at each spin is
 * projected before the spins are differenced (quadratic_in_spin), so that three full matrices
 * are never held at once: projection is linear, the two orders differ by rounding. */
#include "inplane_terms.h"

#include <math.h>
#include <string.h>

#include "numerics.h"

/* The ring's rim-relative DOFs and the coordinates, or 0 for sizes out of range. */
static int ring_dofs(int n_elements, int n_fields)
{
    if (n_elements < INPLANE_RING_MIN_ELEMENTS || n_elements > INPLANE_RING_MAX_ELEMENTS
        || n_fields < INPLANE_RING_MASSLESS || n_fields > INPLANE_RING_LUMPED)
        return 0;
    return n_fields * n_elements;
}

size_t inplane_terms_ny(int n_elements, int n_fields, int free_spin, int n_basis)
{
    int nr = ring_dofs(n_elements, n_fields);
    if (nr == 0 || (free_spin != 0 && free_spin != 1) || n_basis < 0 || n_basis > nr)
        return 0;
    return (size_t)(n_basis > 0 ? n_basis : nr) + (size_t)free_spin;
}

size_t inplane_terms_work_doubles(int n_elements, int n_fields, int free_spin, int n_basis)
{
    size_t ny = inplane_terms_ny(n_elements, n_fields, free_spin, n_basis);
    if (ny == 0)
        return 0;
    size_t nd = inplane_ring_n_dof(n_elements, n_fields, 1);
    size_t ny0 = (size_t)ring_dofs(n_elements, n_fields) + (size_t)free_spin;
    size_t total = 4 * nd * nd + inplane_ring_work_doubles(n_elements, n_fields) + 6 * nd;
    if (n_basis > 0)
        total += ny0 * ny0 + 2 * ny0 * ny;
    return total;
}

/* y = to_abs0^T a to_abs0 (ny0 x ny0) of a ring matrix a (nd x nd); p the turn's pattern (nr),
 * col scratch (nd). */
static void on_coordinates(const double* a, int nd, int nr, int free_spin, const double* p,
                           double* y, double* col)
{
    int ny0 = nr + free_spin;
    for (int i = 0; i < nr; ++i)
        memcpy(y + (size_t)i * ny0, a + (size_t)i * nd, (size_t)nr * sizeof *y);
    if (!free_spin)
        return;
    /* the psi column: a to_abs0's, over every row */
    for (int i = 0; i < nd; ++i) {
        const double* row = a + (size_t)i * nd;
        double s = 0.0;
        for (int k = 0; k < nr; ++k)
            s += row[k] * p[k];
        col[i] = s + row[nr + 2];
    }
    for (int i = 0; i < nr; ++i)
        y[(size_t)i * ny0 + nr] = col[i];
    double* psi_row = y + (size_t)nr * ny0;
    memcpy(psi_row, a + (size_t)(nr + 2) * nd, (size_t)nr * sizeof *y);
    for (int k = 0; k < nr; ++k) {
        if (p[k] == 0.0)
            continue;
        const double* row = a + (size_t)k * nd;
        for (int j = 0; j < nr; ++j)
            psi_row[j] += p[k] * row[j];
    }
    double s = 0.0;
    for (int k = 0; k < nr; ++k)
        s += p[k] * col[k];
    psi_row[nr] = s + col[nr + 2];
}

/* out = b^T y b (ny x ny) for y (ny0 x ny0), b (ny0 x ny); t scratch (ny0 x ny). */
static void on_basis(const double* y, const double* b, int ny0, int ny, double* t, double* out)
{
    memset(t, 0, (size_t)ny0 * ny * sizeof *t);
    for (int i = 0; i < ny0; ++i) {
        double* ti = t + (size_t)i * ny;
        for (int k = 0; k < ny0; ++k) {
            double v = y[(size_t)i * ny0 + k];
            if (v == 0.0)
                continue;
            const double* bk = b + (size_t)k * ny;
            for (int j = 0; j < ny; ++j)
                ti[j] += v * bk[j];
        }
    }
    memset(out, 0, (size_t)ny * ny * sizeof *out);
    for (int k = 0; k < ny0; ++k) {
        const double *bk = b + (size_t)k * ny, *tk = t + (size_t)k * ny;
        for (int i = 0; i < ny; ++i) {
            double v = bk[i];
            if (v == 0.0)
                continue;
            double* oi = out + (size_t)i * ny;
            for (int j = 0; j < ny; ++j)
                oi[j] += v * tk[j];
        }
    }
}

typedef struct {
    int nd, nr, ny0, ny, free_spin;
    const double* p;         /* the turn's pattern, nr */
    const double* bext;      /* ny0 x ny, or NULL: no basis */
    double *y, *t, *col;     /* scratch */
} Projection;

static void project(const Projection* g, const double* a, double* out)
{
    if (g->bext == NULL) {
        on_coordinates(a, g->nd, g->nr, g->free_spin, g->p, out, g->col);
        return;
    }
    on_coordinates(a, g->nd, g->nr, g->free_spin, g->p, g->y, g->col);
    on_basis(g->y, g->bext, g->ny0, g->ny, g->t, out);
}

/* a2 = (a_2 - 2 a_1 + a_0) / 2, a1 = (a_1 - a_0) - a2 in place (a_1 -> a1, a_2 -> a2):
 * quadratic_in_spin's at spins 0, 1, 2 rad/s, in its order of operations. */
static void quadratic(const double* a0, double* a1, double* a2, size_t count)
{
    for (size_t i = 0; i < count; ++i) {
        a2[i] = (a2[i] - 2.0 * a1[i] + a0[i]) * 0.5;
        a1[i] = (a1[i] - a0[i]) * 1.0 - 1.0 * a2[i];
    }
}

int inplane_terms_build(const InPlaneRingData* data, int n_elements, int n_fields, int free_spin,
                        const double* basis, int n_basis, InPlaneTermsOutput* out, double* work,
                        char* why, size_t why_size)
{
    int status = inplane_ring_check(data, n_elements, n_fields, 0.0, why, why_size);
    if (status)
        return status;
    if (free_spin != 0 && free_spin != 1)
        return say_why(why, why_size, INPLANE_TERMS_BAD_WHEEL,
                       "free_spin = %d: allowed 0 (the wheel held) or 1 (free)", free_spin);
    int nr = n_fields * n_elements;
    if (basis == NULL ? n_basis != 0 : (n_basis < 1 || n_basis > nr))
        return say_why(why, why_size, INPLANE_TERMS_BAD_BASIS,
                       "n_basis = %d: allowed an integer in [1, %d] (the ring's DOFs) with a "
                       "basis, 0 without one", n_basis, nr);
    if (basis != NULL)
        for (size_t i = 0; i < (size_t)nr * n_basis; ++i)
            if (!isfinite(basis[i]))
                return say_why(why, why_size, INPLANE_TERMS_BAD_BASIS,
                               "basis[%d, %d] = %g: the entries must be finite",
                               (int)(i / n_basis), (int)(i % n_basis), basis[i]);
    if (out == NULL || work == NULL || out->m == NULL || out->c0 == NULL || out->c1 == NULL
        || out->k0 == NULL || out->k1 == NULL || out->k2 == NULL || out->kh == NULL
        || out->to_abs == NULL || out->rim_inertia == NULL || out->rim_k0 == NULL
        || out->rim_k1 == NULL || out->rim_k2 == NULL || out->rim_kh == NULL
        || out->rim_c0 == NULL || out->rim_c1 == NULL || out->rim_m == NULL
        || out->rim_m_translation == NULL)
        return say_why(why, why_size, INPLANE_TERMS_NULL,
                       "an output array or the scratch memory is missing");

    int nd = (int)inplane_ring_n_dof(n_elements, n_fields, 1);
    int ny0 = nr + free_spin;
    int ny = (int)inplane_terms_ny(n_elements, n_fields, free_spin, n_basis);
    size_t dofs = (size_t)nd * nd, coords = (size_t)ny * ny;
    double *mass = work, *stiffness = mass + dofs, *damping = stiffness + dofs,
           *hysteretic = damping + dofs, *ring_work = hysteretic + dofs;
    /* the rigid patterns on the DOFs: x, z (with the rim's own 1) and the turn's (nr of it) */
    double* px = ring_work + inplane_ring_work_doubles(n_elements, n_fields);
    double *pz = px + nd, *p = pz + nd, *col = p + nd, *u = col + nd;
    Projection g;
    g.nd = nd;
    g.nr = nr;
    g.ny0 = ny0;
    g.ny = ny;
    g.free_spin = free_spin;
    g.p = p;
    g.col = col;
    g.bext = NULL;
    g.y = g.t = NULL;
    double dtheta = 2.0 * 3.14159265358979323846 / n_elements;
    for (int i = 0; i < nr; ++i) {
        int tangential = (i / n_elements) % 2;
        double th = (i % n_elements) * dtheta;
        px[i] = tangential ? -cos(th) : -sin(th);
        pz[i] = tangential ? sin(th) : -cos(th);
        p[i] = tangential ? data->R : 0.0;
    }
    px[nr] = 1.0, px[nr + 1] = 0.0, px[nr + 2] = 0.0;
    pz[nr] = 0.0, pz[nr + 1] = 1.0, pz[nr + 2] = 0.0;
    if (basis != NULL) {
        double* bext = u + 2 * (size_t)nd;
        memset(bext, 0, (size_t)ny0 * ny * sizeof *bext);
        for (int i = 0; i < nr; ++i)
            memcpy(bext + (size_t)i * ny, basis + (size_t)i * n_basis,
                   (size_t)n_basis * sizeof *bext);
        if (free_spin)
            bext[(size_t)nr * ny + n_basis] = 1.0;
        g.bext = bext;
        g.y = bext + (size_t)ny0 * ny;
        g.t = g.y + (size_t)ny0 * ny0;
    }

    /* to_abs = to_abs0 blockdiag(B, 1): the basis's rows, the turn's pattern in psi's column */
    memset(out->to_abs, 0, (size_t)nd * ny * sizeof *out->to_abs);
    for (int i = 0; i < nr; ++i) {
        double* row = out->to_abs + (size_t)i * ny;
        if (basis != NULL)
            memcpy(row, basis + (size_t)i * n_basis, (size_t)n_basis * sizeof *row);
        else
            row[i] = 1.0;
        if (free_spin)
            row[ny - 1] = p[i];
    }
    if (free_spin)
        out->to_abs[(size_t)(nr + 2) * ny + ny - 1] = 1.0;

    /* spin 0: the mass, the hysteretic loss, and the spin polynomials' values at 0. The ring's
     * builds cannot refuse: its data, mesh and fields were checked above, its spins are
     * finite and its memory is given */
    inplane_ring_build(data, n_elements, n_fields, 0.0, 1, 0, mass, stiffness, damping,
                       hysteretic, ring_work, NULL, 0);
    project(&g, mass, out->m);
    project(&g, hysteretic, out->kh);
    project(&g, stiffness, out->k0);
    project(&g, damping, out->c0);
    size_t last = (size_t)(nd - 3) * nd, rows = 3 * (size_t)nd;
    memcpy(out->rim_k0, stiffness + last, rows * sizeof *out->rim_k0);
    memcpy(out->rim_c0, damping + last, rows * sizeof *out->rim_c0);
    memcpy(out->rim_kh, hysteretic + last, rows * sizeof *out->rim_kh);
    memcpy(out->rim_m, mass + last, rows * sizeof *out->rim_m);
    /* the wheel's own inertia is the host's, not the tire's */
    out->rim_m[nd - 3] -= data->wheel_mass_kg;
    out->rim_m[nd + nd - 2] -= data->wheel_mass_kg;
    out->rim_m[2 * (size_t)nd + nd - 1] -= data->wheel_inertia_kg_m2;
    for (int r = 0; r < 3; ++r) {
        const double* row = out->rim_m + (size_t)r * nd;
        double sx = 0.0, sz = 0.0;
        for (int k = 0; k < nd; ++k) {
            sx += row[k] * px[k];
            sz += row[k] * pz[k];
        }
        out->rim_m_translation[2 * r] = sx;
        out->rim_m_translation[2 * r + 1] = sz;
    }
    /* the rim's inertia: to_abs^T (M P) */
    for (int i = 0; i < nd; ++i) {
        const double* row = mass + (size_t)i * nd;
        double sx = 0.0, sz = 0.0;
        for (int k = 0; k < nd; ++k) {
            sx += row[k] * px[k];
            sz += row[k] * pz[k];
        }
        u[2 * (size_t)i] = sx;
        u[2 * (size_t)i + 1] = sz;
    }
    memset(out->rim_inertia, 0, 2 * (size_t)ny * sizeof *out->rim_inertia);
    for (int k = 0; k < nd; ++k) {
        const double* row = out->to_abs + (size_t)k * ny;
        for (int j = 0; j < ny; ++j) {
            out->rim_inertia[2 * (size_t)j] += row[j] * u[2 * (size_t)k];
            out->rim_inertia[2 * (size_t)j + 1] += row[j] * u[2 * (size_t)k + 1];
        }
    }

    /* spins 1 and 2 rad/s: their values, into the terms they become */
    inplane_ring_build(data, n_elements, n_fields, 1.0, 1, 0, mass, stiffness, damping, NULL,
                       ring_work, NULL, 0);
    project(&g, stiffness, out->k1);
    project(&g, damping, out->c1);
    memcpy(out->rim_k1, stiffness + last, rows * sizeof *out->rim_k1);
    for (size_t i = 0; i < coords; ++i)
        out->c1[i] -= out->c0[i];
    for (size_t i = 0; i < rows; ++i)
        out->rim_c1[i] = damping[last + i] - out->rim_c0[i];
    inplane_ring_build(data, n_elements, n_fields, 2.0, 1, 0, mass, stiffness, damping, NULL,
                       ring_work, NULL, 0);
    project(&g, stiffness, out->k2);
    memcpy(out->rim_k2, stiffness + last, rows * sizeof *out->rim_k2);
    quadratic(out->k0, out->k1, out->k2, coords);
    quadratic(out->rim_k0, out->rim_k1, out->rim_k2, rows);
    return INPLANE_TERMS_OK;
}
