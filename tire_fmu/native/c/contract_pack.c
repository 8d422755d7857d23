/* contract_pack.c: the native FMU's builder hands its model to the step kernel as a contract
 * (contract.h), the same fields core/contract.py's build_contract fills in Python, from the
 * same quantities: the free ring's modes grouped by order (ring.c), the zone and the static
 * footprint (contact.c), the road windows. Contact points are the zone nodes themselves. */
#include <string.h>

#include "contract_pack.h"
#include "spec.h"

int contract_substep_work(int n_modes, int n_orders, int n_zone, int n_points)
{
    return SPEC_SUBSTEP_WORK_BASE + n_modes + 2 * n_orders * (n_zone / 2 + 1)
           + 3 * n_points * n_points;
}

void contract_free(TireContract* c, const Memory* mem)
{
#define FREE_ARRAY(name) mem_free(mem, (void*)c->name);
    TIRE_CONTRACT_ARRAYS(FREE_ARRAY)
#undef FREE_ARRAY
    memset(c, 0, sizeof *c);
}

#define NEW(field, count) \
    ((c->field = (void*)(field = mem_alloc(mem, (size_t)(count), sizeof *field))) == NULL)

int contract_pack(TireContract* c, const Memory* mem, const Ring* ring, const Zone* zone,
                  const Footprint* fp, const Windows* windows, const double* compliance,
                  double deflection, double substep_s, int linear, double speed,
                  double min_step_s)
{
    int K = ring->n_modes, Z = zone->n_zone, P = Z, rows = ring->rows, cols = ring->cols, j, r;
    int32_t *order_start, *zone_offset, *point_support;
    cx *lam, *beta, *gamma, *eta, *b_rim, *c_rim;
    double *d, *e, *point_weight, *point_cos, *point_sec, *point_x_road, *point_stiffness;
    double *point_damping, *f_static, *pen_static, *window_early_s, *window_late_s;
    double* static_ring_out;
    memset(c, 0, sizeof *c);
    c->version = TIRE_CONTRACT_VERSION;
    c->n_elements = ring->n_elements;
    c->n_orders = ring->n_orders;
    c->n_modes = K;
    c->n_zone = Z;
    c->n_points = P;
    c->n_support = 1;
    c->n_ring_rows = rows;
    c->n_ring_cols = cols;
    c->linear = linear;
    c->centre_point = zone->centre;
    c->substep_work = contract_substep_work(K, ring->n_orders, Z, P);
    c->substep_s = substep_s;
    c->speed_m_s = speed;
    c->static_deflection_m = deflection;
    c->min_step_s = min_step_s;
    if (NEW(order_start, ring->n_orders + 1) || NEW(lam, K) || NEW(beta, K) || NEW(gamma, K) ||
        NEW(eta, K) || NEW(b_rim, K) || NEW(c_rim, 2 * K) || NEW(d, rows * cols) ||
        NEW(e, rows * cols) || NEW(zone_offset, Z) || NEW(point_support, P) ||
        NEW(point_weight, P) || NEW(point_cos, P) || NEW(point_sec, P) || NEW(point_x_road, P) ||
        NEW(point_stiffness, P) || NEW(point_damping, P) || NEW(f_static, P) ||
        NEW(pen_static, P) || NEW(window_early_s, P) || NEW(window_late_s, P) ||
        NEW(static_ring_out, 3)) {
        contract_free(c, mem);
        return -1;
    }
    for (j = 0; j <= ring->n_orders; j++) order_start[j] = ring->order_start[j];
    memcpy(lam, ring->lam, sizeof(cx) * (size_t)K);
    memcpy(beta, ring->beta, sizeof(cx) * (size_t)K);
    memcpy(gamma, ring->gamma, sizeof(cx) * (size_t)K);
    memcpy(eta, ring->eta, sizeof(cx) * (size_t)K);
    for (r = 0; r < ring->rim_count; r++) {  /* order 1's modes: the rim's coupling */
        b_rim[ring->first_rim + r] = ring->b_rim[r];
        c_rim[ring->first_rim + r] = ring->c_rim[0][r];
        c_rim[K + ring->first_rim + r] = ring->c_rim[1][r];
    }
    memcpy(d, ring->d, sizeof(double) * (size_t)(rows * cols));
    memcpy(e, ring->e, sizeof(double) * (size_t)(rows * cols));
    for (j = 0; j < Z; j++) {
        zone_offset[j] = j - zone->half;
        point_support[j] = j;
        point_weight[j] = 1.0;
        point_cos[j] = zone->cos[j];
        point_sec[j] = zone->sec[j];
        point_x_road[j] = -(zone->radius - deflection) * tan(zone->theta[j]);
        point_stiffness[j] = zone->stiffness;
        point_damping[j] = zone->damping;
        f_static[j] = fp->forces[j];
        pen_static[j] = fp->penetration[j];
        window_early_s[j] = windows->early[j];
        window_late_s[j] = windows->late[j];
    }
    for (j = 0; j < Z; j++) {
        static_ring_out[0] += zone->cos[j] * fp->forces[j];
        static_ring_out[1] += zone->sin[j] * fp->forces[j];
        static_ring_out[2] += compliance[zone->centre * Z + j] * fp->forces[j];
    }
    return 0;
}
#undef NEW
