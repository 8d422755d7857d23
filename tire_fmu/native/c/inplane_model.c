/* inplane_model.c: the reduced in-plane step's set-up in one call (inplane_model.h).
 *
 * Only the bricks' own calls, in CAssembled's order (tests/test_inplane_c_assembly.py): this
 * file adds the arrays between them (the basis transposed and psi appended, the static data's
 * slices, the rim's Fz row at rest) and owns the memory. The bricks check their own input; a
 * refusal is passed up with the brick's name, and everything taken so far is returned. */
#include "inplane_model.h"

#include <string.h>

#include "inplane_ritz.h"
#include "inplane_static.h"
#include "numerics.h"

#define PI 3.14159265358979323846
#define WHY_LOCAL 1024

/* An allocation that records the first failure (then takes nothing more), so that one check
 * after a group of them will do. */
static void* take(const Memory* mem, size_t count, size_t size, int* failed)
{
    void* p;
    if (*failed)
        return NULL;
    p = mem_alloc(mem, count, size);
    if (p == NULL)
        *failed = 1;
    return p;
}

static double* doubles(const Memory* mem, size_t count, int* failed)
{
    return (double*)take(mem, count, sizeof(double), failed);
}

static void take_points(const Memory* mem, int n_points, int n_coords, InPlanePoints* pts,
                        int* failed)
{
    size_t jac = (size_t)n_points * (size_t)n_coords, p = (size_t)n_points;
    memset(pts, 0, sizeof *pts);
    pts->n_points = n_points;
    pts->jn = doubles(mem, jac, failed);
    pts->jx = doubles(mem, jac, failed);
    pts->jnw = doubles(mem, jac, failed);
    pts->jxw = doubles(mem, jac, failed);
    pts->jl = doubles(mem, jac, failed);
    pts->kn = doubles(mem, p, failed);
    pts->cn = doubles(mem, p, failed);
    pts->kx = doubles(mem, p, failed);
    pts->cx = doubles(mem, p, failed);
    pts->pen0 = doubles(mem, p, failed);
    pts->sec = doubles(mem, p, failed);
    pts->s0 = doubles(mem, p, failed);
}

static void free_points(const Memory* mem, InPlanePoints* pts)
{
    double* all[12];
    int k;
    all[0] = pts->jn; all[1] = pts->jx; all[2] = pts->jnw; all[3] = pts->jxw; all[4] = pts->jl;
    all[5] = pts->kn; all[6] = pts->cn; all[7] = pts->kx; all[8] = pts->cx; all[9] = pts->pen0;
    all[10] = pts->sec; all[11] = pts->s0;
    for (k = 0; k < 12; k++)
        mem_free(mem, all[k]);
    memset(pts, 0, sizeof *pts);
}

/* The terms' arrays, in inplane_terms.h's order, and their sizes. */
#define N_TERMS 17
static double** terms_field(InPlaneTermsOutput* t, int k)
{
    double** all[N_TERMS];
    all[0] = &t->m; all[1] = &t->c0; all[2] = &t->c1; all[3] = &t->k0; all[4] = &t->k1;
    all[5] = &t->k2; all[6] = &t->kh; all[7] = &t->to_abs; all[8] = &t->rim_inertia;
    all[9] = &t->rim_k0; all[10] = &t->rim_k1; all[11] = &t->rim_k2; all[12] = &t->rim_kh;
    all[13] = &t->rim_c0; all[14] = &t->rim_c1; all[15] = &t->rim_m;
    all[16] = &t->rim_m_translation;
    return all[k];
}

static size_t terms_size(int k, size_t ny, size_t nd)
{
    if (k < 7) return ny * ny;
    if (k == 7) return nd * ny;
    if (k == 8) return ny * 2;
    if (k < 16) return 3 * nd;
    return 6;
}

/* The build's arrays: the ring's (ny x ny: 0..6; ny x np: 7, 8; np x np: 9, 10; np x ny:
 * 11, 12; np x np: 13..16), the tread's (np x ny: 17, 18; np x np: 19..21; np x 4: 22), a
 * driven wheel's column (ny: 23). */
#define N_BUILD 24
static double** build_field(InPlaneBuildOutput* b, int k)
{
    double** all[N_BUILD];
    all[0] = &b->c; all[1] = &b->k; all[2] = &b->c1; all[3] = &b->k1s; all[4] = &b->k2;
    all[5] = &b->kh; all[6] = &b->a0_inv; all[7] = &b->yn; all[8] = &b->yx; all[9] = &b->wnn;
    all[10] = &b->wnx; all[11] = &b->kg_a; all[12] = &b->kg_b; all[13] = &b->kgn_a;
    all[14] = &b->kgn_b; all[15] = &b->kgx_a; all[16] = &b->kgx_b; all[17] = &b->gain;
    all[18] = &b->kg; all[19] = &b->kgn; all[20] = &b->kgx; all[21] = &b->carry;
    all[22] = &b->carry_weights; all[23] = &b->a0_psi;
    return all[k];
}

static size_t build_size(int k, size_t ny, size_t np)
{
    if (k < 7) return ny * ny;
    if (k < 9) return ny * np;
    if (k < 11) return np * np;
    if (k < 13) return np * ny;
    if (k < 17) return np * np;
    if (k < 19) return np * ny;
    if (k < 22) return np * np;
    if (k < 23) return np * 4;
    return ny;
}

void inplane_model_free(InPlaneModel* model)
{
    const Memory* mem;
    int k;
    if (model == NULL)
        return;
    mem = model->mem != NULL ? model->mem : mem_default();
    mem_free(mem, model->zone_nodes);
    mem_free(mem, model->basis);
    for (k = 0; k < N_TERMS; k++)
        mem_free(mem, *terms_field(&model->terms, k));
    mem_free(mem, model->static_y);
    mem_free(mem, model->rim_fz_row);
    free_points(mem, &model->points);
    mem_free(mem, model->point_theta);
    for (k = 0; k < N_BUILD; k++)
        mem_free(mem, *build_field(&model->build, k));
    mem_free(mem, model->build.carry_base);
    memset(model, 0, sizeof *model);
}

/* The brick's refusal, named, into why. */
static int pass_up(char* why, size_t size, int status, const char* brick, int brick_status,
                   const char* text)
{
    return say_why(why, size, status, "%s refused (status %d): %s", brick, brick_status, text);
}

/* What the build needs only while it runs (returned by assemble on every path). */
typedef struct {
    double *ring_m, *ring_k, *ring_c, *ring_work, *ritz_work, *basis_t, *basis_ring;
    double *terms_work, *k_rest, *jn_rest, *static_work, *build_work;
    int *active, *static_iwork, *build_iwork;
    InPlanePoints rest;
    Zone zone;
    int zone_built;
} Scratch;

static void free_scratch(const Memory* mem, Scratch* s)
{
    double* all[12];
    int k;
    all[0] = s->ring_m; all[1] = s->ring_k; all[2] = s->ring_c; all[3] = s->ring_work;
    all[4] = s->ritz_work; all[5] = s->basis_t; all[6] = s->basis_ring; all[7] = s->terms_work;
    all[8] = s->k_rest; all[9] = s->jn_rest; all[10] = s->static_work; all[11] = s->build_work;
    for (k = 0; k < 12; k++)
        mem_free(mem, all[k]);
    mem_free(mem, s->active);
    mem_free(mem, s->static_iwork);
    mem_free(mem, s->build_iwork);
    free_points(mem, &s->rest);
    if (s->zone_built)
        zone_free(&s->zone, mem);
    memset(s, 0, sizeof *s);
}

static int no_memory(char* why, size_t size, const char* what)
{
    return say_why(why, size, INPLANE_MODEL_NO_MEMORY, "out of memory for %s", what);
}

static int assemble(const InPlaneModelInput* in, InPlaneModel* out, Scratch* s, char* why,
                    size_t size)
{
    const Memory* mem = out->mem;
    const InPlaneRingData* t = &in->tire;
    char text[WHY_LOCAL];
    int N = in->n_elements, nf = in->n_fields, free_spin = in->wheel_free, failed = 0;
    int status, n_dof, rows, r, ny, P, Z, carry, per_node, j, k, i, count = 0;
    double* dummy;
    size_t nd3;
    InPlanePointsInput pin;
    InPlaneStaticData st;

    text[0] = '\0';
    status = inplane_ring_check(t, N, nf, 0.0, text, sizeof text);
    if (status != INPLANE_RING_OK)
        return pass_up(why, size, INPLANE_MODEL_RING, "inplane_ring_check", status, text);
    if (free_spin != 0 && free_spin != 1)
        return say_why(why, size, INPLANE_MODEL_TERMS,
                       "wheel_free = %d: must be 0 (held) or 1 (free)", free_spin);
    if (in->driven != 0 && !(in->driven == 1 && free_spin == 1))
        return say_why(why, size, INPLANE_MODEL_TERMS,
                       "driven = %d: must be 0, or 1 with wheel_free = 1 (a driven wheel's "
                       "turn is a coordinate, as a free one's)", in->driven);
    n_dof = nf * N;
    rows = n_dof + free_spin;

    /* the zone's points and nodes (the points' own check first: its sentences) */
    dummy = doubles(mem, (size_t)rows, &failed);
    if (failed)
        return no_memory(why, size, "the points' check");
    memset(&pin, 0, sizeof pin);
    pin.n_elements = N;
    pin.n_fields = nf;
    pin.wheel_free = free_spin;
    pin.n_coords = 1;
    pin.basis = dummy;
    pin.radius_m = t->R;
    pin.k_cw = in->k_cw;
    pin.beta = t->beta;
    pin.k_tx = t->k_tx;
    pin.zone_length_m = in->zone_length_m;
    pin.point_spacing_m = in->point_spacing_m;
    pin.deflection_m = 0.0;
    pin.speed_m_s = 0.0;
    pin.spin_rad_s = 0.0;
    status = inplane_points_count(&pin, &P, text, sizeof text);
    mem_free(mem, dummy);
    if (status != INPLANE_POINTS_OK)
        return pass_up(why, size, INPLANE_MODEL_POINTS, "inplane_points_count", status, text);
    /* the carrying half and points per node as inplane_points.c's check finds them */
    carry = zone_half_count(t->R, N, in->zone_length_m);
    per_node = points_per_node(t->R * (2.0 * PI / N), in->point_spacing_m);
    if (zone_build(&s->zone, mem, N, t->R, in->k_cw, t->beta, carry, per_node) != 0)
        return no_memory(why, size, "the contact zone");
    s->zone_built = 1;
    if (s->zone.n_points != P)
        return say_why(why, size, INPLANE_MODEL_POINTS,
                       "the zone has %d points, the points' brick counts %d",
                       s->zone.n_points, P);
    Z = s->zone.n_zone;
    out->zone_nodes = (int*)take(mem, (size_t)Z, sizeof(int), &failed);
    out->point_theta = doubles(mem, (size_t)P, &failed);
    if (failed)
        return no_memory(why, size, "the zone's nodes");
    for (j = 0; j < Z; j++)
        out->zone_nodes[j] = ((j - s->zone.half) % N + N) % N;
    memcpy(out->point_theta, s->zone.point_theta, (size_t)P * sizeof(double));
    out->n_zone = Z;
    out->np = P;

    /* the held ring at rest, and its Ritz basis on the zone's nodes */
    s->ring_m = doubles(mem, (size_t)n_dof * (size_t)n_dof, &failed);
    s->ring_k = doubles(mem, (size_t)n_dof * (size_t)n_dof, &failed);
    s->ring_c = doubles(mem, (size_t)n_dof * (size_t)n_dof, &failed);
    s->ring_work = doubles(mem, inplane_ring_work_doubles(N, nf), &failed);
    s->ritz_work = doubles(mem, inplane_ritz_work_doubles(N, nf, Z), &failed);
    s->basis_t = doubles(mem, (size_t)n_dof * (size_t)n_dof, &failed);
    if (failed)
        return no_memory(why, size, "the ring at rest and its basis");
    status = inplane_ring_build(t, N, nf, 0.0, 0, 0, s->ring_m, s->ring_k, s->ring_c, NULL,
                                s->ring_work, text, sizeof text);
    if (status != INPLANE_RING_OK)
        return pass_up(why, size, INPLANE_MODEL_RING, "inplane_ring_build", status, text);
    status = inplane_ritz_build(s->ring_m, s->ring_k, N, nf, out->zone_nodes, Z, in->f_max_hz,
                                n_dof, s->basis_t, &count, s->ritz_work, text, sizeof text);
    if (status != INPLANE_RITZ_OK)
        return pass_up(why, size, INPLANE_MODEL_RITZ, "inplane_ritz_build", status, text);
    r = count;
    ny = r + free_spin;
    s->basis_ring = doubles(mem, (size_t)n_dof * (size_t)r, &failed);
    out->basis = doubles(mem, (size_t)rows * (size_t)ny, &failed);
    if (failed)
        return no_memory(why, size, "the basis");
    for (i = 0; i < n_dof; i++)
        for (k = 0; k < r; k++) {
            double b = s->basis_t[(size_t)k * (size_t)n_dof + (size_t)i];
            s->basis_ring[(size_t)i * (size_t)r + (size_t)k] = b;
            out->basis[(size_t)i * (size_t)ny + (size_t)k] = b;
        }
    if (free_spin) { /* psi is its own coordinate, the last */
        for (k = 0; k < r; k++)
            out->basis[(size_t)n_dof * (size_t)ny + (size_t)k] = 0.0;
        for (i = 0; i < rows; i++)
            out->basis[(size_t)i * (size_t)ny + (size_t)r] = i == n_dof ? 1.0 : 0.0;
    }
    out->n_elements = N;
    out->n_fields = nf;
    out->wheel_free = free_spin;
    out->n_dof = n_dof;
    out->n_basis = r;
    out->ny = ny;

    /* the spin's terms, mass and rim rows on the coordinates */
    if ((int)inplane_terms_ny(N, nf, free_spin, r) != ny)
        return say_why(why, size, INPLANE_MODEL_TERMS,
                       "n_basis = %d: the terms' coordinates are not %d", r, ny);
    nd3 = inplane_ring_n_dof(N, nf, 1);
    for (k = 0; k < N_TERMS; k++)
        *terms_field(&out->terms, k) = doubles(mem, terms_size(k, (size_t)ny, nd3), &failed);
    s->terms_work = doubles(mem, inplane_terms_work_doubles(N, nf, free_spin, r), &failed);
    if (failed)
        return no_memory(why, size, "the spin's terms");
    status = inplane_terms_build(t, N, nf, free_spin, s->basis_ring, r, &out->terms,
                                 s->terms_work, text, sizeof text);
    if (status != INPLANE_TERMS_OK)
        return pass_up(why, size, INPLANE_MODEL_TERMS, "inplane_terms_build", status, text);

    /* the points at rest (deflection 0), and the deflection for the load on them */
    take_points(mem, P, ny, &s->rest, &failed);
    if (failed)
        return no_memory(why, size, "the points at rest");
    pin.n_coords = ny;
    pin.basis = out->basis;
    status = inplane_points_build(&pin, &s->rest, mem, text, sizeof text);
    if (status != INPLANE_POINTS_OK)
        return pass_up(why, size, INPLANE_MODEL_POINTS, "inplane_points_build", status, text);
    s->k_rest = doubles(mem, (size_t)r * (size_t)r, &failed);
    s->jn_rest = doubles(mem, (size_t)P * (size_t)r, &failed);
    out->rim_fz_row = doubles(mem, (size_t)r, &failed);
    out->static_y = doubles(mem, (size_t)r, &failed);
    s->active = (int*)take(mem, (size_t)P, sizeof(int), &failed);
    s->static_work = doubles(mem, inplane_static_work_doubles(r, P), &failed);
    s->static_iwork = (int*)take(mem, inplane_static_work_ints(r, P), sizeof(int), &failed);
    if (failed)
        return no_memory(why, size, "the static footprint");
    /* K and the rim's Fz row at the spin the step is built at (k0 + W k1 + W^2 k2 + s kh, s
     * the loss's share there; at rest k0), on the ring's coordinates only (a free wheel's turn
     * is still): the footprint found on them carries the load rolling steadily at the speed
     * (core/inplane_contact.py's deflection_carrying on the simulator at its speed) */
    {   /* (a spin that is no number is refused by the points' build below, in its words) */
        double w = isfinite(in->spin_rad_s) ? in->spin_rad_s : 0.0;
        double sh = t->loss_factor != 0.0 ? inplane_hysteresis_share(w, t->R) : 0.0;
        for (i = 0; i < r; i++)
            for (k = 0; k < r; k++) {
                size_t at = (size_t)i * (size_t)ny + (size_t)k;
                double v = out->terms.k0[at] + w * out->terms.k1[at] + w * w * out->terms.k2[at];
                if (sh != 0.0) v += sh * out->terms.kh[at];
                s->k_rest[(size_t)i * (size_t)r + (size_t)k] = v;
            }
    }
    for (i = 0; i < P; i++)
        for (k = 0; k < r; k++)
            s->jn_rest[(size_t)i * (size_t)r + (size_t)k] =
                s->rest.jn[(size_t)i * (size_t)ny + (size_t)k];
    {   /* the rim's Fz row at the spin, as rim_force takes it: each power of the spin on the
         * coordinates, then combined */
        double w = isfinite(in->spin_rad_s) ? in->spin_rad_s : 0.0;
        double sh = t->loss_factor != 0.0 ? inplane_hysteresis_share(w, t->R) : 0.0;
        for (k = 0; k < r; k++) {
            double g[4] = {0.0, 0.0, 0.0, 0.0};
            size_t a;
            for (a = 0; a < nd3; a++) {
                double e = out->terms.to_abs[a * (size_t)ny + (size_t)k];
                g[0] += out->terms.rim_k0[nd3 + a] * e;
                g[1] += out->terms.rim_k1[nd3 + a] * e;
                g[2] += out->terms.rim_k2[nd3 + a] * e;
                g[3] += out->terms.rim_kh[nd3 + a] * e;
            }
            out->rim_fz_row[k] = g[0] + g[1] * w + g[2] * (w * w) + g[3] * sh;
        }
    }
    memset(&st, 0, sizeof st);
    st.n_coords = r;
    st.n_points = P;
    st.stiffness = s->k_rest;
    st.jn = s->jn_rest;
    st.kn = s->rest.kn;
    st.sec = s->rest.sec;
    st.rim_fz_row = out->rim_fz_row;
    st.radius_m = t->R;
    st.max_passes = INPLANE_MODEL_MAX_SET_PASSES;
    status = inplane_deflection_for_load(&st, in->load_n, &out->deflection_m,
                                         &out->secant_iterations, out->static_y, s->active,
                                         s->static_work, s->static_iwork, text, sizeof text);
    if (status != INPLANE_STATIC_OK)
        return pass_up(why, size, INPLANE_MODEL_STATIC, "inplane_deflection_for_load", status,
                       text);

    /* the points at the deflection, speed and spin */
    take_points(mem, P, ny, &out->points, &failed);
    if (failed)
        return no_memory(why, size, "the points");
    pin.deflection_m = out->deflection_m;
    pin.speed_m_s = in->speed_m_s;
    pin.spin_rad_s = in->spin_rad_s;
    status = inplane_points_build(&pin, &out->points, mem, text, sizeof text);
    if (status != INPLANE_POINTS_OK)
        return pass_up(why, size, INPLANE_MODEL_POINTS, "inplane_points_build", status, text);

    /* the step's matrices at the spin, the ring's and the tread's */
    for (k = 0; k < N_BUILD; k++)
        *build_field(&out->build, k) = doubles(mem, build_size(k, (size_t)ny, (size_t)P),
                                               &failed);
    out->build.carry_base = (int*)take(mem, (size_t)P, sizeof(int), &failed);
    s->build_work = doubles(mem, inplane_build_work_doubles(ny, P), &failed);
    s->build_iwork = (int*)take(mem, inplane_build_work_ints(ny), sizeof(int), &failed);
    if (failed)
        return no_memory(why, size, "the step's matrices");
    out->build_in.ny = ny;
    out->build_in.np = P;
    out->build_in.hysteretic = t->loss_factor != 0.0;
    out->build_in.h = in->step_s;
    out->build_in.radius_m = t->R;
    out->build_in.m = out->terms.m;
    out->build_in.c0 = out->terms.c0;
    out->build_in.c1 = out->terms.c1;
    out->build_in.k0 = out->terms.k0;
    out->build_in.k1 = out->terms.k1;
    out->build_in.k2 = out->terms.k2;
    out->build_in.kh = out->terms.kh;
    out->build_in.jn = out->points.jn;
    out->build_in.jnw = out->points.jnw;
    out->build_in.jxw = out->points.jxw;
    out->build_in.jl = out->points.jl;
    out->build_in.kx = out->points.kx;
    out->build_in.cx = out->points.cx;
    out->build_in.point_theta = out->point_theta;
    out->build_in.driven = in->driven;
    status = inplane_build(&out->build_in, in->spin_rad_s, &out->build, s->build_work,
                           s->build_iwork, text, sizeof text);
    if (status != INPLANE_BUILD_OK)
        return pass_up(why, size, INPLANE_MODEL_BUILD, "inplane_build", status, text);
    return INPLANE_MODEL_OK;
}

int inplane_model_build(const InPlaneModelInput* in, InPlaneModel* out, const Memory* mem,
                        char* why, size_t size)
{
    Scratch scratch;
    int status;
    if (out == NULL)
        return say_why(why, size, INPLANE_MODEL_NULL, "out is missing (NULL)");
    memset(out, 0, sizeof *out);
    if (in == NULL)
        return say_why(why, size, INPLANE_MODEL_NULL, "in is missing (NULL)");
    out->mem = mem != NULL ? mem : mem_default();
    memset(&scratch, 0, sizeof scratch);
    status = assemble(in, out, &scratch, why, size);
    free_scratch(out->mem, &scratch);
    if (status != INPLANE_MODEL_OK)
        inplane_model_free(out);
    return status;
}
