/* contact.c: the contact zone, its contact points, the static footprint and the road windows
 * (core/contact.py; the definition of the points: cubic Lagrange interpolation of the zone
 * nodes, m points per carrying node).
 *
 * The static contact forces solve a linear complementarity problem whose solution is piecewise
 * linear in the rim deflection; the path is traced exactly by active-set continuation from
 * zero deflection, segment by segment, each ended by the next point to enter or to leave. The
 * points' compliance I G I^T is never formed: each segment is solved in the Z zone nodes
 * (Woodbury), so a path over hundreds of points costs O(Z^2) per segment. */
#include <string.h>

#include "spec.h"
#include "tire.h"

#define PI 3.14159265358979323846

int zone_half_count(double radius, int n_elements, double zone_length)
{
    double dtheta = 2.0 * PI / n_elements;
    double half_angle = fmin(atan(0.5 * zone_length / radius), SPEC_MAX_ZONE_HALF_ANGLE);
    double limit = half_angle * (1 + SPEC_ZONE_ANGLE_SLACK);
    int half = (int)floor(limit / dtheta);
    while (half > 0 && half * dtheta > limit) half--;
    while ((half + 1) * dtheta <= limit && 2 * (half + 1) <= n_elements) half++;
    return half;
}

int points_per_node(double node_arc, double spacing)
{
    double limit = spacing * (1 + SPEC_POINT_SPACING_SLACK), guess = ceil(node_arc / limit);
    int m;
    if (!(guess <= SPEC_MOST_POINTS_PER_NODE)) return SPEC_MOST_POINTS_PER_NODE + 1; /* too many */
    m = guess < 1.0 ? 1 : (int)guess;
    if (m % 2 == 0) m++;
    while (m > 1 && node_arc / (m - 2) <= limit) m -= 2;
    while (node_arc / m > limit) m += 2;
    return m;
}

/* floor(u / m) for m > 0 */
static int floor_div(int u, int m) { return u >= 0 ? u / m : -((-u + m - 1) / m); }

int zone_build(Zone* zone, const Memory* mem, int n_elements, double radius, double k_cw,
               double beta, int carry, int per_node)
{
    int half = per_node > 1 ? carry + 2 : carry, Z = 2 * half + 1, m = per_node;
    int S = per_node > 1 ? 4 : 1, P = (2 * carry + 1) * per_node, j, i, p, s;
    double dtheta = 2.0 * PI / n_elements;
    memset(zone, 0, sizeof *zone);
    zone->n_zone = Z;
    zone->half = half;
    zone->centre = half;
    zone->carry = carry;
    zone->per_node = m;
    zone->n_points = P;
    zone->n_support = S;
    zone->radius = radius;
    zone->dtheta = dtheta;
    zone->theta = (double*)mem_alloc(mem, (size_t)Z, sizeof(double));
    zone->cos = (double*)mem_alloc(mem, (size_t)Z, sizeof(double));
    zone->sin = (double*)mem_alloc(mem, (size_t)Z, sizeof(double));
    zone->support = (int*)mem_alloc(mem, (size_t)(P * S), sizeof(int));
    zone->weight = (double*)mem_alloc(mem, (size_t)(P * S), sizeof(double));
    zone->point_theta = (double*)mem_alloc(mem, (size_t)P, sizeof(double));
    zone->ray_cos = (double*)mem_alloc(mem, (size_t)P, sizeof(double));
    zone->sec = (double*)mem_alloc(mem, (size_t)P, sizeof(double));
    zone->load_cos = (double*)mem_alloc(mem, (size_t)P, sizeof(double));
    zone->load_sin = (double*)mem_alloc(mem, (size_t)P, sizeof(double));
    if (!zone->theta || !zone->cos || !zone->sin || !zone->support || !zone->weight ||
        !zone->point_theta || !zone->ray_cos || !zone->sec || !zone->load_cos ||
        !zone->load_sin) {
        zone_free(zone, mem);
        return -1;
    }
    for (j = 0; j < Z; j++) {
        zone->theta[j] = (j - half) * dtheta;
        zone->cos[j] = cos(zone->theta[j]);
        zone->sin[j] = sin(zone->theta[j]);
    }
    p = 0;
    for (j = -carry; j <= carry; j++) {
        for (i = 0; i < m; i++, p++) {
            int u = j * m + i - (m - 1) / 2;
            int* support = zone->support + p * S;
            double* w = zone->weight + p * S;
            double theta = u * dtheta / m, vertical = 0.0, fore_aft = 0.0;
            if (m == 1) {
                support[0] = j + half;
                w[0] = 1.0;
            } else {  /* cubic Lagrange on the nodes b - 1 .. b + 2, at b + t */
                int b = floor_div(u, m);
                double t = (double)(u - b * m) / m;
                for (s = 0; s < 4; s++) support[s] = b - 1 + s + half;
                w[0] = -t * (t - 1) * (t - 2) / 6;
                w[1] = (t + 1) * (t - 1) * (t - 2) / 2;
                w[2] = -(t + 1) * t * (t - 2) / 2;
                w[3] = (t + 1) * t * (t - 1) / 6;
            }
            for (s = 0; s < S; s++) {
                vertical += w[s] * zone->cos[support[s]];
                fore_aft += w[s] * zone->sin[support[s]];
            }
            zone->point_theta[p] = theta;
            zone->ray_cos[p] = cos(theta);
            zone->sec[p] = 1.0 / zone->ray_cos[p];
            zone->load_cos[p] = vertical;
            zone->load_sin[p] = fore_aft;
            if (u == 0) zone->centre_point = p;
        }
    }
    zone->stiffness = k_cw * (radius * dtheta) / m;
    zone->damping = beta * zone->stiffness;
    return 0;
}

void zone_free(Zone* zone, const Memory* mem)
{
    mem_free(mem, zone->theta);
    mem_free(mem, zone->cos);
    mem_free(mem, zone->sin);
    mem_free(mem, zone->support);
    mem_free(mem, zone->weight);
    mem_free(mem, zone->point_theta);
    mem_free(mem, zone->ray_cos);
    mem_free(mem, zone->sec);
    mem_free(mem, zone->load_cos);
    mem_free(mem, zone->load_sin);
    memset(zone, 0, sizeof *zone);
}

/* sum_s weight[p, s] y[support[p, s]]: the points' reading of node values */
static double at_point(const Zone* zone, int p, const double* y)
{
    int S = zone->n_support, s;
    double sum = 0.0;
    for (s = 0; s < S; s++) sum += zone->weight[p * S + s] * y[zone->support[p * S + s]];
    return sum;
}

/* -- the continuation path ------------------------------------------------------------------ */

static int path_grow(FootprintPath* path, const Memory* mem, int Z, int P)
{
    int capacity = path->capacity ? 2 * path->capacity : 16, i;
    double** arrays[5];
    size_t sizes[5];
    arrays[0] = &path->start;
    arrays[1] = &path->y0;
    arrays[2] = &path->y1;
    arrays[3] = &path->w0;
    arrays[4] = &path->w1;
    sizes[0] = sizes[3] = sizes[4] = 1;
    sizes[1] = sizes[2] = (size_t)Z;
    for (i = 0; i < 5; i++) {
        double* grown = (double*)mem_alloc(mem, (size_t)capacity * sizes[i], sizeof(double));
        if (grown == NULL) return -1;
        if (*arrays[i] != NULL) {
            memcpy(grown, *arrays[i], sizeof(double) * (size_t)path->count * sizes[i]);
            mem_free(mem, *arrays[i]);
        }
        *arrays[i] = grown;
    }
    {
        char* grown = (char*)mem_alloc(mem, (size_t)capacity * (size_t)P, 1);
        if (grown == NULL) return -1;
        if (path->active != NULL) {
            memcpy(grown, path->active, (size_t)path->count * (size_t)P);
            mem_free(mem, path->active);
        }
        path->active = grown;
    }
    path->capacity = capacity;
    return 0;
}

/* The node-space solve of a segment. xinv = (I + G M_A)^-1 for the active set `in`, kept by
 * rank-one (Sherman-Morrison) updates as points enter and leave, rebuilt from scratch every
 * so often; each solve is refined once against G and M_A themselves, so the updates' rounding
 * never reaches the forces. */
typedef struct {
    const Zone* zone;
    const double* g;  /* Z x Z */
    double* xinv;     /* Z x Z */
    double* x;        /* Z x Z: X itself, for a rebuild */
    double* work;     /* Z x Z + Z: the rebuild's scratch */
    int* pivot;       /* Z */
    char* in;         /* P: the set xinv is for */
    double *gw, *u, *v, *b, *gb, *rho, *my; /* Z each */
    int updates;      /* since the last rebuild */
} NodeSolve;

/* the points' radial gap constants: the penetration is r0 + r1 d - I y */
static double gap0(const Zone* zone, int p) { return zone->radius - zone->radius / zone->ray_cos[p]; }

/* rebuild xinv for the set `in`; 0, or -2 for a singular system */
static int node_rebuild(NodeSolve* ns)
{
    const Zone* zone = ns->zone;
    int Z = zone->n_zone, P = zone->n_points, S = zone->n_support, p, s, t, i;
    double* x = ns->x;  /* X = I + G M_A */
    for (i = 0; i < Z * Z; i++) x[i] = 0.0;
    for (i = 0; i < Z; i++) x[i * Z + i] = 1.0;
    for (p = 0; p < P; p++) {  /* + k (G w)(w^T) */
        const int* support = zone->support + p * S;
        const double* w = zone->weight + p * S;
        if (!ns->in[p]) continue;
        for (i = 0; i < Z; i++) {
            double gw = 0.0;
            for (s = 0; s < S; s++) gw += ns->g[i * Z + support[s]] * w[s];
            gw *= zone->stiffness;
            for (t = 0; t < S; t++) x[i * Z + support[t]] += gw * w[t];
        }
    }
    ns->updates = 0;
    return invert(x, Z, ns->xinv, ns->work, ns->pivot) == 0 ? 0 : -2;
}

/* xinv for the set `active` from the set it is for; 0, or -2 */
static int node_update(NodeSolve* ns, const char* active)
{
    const Zone* zone = ns->zone;
    int Z = zone->n_zone, P = zone->n_points, S = zone->n_support, p, s, i, j, changed = 0;
    for (p = 0; p < P; p++) changed += active[p] != ns->in[p];
    if (changed == 0) return 0;
    if (ns->updates + changed > (Z > 32 ? Z : 32)) {
        memcpy(ns->in, active, (size_t)P);
        return node_rebuild(ns);
    }
    for (p = 0; p < P; p++) {
        const int* support = zone->support + p * S;
        const double* w = zone->weight + p * S;
        double k = active[p] ? zone->stiffness : -zone->stiffness, denominator = 1.0;
        if (active[p] == ns->in[p]) continue;
        /* X' = X + k (G w) w^T: X'^-1 = X^-1 - k u v^T / (1 + k w^T u), u = X^-1 G w,
         * v^T = w^T X^-1 */
        for (i = 0; i < Z; i++) {
            double sum = 0.0;
            for (s = 0; s < S; s++) sum += ns->g[i * Z + support[s]] * w[s];
            ns->gw[i] = sum;
        }
        for (i = 0; i < Z; i++) {
            double sum = 0.0;
            for (j = 0; j < Z; j++) sum += ns->xinv[i * Z + j] * ns->gw[j];
            ns->u[i] = sum;
        }
        for (j = 0; j < Z; j++) {
            double sum = 0.0;
            for (s = 0; s < S; s++) sum += w[s] * ns->xinv[support[s] * Z + j];
            ns->v[j] = sum;
        }
        for (s = 0; s < S; s++) denominator += k * w[s] * ns->u[support[s]];
        ns->in[p] = active[p];
        ns->updates++;
        if (!(fabs(denominator) > 1e-8)) {  /* a near-singular update: rebuild instead */
            memcpy(ns->in, active, (size_t)P);
            return node_rebuild(ns);
        }
        for (i = 0; i < Z; i++) {
            double scale = k * ns->u[i] / denominator;
            if (scale == 0.0) continue;
            for (j = 0; j < Z; j++) ns->xinv[i * Z + j] -= scale * ns->v[j];
        }
    }
    return 0;
}

/* y = G (b - M y) for the set `in`: (I + G M) y = G b, with b = sum_A k r w, r = r0 or sec */
static void node_solve(NodeSolve* ns, int which, double* y)
{
    const Zone* zone = ns->zone;
    int Z = zone->n_zone, P = zone->n_points, S = zone->n_support, p, s, i, j, round;
    double k = zone->stiffness;
    for (i = 0; i < Z; i++) ns->b[i] = 0.0;
    for (p = 0; p < P; p++) {
        double r;
        if (!ns->in[p]) continue;
        r = k * (which == 0 ? gap0(zone, p) : zone->sec[p]);
        for (s = 0; s < S; s++) ns->b[zone->support[p * S + s]] += r * zone->weight[p * S + s];
    }
    for (i = 0; i < Z; i++) {
        double sum = 0.0;
        for (j = 0; j < Z; j++) sum += ns->g[i * Z + j] * ns->b[j];
        ns->gb[i] = sum;
    }
    for (i = 0; i < Z; i++) {
        double sum = 0.0;
        for (j = 0; j < Z; j++) sum += ns->xinv[i * Z + j] * ns->gb[j];
        y[i] = sum;
    }
    for (round = 0; round < 1; round++) {  /* refine: rho = G (b - M y) - y */
        for (i = 0; i < Z; i++) ns->my[i] = ns->b[i];
        for (p = 0; p < P; p++) {
            double wy;
            if (!ns->in[p]) continue;
            wy = k * at_point(zone, p, y);
            for (s = 0; s < S; s++) ns->my[zone->support[p * S + s]] -= wy * zone->weight[p * S + s];
        }
        for (i = 0; i < Z; i++) {
            double sum = 0.0;
            for (j = 0; j < Z; j++) sum += ns->g[i * Z + j] * ns->my[j];
            ns->rho[i] = sum - y[i];
        }
        for (i = 0; i < Z; i++) {
            double sum = 0.0;
            for (j = 0; j < Z; j++) sum += ns->xinv[i * Z + j] * ns->rho[j];
            y[i] += sum;
        }
    }
}

int footprint_path(FootprintPath* path, const Memory* mem, const Zone* zone,
                   const double* compliance, double max_deflection)
{
    int Z = zone->n_zone, P = zone->n_points, i, round, status = 0;
    double radius = zone->radius, start = 0.0;
    NodeSolve ns;
    char* active = (char*)mem_alloc(mem, (size_t)(2 * P), 1);
    double* events = (double*)mem_alloc(mem, (size_t)(5 * P), sizeof(double));
    double* nodes = (double*)mem_alloc(mem, (size_t)(3 * Z * Z + 8 * Z), sizeof(double));
    int* pivot = (int*)mem_alloc(mem, (size_t)Z, sizeof(int));
    double *leave = events + P, *enter = leave + P, *pen0 = enter + P, *pen1 = pen0 + P;
    memset(path, 0, sizeof *path);
    memset(&ns, 0, sizeof ns);
    path->max_deflection = max_deflection;
    if (!active || !events || !nodes || !pivot) {
        status = -1;
        goto done;
    }
    ns.zone = zone;
    ns.g = compliance;
    ns.xinv = nodes;
    ns.x = nodes + Z * Z;
    ns.work = ns.x + Z * Z;  /* Z^2 + Z */
    ns.gw = ns.work + Z * Z + Z;
    ns.u = ns.gw + Z;
    ns.v = ns.u + Z;
    ns.b = ns.v + Z;
    ns.gb = ns.b + Z;
    ns.rho = ns.gb + Z;
    ns.my = ns.rho + Z;
    ns.pivot = pivot;
    ns.in = active + P;  /* none active: xinv = I */
    for (i = 0; i < Z * Z; i++) ns.xinv[i] = 0.0;
    for (i = 0; i < Z; i++) ns.xinv[i * Z + i] = 1.0;
    for (round = 0; round < SPEC_SEGMENTS_PER_NODE * (P + 1); round++) {
        double next = HUGE_VAL, *y0, *y1;
        const char* now;
        int any = 0, s, p;
        for (i = 0; i < P; i++) any |= active[i];
        if (!any) {  /* the touching point(s) enter as soon as d > 0 */
            for (i = 0; i < P; i++) {
                active[i] = (char)(fabs(zone->ray_cos[i] - 1.0) <= SPEC_TOUCH_ATOL);
            }
        }
        if (path->count == path->capacity && path_grow(path, mem, Z, P) != 0) {
            status = -1;
            goto done;
        }
        s = path->count;
        status = node_update(&ns, active);
        if (status != 0) goto done;
        y0 = path->y0 + (size_t)s * Z;
        y1 = path->y1 + (size_t)s * Z;
        node_solve(&ns, 0, y0);
        node_solve(&ns, 1, y1);
        path->start[s] = start;
        memcpy(path->active + (size_t)s * P, active, (size_t)P);
        now = path->active + (size_t)s * P;
        path->w0[s] = path->w1[s] = 0.0;
        for (p = 0; p < P; p++) {
            pen0[p] = gap0(zone, p) - at_point(zone, p, y0);
            pen1[p] = zone->sec[p] - at_point(zone, p, y1);
            if (now[p]) {
                path->w0[s] += zone->load_cos[p] * (zone->stiffness * pen0[p]);
                path->w1[s] += zone->load_cos[p] * (zone->stiffness * pen1[p]);
            }
        }
        path->count++;
        /* leaving: an active force falls to 0; entering: an inactive penetration rises to 0 */
        for (i = 0; i < P; i++) {
            double f0 = zone->stiffness * pen0[i], f1 = zone->stiffness * pen1[i];
            enter[i] = (!active[i] && pen1[i] > 0) ? -pen0[i] / pen1[i] : HUGE_VAL;
            leave[i] = (active[i] && f1 < 0) ? -f0 / f1 : HUGE_VAL;
            events[i] = fmin(leave[i], enter[i]);
            if (isnan(leave[i])) events[i] = enter[i];
            if (events[i] <= start * (1 + SPEC_EVENT_TOLERANCE) + SPEC_EVENT_TOLERANCE * radius) {
                events[i] = HUGE_VAL;
            }
            if (events[i] < next) next = events[i];
        }
        if (!isfinite(next) || next >= max_deflection) goto done;
        for (i = 0; i < P; i++) {  /* every event within rounding of the first happens together */
            int together = events[i] <= next * (1 + SPEC_EVENTS_TOGETHER)
                                            + SPEC_EVENT_TOLERANCE * radius;
            if (!together) continue;
            if (leave[i] <= enter[i]) active[i] = 0;
            else if (enter[i] < leave[i]) active[i] = 1;
        }
        start = next;
    }
    status = -2;  /* the continuation did not terminate */
done:
    mem_free(mem, active);
    mem_free(mem, events);
    mem_free(mem, nodes);
    mem_free(mem, pivot);
    if (status != 0) footprint_path_free(path, mem);
    return status;
}

void footprint_path_free(FootprintPath* path, const Memory* mem)
{
    mem_free(mem, path->start);
    mem_free(mem, path->active);
    mem_free(mem, path->y0);
    mem_free(mem, path->y1);
    mem_free(mem, path->w0);
    mem_free(mem, path->w1);
    memset(path, 0, sizeof *path);
}

int footprint_alloc(Footprint* fp, const Memory* mem, const Zone* zone)
{
    int P = zone->n_points;
    memset(fp, 0, sizeof *fp);
    fp->forces = (double*)mem_alloc(mem, (size_t)P, sizeof(double));
    fp->penetration = (double*)mem_alloc(mem, (size_t)P, sizeof(double));
    fp->active = (char*)mem_alloc(mem, (size_t)P, 1);
    fp->x = (double*)mem_alloc(mem, (size_t)P, sizeof(double));
    if (!fp->forces || !fp->penetration || !fp->active || !fp->x) {
        footprint_free(fp, mem);
        return -1;
    }
    return 0;
}

void footprint_free(Footprint* fp, const Memory* mem)
{
    mem_free(mem, fp->forces);
    mem_free(mem, fp->penetration);
    mem_free(mem, fp->active);
    mem_free(mem, fp->x);
    memset(fp, 0, sizeof *fp);
}

void footprint_edges(const double* x, const double* penetration, const char* active, int n,
                     double* front, double* rear)
{
    int first = -1, last = -1, i;
    for (i = 0; i < n; i++) {
        if (active[i]) {
            if (first < 0) first = i;
            last = i;
        }
    }
    if (first < 0) {
        *front = *rear = 0.0;
        return;
    }
    {
        int ends[2][2];
        double* out[2];
        int e;
        ends[0][0] = first;
        ends[0][1] = first - 1;  /* x decreases along the zone (front first) */
        ends[1][0] = last;
        ends[1][1] = last + 1;
        out[0] = front;
        out[1] = rear;
        for (e = 0; e < 2; e++) {
            int inner = ends[e][0], outer = ends[e][1];
            if (outer < 0 || outer >= n) {
                *out[e] = x[inner];
            } else {
                double p_in = penetration[inner], p_out = penetration[outer];
                /* between the two nodes: a neighbour that penetrates without pushing puts
                 * the edge at the neighbour, a node that pushes from above the road (the
                 * linear law) at itself (contact.py's _edges) */
                double share = p_in > p_out && p_in > 0.0 ? fmin(p_in / (p_in - p_out), 1.0)
                                                          : 0.0;
                *out[e] = x[inner] + share * (x[outer] - x[inner]);
            }
        }
    }
}

void footprint_at_deflection(const FootprintPath* path, const Zone* zone, double deflection,
                             Footprint* out)
{
    int Z = zone->n_zone, P = zone->n_points, s = 0, i;
    double radius = zone->radius;
    const double *y0, *y1;
    const char* active;
    for (i = 0; i < path->count; i++) {  /* the last segment starting at or before d */
        if (path->start[i] <= deflection) s = i;
    }
    y0 = path->y0 + (size_t)s * Z;
    y1 = path->y1 + (size_t)s * Z;
    active = path->active + (size_t)s * P;
    out->deflection = deflection;
    for (i = 0; i < P; i++) {
        double p0 = gap0(zone, i) - at_point(zone, i, y0);
        double p1 = zone->sec[i] - at_point(zone, i, y1);
        out->active[i] = (char)(deflection > 0 ? active[i] : 0);
        out->forces[i] = out->active[i] ? zone->stiffness * p0 + zone->stiffness * p1 * deflection
                                        : 0.0;
        out->penetration[i] = p0 + p1 * deflection;
    }
    out->load = deflection > 0 ? path->w0[s] + path->w1[s] * deflection : 0.0;
    out->tangent = path->w1[s];
    out->touches_edge = out->active[0] || out->active[P - 1];
    for (i = 0; i < P; i++) out->x[i] = -(radius - deflection) * tan(zone->point_theta[i]);
    footprint_edges(out->x, out->penetration, out->active, P, &out->front, &out->rear);
    out->length = out->front - out->rear;
}

int footprint_at_load(const FootprintPath* path, const Zone* zone, double load, Footprint* out)
{
    int s;
    if (load <= 0.0) {
        footprint_at_deflection(path, zone, 0.0, out);
        return 0;
    }
    for (s = 0; s < path->count; s++) {
        double end = s + 1 < path->count ? path->start[s + 1] : path->max_deflection;
        double w0 = path->w0[s], w1 = path->w1[s];
        if (w1 > 0 && w0 + w1 * end >= load) {
            footprint_at_deflection(path, zone, fmax((load - w0) / w1, path->start[s]), out);
            return 0;
        }
    }
    return -1;
}

void max_credible_load(const FootprintPath* path, const Zone* zone, double max_length,
                       Footprint* out)
{
    int P = zone->n_points, s, i;
    for (s = 0; s < path->count; s++) {
        double start = path->start[s];
        double end = s + 1 < path->count ? path->start[s + 1] : path->max_deflection;
        const char* active = path->active + (size_t)s * P;
        if (active[0] || active[P - 1]) {  /* an end point enters here, with no force yet */
            footprint_at_deflection(path, zone, start, out);
            return;
        }
        footprint_at_deflection(path, zone, end * (1 - SPEC_EVENT_TOLERANCE), out);
        if (out->length > max_length) {
            double low = start, high = end;
            for (i = 0; i < SPEC_LENGTH_BISECTIONS; i++) {
                double middle = 0.5 * (low + high);
                footprint_at_deflection(path, zone, middle, out);
                if (out->length > max_length) high = middle;
                else low = middle;
            }
            footprint_at_deflection(path, zone, low, out);
            return;
        }
    }
    footprint_at_deflection(path, zone, path->max_deflection, out);
}

/* -- road windows ------------------------------------------------------------------------------ */

int windows_build(Windows* w, const Memory* mem, const Zone* zone, double deflection,
                  double speed)
{
    int P = zone->n_points, j;
    double height = zone->radius - deflection, half = 0.5 * zone->dtheta / zone->per_node;
    memset(w, 0, sizeof *w);
    w->early = (double*)mem_alloc(mem, (size_t)P, sizeof(double));
    w->late = (double*)mem_alloc(mem, (size_t)P, sizeof(double));
    if (!w->early || !w->late) {
        windows_free(w, mem);
        return -1;
    }
    w->front = -HUGE_VAL;
    for (j = 0; j < P; j++) {
        double x_hi = -height * tan(zone->point_theta[j] - half);
        if (x_hi > w->front) w->front = x_hi;
    }
    for (j = 0; j < P; j++) {
        double x_lo = -height * tan(zone->point_theta[j] + half);
        double x_hi = -height * tan(zone->point_theta[j] - half);
        if (speed <= 0.0) {
            w->early[j] = w->late[j] = 0.0;
        } else {
            w->early[j] = (w->front - x_hi) / speed;
            w->late[j] = (w->front - x_lo) / speed;
        }
        if (w->late[j] > w->horizon) w->horizon = w->late[j];
        if (w->late[j] > 0) w->delayed = 1;
    }
    return 0;
}

void windows_free(Windows* w, const Memory* mem)
{
    mem_free(mem, w->early);
    mem_free(mem, w->late);
    memset(w, 0, sizeof *w);
}
