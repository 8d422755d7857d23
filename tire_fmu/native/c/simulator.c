/* simulator.c: stepping with the unilateral contact (core/contact_dynamics.py).
 *
 * The ring is linear and stepped exactly in its free modal basis with the rim motion and the
 * road's push on each zone node ramped over each substep; the end-of-substep contact forces
 * solve the law with the substep's own interface flexibility W (a primal-dual active-set
 * iteration warm-started from the last set, projected Gauss-Seidel if it cycles). The zone
 * readout and the modal input go through the orders: the DFT of the zone forces at the N/2 + 1
 * orders feeds each mode, the modes of one order sum before the inverse DFT at the zone
 * nodes, so a substep costs O(K + N Z) and no mode x node table is ever formed. */
#include <string.h>

#include "spec.h"
#include "tire.h"

struct SolveEntry {
    char* pattern;     /* Z */
    int size;
    double* inverse;   /* (I - S_AA)^-1, size x size */
};

#define SOLVE_CACHE 32  /* per interface; the inverse is recomputed identically when evicted */

/* -- the orders <-> zone transforms ------------------------------------------------------------ */

/* F_n = sum_j e^{-i n theta_j} x_j for n = 0 .. N/2 */
static void zone_dft(const Ring* ring, const double* x, cx* out)
{
    int n_orders = ring->n_orders, half = ring->half, m, n;
    const double* centre = x + half;
    for (n = 0; n < n_orders; n++) out[n] = cx_make(centre[0], 0.0);
    for (m = 1; m <= half; m++) {
        double even = centre[m] + centre[-m], odd = centre[m] - centre[-m];
        const double* c = ring->cos_nm + (size_t)m * n_orders;
        const double* s = ring->sin_nm + (size_t)m * n_orders;
        if (even == 0.0 && odd == 0.0) continue;  /* nodes off the road push nothing */
        for (n = 0; n < n_orders; n++) {
            out[n].re += c[n] * even;
            out[n].im -= s[n] * odd;
        }
    }
}

/* y_j = sum_n Re(a_n e^{i n theta_j}) at the zone nodes */
static void zone_idft(const Ring* ring, const cx* a, double* y)
{
    int n_orders = ring->n_orders, half = ring->half, m, n;
    double* centre = y + half;
    for (m = 0; m <= half; m++) {
        const double* c = ring->cos_nm + (size_t)m * n_orders;
        const double* s = ring->sin_nm + (size_t)m * n_orders;
        double even = 0.0, odd = 0.0, even2 = 0.0, odd2 = 0.0;
        for (n = 0; n + 1 < n_orders; n += 2) {  /* two sums each: independent chains */
            even += a[n].re * c[n];
            odd += a[n].im * s[n];
            even2 += a[n + 1].re * c[n + 1];
            odd2 += a[n + 1].im * s[n + 1];
        }
        if (n < n_orders) {
            even += a[n].re * c[n];
            odd += a[n].im * s[n];
        }
        even += even2;
        odd += odd2;
        centre[m] = even - odd;
        centre[-m] = even + odd;
    }
}

/* T(delta) = sum_n Re(s_n e^{i n delta dtheta}), delta = -2 half .. 2 half */
static void kernel_toeplitz(const Ring* ring, const cx* s, double* out)
{
    int n_orders = ring->n_orders, half = ring->half, m, n;
    for (m = 0; m <= 2 * half; m++) {
        const double* c = ring->cos_nm + (size_t)m * n_orders;
        const double* si = ring->sin_nm + (size_t)m * n_orders;
        double even = 0.0, odd = 0.0;
        for (n = 0; n < n_orders; n++) {
            even += s[n].re * c[n];
            odd += s[n].im * si[n];
        }
        out[2 * half + m] = even - odd;
        out[2 * half - m] = even + odd;
    }
}

/* -- kernels ------------------------------------------------------------------------------------- */

static void kernel_free(Kernel* k, const Memory* mem, int n_zone)
{
    int i;
    (void)n_zone;
    mem_free(mem, k->decay);
    mem_free(mem, k->beta_c);
    mem_free(mem, k->beta_d);
    mem_free(mem, k->fused);
    mem_free(mem, k->m);
    mem_free(mem, k->out_f);
    mem_free(mem, k->pen_const);
    mem_free(mem, k->rate_const);
    if (k->solves != NULL) {
        for (i = 0; i < k->n_solves; i++) {
            mem_free(mem, k->solves[i].pattern);
            mem_free(mem, k->solves[i].inverse);
        }
        mem_free(mem, k->solves);
    }
    memset(k, 0, sizeof *k);
}

static int interface_alloc(Kernel* k, const Memory* mem, int Z)
{
    k->m = (double*)mem_alloc(mem, (size_t)(3 * Z * Z), sizeof(double));
    k->out_f = (double*)mem_alloc(mem, (size_t)(3 * Z), sizeof(double));
    k->pen_const = (double*)mem_alloc(mem, (size_t)Z, sizeof(double));
    k->rate_const = (double*)mem_alloc(mem, (size_t)Z, sizeof(double));
    k->solves = (SolveEntry*)mem_alloc(mem, SOLVE_CACHE, sizeof(SolveEntry));
    return (k->m && k->out_f && k->pen_const && k->rate_const && k->solves) ? 0 : -1;
}

#define D_AT(ring, row, col) (ring)->d[(size_t)(row) * (size_t)(ring)->cols + (size_t)(col)]
#define E_AT(ring, row, col) (ring)->e[(size_t)(row) * (size_t)(ring)->cols + (size_t)(col)]

/* rows [S; W_p; W_r] of the interface from the ring outputs per unit end force W */
static void interface_rows(const Simulator* sim, Kernel* k, const double* w_w,
                           const double* w_r)
{
    int Z = sim->n_zone, i, l;
    double kj = sim->zone->stiffness, cj = sim->zone->damping;
    for (i = 0; i < Z; i++) {
        double pc = sim->pen_static[i], rc = 0.0;
        for (l = 0; l < Z; l++) {
            double wp = w_w[i * Z + l], wr = w_r[i * Z + l];
            k->m[(size_t)i * Z + l] = kj * wp + cj * wr;
            k->m[(size_t)(Z + i) * Z + l] = wp;
            k->m[(size_t)(2 * Z + i) * Z + l] = wr;
            pc -= wp * sim->f_static[l];
            rc -= wr * sim->f_static[l];
        }
        k->pen_const[i] = pc;
        k->rate_const[i] = rc;
    }
}

static int make_kernel(Simulator* sim, Kernel* k, double h)
{
    const Ring* ring = sim->ring;
    const Memory* mem = sim->mem;
    int K = ring->n_modes, Z = sim->n_zone, half = ring->half, n, j, l, i, r;
    cx* u = sim->orders_a;
    cx* v = sim->orders_b;
    double* tw = sim->work;             /* 4 half + 1 */
    double* tr = tw + (4 * half + 1);   /* 4 half + 1 */
    double* w_w = tr + (4 * half + 1);  /* Z x Z */
    double* w_r = w_w + Z * Z;          /* Z x Z */
    memset(k, 0, sizeof *k);
    k->h = h;
    k->decay = (cx*)mem_alloc(mem, (size_t)K, sizeof(cx));
    k->beta_c = (cx*)mem_alloc(mem, (size_t)K, sizeof(cx));
    k->beta_d = (cx*)mem_alloc(mem, (size_t)K, sizeof(cx));
    k->fused = (cx*)mem_alloc(mem, (size_t)K, sizeof(cx));
    if (!k->decay || !k->beta_c || !k->beta_d || !k->fused || interface_alloc(k, mem, Z) != 0) {
        kernel_free(k, mem, Z);
        return -1;
    }
    for (n = 0; n < ring->n_orders; n++) {
        u[n] = cx_make(0.0, 0.0);
        v[n] = cx_make(0.0, 0.0);
    }
    for (n = 0; n < ring->n_orders; n++) {
        int q;
        for (q = ring->order_start[n]; q < ring->order_start[n + 1]; q++) {
            cx z = cx_scale(ring->lam[q], h), phi1, phi2, hphi2;
            phi_functions(z, SPEC_SERIES_LIMIT, &phi1, &phi2);
            k->decay[q] = cx_exp(z);
            hphi2 = cx_scale(phi2, h);
            k->beta_c[q] = cx_mul(cx_scale(cx_sub(phi1, phi2), h), ring->beta[q]);
            k->beta_d[q] = cx_mul(hphi2, ring->beta[q]);
            k->fused[q] = cx_add(cx_mul(k->decay[q], k->beta_d[q]), k->beta_c[q]);
            u[n] = cx_add(u[n], cx_mul(ring->gamma[q], k->beta_d[q]));
            v[n] = cx_add(v[n], cx_mul(ring->eta[q], k->beta_d[q]));
            if (n == 1) {
                r = q - ring->first_rim;
                k->rim_z[r] = cx_mul(cx_scale(phi1, h), ring->b_rim[r]);
                k->rim_vz[r] = cx_mul(cx_scale(phi2, h * h), ring->b_rim[r]);
            }
        }
    }
    /* W = Re(C g_f) + D_f + E_f / h per unit end force */
    kernel_toeplitz(ring, u, tw);
    kernel_toeplitz(ring, v, tr);
    for (i = 0; i < Z; i++) {
        for (l = 0; l < Z; l++) {
            w_w[i * Z + l] = tw[(i - l) + 2 * half] + D_AT(ring, 3 + i, 1 + l)
                             + E_AT(ring, 3 + i, 1 + l) / h;
            w_r[i * Z + l] = tr[(i - l) + 2 * half] + D_AT(ring, 3 + Z + i, 1 + l)
                             + E_AT(ring, 3 + Z + i, 1 + l) / h;
        }
    }
    for (l = 0; l < Z; l++) {
        double rows[2] = {0.0, 0.0};
        for (r = 0; r < ring->rim_count; r++) {
            int q = ring->first_rim + r;
            /* e^{-i theta_l}: conj of order 1's phase at the node */
            int m = l - half, idx = m < 0 ? -m : m;
            cx p = cx_make(ring->cos_nm[(size_t)idx * ring->n_orders + 1],
                           (m < 0 ? 1.0 : -1.0) * ring->sin_nm[(size_t)idx * ring->n_orders + 1]);
            cx b = cx_mul(k->beta_d[q], p);
            rows[0] += cx_mul(ring->c_rim[0][r], b).re;
            rows[1] += cx_mul(ring->c_rim[1][r], b).re;
        }
        for (j = 0; j < 2; j++) k->out_f[j * Z + l] = rows[j] + D_AT(ring, j, 1 + l)
                                                      + E_AT(ring, j, 1 + l) / h;
        k->out_f[2 * Z + l] = -tw[(0 - (l - half)) + 2 * half] + D_AT(ring, 2, 1 + l)
                              + E_AT(ring, 2, 1 + l) / h;
    }
    interface_rows(sim, k, w_w, w_r);
    return 0;
}

static int instant_kernel(Simulator* sim, Kernel* k)
{
    const Ring* ring = sim->ring;
    int Z = sim->n_zone, i, l;
    double* w_w = sim->work;
    double* w_r = w_w + Z * Z;
    memset(k, 0, sizeof *k);
    if (interface_alloc(k, sim->mem, Z) != 0) {
        kernel_free(k, sim->mem, Z);
        return -1;
    }
    for (i = 0; i < Z; i++) {
        for (l = 0; l < Z; l++) {
            w_w[i * Z + l] = D_AT(ring, 3 + i, 1 + l);
            w_r[i * Z + l] = D_AT(ring, 3 + Z + i, 1 + l);
        }
    }
    for (l = 0; l < Z; l++) {
        for (i = 0; i < 3; i++) k->out_f[i * Z + l] = D_AT(ring, i, 1 + l);
    }
    interface_rows(sim, k, w_w, w_r);
    return 0;
}

/* the communication step h: its substep kernel, from the cache (a step within rounding of a
 * cached one is that step) or made; NULL when out of memory */
static Kernel* step_kernel(Simulator* sim, double h)
{
    int i, slot;
    for (i = 0; i < sim->n_kernels; i++) {
        if (sim->kernels[i].h_comm == h) return &sim->kernels[i];
    }
    for (i = 0; i < sim->n_kernels; i++) {
        if (fabs(h - sim->kernels[i].h_comm) <= SPEC_SAME_POINT_EPS * (fabs(sim_time(sim)) + h)) {
            return &sim->kernels[i];
        }
    }
    {
        Kernel made;
        int n_sub = (int)ceil(h / sim->substep_s * (1 - SPEC_SUBSTEP_SLACK));
        if (n_sub < 1) n_sub = 1;
        if (make_kernel(sim, &made, h / n_sub) != 0) return NULL;
        made.h_comm = h;
        made.n_sub = n_sub;
        if (sim->n_kernels < SPEC_KERNEL_CACHE_SIZE) {
            slot = sim->n_kernels++;
        } else {
            slot = sim->next_kernel;  /* the oldest, unless the last step's end needs it */
            if (&sim->kernels[slot] == sim->last) slot = (slot + 1) % SPEC_KERNEL_CACHE_SIZE;
            sim->next_kernel = (slot + 1) % SPEC_KERNEL_CACHE_SIZE;
            kernel_free(&sim->kernels[slot], sim->mem, sim->n_zone);
        }
        sim->kernels[slot] = made;
        return &sim->kernels[slot];
    }
}

/* -- the contact solve ---------------------------------------------------------------------- */

/* f_A = (I - S_AA)^-1 sigma0_A into f (zeros elsewhere); -1 out of memory or singular */
static int active_solve(Simulator* sim, Kernel* k, const char* active, const double* sigma0,
                        double* f)
{
    int Z = sim->n_zone, a = 0, i, j, e;
    int* index = sim->iwork;
    SolveEntry* entry = NULL;
    for (i = 0; i < Z; i++) {
        f[i] = 0.0;
        if (active[i]) index[a++] = i;
    }
    if (a == 0) return 0;
    for (e = 0; e < k->n_solves; e++) {
        if (memcmp(k->solves[e].pattern, active, (size_t)Z) == 0) {
            entry = &k->solves[e];
            break;
        }
    }
    if (entry == NULL) {
        double* block = sim->work;
        double* scratch = block + Z * Z;
        int* pivot = sim->iwork + Z;
        if (k->n_solves < SOLVE_CACHE) {
            entry = &k->solves[k->n_solves++];
        } else {
            entry = &k->solves[k->next_solve];
            k->next_solve = (k->next_solve + 1) % SOLVE_CACHE;
            mem_free(sim->mem, entry->pattern);
            mem_free(sim->mem, entry->inverse);
        }
        entry->pattern = (char*)mem_alloc(sim->mem, (size_t)Z, 1);
        entry->inverse = (double*)mem_alloc(sim->mem, (size_t)(a * a), sizeof(double));
        entry->size = a;
        if (!entry->pattern || !entry->inverse) {
            mem_free(sim->mem, entry->pattern);
            mem_free(sim->mem, entry->inverse);
            entry->pattern = NULL;
            entry->inverse = NULL;
            k->n_solves--;
            return -1;
        }
        memcpy(entry->pattern, active, (size_t)Z);
        for (i = 0; i < a; i++) {
            for (j = 0; j < a; j++) {
                block[i * a + j] = (i == j ? 1.0 : 0.0) - k->m[(size_t)index[i] * Z + index[j]];
            }
        }
        if (invert(block, a, entry->inverse, scratch, pivot) != 0) {
            /* a singular block: keep the entry usable (zeros) rather than fail the step */
            memset(entry->inverse, 0, sizeof(double) * (size_t)(a * a));
        }
    }
    for (i = 0; i < a; i++) {
        double sum = 0.0;
        for (j = 0; j < a; j++) sum += entry->inverse[i * a + j] * sigma0[index[j]];
        f[index[i]] = sum;
    }
    return 0;
}

/* rows [first, last) of combined = base + M f, over the nonzero entries of f only (the
 * contact forces are zero off the few pushing nodes) */
static void combine(const Simulator* sim, const Kernel* k, const double* base, const double* f,
                    double* combined, int first, int last)
{
    int Z = sim->n_zone, r, l, n = 0;
    int* nonzero = sim->iwork + 2 * Z;
    for (l = 0; l < Z; l++) {
        if (f[l] != 0.0) nonzero[n++] = l;
    }
    for (r = first; r < last; r++) {
        const double* row = k->m + (size_t)r * Z;
        double sum = 0.0;
        for (l = 0; l < n; l++) sum += row[nonzero[l]] * f[nonzero[l]];
        combined[r] = base[r] + sum;
    }
}

static void fallback(Simulator* sim, const Kernel* k, const double* base, double* f)
{
    int Z = sim->n_zone, sweep, j, l;
    const double* s = k->m;
    const double* w_p = k->m + (size_t)Z * Z;
    double* previous = sim->work;
    sim->solver_fallbacks++;
    for (j = 0; j < Z; j++) {
        double total = sim->f_static[j] + sim->df[j];
        f[j] = total > 0.0 ? total : 0.0;
    }
    for (sweep = 0; sweep < SPEC_PGS_SWEEPS; sweep++) {
        double change = 0.0, biggest = 0.0;
        memcpy(previous, f, sizeof(double) * (size_t)Z);
        for (j = 0; j < Z; j++) {
            double pen = base[Z + j], rest = base[j];
            for (l = 0; l < Z; l++) {
                pen += w_p[j * Z + l] * f[l];
                rest += s[j * Z + l] * f[l];
            }
            rest -= s[j * Z + j] * f[j];
            f[j] = pen > 0.0 ? fmax(0.0, rest / (1.0 - s[j * Z + j])) : 0.0;
        }
        for (j = 0; j < Z; j++) {
            if (fabs(f[j] - previous[j]) > change) change = fabs(f[j] - previous[j]);
            if (fabs(f[j]) > biggest) biggest = fabs(f[j]);
        }
        if (change <= SPEC_PGS_TOLERANCE * fmax(1.0, biggest)) break;
    }
    for (j = 0; j < Z; j++) sim->active[j] = (char)(f[j] > 0.0);
}

/* total forces with [sigma; p; p'] = base + M f and the law (or two-sided springs on the
 * static footprint for the linear law); combined (3Z) receives base + M f */
static int solve(Simulator* sim, Kernel* k, const double* base, double* f, double* combined)
{
    int Z = sim->n_zone, iteration, j, limit = SPEC_ACTIVE_SET_PER_NODE * Z + SPEC_ACTIVE_SET_EXTRA;
    char* active = sim->cwork;
    if (sim->linear) {
        if (active_solve(sim, k, sim->static_active, base, f) != 0) return -1;
        combine(sim, k, base, f, combined, 0, 3 * Z);
        return 0;
    }
    memcpy(active, sim->active, (size_t)Z);
    for (iteration = 0; iteration < limit; iteration++) {
        int same = 1;
        if (active_solve(sim, k, active, base, f) != 0) return -1;
        combine(sim, k, base, f, combined, 0, 2 * Z);
        for (j = 0; j < Z; j++) {
            char now = (char)(combined[Z + j] > 0.0 && combined[j] > 0.0);
            if (now != active[j]) same = 0;
            active[j] = now;
        }
        if (same) {
            memcpy(sim->active, active, (size_t)Z);
            combine(sim, k, base, f, combined, 2 * Z, 3 * Z);
            for (j = 0; j < Z; j++) f[j] = fmax(f[j], 0.0);
            return 0;
        }
    }
    fallback(sim, k, base, f);
    combine(sim, k, base, f, combined, 0, 3 * Z);
    return 0;
}

/* -- stepping ------------------------------------------------------------------------------- */

/* q += beta_d DFT(change); with the DFT of df known (ok), it is kept current; returns ok */
static int add_dft_change(Simulator* sim, const Kernel* k, const double* change, int ok)
{
    const Ring* ring = sim->ring;
    cx* F = sim->orders_a;
    int n, q;
    zone_dft(ring, change, F);
    for (n = 0; n < ring->n_orders; n++) {
        for (q = ring->order_start[n]; q < ring->order_start[n + 1]; q++) {
            sim->q[q] = cx_add(sim->q[q], cx_mul(k->beta_d[q], F[n]));
        }
        if (ok) sim->dft[n] = cx_add(sim->dft[n], F[n]);
    }
    return ok;
}

/* scratch layout: [0, 2Z^2 + 4Z) the solve (and kernel making), then the step's arrays */
#define STEP_WORK(sim) ((sim)->work + 2 * (sim)->n_zone * (sim)->n_zone + 4 * (sim)->n_zone)

/* forces at time for the inputs given at time (contact_dynamics.ContactSimulator._start):
 * the last substep's end solved again with the inputs given now */
static int start(Simulator* sim, double z, double vz, const double* heights,
                 const double* slopes)
{
    const Ring* ring = sim->ring;
    const Zone* zone = sim->zone;
    int Z = sim->n_zone, j, i;
    double dz = z - sim->seen_z, dvz = vz - sim->seen_vz;
    double* base = STEP_WORK(sim);  /* 3Z */
    double* f = base + 3 * Z;
    double* change = f + Z;
    double* pen = change + Z;
    double* rate = pen + Z;
    double kj = zone->stiffness, cj = zone->damping;
    Kernel* k = NULL;
    int dft_ok = sim->dft_ok;
    for (j = 0; j < Z; j++) {
        pen[j] = sim->penetration[j] + (D_AT(ring, 3 + j, 0) - zone->sec[j]) * dz
                 + zone->sec[j] * (heights[j] - sim->seen_heights[j]);
        rate[j] = sim->rate[j] + (E_AT(ring, 3 + Z + j, 0) - zone->sec[j]) * dvz
                  + zone->sec[j] * (slopes[j] - sim->seen_slopes[j]);
    }
    for (i = 0; i < 3; i++) sim->ring_out[i] += D_AT(ring, i, 0) * dz + E_AT(ring, i, 0) * dvz;
    if (sim->has_last) k = sim->last;
    else if (!sim->linear && sim->has_instant) k = &sim->instant;
    if (k != NULL) {
        double* combined = sim->work + 2 * Z * Z + Z;  /* the solve's own, free after it */
        for (j = 0; j < Z; j++) {
            change[j] = sim->f_static[j] + sim->df[j];  /* f_old for now */
            base[j] = kj * pen[j] + cj * rate[j];
            base[Z + j] = pen[j];
            base[2 * Z + j] = rate[j];
        }
        {
            double* zero = combined;  /* base - M f_old = (base + M (-f_old)) */
            for (j = 0; j < Z; j++) zero[j] = -change[j];
            combine(sim, k, base, zero, base, 0, 3 * Z);
        }
        if (solve(sim, k, base, f, combined) != 0) return -1;
        for (j = 0; j < Z; j++) change[j] = f[j] - change[j];
        if (sim->has_last) {
            if (sim->pending) {
                /* q + beta_d DFT(df) stays the state: the change enters through the DFT */
                cx* F = sim->orders_a;
                int n;
                zone_dft(ring, change, F);
                for (n = 0; n < ring->n_orders; n++) sim->dft[n] = cx_add(sim->dft[n], F[n]);
            } else {
                dft_ok = add_dft_change(sim, k, change, dft_ok);
            }
        }
        for (i = 0; i < 3; i++) {
            double sum = 0.0;
            for (j = 0; j < Z; j++) sum += k->out_f[i * Z + j] * change[j];
            sim->ring_out[i] += sum;
        }
        for (j = 0; j < Z; j++) {
            pen[j] = combined[Z + j];
            rate[j] = combined[2 * Z + j];
        }
    } else if (sim->linear) {
        for (j = 0; j < Z; j++) {
            f[j] = sim->static_active[j]
                       ? sim->f_static[j] + kj * (pen[j] - sim->pen_static[j]) + cj * rate[j]
                       : 0.0;
        }
    } else {
        for (j = 0; j < Z; j++) {  /* the law at an instant */
            double push = kj * pen[j] + cj * rate[j];
            f[j] = pen[j] > 0.0 ? fmax(push, 0.0) : 0.0;
            sim->active[j] = (char)(f[j] > 0.0);
        }
    }
    for (j = 0; j < Z; j++) {
        sim->df[j] = f[j] - sim->f_static[j];
        sim->penetration[j] = pen[j];
        sim->rate[j] = rate[j];
        sim->seen_heights[j] = heights[j];
        sim->seen_slopes[j] = slopes[j];
    }
    sim->seen_z = z;
    sim->seen_vz = vz;
    sim->dft_ok = sim->pending || (k != NULL && sim->has_last && dft_ok);
    return 0;
}

/* one substep of length k->h with the rim at z moving at vz; the road in sim->heights and
 * sim->slopes, which ramp on into the next substep */
static int substep(Simulator* sim, Kernel* k, double z, double vz)
{
    const Ring* ring = sim->ring;
    const Zone* zone = sim->zone;
    int Z = sim->n_zone, K = ring->n_modes, n, q, j, i, l, rows = ring->rows;
    double h = k->h, kj = zone->stiffness, cj = zone->damping;
    double* base = STEP_WORK(sim);
    double* f = base + 3 * Z;
    double* df_end = f + Z;
    double* y = df_end + 2 * Z;  /* rows: rim_Fz, rim_Fx, deflection, w (Z), rate (Z) */
    double* combined = sim->work + 2 * Z * Z + Z;
    cx* A = sim->orders_a;
    cx* B = sim->orders_b;
    cx* F = sim->dft;
    double rim[2] = {0.0, 0.0}, deflection = 0.0;
    (void)K;
    if (!sim->dft_ok) {
        zone_dft(ring, sim->df, F);
        sim->dft_ok = 1;
    }
    /* the free response at t + h: decay, the rim's ramp, the forces at t held to their ramp */
    if (sim->pending && sim->last != k) {  /* another kernel's ramp: add it first */
        for (n = 0; n < ring->n_orders; n++) {
            for (q = ring->order_start[n]; q < ring->order_start[n + 1]; q++) {
                sim->q[q] = cx_add(sim->q[q], cx_mul(sim->last->beta_d[q], F[n]));
            }
        }
        sim->pending = 0;
    }
    {
        /* one pass: the last ramp (pending) and this one's start forces held to their ramp,
         * decayed, then read at the zone through the orders */
        const cx* into = sim->pending ? k->fused : k->beta_c;
        for (n = 0; n < ring->n_orders; n++) {
            double ar = 0.0, ai = 0.0, br = 0.0, bi = 0.0, fr = F[n].re, fi = F[n].im;
            for (q = ring->order_start[n]; q < ring->order_start[n + 1]; q++) {
                const cx d = k->decay[q], c = into[q], x = sim->q[q];
                const cx g = ring->gamma[q], e = ring->eta[q];
                double vr = d.re * x.re - d.im * x.im + c.re * fr - c.im * fi;
                double vi = d.re * x.im + d.im * x.re + c.re * fi + c.im * fr;
                sim->q[q].re = vr;
                sim->q[q].im = vi;
                ar += g.re * vr - g.im * vi;
                ai += g.re * vi + g.im * vr;
                br += e.re * vr - e.im * vi;
                bi += e.re * vi + e.im * vr;
            }
            A[n] = cx_make(ar, ai);
            B[n] = cx_make(br, bi);
            deflection -= ar;
        }
    }
    for (i = 0; i < ring->rim_count; i++) {
        int m = ring->first_rim + i;
        cx add = cx_add(cx_scale(k->rim_z[i], z), cx_scale(k->rim_vz[i], vz));
        sim->q[m] = cx_add(sim->q[m], add);
        /* its share of the order-1 sums */
        A[1] = cx_add(A[1], cx_mul(ring->gamma[m], add));
        B[1] = cx_add(B[1], cx_mul(ring->eta[m], add));
        deflection -= cx_mul(ring->gamma[m], add).re;
    }
    for (i = 0; i < ring->rim_count; i++) {
        int m = ring->first_rim + i;
        rim[0] += cx_mul(ring->c_rim[0][i], sim->q[m]).re;
        rim[1] += cx_mul(ring->c_rim[1][i], sim->q[m]).re;
    }
    zone_idft(ring, A, y + 3);
    zone_idft(ring, B, y + 3 + Z);
    y[0] = rim[0];
    y[1] = rim[1];
    y[2] = deflection;
    /* direct terms: D r(t + h) + E r' with r = [z + h vz, forces held]; on the forces only
     * when the truncation reaches them */
    for (i = 0; i < rows; i++) {
        y[i] += D_AT(ring, i, 0) * (z + h * vz) + E_AT(ring, i, 0) * vz;
    }
    if (ring->truncated) {
        for (i = 0; i < rows; i++) {
            double sum = 0.0;
            for (l = 0; l < Z; l++) sum += E_AT(ring, i, 1 + l) * sim->df[l];
            y[i] -= sum / h;
        }
    }
    /* the interface at t + h for zero total end forces: [sigma0; p0; p0'] */
    for (j = 0; j < Z; j++) {
        double sec = zone->sec[j];
        double p = y[3 + j] - sec * (z + h * vz) + sec * (sim->heights[j] + h * sim->slopes[j])
                   + k->pen_const[j];
        double r = y[3 + Z + j] - sec * vz + sec * sim->slopes[j] + k->rate_const[j];
        base[j] = kj * p + cj * r;
        base[Z + j] = p;
        base[2 * Z + j] = r;
    }
    if (solve(sim, k, base, f, combined) != 0) return -1;
    for (j = 0; j < Z; j++) df_end[j] = f[j] - sim->f_static[j];
    /* the end forces' ramp into the modes */
    zone_dft(ring, df_end, F);  /* the end forces' ramp: pending until the next pass */
    sim->pending = 1;
    for (i = 0; i < 3; i++) {
        double sum = 0.0;
        for (j = 0; j < Z; j++) sum += k->out_f[i * Z + j] * df_end[j];
        sim->ring_out[i] = y[i] + sum;
    }
    for (j = 0; j < Z; j++) {
        sim->df[j] = df_end[j];
        sim->penetration[j] = combined[Z + j];
        sim->rate[j] = combined[2 * Z + j];
        sim->heights[j] += h * sim->slopes[j];
        sim->seen_heights[j] = sim->heights[j];
        sim->seen_slopes[j] = sim->slopes[j];
    }
    sim->seen_z = z + h * vz;
    sim->seen_vz = vz;
    sim->last = k;
    sim->dft_ok = 1;  /* F holds the DFT of df */
    return 0;
}

static void update_outputs(Simulator* sim)
{
    int Z = sim->n_zone, j;
    double contact = 0.0;
    for (j = 0; j < Z; j++) contact += sim->zone->cos[j] * (sim->f_static[j] + sim->df[j]);
    sim->outputs[0] = sim->static_ring[0] + sim->ring_out[0];
    sim->outputs[1] = sim->static_ring[1] + sim->ring_out[1];
    sim->outputs[2] = contact;
    /* the rim's lowering at the contact centre: the static one, the road's rise under the
     * centre node, less the rim's (the same sum as the core's ContactSimulator.deflection) */
    sim->outputs[3] = sim->static_deflection + sim->seen_heights[sim->zone->centre] - sim->seen_z;
    sim->outputs[4] = sim_contact_length(sim);
    sim->outputs[5] = sim->static_ring[2] + sim->ring_out[2];
}

double sim_time(const Simulator* sim) { return sim->start_time + sim->elapsed; }

double clock_resolved_until(double h)
{
    int exponent;
    frexp(h, &exponent);
    return ldexp(1.0, exponent + 52);
}

int clock_resolves(double time, double h) { return fabs(time) + h < clock_resolved_until(h); }

double sim_contact_length(const Simulator* sim)
{
    int Z = sim->n_zone, j;
    double front, rear;
    char* active = sim->cwork + Z;
    for (j = 0; j < Z; j++) active[j] = (char)(sim->f_static[j] + sim->df[j] > 0.0);
    footprint_edges(sim->x_road, sim->penetration, active, Z, &front, &rear);
    return front - rear;
}

int sim_in_contact(const Simulator* sim) { return sim->outputs[2] > 0.0; }

int sim_at_zone_edge(const Simulator* sim)
{
    int Z = sim->n_zone;
    return sim->df[0] > -sim->f_static[0] || sim->df[Z - 1] > -sim->f_static[Z - 1];
}

int sim_step(Simulator* sim, double h, const double inputs[4])
{
    Kernel* k = step_kernel(sim, h);
    int i;
    if (k == NULL) return -1;
    if (road_read(&sim->road, sim->mem, sim->elapsed, inputs[2], inputs[3], h, sim->heights,
                  sim->slopes) != 0) {
        return -1;
    }
    if (start(sim, inputs[0], inputs[1], sim->heights, sim->slopes) != 0) return -1;
    for (i = 0; i < k->n_sub; i++) {
        if (substep(sim, k, inputs[0] + i * k->h * inputs[1], inputs[1]) != 0) return -1;
    }
    {   /* elapsed += h, compensated (core/clock.py: advance) */
        double y = h - sim->carry, total = sim->elapsed + y;
        sim->carry = (total - sim->elapsed) - y;
        sim->elapsed = total;
    }
    sim->last_step = h;
    sim->has_last = 1;
    update_outputs(sim);
    return 0;
}

int sim_outputs_with(Simulator* sim, const double inputs[4])
{
    double h = sim->has_last ? sim->last_step : NAN;
    if (road_read(&sim->road, sim->mem, sim->elapsed, inputs[2], inputs[3], h, sim->heights,
                  sim->slopes) != 0) {
        return -1;
    }
    if (start(sim, inputs[0], inputs[1], sim->heights, sim->slopes) != 0) return -1;
    update_outputs(sim);
    return 0;
}

/* q with the pending ramp added (the state the core's simulator holds) */
void sim_settle(Simulator* sim)
{
    const Ring* ring = sim->ring;
    int n, q;
    if (!sim->pending) return;
    for (n = 0; n < ring->n_orders; n++) {
        for (q = ring->order_start[n]; q < ring->order_start[n + 1]; q++) {
            sim->q[q] = cx_add(sim->q[q], cx_mul(sim->last->beta_d[q], sim->dft[n]));
        }
    }
    sim->pending = 0;
}

/* the kernel of a restored state's last step (set_state: self._kernel(last_step_s).last) */
int sim_restore_last(Simulator* sim)
{
    if (!sim->has_last) {
        sim->last = NULL;
        return 0;
    }
    sim->last = step_kernel(sim, sim->last_step);
    return sim->last != NULL ? 0 : -1;
}

void sim_reset(Simulator* sim, double start_time)
{
    int Z = sim->n_zone, K = sim->ring->n_modes, j;
    sim->start_time = start_time;
    sim->elapsed = 0.0;
    sim->carry = 0.0;
    for (j = 0; j < K; j++) sim->q[j] = cx_make(0.0, 0.0);
    for (j = 0; j < Z; j++) {
        sim->df[j] = 0.0;
        sim->active[j] = sim->static_active[j];
        sim->penetration[j] = sim->pen_static[j];
        sim->rate[j] = 0.0;
        sim->seen_heights[j] = 0.0;
        sim->seen_slopes[j] = 0.0;
    }
    sim->seen_z = sim->seen_vz = 0.0;
    sim->ring_out[0] = sim->ring_out[1] = sim->ring_out[2] = 0.0;
    sim->last = NULL;
    sim->has_last = 0;
    sim->last_step = 0.0;
    sim->dft_ok = 0;
    sim->pending = 0;
    road_reset(&sim->road, sim->mem);
    sim->road.origin = start_time;
    update_outputs(sim);
}

int sim_init(Simulator* sim, const Memory* mem, const Ring* ring, const Zone* zone,
             const Footprint* fp, const Windows* windows, const double* compliance,
             double deflection, double k_cw, double rhoA, int linear)
{
    int Z = zone->n_zone, K = ring->n_modes, j, l;
    size_t work = (size_t)(2 * Z * Z + 4 * Z + 9 * Z + 8);
    memset(sim, 0, sizeof *sim);
    sim->ring = ring;
    sim->zone = zone;
    sim->mem = mem;
    sim->n_zone = Z;
    sim->linear = linear;
    sim->substep_s = fmin(SPEC_MAX_SUBSTEP_S, 1.0 / sqrt(k_cw / rhoA));
#define ALLOC(field, count, type) \
    (sim->field = (type*)mem_alloc(mem, (size_t)(count), sizeof(type))) == NULL
    if (ALLOC(f_static, Z, double) || ALLOC(pen_static, Z, double) ||
        ALLOC(static_active, Z, char) || ALLOC(x_road, Z, double) || ALLOC(q, K, cx) ||
        ALLOC(df, Z, double) || ALLOC(active, Z, char) || ALLOC(penetration, Z, double) ||
        ALLOC(rate, Z, double) || ALLOC(seen_heights, Z, double) ||
        ALLOC(seen_slopes, Z, double) || ALLOC(kernels, SPEC_KERNEL_CACHE_SIZE, Kernel) ||
        ALLOC(dft, ring->n_orders, cx) || ALLOC(work, work, double) || ALLOC(iwork, 3 * Z, int) ||
        ALLOC(cwork, 2 * Z, char) || ALLOC(orders_a, ring->n_orders, cx) ||
        ALLOC(orders_b, ring->n_orders, cx) || ALLOC(heights, Z, double) ||
        ALLOC(slopes, Z, double)) {
        sim_free(sim);
        return -1;
    }
#undef ALLOC
    for (j = 0; j < Z; j++) {
        sim->f_static[j] = fp->forces[j];
        sim->pen_static[j] = fp->penetration[j];
        sim->static_active[j] = (char)(fp->forces[j] > 0.0);
        sim->x_road[j] = -(zone->radius - deflection) * tan(zone->theta[j]);
    }
    sim->static_ring[0] = sim->static_ring[1] = sim->static_ring[2] = 0.0;
    sim->static_deflection = deflection;
    for (j = 0; j < Z; j++) {
        sim->static_ring[0] += zone->cos[j] * fp->forces[j];
        sim->static_ring[1] += zone->sin[j] * fp->forces[j];
    }
    for (l = 0; l < Z; l++) sim->static_ring[2] += compliance[zone->centre * Z + l] * fp->forces[l];
    if (ring->truncated) {
        if (instant_kernel(sim, &sim->instant) != 0) {
            sim_free(sim);
            return -1;
        }
        sim->has_instant = 1;
    }
    road_init(&sim->road, mem, windows, Z);
    sim_reset(sim, 0.0);
    return 0;
}

void sim_free(Simulator* sim)
{
    const Memory* mem = sim->mem;
    int i;
    if (mem == NULL) return;
    if (sim->kernels != NULL) {
        for (i = 0; i < sim->n_kernels; i++) kernel_free(&sim->kernels[i], mem, sim->n_zone);
    }
    if (sim->has_instant) kernel_free(&sim->instant, mem, sim->n_zone);
    road_free(&sim->road, mem);
    mem_free(mem, sim->f_static);
    mem_free(mem, sim->pen_static);
    mem_free(mem, sim->static_active);
    mem_free(mem, sim->x_road);
    mem_free(mem, sim->q);
    mem_free(mem, sim->df);
    mem_free(mem, sim->active);
    mem_free(mem, sim->penetration);
    mem_free(mem, sim->rate);
    mem_free(mem, sim->seen_heights);
    mem_free(mem, sim->seen_slopes);
    mem_free(mem, sim->kernels);
    mem_free(mem, sim->dft);
    mem_free(mem, sim->work);
    mem_free(mem, sim->iwork);
    mem_free(mem, sim->cwork);
    mem_free(mem, sim->orders_a);
    mem_free(mem, sim->orders_b);
    mem_free(mem, sim->heights);
    mem_free(mem, sim->slopes);
    memset(sim, 0, sizeof *sim);
}
