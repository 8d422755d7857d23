/* road_samples.h: a road given by samples along it, read by position (road_samples.c).
 *
 * n samples: distances s (m, strictly increasing), heights z (m) and the running integral at
 * of z from s[0] (m^2, trapezoids: exact for the profile), linear between samples and level at
 * the end heights beyond them; no samples: a level road at 0. A road file (road_file.h's s, z,
 * area) and a host's samples (core/obstacles.py's PositionRoad and HostRoad) are such roads;
 * core/obstacles.py's sampled_reads and sampled_window_reads are this C's arithmetic in numpy.
 * Read by the in-plane tire (inplane_tire_model.c) and by the radial step kernel (kernel.c). */
#ifndef TIRE_ROAD_SAMPLES_H
#define TIRE_ROAD_SAMPLES_H

/* The height (m) and the integral from s[0] (m^2) at x. */
void road_samples_at(const double* s, const double* z, const double* at, int n, double x,
                     double* height, double* integral);

/* The road read over p windows [x_lo + shift, x_hi + shift]: the mean height over each (the
 * height at its rear end where it has no width) and its rate as the road passes at speed,
 * speed (h(hi) - h(lo)) / width (exact for the continuous profile; 0 without width). */
void host_road_window_reads(const double* s, const double* z, const double* at, int n,
                            const double* x_lo, const double* x_hi, int p, double shift,
                            double speed, double* mean, double* rate);
/* The same, the samples searched from *guess (any index; NULL: the middle), where the search
 * ended left there for the next call: the same values, found in a few comparisons when the
 * windows have moved a few samples since. */
void road_samples_window_reads(const double* s, const double* z, const double* at, int n,
                               const double* x_lo, const double* x_hi, int p, double shift,
                               double speed, double* mean, double* rate, int* guess);

#endif
