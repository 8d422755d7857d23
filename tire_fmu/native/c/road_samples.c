/* road_samples.c: a road given by samples along it, read by position (road_samples.h).
 *
 * A window read finds the segment of each of its ends from the one found before (the points'
 * windows follow one another along the road, and a substep moves them a few samples): a
 * search that gallops out from the guess and halves back finds the segment the plain binary
 * search finds, in a few comparisons instead of log2(n). */
#include <stddef.h>

#include "road_samples.h"

/* The last sample at or before x (numpy's searchsorted(s, x, "right") - 1) kept within
 * [0, n - 2], found from the guess (n >= 2). */
static int segment(const double* s, int n, double x, int guess)
{
    /* lo: a sample at or before x, or -1; hi: one after it, or n */
    int lo, hi, step = 1;
    if (guess < 0) guess = 0;
    if (guess > n - 2) guess = n - 2;
    if (s[guess] <= x) {
        lo = guess;
        hi = guess + 1;
        while (hi < n && s[hi] <= x) {
            lo = hi;
            hi = step < n - lo ? lo + step : n;
            step *= 2;
        }
    } else {
        hi = guess;
        lo = guess - 1;
        while (lo >= 0 && s[lo] > x) {
            hi = lo;
            lo = step <= hi ? hi - step : -1;
            step *= 2;
        }
    }
    while (hi - lo > 1) {
        int mid = lo + (hi - lo) / 2;
        if (s[mid] <= x) lo = mid;
        else hi = mid;
    }
    if (lo < 0) lo = 0;
    if (lo > n - 2) lo = n - 2;
    return lo;
}

/* road_samples_at on segment k of at least two samples */
static void read_on(const double* s, const double* z, const double* at, int n, int k, double x,
                    double* height, double* integral)
{
    double slope = (z[k + 1] - z[k]) / (s[k + 1] - s[k]);
    double inside = x < s[0] ? s[0] : (x > s[n - 1] ? s[n - 1] : x);
    double past = inside - s[k];
    *height = z[k] + slope * past;
    *integral = at[k] + (z[k] + 0.5 * slope * past) * past + (x - inside) * *height;
}

void road_samples_at(const double* s, const double* z, const double* at, int n, double x,
                     double* height, double* integral)
{
    if (n < 2) {
        double level = n ? z[0] : 0.0;
        *height = level;
        *integral = level * (x - (n ? s[0] : 0.0));
        return;
    }
    read_on(s, z, at, n, segment(s, n, x, n / 2), x, height, integral);
}

void road_samples_window_reads(const double* s, const double* z, const double* at, int n,
                               const double* x_lo, const double* x_hi, int p, double shift,
                               double speed, double* mean, double* rate, int* guess)
{
    int k = guess != NULL ? *guess : n / 2;
    for (int i = 0; i < p; ++i) {
        double a = x_lo[i] + shift, b = x_hi[i] + shift, ha, ia, hb, ib;
        if (n < 2) {
            road_samples_at(s, z, at, n, a, &ha, &ia);
            road_samples_at(s, z, at, n, b, &hb, &ib);
        } else {
            k = segment(s, n, a, k);
            read_on(s, z, at, n, k, a, &ha, &ia);
            k = segment(s, n, b, k);
            read_on(s, z, at, n, k, b, &hb, &ib);
        }
        double width = b - a, safe = width > 0.0 ? width : 1.0;
        mean[i] = width > 0.0 ? (ib - ia) / safe : ha;
        rate[i] = speed * (hb - ha) / safe;
    }
    if (guess != NULL) *guess = k;
}

void host_road_window_reads(const double* s, const double* z, const double* at, int n,
                            const double* x_lo, const double* x_hi, int p, double shift,
                            double speed, double* mean, double* rate)
{
    road_samples_window_reads(s, z, at, n, x_lo, x_hi, p, shift, speed, mean, rate, NULL);
}
