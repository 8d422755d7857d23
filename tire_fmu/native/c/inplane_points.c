/* inplane_points.c: the in-plane simulator's point Jacobians and point data (see
 * inplane_points.h).
 *
 * Each unreduced row is sparse (a point reads 4 zone nodes, 1 for one point per node; L's
 * central difference spreads that to the nodes' neighbours), so a row of J basis is a sum
 * of a few dozen of the basis's rows: J is never formed at the DOFs' size, and the identity
 * basis (every DOF) costs the same per row as a reduced one. */
#include "inplane_points.h"

#include <math.h>
#include <string.h>

#include "numerics.h"
#include "spec.h"
#include "tire.h"

#define PI 3.14159265358979323846
#define MOST_ELEMENTS 100000
#define MOST_COORDS 1000000

static int is_finite(double x) { return x - x == 0.0; }

/* the zone's carrying half count and points per node for a checked input */
static int check(const InPlanePointsInput* in, int* carry_out, int* per_node_out, char* why,
                 size_t why_size)
{
    double R, limit, dtheta, node_arc, points;
    int carry, m, rows;
    size_t k, count;
    if (in == NULL)
        return say_why(why, why_size, INPLANE_POINTS_NULL, "the input is missing (NULL)");
    if (in->n_elements < 4 || in->n_elements > MOST_ELEMENTS)
        return say_why(why, why_size, INPLANE_POINTS_BAD_SIZE,
                       "n_elements = %d: must be in [4, %d]", in->n_elements, MOST_ELEMENTS);
    if (in->n_fields < 2 || in->n_fields > 4)
        return say_why(why, why_size, INPLANE_POINTS_BAD_SIZE,
                       "n_fields = %d: must be in [2, 4] (w and v, then the sidewall's)",
                       in->n_fields);
    if (in->wheel_free != 0 && in->wheel_free != 1)
        return say_why(why, why_size, INPLANE_POINTS_BAD_SIZE,
                       "wheel_free = %d: must be 0 (held) or 1 (free)", in->wheel_free);
    if (in->n_coords < 1 || in->n_coords > MOST_COORDS)
        return say_why(why, why_size, INPLANE_POINTS_BAD_SIZE,
                       "n_coords = %d: must be in [1, %d]", in->n_coords, MOST_COORDS);
    if (in->basis == NULL)
        return say_why(why, why_size, INPLANE_POINTS_NULL, "basis is missing (NULL)");
    R = in->radius_m;
    if (!(is_finite(R) && R > 0.0))
        return say_why(why, why_size, INPLANE_POINTS_BAD_DATA,
                       "radius_m = %g m: must be finite and > 0 m", R);
    if (!(is_finite(in->k_cw) && in->k_cw >= 0.0))
        return say_why(why, why_size, INPLANE_POINTS_BAD_DATA,
                       "k_cw = %g N/m^2: must be finite and >= 0 N/m^2", in->k_cw);
    if (!(is_finite(in->beta) && in->beta >= 0.0))
        return say_why(why, why_size, INPLANE_POINTS_BAD_DATA,
                       "beta = %g s: must be finite and >= 0 s", in->beta);
    if (!(is_finite(in->k_tx) && in->k_tx >= 0.0))
        return say_why(why, why_size, INPLANE_POINTS_BAD_DATA,
                       "k_tx = %g N/m^2: must be finite and >= 0 N/m^2", in->k_tx);
    limit = 2.0 * R * tan(SPEC_MAX_ZONE_HALF_ANGLE);
    if (!(is_finite(in->zone_length_m) && in->zone_length_m > 0.0 && in->zone_length_m <= limit))
        return say_why(why, why_size, INPLANE_POINTS_BAD_DATA,
                       "zone_length_m = %g m: must be in (0, %.4g] m (at most 60 degrees of the "
                       "ring either side of the contact centre)", in->zone_length_m, limit);
    if (!(is_finite(in->point_spacing_m) && in->point_spacing_m >= SPEC_MIN_POINT_SPACING_M &&
          in->point_spacing_m <= SPEC_MAX_POINT_SPACING_M))
        return say_why(why, why_size, INPLANE_POINTS_BAD_DATA,
                       "point_spacing_m = %g m: must be in [%g, %g] m", in->point_spacing_m,
                       SPEC_MIN_POINT_SPACING_M, SPEC_MAX_POINT_SPACING_M);
    if (!(is_finite(in->deflection_m) && in->deflection_m >= 0.0 && in->deflection_m < R))
        return say_why(why, why_size, INPLANE_POINTS_BAD_DATA,
                       "deflection_m = %g m: must be in [0, %g) m (below the radius)",
                       in->deflection_m, R);
    if (!is_finite(in->speed_m_s))
        return say_why(why, why_size, INPLANE_POINTS_BAD_DATA,
                       "speed_m_s = %g m/s: must be finite", in->speed_m_s);
    if (!is_finite(in->spin_rad_s))
        return say_why(why, why_size, INPLANE_POINTS_BAD_DATA,
                       "spin_rad_s = %g rad/s: must be finite", in->spin_rad_s);
    rows = in->n_fields * in->n_elements + in->wheel_free;
    count = (size_t)rows * (size_t)in->n_coords;
    for (k = 0; k < count; k++)
        if (!is_finite(in->basis[k]))
            return say_why(why, why_size, INPLANE_POINTS_BAD_DATA,
                           "basis[%d, %d] = %g: must be finite", (int)(k / in->n_coords),
                           (int)(k % in->n_coords), in->basis[k]);
    dtheta = 2.0 * PI / in->n_elements;
    carry = zone_half_count(R, in->n_elements, in->zone_length_m);
    if (carry < 1)
        return say_why(why, why_size, INPLANE_POINTS_BAD_DATA,
                       "zone_length_m = %g m: must be at least %.4g m (one node either side), "
                       "or refine the mesh of %d elements", in->zone_length_m,
                       2.0 * R * tan(dtheta), in->n_elements);
    node_arc = R * dtheta;
    m = points_per_node(node_arc, in->point_spacing_m);
    points = (2.0 * carry + 1.0) * m;
    if (points > SPEC_MAX_CONTACT_POINTS)
        return say_why(why, why_size, INPLANE_POINTS_BAD_SIZE,
                       "point_spacing_m = %g m: %d points on each of %d carrying nodes make %.0f "
                       "contact points, more than the %d allowed", in->point_spacing_m, m,
                       2 * carry + 1, points, SPEC_MAX_CONTACT_POINTS);
    *carry_out = carry;
    *per_node_out = m;
    return INPLANE_POINTS_OK;
}

int inplane_points_count(const InPlanePointsInput* in, int* n_points, char* why,
                         size_t why_size)
{
    int carry = 0, m = 0, status;
    if (n_points == NULL)
        return say_why(why, why_size, INPLANE_POINTS_NULL, "n_points is missing (NULL)");
    status = check(in, &carry, &m, why, why_size);
    if (status != INPLANE_POINTS_OK)
        return status;
    *n_points = (2 * carry + 1) * m;
    return INPLANE_POINTS_OK;
}

/* row += a basis[k] */
static void add_row(double* row, double a, const double* basis, int k, int r)
{
    const double* b = basis + (size_t)k * (size_t)r;
    int c;
    for (c = 0; c < r; c++)
        row[c] += a * b[c];
}

int inplane_points_build(const InPlanePointsInput* in, const InPlanePoints* out,
                         const Memory* mem, char* why, size_t why_size)
{
    Zone zone;
    int carry = 0, m = 0, status, N, P, S, r, p, s, psi;
    double R, dtheta, half_d, kappa1, arc, kx;
    if (out == NULL)
        return say_why(why, why_size, INPLANE_POINTS_NULL, "the outputs are missing (NULL)");
    status = check(in, &carry, &m, why, why_size);
    if (status != INPLANE_POINTS_OK)
        return status;
    P = (2 * carry + 1) * m;
    if (out->n_points != P)
        return say_why(why, why_size, INPLANE_POINTS_BAD_SIZE,
                       "n_points = %d: must be %d, the points this zone and spacing make",
                       out->n_points, P);
    if (!out->jn || !out->jx || !out->jnw || !out->jxw || !out->jl || !out->kn || !out->cn ||
        !out->kx || !out->cx || !out->pen0 || !out->sec || !out->s0)
        return say_why(why, why_size, INPLANE_POINTS_NULL, "an output array is missing (NULL)");
    N = in->n_elements;
    R = in->radius_m;
    if (mem == NULL)
        mem = mem_default();
    if (zone_build(&zone, mem, N, R, in->k_cw, in->beta, carry, m) != 0)
        return say_why(why, why_size, INPLANE_POINTS_NO_MEMORY,
                       "out of memory for a zone of %d points", P);
    S = zone.n_support;
    r = in->n_coords;
    psi = in->n_fields * N; /* the turn's row, when free */
    dtheta = 2.0 * PI / N;
    half_d = 0.5 / dtheta;
    kappa1 = sin(dtheta) / dtheta;
    arc = R * dtheta / m;
    kx = in->k_tx * arc;
    for (p = 0; p < P; p++) {
        size_t at = (size_t)p * (size_t)r;
        double *jn = out->jn + at, *jx = out->jx + at, *jl = out->jl + at;
        double c = zone.ray_cos[p], sn = sin(zone.point_theta[p]);
        memset(jn, 0, (size_t)r * sizeof(double));
        memset(jx, 0, (size_t)r * sizeof(double));
        memset(jl, 0, (size_t)r * sizeof(double));
        for (s = 0; s < S; s++) {
            int k = ((zone.support[p * S + s] - zone.half) % N + N) % N; /* the ring node */
            int next = (k + 1) % N, prev = (k + N - 1) % N;
            double w = zone.weight[p * S + s];
            double a = -sn * w, b = -c * w; /* jx on w and on v at node k */
            add_row(jn, w, in->basis, k, r);
            add_row(jx, a, in->basis, k, r);
            add_row(jx, b, in->basis, N + k, r);
            /* [a on w, b on v] L: D1's (i, i +- 1) entries +- 1/(2 dtheta) move each to the
             * neighbours; kappa1 J exchanges the pair */
            add_row(jl, a * half_d, in->basis, next, r);
            add_row(jl, -(a * half_d), in->basis, prev, r);
            add_row(jl, kappa1 * b, in->basis, k, r);
            add_row(jl, -(kappa1 * a), in->basis, N + k, r);
            add_row(jl, b * half_d, in->basis, N + next, r);
            add_row(jl, -(b * half_d), in->basis, N + prev, r);
        }
        memcpy(out->jnw + at, jn, (size_t)r * sizeof(double));
        memcpy(out->jxw + at, jx, (size_t)r * sizeof(double));
        if (in->wheel_free) /* the radial push has no moment about the axle; the fore-aft one
                               has: the turn moves the point's material by -R cos theta */
            add_row(out->jxw + at, -R * c, in->basis, psi, r);
        out->kn[p] = zone.stiffness;
        out->cn[p] = zone.damping;
        out->kx[p] = kx;
        out->cx[p] = in->beta * kx;
        out->pen0[p] = R - (R - in->deflection_m) / c;
        out->sec[p] = zone.sec[p];
        out->s0[p] = in->speed_m_s - in->spin_rad_s * R * c;
    }
    zone_free(&zone, mem);
    return INPLANE_POINTS_OK;
}
