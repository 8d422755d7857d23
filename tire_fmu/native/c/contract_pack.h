/* contract_pack.h: the native FMU's model as a step contract (contract_pack.c). */
#ifndef TIRE_CONTRACT_PACK_H
#define TIRE_CONTRACT_PACK_H

#include "tire.h" /* numerics.h first: contract.h uses its types */
#include "contract.h"

/* fill c (its arrays allocated with mem); 0, or -1 out of memory (nothing allocated then) */
int contract_pack(TireContract* c, const Memory* mem, const Ring* ring, const Zone* zone,
                  const Footprint* fp, const Windows* windows, const double* compliance,
                  double deflection, double substep_s, int linear, double speed,
                  double min_step_s);
/* the work of one sub-step of the kernel (units: core/step_limits.py substep_work); truncated:
 * a ring truncated with static correction (its rate term reads the held forces) */
int contract_substep_work(int n_modes, int n_orders, int n_zone, int n_points, int n_support,
                          int truncated);
/* free the arrays of a packed contract */
void contract_free(TireContract* c, const Memory* mem);

#endif
