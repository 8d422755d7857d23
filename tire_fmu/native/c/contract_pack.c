/* contract_pack.c: the native FMU's builder hands its model to the step kernel as a contract
 * (contract.h), the same fields core/contract.py's build_contract fills in Python, from the
 * same quantities: the free ring's modes grouped by order (ring.c), the zone, its contact
 * points and the static footprint on them (contact.c), the points' road windows (by time and
 * by position). */
#include <string.h>

#include "contract_pack.h"
#include "spec.h"

int contract_substep_work(int n_modes, int n_orders, int n_zone, int n_points, int n_support,
                          int truncated)
{
    return SPEC_SUBSTEP_WORK_BASE + SPEC_SUBSTEP_WORK_PER_MODE * n_modes
           + SPEC_SUBSTEP_WORK_PER_ORDER_NODE * n_orders * (n_zone / 2 + 1)
           + SPEC_SUBSTEP_WORK_PER_SUPPORT * n_points * n_support
           + SPEC_SUBSTEP_WORK_PER_POINT * n_points
           + SPEC_SUBSTEP_WORK_PER_NODE_PAIR * n_zone * n_zone
           + (truncated ? SPEC_SUBSTEP_WORK_PER_RATE_ENTRY * (3 + 2 * n_zone) * n_zone : 0);
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
    int K = ring->n_modes, Z = zone->n_zone, P = zone->n_points, S = zone->n_support;
    int rows = ring->rows, cols = ring->cols, j, r, p, s;
    int32_t *order_start, *zone_offset, *point_support;
    cx *lam, *beta, *gamma, *eta, *b_rim, *c_rim;
    double *d, *e, *point_weight, *point_cos, *point_sec, *point_x_road, *point_stiffness;
    double *point_damping, *f_static, *pen_static, *window_early_s, *window_late_s;
    double *window_lo_m, *window_hi_m, *static_ring_out;
    /* each point's arc [theta_p -+ dtheta / 2m] on the road, as contact.c's windows_build */
    double height = zone->radius - deflection, half = 0.5 * zone->dtheta / zone->per_node;
    memset(c, 0, sizeof *c);
    c->version = TIRE_CONTRACT_VERSION;
    c->n_elements = ring->n_elements;
    c->n_orders = ring->n_orders;
    c->n_modes = K;
    c->n_zone = Z;
    c->n_points = P;
    c->n_support = S;
    c->n_ring_rows = rows;
    c->n_ring_cols = cols;
    c->linear = linear;
    c->centre_point = zone->centre_point;
    c->substep_work = contract_substep_work(K, ring->n_orders, Z, P, S, ring->truncated);
    c->substep_s = substep_s;
    c->speed_m_s = speed;
    c->static_deflection_m = deflection;
    c->min_step_s = min_step_s;
    if (NEW(order_start, ring->n_orders + 1) || NEW(lam, K) || NEW(beta, K) || NEW(gamma, K) ||
        NEW(eta, K) || NEW(b_rim, K) || NEW(c_rim, 2 * K) || NEW(d, rows * cols) ||
        NEW(e, rows * cols) || NEW(zone_offset, Z) || NEW(point_support, P * S) ||
        NEW(point_weight, P * S) || NEW(point_cos, P) || NEW(point_sec, P) || NEW(point_x_road, P) ||
        NEW(point_stiffness, P) || NEW(point_damping, P) || NEW(f_static, P) ||
        NEW(pen_static, P) || NEW(window_early_s, P) || NEW(window_late_s, P) ||
        NEW(window_lo_m, P) || NEW(window_hi_m, P) || NEW(static_ring_out, 3)) {
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
    for (j = 0; j < Z; j++) zone_offset[j] = j - zone->half;
    for (j = 0; j < P * S; j++) {
        point_support[j] = zone->support[j];
        point_weight[j] = zone->weight[j];
    }
    for (p = 0; p < P; p++) {
        point_cos[p] = zone->load_cos[p];
        point_sec[p] = zone->sec[p];
        point_x_road[p] = -(zone->radius - deflection) * tan(zone->point_theta[p]);
        point_stiffness[p] = zone->stiffness;
        point_damping[p] = zone->damping;
        f_static[p] = fp->forces[p];
        pen_static[p] = fp->penetration[p];
        window_early_s[p] = windows->early[p];
        window_late_s[p] = windows->late[p];
        window_lo_m[p] = -height * tan(zone->point_theta[p] + half);
        window_hi_m[p] = -height * tan(zone->point_theta[p] - half);
    }
    /* the static outputs: the points' forces on the rim and the tread's compression at the
     * centre node, (G I^T f)_centre */
    for (p = 0; p < P; p++) {
        static_ring_out[0] += zone->load_cos[p] * fp->forces[p];
        static_ring_out[1] += zone->load_sin[p] * fp->forces[p];
        if (fp->forces[p] == 0.0) continue;
        for (s = 0; s < S; s++) {
            static_ring_out[2] += compliance[zone->centre * Z + zone->support[p * S + s]]
                                  * (zone->weight[p * S + s] * fp->forces[p]);
        }
    }
    return 0;
}
#undef NEW
