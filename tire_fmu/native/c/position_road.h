/* position_road.h: the road a host gives by samples at positions along it (position_road.c),
 * the C of core/obstacles.py's PositionRoad, with its arithmetic: a sample at a position
 * already held (within PR_SAME_POSITION of it, relative, or 1e-12 m) replaces its height, one
 * between held positions is inserted, the running integral (trapezoids) is taken again from
 * the first sample a call changed, and samples further behind the newest than keep_m are
 * forgotten (the one just before that reach is kept). Read as road_samples.h reads a sampled
 * road: linear between samples, level at the end heights beyond them.
 *
 * The live samples are s[0..n), z[0..n), at[0..n) (position_road_s/z/at, n =
 * position_road_count); the arrays move when the road grows, so read them after each change. */
#ifndef TIRE_POSITION_ROAD_H
#define TIRE_POSITION_ROAD_H

#include "tire.h"

/* PositionRoad.SAME_POSITION */
#define PR_SAME_POSITION 1e-12

typedef struct {
    const Memory* mem;
    double keep_m;
    double* buffer; /* rows s, z, at of capacity each; live columns [lo, hi) */
    int capacity, lo, hi;
} PositionRoad;

/* An empty road keeping keep_m (m) behind its newest sample; 0, or -1 out of memory. */
int position_road_init(PositionRoad* road, const Memory* mem, double keep_m);
void position_road_free(PositionRoad* road);

/* PositionRoad.set_samples: n heights (m) at these positions (m, any order); 0, or -1 out of
 * memory (the road is then as it was). */
int position_road_set(PositionRoad* road, const double* positions, const double* heights,
                      int n);

int position_road_count(const PositionRoad* road);
const double* position_road_s(const PositionRoad* road);
const double* position_road_z(const PositionRoad* road);
const double* position_road_at(const PositionRoad* road);

/* PositionRoad.state: the samples as rows (s, z, at), count x 3, into out. */
void position_road_write(const PositionRoad* road, double* out);
/* PositionRoad.restore: count rows (s, z, at) as position_road_write wrote them; 0, or -1 out
 * of memory (the road is then as it was). */
int position_road_restore(PositionRoad* road, const double* rows, int count);
/* to := from's samples (keep_m too); 0, or -1 out of memory (to is then as it was). */
int position_road_copy(PositionRoad* to, const PositionRoad* from);

/* core/wheel_centre.py's road_queries: where a tire needs its host's road next, count
 * positions into out, for the wheel centre at x moving at vx over a step of step_s, its
 * contact zone from rear_m to front_m about it, its points spacing_m apart, the samples held
 * in road. */
void position_road_queries(const PositionRoad* road, int count, double x, double vx,
                           double step_s, double rear_m, double front_m, double spacing_m,
                           double* out);

/* The height (m) at x (m): 0 with no samples. */
double position_road_height(const PositionRoad* road, double x);

#endif
