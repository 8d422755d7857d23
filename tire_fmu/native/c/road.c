/* road.c: the road under each contact node (core/road.py), the same rules and the same sums.
 *
 * Node j sees the window average of the cubic Hermite interpolant of the host's (road_z,
 * road_vz) samples over [t - late_j, t - early_j]. The general path searches the recorded
 * history; once the steps have had one size h for the whole reach of the windows, a delay line
 * reads each window end with fixed weights from a ring buffer of samples. Times are the
 * simulator's time since its start; the same-step tolerances use origin + now, the host's
 * absolute clock, whose rounding jitters the steps it passes. */
#include <string.h>

#include "spec.h"
#include "tire.h"

static int upper_index(const double* t, int n, double x)
{
    /* numpy.searchsorted(t, x, side="right"): how many t are <= x */
    int lo = 0, hi = n;
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if (t[mid] <= x) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

static int interval(const double* t, int n, double x)
{
    int i = upper_index(t, n, x) - 1;
    if (i < 0) i = 0;
    if (i > n - 2) i = n - 2;
    return i;
}

static void hermite_value(const double* t, const double* z, const double* v, int n, double x,
                          double* height, double* slope)
{
    int i;
    double dt, s, z0, z1, v0, v1, s2, s3;
    if (n == 1) {
        *height = z[0];
        *slope = x < t[0] ? 0.0 : v[0];
        return;
    }
    if (x < t[0]) {
        *height = z[0];
        *slope = 0.0;
        return;
    }
    i = interval(t, n, x);
    dt = t[i + 1] - t[i];
    s = (x - t[i]) / dt;
    z0 = z[i];
    z1 = z[i + 1];
    v0 = v[i] * dt;
    v1 = v[i + 1] * dt;
    s2 = s * s;
    s3 = s * s * s;
    *height = (2 * s3 - 3 * s2 + 1) * z0 + (s3 - 2 * s2 + s) * v0 + (-2 * s3 + 3 * s2) * z1
              + (s3 - s2) * v1;
    *slope = ((6 * s2 - 6 * s) * z0 + (3 * s2 - 4 * s + 1) * v0 + (-6 * s2 + 6 * s) * z1
              + (3 * s2 - 2 * s) * v1) / dt;
}

static double partial_integral(double s, double z0, double v0, double z1, double v1)
{
    double s2 = s * s, s3 = s * s * s, s4 = s * s * s * s;
    return (0.5 * s4 - s3 + s) * z0 + (0.25 * s4 - 2 * s3 / 3 + 0.5 * s2) * v0
           + (-0.5 * s4 + s3) * z1 + (0.25 * s4 - s3 / 3) * v1;
}

static double hermite_integral(const double* t, const double* z, const double* v, int n,
                               const double* cumulative, double x)
{
    int i;
    double width, s;
    if (n == 1) return (x - t[0]) * z[0];
    if (x < t[0]) return (x - t[0]) * z[0];
    if (x > t[n - 1]) return cumulative[n - 1] + (x - t[n - 1]) * z[n - 1];
    i = interval(t, n, x);
    width = t[i + 1] - t[i];
    s = (x - t[i]) / width;
    if (s < 0.0) s = 0.0;
    return cumulative[i] + width * partial_integral(s, z[i], v[i] * width, z[i + 1],
                                                    v[i + 1] * width);
}

static void window_reads(RoadReader* road, double now, double* heights, double* slopes)
{
    const Windows* w = road->windows;
    const double *t = road->t, *z = road->z, *v = road->v;
    int n = road->length, j;
    double* cumulative = road->work;
    if (n > 1) {
        cumulative[0] = 0.0;
        for (j = 0; j + 1 < n; j++) {
            double dt = t[j + 1] - t[j];
            cumulative[j + 1] = cumulative[j]
                                + dt * (0.5 * (z[j] + z[j + 1]) + dt * (v[j] - v[j + 1]) / 12.0);
        }
    }
    for (j = 0; j < road->n; j++) {
        double early = now - w->early[j], late = now - w->late[j];
        double width = w->late[j] - w->early[j];
        double end_value, end_slope, start_value, start_slope;
        hermite_value(t, z, v, n, early, &end_value, &end_slope);
        if (width <= 0.0) {
            heights[j] = end_value;
            slopes[j] = end_slope;
            continue;
        }
        hermite_value(t, z, v, n, late, &start_value, &start_slope);
        heights[j] = (hermite_integral(t, z, v, n, cumulative, early)
                      - hermite_integral(t, z, v, n, cumulative, late)) / width;
        slopes[j] = (end_value - start_value) / width;
    }
}

/* -- the delay line ----------------------------------------------------------------------------- */

static int samples_needed(const Windows* w, double h)
{
    return (int)floor(w->horizon / h + SPEC_LAG_SLACK) + 2;
}

static void line_free(DelayLine* line, const Memory* mem)
{
    mem_free(mem, line->index);
    mem_free(mem, line->combine);
    mem_free(mem, line->buffer);
    memset(line, 0, sizeof *line);
}

static void line_push(DelayLine* line, double time, double z, double v)
{
    double vh = v * line->h, c;
    int size = line->size, row, offset;
    double* buffer = line->buffer;
    if (fabs(time - line->newest_time) < 0.5 * line->h) {
        row = line->start;  /* replace: its integral follows from the sample before it */
    } else {
        row = (line->start - 1 + size) % size;
        line->start = row;
        line->newest_time = time;
        line->count++;
    }
    if (line->count == 1) {
        c = 0.0;
    } else {
        int older = 3 * ((row + 1) % size);
        double z0 = buffer[older], v0 = buffer[older + 1];
        c = buffer[older + 2] + (0.5 * (z0 + z) + (v0 - vh) / 12.0);
    }
    for (offset = 0; offset <= size; offset += size) {
        int base = 3 * (row + offset);
        buffer[base] = z;
        buffer[base + 1] = vh;
        buffer[base + 2] = c;
    }
    if (row == 0 && c != 0.0) {
        /* re-base the integral on the newest sample (a read uses differences only) */
        int k;
        for (k = 2; k < 6 * size; k += 3) buffer[k] -= c;
    }
}

static int line_build(DelayLine* line, const Memory* mem, const Windows* w, int n, double h,
                      const double* t, const double* z, const double* v, int count)
{
    int end, q;
    memset(line, 0, sizeof *line);
    line->h = h;
    line->size = samples_needed(w, h);
    line->index = (int*)mem_alloc(mem, (size_t)(10 * n), sizeof(int));
    line->combine = (double*)mem_alloc(mem, (size_t)(20 * n), sizeof(double));
    line->buffer = (double*)mem_alloc(mem, (size_t)(6 * line->size), sizeof(double));
    if (!line->index || !line->combine || !line->buffer) {
        line_free(line, mem);
        return -1;
    }
    for (end = 0; end < 2 * n; end++) {
        int node = end % n, older;
        double sign = end < n ? 1.0 : -1.0;
        double width = w->late[node] - w->early[node];
        double lag = (end < n ? w->early[node] : w->late[node]) / h;
        double s, s2, s3, wz[4], in[4];
        older = (int)floor(lag + SPEC_LAG_SLACK) + 1;
        s = older - lag;
        if (s < 0.0) s = 0.0;
        if (s > 1.0) s = 1.0;
        s2 = s * s;
        s3 = s * s * s;
        wz[0] = 2 * s3 - 3 * s2 + 1;
        wz[1] = s3 - 2 * s2 + s;
        wz[2] = -2 * s3 + 3 * s2;
        wz[3] = s3 - s2;
        in[0] = 0.5 * s2 * s2 - s3 + s;
        in[1] = 0.25 * s2 * s2 - 2 * s3 / 3 + 0.5 * s2;
        in[2] = -0.5 * s2 * s2 + s3;
        in[3] = 0.25 * s2 * s2 - s3 / 3;
        /* gather per end: [z_o, v_o h, C_o, z_n, v_n h] */
        line->index[5 * end + 0] = 3 * older;
        line->index[5 * end + 1] = 3 * older + 1;
        line->index[5 * end + 2] = 3 * older + 2;
        line->index[5 * end + 3] = 3 * (older - 1);
        line->index[5 * end + 4] = 3 * (older - 1) + 1;
        {
            double mean[5], slope[5];
            mean[0] = in[0];
            mean[1] = in[1];
            mean[2] = 1.0;
            mean[3] = in[2];
            mean[4] = in[3];
            slope[0] = wz[0];
            slope[1] = wz[1];
            slope[2] = 0.0;
            slope[3] = wz[2];
            slope[4] = wz[3];
            for (q = 0; q < 5; q++) {
                line->combine[5 * end + q] = sign * h / width * mean[q];
                line->combine[10 * n + 5 * end + q] = sign / width * slope[q];
            }
        }
    }
    line->start = 0;
    line->newest_time = NAN;
    line->count = 0;
    for (q = count - line->size; q < count; q++) line_push(line, t[q], z[q], v[q]);
    return 0;
}

static void line_read(const DelayLine* line, int n, double* heights, double* slopes)
{
    int j, q;
    const double* buffer = line->buffer + 3 * line->start;
    for (j = 0; j < n; j++) {
        const int* early = line->index + 5 * j;
        const int* late = line->index + 5 * (n + j);
        const double* me = line->combine + 5 * j;
        const double* ml = line->combine + 5 * (n + j);
        const double* se = line->combine + 10 * n + 5 * j;
        const double* sl = line->combine + 10 * n + 5 * (n + j);
        double mean = 0.0, slope = 0.0;
        for (q = 0; q < 5; q++) {
            mean += me[q] * buffer[early[q]];
            slope += se[q] * buffer[early[q]];
        }
        for (q = 0; q < 5; q++) {
            mean += ml[q] * buffer[late[q]];
            slope += sl[q] * buffer[late[q]];
        }
        heights[j] = mean;
        slopes[j] = slope;
    }
}

static void line_history(const DelayLine* line, double* t, double* z, double* v)
{
    int k;
    for (k = 0; k < line->size; k++) {  /* k = 0 newest; written oldest first */
        int row = (line->start + k) % line->size, out = line->size - 1 - k;
        z[out] = line->buffer[3 * row];
        v[out] = line->buffer[3 * row + 1] / line->h;
        t[out] = line->newest_time - k * line->h;
    }
}

/* -- the reader ------------------------------------------------------------------------------------ */

int road_init(RoadReader* road, const Memory* mem, const Windows* windows, int n)
{
    memset(road, 0, sizeof *road);
    road->windows = windows;
    road->n = n;
    road_reset(road, mem);
    return 0;
}

void road_free(RoadReader* road, const Memory* mem)
{
    line_free(&road->line, mem);
    mem_free(mem, road->t);
    mem_free(mem, road->z);
    mem_free(mem, road->v);
    mem_free(mem, road->work);
    memset(road, 0, sizeof *road);
}

void road_reset(RoadReader* road, const Memory* mem)
{
    road->length = 0;
    if (road->line_on) line_free(&road->line, mem);
    road->line_on = 0;
    road->line_h = NAN;
    road->uniform_run = -1;
}

static int reserve(RoadReader* road, const Memory* mem, int capacity)
{
    double *t, *z, *v, *work;
    if (capacity <= road->capacity) return 0;
    if (capacity < 2 * road->capacity) capacity = 2 * road->capacity;
    if (capacity < 16) capacity = 16;
    t = (double*)mem_alloc(mem, (size_t)capacity, sizeof(double));
    z = (double*)mem_alloc(mem, (size_t)capacity, sizeof(double));
    v = (double*)mem_alloc(mem, (size_t)capacity, sizeof(double));
    work = (double*)mem_alloc(mem, (size_t)capacity, sizeof(double));
    if (!t || !z || !v || !work) {
        mem_free(mem, t);
        mem_free(mem, z);
        mem_free(mem, v);
        mem_free(mem, work);
        return -1;
    }
    if (road->length > 0) {
        memcpy(t, road->t, sizeof(double) * (size_t)road->length);
        memcpy(z, road->z, sizeof(double) * (size_t)road->length);
        memcpy(v, road->v, sizeof(double) * (size_t)road->length);
    }
    mem_free(mem, road->t);
    mem_free(mem, road->z);
    mem_free(mem, road->v);
    mem_free(mem, road->work);
    road->t = t;
    road->z = z;
    road->v = v;
    road->work = work;
    road->capacity = capacity;
    return 0;
}

/* add the sample of now, or replace the newest if it is that point again; 1 if appended */
static int record(RoadReader* road, const Memory* mem, double now, double z, double vz)
{
    int n = road->length, keep;
    if (reserve(road, mem, n + 1) != 0) return -1;  /* before anything changes */
    if (n > 0 && road->t[n - 1] >= now - SPEC_SAME_POINT_EPS * (fabs(now) + 1.0)) {
        road->z[n - 1] = z;
        road->v[n - 1] = vz;
        return 0;
    }
    /* keep what the longest window can still reach, plus the sample just before it */
    keep = upper_index(road->t, n, now - road->windows->horizon) - 1;
    if (keep < 0) keep = 0;
    if (keep > 0) {
        memmove(road->t, road->t + keep, sizeof(double) * (size_t)(n - keep));
        memmove(road->z, road->z + keep, sizeof(double) * (size_t)(n - keep));
        memmove(road->v, road->v + keep, sizeof(double) * (size_t)(n - keep));
        n -= keep;
    }
    road->t[n] = now;
    road->z[n] = z;
    road->v[n] = vz;
    road->length = n + 1;
    return 1;
}

static int uniform_run(const double* t, int n, double h, double resolution)
{
    int k, last_irregular = -1;
    if (n == 0) return 0;
    for (k = 0; k + 1 < n; k++) {
        if (!(fabs(t[k + 1] - t[k] - h) <= resolution)) last_irregular = k;
    }
    return n - (last_irregular + 1);
}

int road_read(RoadReader* road, const Memory* mem, double now, double z, double vz, double h,
              double* heights, double* slopes)
{
    const Windows* w = road->windows;
    int j, appended, needed;
    double resolution;
    if (!w->delayed) {
        for (j = 0; j < road->n; j++) {
            heights[j] = z;
            slopes[j] = vz;
        }
        return 0;
    }
    resolution = SPEC_SAME_POINT_EPS * (fabs(road->origin + now) + h);
    if (road->line_on && fabs(h - road->line_h) <= resolution) {
        line_push(&road->line, now, z, vz);
        line_read(&road->line, road->n, heights, slopes);
        return 0;
    }
    if (road->line_on) {  /* the step size changed: back to the recorded history */
        if (reserve(road, mem, road->line.size + 1) != 0) return -1;
        line_history(&road->line, road->t, road->z, road->v);
        road->length = road->line.size;
        line_free(&road->line, mem);
        road->line_on = 0;
        road->uniform_run = -1;
    }
    appended = record(road, mem, now, z, vz);
    if (appended < 0) return -1;
    if (!(h > 0 && isfinite(h))) {  /* no step size yet: read the history */
        window_reads(road, now, heights, slopes);
        return 0;
    }
    needed = samples_needed(w, h);
    if (road->uniform_run < 0) {
        road->uniform_run = uniform_run(road->t, road->length, h, resolution);
    } else if (appended) {
        int n = road->length;
        int uniform = n > 1 && fabs(road->t[n - 1] - road->t[n - 2] - h) <= resolution;
        road->uniform_run = uniform ? road->uniform_run + 1 : 1;
    }
    if (road->uniform_run >= needed) {
        if (line_build(&road->line, mem, w, road->n, h, road->t, road->z, road->v,
                       road->length) != 0) {
            return -1;
        }
        road->line_on = 1;
        road->line_h = h;
        line_read(&road->line, road->n, heights, slopes);
        return 0;
    }
    window_reads(road, now, heights, slopes);
    return 0;
}

int road_history_length(const RoadReader* road)
{
    return road->line_on ? road->line.size : road->length;
}

void road_history(const RoadReader* road, double* t, double* z, double* v)
{
    if (road->line_on) {
        line_history(&road->line, t, z, v);
        return;
    }
    if (road->length > 0) {
        memcpy(t, road->t, sizeof(double) * (size_t)road->length);
        memcpy(z, road->z, sizeof(double) * (size_t)road->length);
        memcpy(v, road->v, sizeof(double) * (size_t)road->length);
    }
}

int road_set_history(RoadReader* road, const Memory* mem, const double* t, const double* z,
                     const double* v, int count)
{
    road_reset(road, mem);
    if (reserve(road, mem, count) != 0) return -1;
    if (count > 0) {
        memcpy(road->t, t, sizeof(double) * (size_t)count);
        memcpy(road->z, z, sizeof(double) * (size_t)count);
        memcpy(road->v, v, sizeof(double) * (size_t)count);
    }
    road->length = count;
    return 0;
}

/* the history kept, the delay line dropped: the reader as a restore of its history leaves it
 * (the line is built again by the next read, from the same samples) */
void road_rebuild(RoadReader* road, const Memory* mem)
{
    if (!road->line_on) {
        road->uniform_run = -1;
        return;
    }
    {
        int count = road_history_length(road);
        double* scratch = (double*)mem_alloc(mem, (size_t)(3 * count), sizeof(double));
        if (scratch == NULL) return;  /* the line stays: the same values to rounding */
        road_history(road, scratch, scratch + count, scratch + 2 * count);
        road_set_history(road, mem, scratch, scratch + count, scratch + 2 * count, count);
        mem_free(mem, scratch);
    }
}
