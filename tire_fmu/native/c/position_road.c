/* position_road.c: the host's road by position (position_road.h), core/obstacles.py's
 * PositionRoad in C: the same samples kept, the same integral to the bit (the same sums in the
 * same order), so that a state of either runtime reads the same road in the other.
 *
 * The room a call needs is made before it changes anything (the live samples moved to the
 * buffer's start, or a larger buffer), so that running out of memory leaves the road as it
 * was and no index moves while the samples go in. */
#include <math.h>
#include <string.h>

#include "position_road.h"
#include "road_samples.h"
#include "spec.h"

#define PR_MIN_CAPACITY 64

static double* row(const PositionRoad* road, int r) { return road->buffer + (size_t)r * road->capacity; }

/* a buffer of capacity columns holding the live samples from column 0 */
static int reallocate(PositionRoad* road, int capacity)
{
    int live = road->hi - road->lo, r;
    double* grown = (double*)mem_alloc(road->mem, 3 * (size_t)capacity, sizeof(double));
    if (grown == NULL) return -1;
    for (r = 0; r < 3 && road->buffer != NULL && live > 0; r++)
        memcpy(grown + (size_t)r * capacity, row(road, r) + road->lo,
               (size_t)live * sizeof(double));
    mem_free(road->mem, road->buffer);
    road->buffer = grown;
    road->capacity = capacity;
    road->lo = 0;
    road->hi = live;
    return 0;
}

int position_road_init(PositionRoad* road, const Memory* mem, double keep_m)
{
    memset(road, 0, sizeof *road);
    road->mem = mem;
    road->keep_m = keep_m;
    return reallocate(road, PR_MIN_CAPACITY);
}

void position_road_free(PositionRoad* road)
{
    if (road == NULL || road->mem == NULL) return;
    mem_free(road->mem, road->buffer);
    road->buffer = NULL;
    road->capacity = road->lo = road->hi = 0;
}

int position_road_count(const PositionRoad* road) { return road->hi - road->lo; }
const double* position_road_s(const PositionRoad* road) { return row(road, 0) + road->lo; }
const double* position_road_z(const PositionRoad* road) { return row(road, 1) + road->lo; }
const double* position_road_at(const PositionRoad* road) { return row(road, 2) + road->lo; }

/* room for n more samples after the live ones */
static int reserve(PositionRoad* road, int n)
{
    int live = road->hi - road->lo, r;
    if (road->hi + n <= road->capacity) return 0;
    if (live + n <= road->capacity) { /* the forgotten columns make the room */
        for (r = 0; r < 3; r++)
            memmove(row(road, r), row(road, r) + road->lo, (size_t)live * sizeof(double));
        road->lo = 0;
        road->hi = live;
        return 0;
    }
    return reallocate(road, 2 * (live + n) + 2 > PR_MIN_CAPACITY ? 2 * (live + n) + 2
                                                                  : PR_MIN_CAPACITY);
}

/* the first live column whose position is at or after x (side "left"), or after x (side
 * "right"): numpy's searchsorted on the live positions, as a column index */
static int search(const PositionRoad* road, double x, int right)
{
    const double* s = row(road, 0);
    int a = road->lo, b = road->hi;
    while (a < b) {
        int mid = a + (b - a) / 2;
        if (right ? s[mid] <= x : s[mid] < x) a = mid + 1;
        else b = mid;
    }
    return a;
}

/* PositionRoad._integrate_from: the running integral again from column k on */
static void integrate_from(PositionRoad* road, int k)
{
    double *s = row(road, 0), *z = row(road, 1), *at = row(road, 2);
    int i;
    if (k <= road->lo) {
        at[road->lo] = 0.0;
        k = road->lo + 1;
    }
    for (i = k; i < road->hi; i++) at[i] = at[i - 1] + 0.5 * (s[i] - s[i - 1]) * (z[i] + z[i - 1]);
}

/* PositionRoad._forget */
static void forget(PositionRoad* road)
{
    int k;
    if (road->hi - road->lo < 2) return;
    k = search(road, row(road, 0)[road->hi - 1] - road->keep_m, 1) - 1;
    road->lo = k > road->lo ? k : road->lo;
}

/* (x, z) pairs in Python's tuple order: by position, then height */
static int before(const double* a, const double* b)
{
    return a[0] < b[0] || (a[0] == b[0] && a[1] < b[1]);
}

int position_road_set(PositionRoad* road, const double* positions, const double* heights, int n)
{
    double* pairs;
    int i, j, first = -1;
    if (n <= 0) return 0;
    pairs = (double*)mem_alloc(road->mem, 2 * (size_t)n, sizeof(double));
    if (pairs == NULL || reserve(road, n) != 0) {
        mem_free(road->mem, pairs);
        return -1;
    }
    for (i = 0; i < n; i++) { /* insertion sort: a host gives a few at a time */
        double pair[2];
        pair[0] = positions[i];
        pair[1] = heights[i];
        for (j = i; j > 0 && before(pair, pairs + 2 * (j - 1)); j--) {
            pairs[2 * j] = pairs[2 * (j - 1)];
            pairs[2 * j + 1] = pairs[2 * (j - 1) + 1];
        }
        pairs[2 * j] = pair[0];
        pairs[2 * j + 1] = pair[1];
    }
    for (i = 0; i < n; i++) {
        double x = pairs[2 * i], height = pairs[2 * i + 1];
        double same = fabs(x) * PR_SAME_POSITION + 1e-12, *s = row(road, 0), *z = row(road, 1);
        int k = search(road, x, 0);
        if (k < road->hi && fabs(s[k] - x) <= same) {
            z[k] = height;
        } else if (k > road->lo && fabs(s[k - 1] - x) <= same) {
            k -= 1;
            z[k] = height;
        } else {
            int r;
            for (r = 0; r < 3; r++)
                memmove(row(road, r) + k + 1, row(road, r) + k,
                        (size_t)(road->hi - k) * sizeof(double));
            s[k] = x;
            z[k] = height;
            road->hi += 1;
        }
        first = first < 0 || k < first ? k : first;
    }
    mem_free(road->mem, pairs);
    integrate_from(road, first);
    forget(road);
    return 0;
}

void position_road_write(const PositionRoad* road, double* out)
{
    int i, r, n = position_road_count(road);
    for (i = 0; i < n; i++)
        for (r = 0; r < 3; r++) out[3 * (size_t)i + r] = row(road, r)[road->lo + i];
}

int position_road_restore(PositionRoad* road, const double* rows, int count)
{
    int i, r;
    if (count > road->capacity) {
        int capacity = 2 * count + 2 > PR_MIN_CAPACITY ? 2 * count + 2 : PR_MIN_CAPACITY;
        double* grown = (double*)mem_alloc(road->mem, 3 * (size_t)capacity, sizeof(double));
        if (grown == NULL) return -1;
        mem_free(road->mem, road->buffer);
        road->buffer = grown;
        road->capacity = capacity;
    }
    for (i = 0; i < count; i++)
        for (r = 0; r < 3; r++) row(road, r)[i] = rows[3 * (size_t)i + r];
    road->lo = 0;
    road->hi = count;
    return 0;
}

int position_road_copy(PositionRoad* to, const PositionRoad* from)
{
    int n = position_road_count(from), r;
    if (n > to->capacity) {
        int capacity = n > PR_MIN_CAPACITY ? n : PR_MIN_CAPACITY;
        double* grown = (double*)mem_alloc(to->mem, 3 * (size_t)capacity, sizeof(double));
        if (grown == NULL) return -1;
        mem_free(to->mem, to->buffer);
        to->buffer = grown;
        to->capacity = capacity;
    }
    for (r = 0; r < 3; r++)
        memcpy(row(to, r), row(from, r) + from->lo, (size_t)n * sizeof(double));
    to->lo = 0;
    to->hi = n;
    to->keep_m = from->keep_m;
    return 0;
}

double position_road_height(const PositionRoad* road, double x)
{
    double height, integral;
    road_samples_at(position_road_s(road), position_road_z(road), position_road_at(road),
                    position_road_count(road), x, &height, &integral);
    return height;
}

void position_road_queries(const PositionRoad* road, int count, double x, double vx,
                           double step_s, double rear_m, double front_m, double spacing_m,
                           double* out)
{
    double rear = x + rear_m, front = x + front_m;
    double reach = front + fabs(vx) * step_s + spacing_m, newest, gap;
    int n = position_road_count(road), i;
    newest = n > 0 ? position_road_s(road)[n - 1] : -HUGE_VAL;
    if (newest >= reach - SPEC_ROAD_QUERY_SLACK_M || n == 0) { /* the zone itself */
        for (i = 0; i < count; i++) out[i] = rear + (front - rear) * (double)i / (count - 1);
        return;
    }
    gap = (reach - newest) / count;
    /* never closer than a share of the points' spacing: a creeping wheel's samples */
    if (gap < SPEC_ROAD_QUERY_FLOOR_SHARE * spacing_m) {
        gap = SPEC_ROAD_QUERY_FLOOR_SHARE * spacing_m;
    }
    for (i = 0; i < count; i++) out[i] = newest + gap * (double)(i + 1);
}
