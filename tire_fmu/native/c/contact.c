/* contact.c: the contact zone, the static footprint and the road windows (core/contact.py).
 *
 * The static contact forces solve a linear complementarity problem whose solution is piecewise
 * linear in the rim deflection; the path is traced exactly by active-set continuation from
 * zero deflection, segment by segment, each ended by the next node to enter or to leave. */
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

int zone_build(Zone* zone, const Memory* mem, int n_elements, double radius, double k_cw,
               double beta, int half)
{
    int Z = 2 * half + 1, j;
    double dtheta = 2.0 * PI / n_elements;
    memset(zone, 0, sizeof *zone);
    zone->n_zone = Z;
    zone->half = half;
    zone->centre = half;
    zone->radius = radius;
    zone->theta = (double*)mem_alloc(mem, (size_t)Z, sizeof(double));
    zone->cos = (double*)mem_alloc(mem, (size_t)Z, sizeof(double));
    zone->sin = (double*)mem_alloc(mem, (size_t)Z, sizeof(double));
    zone->sec = (double*)mem_alloc(mem, (size_t)Z, sizeof(double));
    if (!zone->theta || !zone->cos || !zone->sin || !zone->sec) {
        zone_free(zone, mem);
        return -1;
    }
    for (j = 0; j < Z; j++) {
        zone->theta[j] = (j - half) * dtheta;
        zone->cos[j] = cos(zone->theta[j]);
        zone->sin[j] = sin(zone->theta[j]);
        zone->sec[j] = 1.0 / zone->cos[j];
    }
    zone->stiffness = k_cw * (radius * dtheta);
    zone->damping = beta * zone->stiffness;
    return 0;
}

void zone_free(Zone* zone, const Memory* mem)
{
    mem_free(mem, zone->theta);
    mem_free(mem, zone->cos);
    mem_free(mem, zone->sin);
    mem_free(mem, zone->sec);
    memset(zone, 0, sizeof *zone);
}

/* -- the continuation path ------------------------------------------------------------------ */

static int path_grow(FootprintPath* path, const Memory* mem, int Z)
{
    int capacity = path->capacity ? 2 * path->capacity : 16, i;
    double** arrays[7];
    size_t sizes[7];
    arrays[0] = &path->start;
    sizes[0] = 1;
    arrays[1] = &path->f0;
    arrays[2] = &path->f1;
    arrays[3] = &path->p0;
    arrays[4] = &path->p1;
    for (i = 1; i < 5; i++) sizes[i] = (size_t)Z;
    arrays[5] = &path->w0;
    arrays[6] = &path->w1;
    sizes[5] = sizes[6] = 1;
    for (i = 0; i < 7; i++) {
        double* grown = (double*)mem_alloc(mem, (size_t)capacity * sizes[i], sizeof(double));
        if (grown == NULL) return -1;
        if (*arrays[i] != NULL) {
            memcpy(grown, *arrays[i], sizeof(double) * (size_t)path->count * sizes[i]);
            mem_free(mem, *arrays[i]);
        }
        *arrays[i] = grown;
    }
    {
        char* grown = (char*)mem_alloc(mem, (size_t)capacity * (size_t)Z, 1);
        if (grown == NULL) return -1;
        if (path->active != NULL) {
            memcpy(grown, path->active, (size_t)path->count * (size_t)Z);
            mem_free(mem, path->active);
        }
        path->active = grown;
    }
    path->capacity = capacity;
    return 0;
}

/* one segment: f_A = k_A p_A, (diag(1/k_A) + G_AA) f_A = p0_A + p1_A d */
static int path_segment(FootprintPath* path, const Zone* zone, double radius, const double* g,
                        double start, const char* active, double* system, int* pivot,
                        double* rhs)
{
    int Z = zone->n_zone, s = path->count, i, j, a = 0;
    int* index = pivot + Z;
    double *f0 = path->f0 + (size_t)s * Z, *f1 = path->f1 + (size_t)s * Z;
    double *p0 = path->p0 + (size_t)s * Z, *p1 = path->p1 + (size_t)s * Z;
    path->start[s] = start;
    memcpy(path->active + (size_t)s * Z, active, (size_t)Z);
    for (i = 0; i < Z; i++) {
        f0[i] = f1[i] = 0.0;
        if (active[i]) index[a++] = i;
    }
    if (a > 0) {
        for (i = 0; i < a; i++) {
            for (j = 0; j < a; j++) system[i * a + j] = g[index[i] * Z + index[j]];
            system[i * a + i] += 1.0 / zone->stiffness;
        }
        if (lu_factor(system, a, pivot) != 0) return -2;
        for (i = 0; i < a; i++) rhs[i] = radius - radius / zone->cos[index[i]];
        lu_solve(system, a, pivot, rhs);
        for (i = 0; i < a; i++) f0[index[i]] = rhs[i];
        for (i = 0; i < a; i++) rhs[i] = 1.0 / zone->cos[index[i]];
        lu_solve(system, a, pivot, rhs);
        for (i = 0; i < a; i++) f1[index[i]] = rhs[i];
    }
    path->w0[s] = path->w1[s] = 0.0;
    for (i = 0; i < Z; i++) {
        double gf0 = 0.0, gf1 = 0.0;
        for (j = 0; j < Z; j++) {
            gf0 += g[i * Z + j] * f0[j];
            gf1 += g[i * Z + j] * f1[j];
        }
        p0[i] = (radius - radius / zone->cos[i]) - gf0;
        p1[i] = 1.0 / zone->cos[i] - gf1;
        path->w0[s] += zone->cos[i] * f0[i];
        path->w1[s] += zone->cos[i] * f1[i];
    }
    path->count++;
    return 0;
}

int footprint_path(FootprintPath* path, const Memory* mem, const Zone* zone, double radius,
                   const double* compliance, double max_deflection)
{
    int Z = zone->n_zone, i, round, status = 0;
    char* active = (char*)mem_alloc(mem, (size_t)Z, 1);
    double* system = (double*)mem_alloc(mem, (size_t)(Z * Z + 3 * Z), sizeof(double));
    int* pivot = (int*)mem_alloc(mem, (size_t)(2 * Z), sizeof(int));
    double* events = system + Z * Z;
    double* leave = events + Z;
    double* rhs = leave + Z;
    double start = 0.0;
    memset(path, 0, sizeof *path);
    path->max_deflection = max_deflection;
    if (!active || !system || !pivot) {
        status = -1;
        goto done;
    }
    for (round = 0; round < SPEC_SEGMENTS_PER_NODE * (Z + 1); round++) {
        double next = HUGE_VAL, *f0, *f1, *p0, *p1;
        int any = 0, s;
        for (i = 0; i < Z; i++) any |= active[i];
        if (!any) {
            for (i = 0; i < Z; i++) active[i] = (char)(fabs(zone->cos[i] - 1.0) <= SPEC_TOUCH_ATOL);
        }
        if (path->count == path->capacity && path_grow(path, mem, Z) != 0) {
            status = -1;
            goto done;
        }
        status = path_segment(path, zone, radius, compliance, start, active, system, pivot, rhs);
        if (status != 0) goto done;
        s = path->count - 1;
        f0 = path->f0 + (size_t)s * Z;
        f1 = path->f1 + (size_t)s * Z;
        p0 = path->p0 + (size_t)s * Z;
        p1 = path->p1 + (size_t)s * Z;
        for (i = 0; i < Z; i++) {
            double enter = (!active[i] && p1[i] > 0) ? -p0[i] / p1[i] : HUGE_VAL;
            leave[i] = (active[i] && f1[i] < 0) ? -f0[i] / f1[i] : HUGE_VAL;
            events[i] = fmin(leave[i], enter);
            if (isnan(leave[i])) events[i] = enter;
            if (events[i] <= start * (1 + SPEC_EVENT_TOLERANCE) + SPEC_EVENT_TOLERANCE * radius) {
                events[i] = HUGE_VAL;
            }
            if (events[i] < next) next = events[i];
            rhs[i] = enter;  /* keep the entering value beside the leaving one */
        }
        if (!isfinite(next) || next >= max_deflection) goto done;
        for (i = 0; i < Z; i++) {
            int together = events[i] <= next * (1 + SPEC_EVENTS_TOGETHER)
                                            + SPEC_EVENT_TOLERANCE * radius;
            if (!together) continue;
            if (leave[i] <= rhs[i]) active[i] = 0;
            else if (rhs[i] < leave[i]) active[i] = 1;
        }
        start = next;
    }
    status = -2;  /* the continuation did not terminate */
done:
    mem_free(mem, active);
    mem_free(mem, system);
    mem_free(mem, pivot);
    if (status != 0) footprint_path_free(path, mem);
    return status;
}

void footprint_path_free(FootprintPath* path, const Memory* mem)
{
    mem_free(mem, path->start);
    mem_free(mem, path->active);
    mem_free(mem, path->f0);
    mem_free(mem, path->f1);
    mem_free(mem, path->p0);
    mem_free(mem, path->p1);
    mem_free(mem, path->w0);
    mem_free(mem, path->w1);
    memset(path, 0, sizeof *path);
}

int footprint_alloc(Footprint* fp, const Memory* mem, int n_zone)
{
    memset(fp, 0, sizeof *fp);
    fp->forces = (double*)mem_alloc(mem, (size_t)n_zone, sizeof(double));
    fp->penetration = (double*)mem_alloc(mem, (size_t)n_zone, sizeof(double));
    fp->active = (char*)mem_alloc(mem, (size_t)n_zone, 1);
    fp->x = (double*)mem_alloc(mem, (size_t)n_zone, sizeof(double));
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

void footprint_at_deflection(const FootprintPath* path, const Zone* zone, double radius,
                             double deflection, Footprint* out)
{
    int Z = zone->n_zone, s = 0, i;
    const double *f0, *f1, *p0, *p1;
    const char* active;
    for (i = 0; i < path->count; i++) {  /* the last segment starting at or before d */
        if (path->start[i] <= deflection) s = i;
    }
    f0 = path->f0 + (size_t)s * Z;
    f1 = path->f1 + (size_t)s * Z;
    p0 = path->p0 + (size_t)s * Z;
    p1 = path->p1 + (size_t)s * Z;
    active = path->active + (size_t)s * Z;
    out->deflection = deflection;
    for (i = 0; i < Z; i++) {
        out->active[i] = (char)(deflection > 0 ? active[i] : 0);
        out->forces[i] = out->active[i] ? f0[i] + f1[i] * deflection : 0.0;
        out->penetration[i] = p0[i] + p1[i] * deflection;
    }
    out->load = deflection > 0 ? path->w0[s] + path->w1[s] * deflection : 0.0;
    out->tangent = path->w1[s];
    out->touches_edge = out->active[0] || out->active[Z - 1];
    for (i = 0; i < Z; i++) out->x[i] = -(radius - deflection) * tan(zone->theta[i]);
    footprint_edges(out->x, out->penetration, out->active, Z, &out->front, &out->rear);
    out->length = out->front - out->rear;
}

int footprint_at_load(const FootprintPath* path, const Zone* zone, double radius, double load,
                      Footprint* out)
{
    int s;
    if (load <= 0.0) {
        footprint_at_deflection(path, zone, radius, 0.0, out);
        return 0;
    }
    for (s = 0; s < path->count; s++) {
        double end = s + 1 < path->count ? path->start[s + 1] : path->max_deflection;
        double w0 = path->w0[s], w1 = path->w1[s];
        if (w1 > 0 && w0 + w1 * end >= load) {
            footprint_at_deflection(path, zone, radius, fmax((load - w0) / w1, path->start[s]),
                                    out);
            return 0;
        }
    }
    return -1;
}

void max_credible_load(const FootprintPath* path, const Zone* zone, double radius,
                       double max_length, Footprint* out)
{
    int Z = zone->n_zone, s, i;
    for (s = 0; s < path->count; s++) {
        double start = path->start[s];
        double end = s + 1 < path->count ? path->start[s + 1] : path->max_deflection;
        const char* active = path->active + (size_t)s * Z;
        if (active[0] || active[Z - 1]) {
            footprint_at_deflection(path, zone, radius, start, out);
            return;
        }
        footprint_at_deflection(path, zone, radius, end * (1 - SPEC_EVENT_TOLERANCE), out);
        if (out->length > max_length) {
            double low = start, high = end;
            for (i = 0; i < SPEC_LENGTH_BISECTIONS; i++) {
                double middle = 0.5 * (low + high);
                footprint_at_deflection(path, zone, radius, middle, out);
                if (out->length > max_length) high = middle;
                else low = middle;
            }
            footprint_at_deflection(path, zone, radius, low, out);
            return;
        }
    }
    footprint_at_deflection(path, zone, radius, path->max_deflection, out);
}

/* -- road windows ------------------------------------------------------------------------------ */

int windows_build(Windows* w, const Memory* mem, const Zone* zone, double radius,
                  int n_elements, double deflection, double speed)
{
    int Z = zone->n_zone, j;
    double height = radius - deflection, half = 0.5 * (2.0 * PI / n_elements);
    memset(w, 0, sizeof *w);
    w->early = (double*)mem_alloc(mem, (size_t)Z, sizeof(double));
    w->late = (double*)mem_alloc(mem, (size_t)Z, sizeof(double));
    if (!w->early || !w->late) {
        windows_free(w, mem);
        return -1;
    }
    w->front = -HUGE_VAL;
    for (j = 0; j < Z; j++) {
        double x_hi = -height * tan(zone->theta[j] - half);
        if (x_hi > w->front) w->front = x_hi;
    }
    for (j = 0; j < Z; j++) {
        double x_lo = -height * tan(zone->theta[j] + half);
        double x_hi = -height * tan(zone->theta[j] - half);
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
