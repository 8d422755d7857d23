/* inplane_tire_model.c: the in-plane tire (tangential tread motion, the wheel's rotation,
 * friction in the footprint) as a model of the generic FMI layer (model.h): the native twin of
 * the Python FMU TireInPlane (tire_fmu/fmu/inplane_slave.py), with its variables.
 *
 * At initialisation the parameters are checked as core/inplane_host.py's build_host_stepper
 * checks them, in its order and words (every problem of the data at once; then the critical
 * speed, which needs the tire; then what needs the built model: the deflection and the
 * footprint against the zone), and the model is built by one call, inplane_model_build; the
 * road is the road_file's (road_file.c, refused naming road_file, the path and what is wrong,
 * with the other problems) or the host's (position_road.c). Each step then does what
 * core/inplane_contact.py's InPlaneStepper.advance_wheel and advance do, line for line: the
 * host's road samples taken in (road_z_i at the road_x_i last asked for), the wheel centre
 * mapped onto the rim's deviations from the origin (its position and the road's height under
 * it at the first step), the host's values taken as those at the step's start (the rim's jump
 * from where the last step's extension left it taken off the tire's coordinates), extended
 * over the step along their rates and the rates' last change (input_path), cut into the
 * tire's own steps (substeps: whole step_size steps, or equal shorter ones ending exactly at
 * t + h), a free wheel's step following its spin (_follow_spin: the tread's terms rebuilt when
 * the spin has moved by SPEC_INPLANE_SPIN_REBUILD_FRACTION, the ring's by
 * SPEC_INPLANE_RING_REBUILD_FRACTION), the road read by position under every contact point
 * at each of them (road_samples.c), and inplane_step.c's step. A step whose sets do not
 * settle is undone and refused (MODEL_DISCARD), as the Python FMU rolls back. The outputs
 * are the Python FMU's (_show_outputs: the stepper's wheel_outputs and road_queries). The FMU
 * state's model part is the Python stepper's state bytes (INPLANE3) after the layer's two
 * flags. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "inplane_critical.h"
#include "inplane_model.h"
#include "inplane_static.h"
#include "inplane_step.h"
#include "model.h"
#include "model_problems.h"
#include "position_road.h"
#include "road_file.h"
#include "road_samples.h"
#include "spec.h"

#define MESSAGE_SIZE 1024
#define FLAGS SPEC_STATE_MODEL_FLAGS
/* the host road's heights a step takes (road_z_i at road_x_i) */
#define ROAD_QUERIES SPEC_ROAD_QUERIES
/* below this spin (rad/s) the effective rolling radius is R (InPlaneStepper.wheel_outputs) */
#define SPIN_AT_REST_RAD_S 1e-9

/* the stepper part of a state (core/inplane_contact.py's STEPPER_STATE_HEAD "<8sIIIqII":
 * magic, coordinates, points, road samples, steps taken, the tire's absolute DOFs, its basis'
 * fingerprint) */
#define STEPPER_MAGIC "INPLANE3"
#define STEPPER_HEAD (8 + 4 + 4 + 4 + 8 + 4 + 4)
/* given (6), rim (6), spin, road speed, the ring's spin, the wheel_rate given, the last host
 * step, the elapsed time, its carry, the tire's step length, the rates' last change (3) and
 * the step it was made over, the origin (position, road height; NaN before the first step)
 * (STEPPER_SCALARS in the core) */
#define STEPPER_SCALARS 26
#define ORIGIN_AT 24

struct Model {
    ModelHost host;
    int built;
    double built_for[SPEC_N_VARIABLES];
    InPlaneModel m;   /* every matrix, built by inplane_model_build */
    InPlaneStep step; /* what inplane_step reads: pointers into m */
    int ny, np, nr, free_spin, driven, hysteretic;
    double h, radius, speed, critical;
    /* the running limits (InPlaneStepper's): spin (rad/s), road speed (m/s), force (N) */
    double spin_limit, speed_limit, force_limit, load;
    double* cos_theta;    /* np: the points' cos theta (for the slip's reference s0) */
    double *x_lo, *x_hi;  /* np: the road each point's arc covers (m, at the deflection) */
    double *height, *rate;
    double* rim_rows;     /* 7 x 3 x ny: the rim's rows k0 k1 k2 kh c0 c1 m on the coordinates */
    double* projection;   /* ny x 2: translation_projection, M^-1 (to_abs^T M P) */
    uint32_t fingerprint; /* basis_fingerprint: CRC-32 of to_abs, (n_dof + 3) x ny */
    double* work;
    int* iwork;
    double* build_work;
    int* build_iwork;
    /* the state (now), the step's result (next) and the step's checkpoint (saved) */
    InPlaneState now, next, saved;
    double* state_doubles;
    int* state_ints;
    long long steps, saved_steps;
    /* the host's values at the last communication point (x, vx, z, vz, road z, road vz), the
     * wheel_rate given there, the host step that followed (0 before the first), the tire's
     * elapsed time and its Kahan carry; the rim at the last step's end */
    double given[6], rim[6], saved_given[6], saved_rim[6];
    double rate_given, h_given, elapsed, carry, saved_clock[5];
    double accel[3], h_accel, saved_accel[4]; /* the rates' last change and its step */
    double spin_now, speed_now, saved_spin, saved_speed, saved_ring_spin;
    /* the road: the road_file's (file_open; its path as given, for the warning), else the
     * host's samples (road); the segment a read found last (where the next starts) */
    RoadFile file;
    int file_open;
    char* road_path;
    PositionRoad road, saved_road;
    int road_guess;
    /* the wheel-centre mode's origin (the wheel's position and the road's height under it at
     * the first step; NaN before it), the contact points' reach behind and ahead of the
     * wheel centre (m), the contact_point_spacing (m), whether the extent warning may be said */
    double origin[2], saved_origin[2];
    double rear_m, front_m, spacing_m;
    int extent_armed;
    double start_time;
    int in_contact;
    char refusal[MESSAGE_SIZE];
};

static void say(const Model* model, int status, const char* category, const char* text)
{
    if (model->host.log != NULL) model->host.log(model->host.layer, status, category, text);
}

Model* model_create(const ModelHost* host)
{
    Model* model = (Model*)mem_alloc(&host->mem, 1, sizeof(Model));
    if (model == NULL) return NULL;
    memset(model, 0, sizeof *model);
    model->host = *host;
    return model;
}

static void model_clear(Model* model)
{
    const Memory* mem = &model->host.mem;
    void* owned[] = {model->cos_theta, model->x_lo, model->x_hi, model->height, model->rate,
                     model->rim_rows, model->projection, model->work, model->iwork, model->build_work,
                     model->build_iwork, model->state_doubles, model->state_ints, model->road_path};
    size_t i;
    inplane_model_free(&model->m);
    for (i = 0; i < sizeof owned / sizeof owned[0]; i++) mem_free(mem, owned[i]);
    if (model->file_open) road_file_free(&model->file);
    position_road_free(&model->road);
    position_road_free(&model->saved_road);
    {
        ModelHost host = model->host;
        memset(model, 0, sizeof *model);
        model->host = host;
    }
}

void model_destroy(Model* model)
{
    Memory mem;
    if (model == NULL) return;
    mem = model->host.mem;
    model_clear(model);
    mem_free(&mem, model);
}

void model_preview(const double* values, double* out_values)
{
    /* before initialisation the forces echo the static load (a load that is no number is not
     * echoed: no output is ever non-finite) */
    double load = values[SPEC_VR_LOAD];
    if (!isfinite(load)) return;
    out_values[SPEC_VR_RIM_FZ] = load;
    out_values[SPEC_VR_CONTACT_FZ] = load;
    out_values[SPEC_VR_IN_CONTACT] = load > 0 ? 1.0 : 0.0;
}

/* -- the problems, in the core's words ------------------------------------------------------- */

static double value_of(const double* values, const char* name)
{
    int vr = variable_index(name);
    return vr < 0 ? NAN : values[vr];
}

/* "a number in [low, high] unit" (core/inplane.py's tangential_problems) */
static void range_words(const SpecRange* r, char* out, size_t size)
{
    snprintf(out, size, "%s in [%g, %g]%s%s", r->integer ? "an integer" : "a number", r->low,
             r->high, r->unit[0] ? " " : "", r->unit);
}

static int outside(const SpecRange* r, double value)
{
    return !(isfinite(value) && r->low <= value && value <= r->high &&
             (!r->integer || value == floor(value)));
}

/* the load's problem when the static footprint is not found (inplane_host.footprint_problem:
 * the secant or the contact set of inplane_static.c refused, at rest or at the speed) */
static void footprint_problem(const double* values, Problems* p)
{
    char allowed[256], reason[512], k_cw[64];
    value_text(values[SPEC_VR_K_CW], "N/m^2", k_cw, sizeof k_cw);
    snprintf(allowed, sizeof allowed, "%s", SPEC_MSG_INPLANE_FOOTPRINT_ALLOWED);
    snprintf(reason, sizeof reason, SPEC_MSG_INPLANE_FOOTPRINT_REASON, k_cw,
             (int)values[SPEC_VR_N_ELEMENTS]);
    add_problem(p, "load", values[SPEC_VR_LOAD], "N", allowed, reason);
}

/* settings_problems of core/inplane_host.py: the tire data (parameters.tire_problems), the
 * tangential data (inplane.tangential_problems), the operating point (HOST_FIELDS), with
 * none of those the contact zone on the mesh, and then what InPlaneTire refuses */
static void data_problems(const double* values, Problems* p)
{
    char allowed[160];
    int field;
    double radius = values[SPEC_VR_R];
    tire_field_problems(values, p);
    for (field = 0; field < SPEC_N_TANGENTIAL_FIELDS; field++) {
        const SpecRange* r = &SPEC_TANGENTIAL_FIELDS[field];
        double value = value_of(values, r->name);
        if (outside(r, value)) {
            range_words(r, allowed, sizeof allowed);
            add_problem(p, r->name, value, r->unit, allowed, "");
        }
    }
    if (isfinite(values[SPEC_VR_RIM_RADIUS_M]) && values[SPEC_VR_RIM_RADIUS_M] >= radius) {
        snprintf(allowed, sizeof allowed, "below the tread radius R = %g m", radius);
        add_problem(p, "rim_radius_m", values[SPEC_VR_RIM_RADIUS_M], "m", allowed,
                    "the sidewall spans from the rim to the tread");
    }
    field_problems(SPEC_INPLANE_FIELDS, SPEC_N_INPLANE_FIELDS, values, p);
    if (p->count == 0) {
        /* the contact zone on this mesh, as the radial FMU's (contact.zone_problems) */
        int n = (int)values[SPEC_VR_N_ELEMENTS], per_node;
        double length = values[SPEC_VR_CONTACT_ZONE_LENGTH];
        if (!zone_length_problem(radius, n, length, p))
            point_count_problem(radius, n, zone_half_count(radius, n, length),
                                values[SPEC_VR_CONTACT_POINT_SPACING], &per_node, p);
    }
    if (p->count == 0 && values[SPEC_VR_SIDEWALL_SHEAR] > 0.0) {
        add_problem(p, "sidewall_shear", values[SPEC_VR_SIDEWALL_SHEAR], "N",
                    "0 for the in-plane ring",
                    "its sidewall masses have no circumferential coupling; to move the "
                    "sidewall's band out of the high orders tie it instead (sidewall_max_order, "
                    "e.g. 8)");
    }
}

static void ring_data_of(const double* values, InPlaneRingData* d)
{
    d->R = values[SPEC_VR_R];
    d->b = values[SPEC_VR_B];
    d->inflation_pressure = values[SPEC_VR_INFLATION_PRESSURE];
    d->rhoA = values[SPEC_VR_RHOA];
    d->m_s = values[SPEC_VR_M_S];
    d->k_r1 = values[SPEC_VR_K_R1];
    d->k_r2 = values[SPEC_VR_K_R2];
    d->EI = values[SPEC_VR_EI];
    d->alpha = values[SPEC_VR_ALPHA];
    d->beta = values[SPEC_VR_BETA];
    d->sidewall_pressure_exponent = values[SPEC_VR_SIDEWALL_PRESSURE_EXPONENT];
    d->reference_pressure = values[SPEC_VR_REFERENCE_PRESSURE];
    d->sidewall_max_order = values[SPEC_VR_SIDEWALL_MAX_ORDER];
    d->EA = values[SPEC_VR_EA];
    d->k_t1 = values[SPEC_VR_K_T1];
    d->k_t2 = values[SPEC_VR_K_T2];
    d->rim_radius_m = values[SPEC_VR_RIM_RADIUS_M];
    d->wheel_mass_kg = values[SPEC_VR_WHEEL_MASS_KG];
    d->wheel_inertia_kg_m2 = values[SPEC_VR_WHEEL_INERTIA_KG_M2];
    d->k_tx = values[SPEC_VR_K_TX];
    d->friction_coefficient = values[SPEC_VR_FRICTION_COEFFICIENT];
    d->loss_factor = values[SPEC_VR_LOSS_FACTOR];
}

/* the speed against the mesh's critical speed (build_host_stepper's check) */
static int critical_problem(Model* model, const double* values, const InPlaneRingData* data,
                            Problems* p)
{
    const Memory* mem = &model->host.mem;
    int n = (int)values[SPEC_VR_N_ELEMENTS], order, branch, status;
    double speed = values[SPEC_VR_SPEED], spin, critical, *work;
    char why[512], allowed[256];
    model->critical = NAN;
    /* at rest too: the running tire's spin and road speed are held below it at every step */
    work = (double*)mem_alloc(mem, inplane_critical_work_doubles(n, INPLANE_RING_TIED),
                              sizeof(double));
    if (work == NULL) {
        PROBLEM(p, "out of memory finding the critical speed (N = %d)", n);
        return 1;
    }
    status = inplane_critical_speed(data, n, INPLANE_RING_TIED, &spin, &critical, &order,
                                    &branch, work, why, sizeof why);
    mem_free(mem, work);
    if (status != 0) {
        PROBLEM(p, "%s", why);
        return 1;
    }
    model->critical = critical;
    model->speed_limit = SPEC_INPLANE_CRITICAL_SPEED_FRACTION * critical;
    model->spin_limit = model->speed_limit / values[SPEC_VR_R];
    model->load = values[SPEC_VR_LOAD];
    model->force_limit = SPEC_INPLANE_MAX_FORCE_LOADS * model->load;
    if (speed > 0.0 && speed > SPEC_INPLANE_CRITICAL_SPEED_FRACTION * critical) {
        snprintf(allowed, sizeof allowed,
                 "at most %g of the mesh's critical speed %.4g m/s (n_elements = %d)",
                 SPEC_INPLANE_CRITICAL_SPEED_FRACTION, critical, n);
        add_problem(p, "speed", speed, "m/s", allowed,
                    values[SPEC_VR_SIDEWALL_MAX_ORDER] == 0.0
                        ? "with the paper's lumped sidewall (sidewall_max_order = 0) a finer "
                          "mesh lowers it: use fewer elements, or tie the sidewall "
                          "(sidewall_max_order = 8)"
                        : "the sidewall's highest free order sets it: lower sidewall_max_order");
        return 1;
    }
    return 0;
}

/* -- the step's set-up -------------------------------------------------------------------------- */

static double share(const Model* model, double spin_rad_s)
{
    return model->hysteretic ? inplane_hysteresis_share(spin_rad_s, model->radius) : 0.0;
}

/* _set_speed: the road's speed and the slip's reference s0 at the tread's spin */
static void set_speed(Model* model, double speed_m_s)
{
    int i;
    double turn = model->spin_now * model->radius;
    model->speed_now = speed_m_s;
    for (i = 0; i < model->np; i++) model->m.points.s0[i] = speed_m_s - turn * model->cos_theta[i];
}

/* _set_tread_spin (the tread's part of the step at this spin: points-sized) */
static int set_tread_spin(Model* model, double spin_rad_s, double speed_m_s)
{
    model->spin_now = spin_rad_s;
    set_speed(model, speed_m_s);
    return inplane_build_tread(&model->m.build_in, spin_rad_s, &model->m.build, NULL, 0);
}

/* _set_ring_spin (the ring's part: an inverse of the coordinates' size) */
static int set_ring_spin(Model* model, double spin_rad_s)
{
    return inplane_build_ring(&model->m.build_in, spin_rad_s, &model->m.build,
                              model->build_work, model->build_iwork, NULL, 0);
}

/* _follow_spin for the free wheel (the only one whose spin moves in a stepper); the ring's
 * part only when ring is set */
static int follow_spin(Model* model, double* yd, int ring)
{
    double spin = model->spin_now + yd[model->ny - 1];
    double scale = fabs(model->spin_now) > 1.0 ? fabs(model->spin_now) : 1.0;
    int status = 0;
    if (fabs(spin - model->spin_now) > SPEC_INPLANE_SPIN_REBUILD_FRACTION * scale) {
        yd[model->ny - 1] = 0.0;
        status = set_tread_spin(model, spin, model->speed);
    } else {
        set_speed(model, model->speed);
    }
    if (status == 0 && ring &&
        fabs(spin - model->m.build.ring_spin) > SPEC_INPLANE_RING_REBUILD_FRACTION * scale) {
        status = set_ring_spin(model, spin);
        if (status == 0) status = set_tread_spin(model, model->spin_now, model->speed_now);
    }
    return status;
}

/* _take_spins: the step at these spins for steps of length_s (a state taken back) */
static int take_spins(Model* model, double ring_spin, double spin, double speed,
                      double length_s)
{
    int rebuilt = ring_spin != model->m.build.ring_spin || length_s != model->step.h,
        status = 0;
    model->m.build_in.h = length_s;
    model->step.h = length_s;
    if (rebuilt) status = set_ring_spin(model, ring_spin);
    if (status == 0 && (rebuilt || spin != model->spin_now))
        status = set_tread_spin(model, spin, speed);
    set_speed(model, speed);
    return status;
}

static void point_step_at(Model* model)
{
    InPlaneStep* d = &model->step;
    InPlaneModel* m = &model->m;
    InPlaneBuildOutput* b = &m->build;
    d->ny = model->ny;
    d->np = model->np;
    d->free_spin = model->free_spin;
    d->max_passes = SPEC_INPLANE_MAX_SET_PASSES;
    d->settle_passes = SPEC_INPLANE_SETTLE_PASSES;
    d->h = model->h;
    d->m = m->terms.m;
    d->c = b->c;
    d->a0_inv = b->a0_inv;
    d->yn = b->yn;
    d->yx = b->yx;
    d->wnn = b->wnn;
    d->wnx = b->wnx;
    d->kg = b->kg;
    d->kgn = b->kgn;
    d->kgx = b->kgx;
    d->gain = b->gain;
    d->carry = b->carry;
    d->jn = m->points.jn;
    d->jxw = m->points.jxw;
    d->jl = m->points.jl;
    d->rim_inertia = m->terms.rim_inertia;
    d->c1 = b->c1;
    d->k1s = b->k1s;
    d->k2 = b->k2;
    d->kh = b->kh;
    d->kn = m->points.kn;
    d->cn = m->points.cn;
    d->kx = m->points.kx;
    d->cx = m->points.cx;
    d->pen0 = m->points.pen0;
    d->sec = m->points.sec;
    d->s0 = m->points.s0;
    d->carry_base = b->carry_base;
    d->carry_weights = b->carry_weights;
    d->min_entering = SPEC_INPLANE_MIN_ENTERING_FRACTION;
    d->driven = model->driven;
    d->a0_psi = b->a0_psi;
}

/* translation_projection: M^-1 (to_abs^T M P), ny x 2 (a driven wheel's turn row zero) */
static int translation_projection(Model* model)
{
    const Memory* mem = &model->host.mem;
    int ny = model->ny, i, column, failed = 0;
    double* lu = (double*)mem_alloc(mem, (size_t)ny * ny, sizeof(double));
    double* b = (double*)mem_alloc(mem, (size_t)ny, sizeof(double));
    int* pivot = (int*)mem_alloc(mem, (size_t)ny, sizeof(int));
    if (lu == NULL || b == NULL || pivot == NULL) {
        failed = -1;
        goto done;
    }
    memcpy(lu, model->m.terms.m, (size_t)ny * ny * sizeof(double));
    if (lu_factor(lu, ny, pivot) != 0) {
        failed = -1;
        goto done;
    }
    for (column = 0; column < 2; column++) {
        for (i = 0; i < ny; i++) b[i] = model->m.terms.rim_inertia[2 * (size_t)i + column];
        lu_solve(lu, ny, pivot, b);
        if (model->driven) b[ny - 1] = 0.0;
        for (i = 0; i < ny; i++) model->projection[2 * (size_t)i + column] = b[i];
    }
done:
    mem_free(mem, lu);
    mem_free(mem, b);
    mem_free(mem, pivot);
    return failed;
}

/* the rim's rows of the tire's forces on the coordinates (_rim_stack): rows (3 x n_dof + 3)
 * times to_abs ((n_dof + 3) x ny) */
static void rim_rows_on_coordinates(Model* model)
{
    const InPlaneTermsOutput* t = &model->m.terms;
    const double* rows[7] = {t->rim_k0, t->rim_k1, t->rim_k2, t->rim_kh,
                             t->rim_c0, t->rim_c1, t->rim_m};
    int nd3 = model->m.n_dof + 3, ny = model->ny, g, i, j, k;
    for (g = 0; g < 7; g++)
        for (i = 0; i < 3; i++)
            for (j = 0; j < ny; j++) {
                double s = 0.0;
                for (k = 0; k < nd3; k++)
                    s += rows[g][(size_t)i * nd3 + k] * t->to_abs[(size_t)k * ny + j];
                model->rim_rows[((size_t)g * 3 + i) * ny + j] = s;
            }
}

static double dot(const double* a, const double* b, int n)
{
    double s = 0.0;
    int i;
    for (i = 0; i < n; i++) s += a[i] * b[i];
    return s;
}

/* rim_force: (Fx, Fz, My) on the rim at the wheel's spin, with the rim's translation's
 * inertia */
static void rim_force(const Model* model, const double* y, const double* yd, const double* ydd,
                      double spin_now, const double* rim, double* f)
{
    int ny = model->ny, i;
    /* the hysteretic share at the road's speed under the axle (_road_share) */
    double o = spin_now + (model->free_spin ? yd[ny - 1] : 0.0),
           s = share(model, (model->speed_now + rim[1]) / model->radius);
    const double* r = model->rim_rows;
    const double* mt = model->m.terms.rim_m_translation;
#define ROW(g, i) (r + ((size_t)(g) * 3 + (i)) * ny)
    for (i = 0; i < 3; i++) {
        double g0 = dot(ROW(0, i), y, ny) + dot(ROW(4, i), yd, ny) + dot(ROW(6, i), ydd, ny);
        double g1 = dot(ROW(1, i), y, ny) + dot(ROW(5, i), yd, ny);
        double g2 = dot(ROW(2, i), y, ny), g3 = dot(ROW(3, i), y, ny);
        f[i] = -(g0 + g1 * o + g2 * (o * o) + g3 * s + mt[2 * i] * rim[2] + mt[2 * i + 1] * rim[5]);
    }
#undef ROW
}

/* -- building ------------------------------------------------------------------------------------ */

static int allocate(Model* model)
{
    const Memory* mem = &model->host.mem;
    int ny = model->ny, p = model->np, k, failed = 0;
    InPlaneState* states[3] = {&model->now, &model->next, &model->saved};
    size_t per_state = 3 * (size_t)ny + 3 * (size_t)p;
#define TAKE(field, count, type)                                             \
    do {                                                                     \
        model->field = (type*)mem_alloc(mem, (size_t)(count), sizeof(type)); \
        if (model->field == NULL) failed = 1;                                \
    } while (0)
    TAKE(cos_theta, p, double);
    TAKE(x_lo, p, double);
    TAKE(x_hi, p, double);
    TAKE(height, p, double);
    TAKE(rate, p, double);
    TAKE(rim_rows, 21 * (size_t)ny, double);
    TAKE(projection, 2 * (size_t)ny, double);
    TAKE(work, inplane_work_doubles(ny, p), double);
    TAKE(iwork, inplane_work_ints(p), int);
    TAKE(build_work, inplane_build_work_doubles(ny, p), double);
    TAKE(build_iwork, inplane_build_work_ints(ny), int);
    TAKE(state_doubles, 3 * per_state, double);
    TAKE(state_ints, 3 * 2 * (size_t)p, int);
#undef TAKE
    if (failed) return -1;
    for (k = 0; k < 3; k++) {
        double* d = model->state_doubles + (size_t)k * per_state;
        int* n = model->state_ints + (size_t)k * 2 * p;
        states[k]->y = d;
        states[k]->yd = d + ny;
        states[k]->ydd = d + 2 * (size_t)ny;
        states[k]->e = d + 3 * (size_t)ny;
        states[k]->slip_sign = states[k]->e + p;
        states[k]->f_n = states[k]->slip_sign + p;
        states[k]->contact = n;
        states[k]->stick = n + p;
    }
    return 0;
}

/* the road windows (core/contact.py's road_windows_m) on contact.c's zone */
static int windows(Model* model, const InPlaneRingData* data, const double* values)
{
    Zone zone;
    int n = model->m.n_elements, i;
    int carry = zone_half_count(data->R, n, values[SPEC_VR_CONTACT_ZONE_LENGTH]);
    int per_node = points_per_node(data->R * (2.0 * 3.14159265358979323846 / n),
                                   values[SPEC_VR_CONTACT_POINT_SPACING]);
    double height, half;
    memset(&zone, 0, sizeof zone);
    if (zone_build(&zone, &model->host.mem, n, data->R, values[SPEC_VR_K_CW], data->beta,
                   carry, per_node) != 0)
        return -1;
    height = zone.radius - model->m.deflection_m;
    half = 0.5 * zone.dtheta / zone.per_node;
    model->front_m = -HUGE_VAL;
    model->rear_m = HUGE_VAL;
    for (i = 0; i < model->np; i++) {
        model->x_lo[i] = -height * tan(zone.point_theta[i] + half);
        model->x_hi[i] = -height * tan(zone.point_theta[i] - half);
        if (model->x_hi[i] > model->front_m) model->front_m = model->x_hi[i];
        if (model->x_lo[i] < model->rear_m) model->rear_m = model->x_lo[i];
    }
    zone_free(&zone, &model->host.mem);
    return 0;
}

/* InPlaneStepper.__init__: the static state at the step's spin (frictionless, the tread's
 * elements relaxed), its contact forces and the acceleration they give */
static int start_state(Model* model, const double* values, Problems* p)
{
    const Memory* mem = &model->host.mem;
    int ny = model->ny, nr = model->nr, P = model->np, i, j, status;
    InPlaneState* s = &model->now;
    InPlaneStaticData data;
    double *k = NULL, *jn = NULL, *work = NULL, *lu = NULL, *force = NULL;
    int *iwork = NULL, *pivot = NULL, failed = 0;
    char why[512];
    k = (double*)mem_alloc(mem, (size_t)nr * nr, sizeof(double));
    jn = (double*)mem_alloc(mem, (size_t)P * nr, sizeof(double));
    work = (double*)mem_alloc(mem, inplane_static_work_doubles(nr, P), sizeof(double));
    iwork = (int*)mem_alloc(mem, inplane_static_work_ints(nr, P), sizeof(int));
    lu = (double*)mem_alloc(mem, (size_t)ny * ny, sizeof(double));
    force = (double*)mem_alloc(mem, (size_t)ny, sizeof(double));
    pivot = (int*)mem_alloc(mem, (size_t)ny, sizeof(int));
    if (!k || !jn || !work || !iwork || !lu || !force || !pivot) {
        PROBLEM(p, "out of memory finding the static state (%d coordinates)", ny);
        failed = 1;
        goto done;
    }
    for (i = 0; i < nr; i++)
        for (j = 0; j < nr; j++) k[(size_t)i * nr + j] = model->m.build.k[(size_t)i * ny + j];
    for (i = 0; i < P; i++)
        for (j = 0; j < nr; j++) jn[(size_t)i * nr + j] = model->m.points.jn[(size_t)i * ny + j];
    data.n_coords = nr;
    data.n_points = P;
    data.stiffness = k;
    data.jn = jn;
    data.kn = model->m.points.kn;
    data.sec = model->m.points.sec;
    data.rim_fz_row = model->m.rim_fz_row;
    data.radius_m = model->radius;
    data.max_passes = SPEC_INPLANE_MAX_SET_PASSES;
    memset(s->y, 0, (size_t)ny * sizeof(double));
    status = inplane_static_state(&data, model->m.deflection_m, s->y, s->contact, NULL, NULL,
                                  work, iwork, why, sizeof why);
    if (status != INPLANE_STATIC_OK) {
        footprint_problem(values, p);
        failed = 1;
        goto done;
    }
    /* _contact_and_rates at rest on the flat road: the points pushing, the tread relaxed */
    for (i = 0; i < P; i++) {
        double pen = model->m.points.pen0[i] + dot(model->m.points.jn + (size_t)i * ny, s->y, ny);
        double f = pen > 0.0 ? model->m.points.kn[i] * pen : 0.0;
        s->f_n[i] = f > 0.0 ? f : 0.0;
        s->contact[i] = s->f_n[i] > 0.0;
        s->stick[i] = 1;
        s->slip_sign[i] = 1.0;
        s->e[i] = 0.0;
    }
    for (j = 0; j < ny; j++) {
        double f = 0.0;
        for (i = 0; i < P; i++) f -= model->m.points.jnw[(size_t)i * ny + j] * s->f_n[i];
        force[j] = f - dot(model->m.build.k + (size_t)j * ny, s->y, ny);
        s->yd[j] = 0.0;
    }
    {   /* a driven wheel starts at its steady spin: its turn's acceleration 0, the ring's
         * rows solved for the rest */
        int n = model->driven ? ny - 1 : ny;
        for (i = 0; i < n; i++)
            for (j = 0; j < n; j++) lu[(size_t)i * n + j] = model->m.terms.m[(size_t)i * ny + j];
        if (lu_factor(lu, n, pivot) != 0) {
            PROBLEM(p, "the tire's mass on its %d coordinates is singular", n);
            failed = 1;
            goto done;
        }
        lu_solve(lu, n, pivot, force);
        memcpy(s->ydd, force, (size_t)n * sizeof(double));
        if (model->driven) s->ydd[ny - 1] = 0.0;
    }
done:
    mem_free(mem, k);
    mem_free(mem, jn);
    mem_free(mem, work);
    mem_free(mem, iwork);
    mem_free(mem, lu);
    mem_free(mem, force);
    mem_free(mem, pivot);
    return failed;
}

static int build(Model* model, const double* values, Problems* p)
{
    InPlaneModelInput in;
    InPlaneRingData data;
    char why[1024], allowed[256];
    int status, i;
    ring_data_of(values, &data);
    if (critical_problem(model, values, &data, p)) return MODEL_ERROR;
    memset(&in, 0, sizeof in);
    in.tire = data;
    in.k_cw = values[SPEC_VR_K_CW];
    in.n_elements = (int)values[SPEC_VR_N_ELEMENTS];
    in.n_fields = INPLANE_RING_TIED;
    in.driven = values[SPEC_VR_WHEEL_DRIVEN] != 0.0;
    in.wheel_free = values[SPEC_VR_WHEEL_FREE] != 0.0 || in.driven;
    in.f_max_hz = values[SPEC_VR_F_MAX];
    in.zone_length_m = values[SPEC_VR_CONTACT_ZONE_LENGTH];
    in.point_spacing_m = values[SPEC_VR_CONTACT_POINT_SPACING];
    in.load_n = values[SPEC_VR_LOAD];
    in.speed_m_s = values[SPEC_VR_SPEED];
    in.spin_rad_s = in.speed_m_s / data.R;
    in.step_s = values[SPEC_VR_STEP_SIZE];
    status = inplane_model_build(&in, &model->m, &model->host.mem, why, sizeof why);
    if (status != INPLANE_MODEL_OK) {
        if (status == INPLANE_MODEL_STATIC)
            footprint_problem(values, p);
        else if (status == INPLANE_MODEL_NO_MEMORY)
            PROBLEM(p, "out of memory while building the model (N = %d): %.900s", in.n_elements,
                    why);
        else
            PROBLEM(p, "%s", why);
        return MODEL_ERROR;
    }
    if (!(0.0 < model->m.deflection_m &&
          model->m.deflection_m < SPEC_INPLANE_MAX_DEFLECTION_FRACTION * data.R)) {
        snprintf(allowed, sizeof allowed, "a load the tire carries below %g m of deflection",
                 SPEC_INPLANE_MAX_DEFLECTION_FRACTION * data.R);
        add_problem(p, "load", in.load_n, "N", allowed, "");
        return MODEL_ERROR;
    }
    model->ny = model->m.ny;
    model->np = model->m.np;
    model->nr = model->m.n_basis;
    model->free_spin = in.wheel_free;
    model->driven = in.driven;
    model->hysteretic = data.loss_factor != 0.0;
    model->h = in.step_s;
    model->radius = data.R;
    model->speed = in.speed_m_s;
    if (allocate(model) != 0 || windows(model, &data, values) != 0) {
        PROBLEM(p, "out of memory while building the model (N = %d)", in.n_elements);
        return MODEL_ERROR;
    }
    for (i = 0; i < model->np; i++) model->cos_theta[i] = cos(model->m.point_theta[i]);
    rim_rows_on_coordinates(model);
    {   /* basis_fingerprint: CRC-32 (zlib's) of to_abs's bytes, as the core's */
        const unsigned char* bytes = (const unsigned char*)model->m.terms.to_abs;
        size_t count = ((size_t)model->m.n_dof + 3) * (size_t)model->ny * sizeof(double), i;
        unsigned long crc = 0xfffffffful;
        for (i = 0; i < count; i++) crc = SPEC_CRC32_TABLE[(crc ^ bytes[i]) & 0xff] ^ (crc >> 8);
        model->fingerprint = (uint32_t)(crc ^ 0xfffffffful);
    }
    if (translation_projection(model) != 0) {
        PROBLEM(p, "the tire's mass on its %d coordinates is singular", model->ny);
        return MODEL_ERROR;
    }
    point_step_at(model);
    model->step.mu = data.friction_coefficient;
    /* InPlaneStepper: the step at the nominal spin (the one call built it there) */
    model->spin_now = model->m.build.spin_now;
    set_speed(model, model->speed);
    if (start_state(model, values, p)) return MODEL_ERROR;
    if (model->np > 0 && (model->now.contact[0] || model->now.contact[model->np - 1])) {
        snprintf(allowed, sizeof allowed, "longer than the footprint at %g N", in.load_n);
        add_problem(p, "contact_zone_length", values[SPEC_VR_CONTACT_ZONE_LENGTH], "m",
                    allowed, "the static footprint reaches the end of the contact zone");
        return MODEL_ERROR;
    }
    model->steps = 0;
    model->elapsed = model->carry = model->rate_given = model->h_given = 0.0;
    model->accel[0] = model->accel[1] = model->accel[2] = model->h_accel = 0.0;
    memset(model->given, 0, sizeof model->given);
    memset(model->rim, 0, sizeof model->rim);
    model->origin[0] = model->origin[1] = NAN;
    model->spacing_m = in.point_spacing_m;
    model->extent_armed = 1;
    {   /* the host's samples, kept the zone and the margin behind the newest (inplane_slave's
         * _road) */
        double keep = in.zone_length_m + SPEC_INPLANE_HOST_ROAD_MARGIN_M;
        if (position_road_init(&model->road, &model->host.mem, keep) != 0 ||
            position_road_init(&model->saved_road, &model->host.mem, keep) != 0) {
            PROBLEM(p, "out of memory while building the model (N = %d)", in.n_elements);
            return MODEL_ERROR;
        }
    }
    return MODEL_OK;
}

/* -- the road -------------------------------------------------------------------------------- */

/* Python's repr of a text (the value a problem shows for a String, parameters.value_text):
 * single quotes unless it holds one and no double quote, the backslash, the quote and the
 * control characters escaped */
static void text_repr(const char* text, char* out, size_t size)
{
    char quote = strchr(text, '\'') != NULL && strchr(text, '"') == NULL ? '"' : '\'';
    size_t used = 0;
    const unsigned char* c;
#define PUT(...) \
    used += (size_t)snprintf(out + (used < size ? used : size), used < size ? size - used : 0, \
                             __VA_ARGS__)
    PUT("%c", quote);
    for (c = (const unsigned char*)text; *c != '\0'; c++) {
        if (*c == '\\' || *c == (unsigned char)quote) PUT("\\%c", *c);
        else if (*c == '\n') PUT("\\n");
        else if (*c == '\r') PUT("\\r");
        else if (*c == '\t') PUT("\\t");
        else if (*c < 0x20 || *c == 0x7f) PUT("\\x%02x", *c);
        else PUT("%c", *c);
    }
    PUT("%c", quote);
#undef PUT
}

/* inplane_slave._road: the road_file's road, read at road_lateral_offset, or (no file) the
 * host's; a file that cannot be used is a problem naming road_file, the path (the value) and
 * what is wrong (road_file.c's words after the path); 1 with it added, else 0 */
static int road_problem(Model* model, const double* values, Problems* p)
{
    const char* path = model->host.string != NULL
                           ? model->host.string(model->host.layer, SPEC_VR_ROAD_FILE) : "";
    /* (sized so that the problem's line holds them all: the path shown, then why) */
    char why[PROBLEM_SIZE / 2 - 16], shown[PROBLEM_SIZE / 4], line[PROBLEM_SIZE / 2];
    size_t length = strlen(path);
    const char* what = why;
    if (path[0] == '\0') return 0;
    model->road_path = (char*)mem_alloc(&model->host.mem, length + 1, 1);
    if (model->road_path == NULL) {
        PROBLEM(p, "out of memory reading road_file");
        return 1;
    }
    memcpy(model->road_path, path, length + 1);
    if (road_file_open(path, values[SPEC_VR_ROAD_LATERAL_OFFSET], &model->host.mem,
                       &model->file, why, sizeof why) == ROAD_FILE_OK) {
        model->file_open = 1;
        return 0;
    }
    if (strncmp(why, path, length) == 0 && why[length] == ':' && why[length + 1] == ' ')
        what = why + length + 2;
    text_repr(path, shown, sizeof shown);
    snprintf(line, sizeof line, SPEC_MSG_PROBLEM, "road_file", shown,
             SPEC_MSG_ROAD_FILE_ALLOWED);
    PROBLEM(p, SPEC_MSG_REASON, line, what);
    return 1;
}

/* the road's height (m) at x (m) along it: InPlaneStepper.road_height */
static double road_height(const Model* model, double x)
{
    double height, integral;
    if (model->file_open) {
        road_samples_at(model->file.s, model->file.z, model->file.area, (int)model->file.n, x,
                        &height, &integral);
        return height;
    }
    return position_road_height(&model->road, x);
}

/* the mean height and its rate over each point's window, the wheel centre at shift along
 * the road, the road passing at speed (the position road's window_reads) */
static void road_reads(Model* model, double shift, double speed)
{
    if (model->file_open) {
        road_samples_window_reads(model->file.s, model->file.z, model->file.area,
                                  (int)model->file.n, model->x_lo, model->x_hi, model->np,
                                  shift, speed, model->height, model->rate, &model->road_guess);
    } else {
        road_samples_window_reads(position_road_s(&model->road), position_road_z(&model->road),
                                  position_road_at(&model->road),
                                  position_road_count(&model->road), model->x_lo, model->x_hi,
                                  model->np, shift, speed, model->height, model->rate,
                                  &model->road_guess);
    }
}

/* the loaded radius on a flat road (InPlaneStepper.loaded_radius_m) */
static double loaded_radius(const Model* model) { return model->radius - model->m.deflection_m; }

/* InPlaneStepper.road_queries: where the tire needs the host's road next, count positions */
static void road_queries(const Model* model, int count, double x, double vx, double step_s,
                         double* out)
{
    position_road_queries(&model->road, count, x, vx, step_s, model->rear_m, model->front_m,
                          model->spacing_m, out);
}

/* InPlaneStepper.wheel_centre: where the last step left the wheel centre (position along
 * the road, speed, height above the road's datum) */
static void wheel_centre(const Model* model, double* x, double* vx, double* z)
{
    *x = model->origin[0] + model->speed * model->elapsed + model->rim[0];
    *vx = model->speed + model->rim[1];
    *z = model->origin[1] + loaded_radius(model) + model->rim[3];
}

/* the outputs at the last step's end (no feed-through) after a step of step_s, or before the
 * first (the static tire, its wheel at the loaded radius above the road under wheel_x), as
 * inplane_slave's _show_outputs: the forces, the wheel centre's outputs (wheel_outputs), where
 * the host's road is wanted next (road_queries; 0 with a road file), in_contact */
static void show_outputs(const Model* model, double* values, double step_s)
{
    const InPlaneState* s = &model->now;
    double f[3], fz = 0.0, fx = 0.0, x, vx, z, spin, lo = HUGE_VAL, hi = -HUGE_VAL;
    int i, sliding = 0;
    rim_force(model, s->y, s->yd, s->ydd, model->spin_now, model->rim, f);
    for (i = 0; i < model->np; i++) {
        fz += s->f_n[i];
        fx += model->m.points.kx[i] * s->e[i];
        sliding += s->contact[i] && !s->stick[i];
        if (s->f_n[i] > 0.0) {
            if (model->x_lo[i] < lo) lo = model->x_lo[i];
            if (model->x_hi[i] > hi) hi = model->x_hi[i];
        }
    }
    spin = model->spin_now + (model->free_spin ? s->yd[model->ny - 1] : 0.0);
    values[SPEC_VR_RIM_FZ] = f[1];
    values[SPEC_VR_RIM_FX] = f[0];
    values[SPEC_VR_RIM_MY] = f[2];
    values[SPEC_VR_CONTACT_FZ] = fz;
    values[SPEC_VR_CONTACT_FX] = -fx;
    values[SPEC_VR_WHEEL_SPIN] = spin;
    values[SPEC_VR_SLIDING_POINTS] = (double)sliding;
    if (isnan(model->origin[0])) {
        x = values[SPEC_VR_WHEEL_X];
        vx = values[SPEC_VR_WHEEL_VX];
        z = road_height(model, x) + loaded_radius(model);
    } else {
        wheel_centre(model, &x, &vx, &z);
    }
    values[SPEC_VR_LOADED_RADIUS] = z - road_height(model, x);
    values[SPEC_VR_EFFECTIVE_ROLLING_RADIUS] = fabs(spin) > SPIN_AT_REST_RAD_S ? vx / spin
                                                                               : model->radius;
    values[SPEC_VR_LONGITUDINAL_SLIP] = (spin * model->radius - vx) /
                                        fmax(fabs(vx), SPEC_SLIP_SPEED_FLOOR_M_S);
    values[SPEC_VR_CONTACT_LENGTH] = hi > lo ? hi - lo : 0.0;
    if (model->file_open) {
        for (i = 0; i < ROAD_QUERIES; i++) values[SPEC_VR_ROAD_X_1 + i] = 0.0;
    } else {
        road_queries(model, ROAD_QUERIES, x, vx, step_s, values + SPEC_VR_ROAD_X_1);
    }
    values[SPEC_VR_IN_CONTACT] = fz > 0.0 ? 1.0 : 0.0;
}

int model_initialise(Model* model, const double* values, double start_time, double* out_values)
{
    Problems problems;
    char line[MESSAGE_SIZE + 64];
    clock_t started = clock();
    int status = MODEL_OK, i, in_contact = 0, road;
    problems.count = 0;
    model_clear(model);
    /* every problem at once, the road's first (inplane_slave._build) */
    road = road_problem(model, values, &problems);
    data_problems(values, &problems);
    if (problems.count == road) status = build(model, values, &problems);
    if (problems.count) status = MODEL_ERROR;
    if (status != MODEL_OK) {
        for (i = 0; i < problems.count; i++) {
            snprintf(line, sizeof line, SPEC_MSG_PROBLEM_LINE, i + 1, problems.count,
                     problems.text[i]);
            say(model, MODEL_ERROR, "logStatusError", line);
        }
        model_clear(model);
        return MODEL_ERROR;
    }
    model->built = 1;
    memcpy(model->built_for, values, sizeof model->built_for);
    model->start_time = start_time;
    show_outputs(model, out_values, 0.0); /* no samples yet: the zone is asked for */
    model->in_contact = out_values[SPEC_VR_IN_CONTACT] != 0.0;
    for (i = 0; i < model->np; i++) in_contact += model->now.contact[i];
    {
        char road_words[MESSAGE_SIZE / 2];
        if (model->file_open) {
            snprintf(road_words, sizeof road_words, "road %s (%s, %.6g to %.6g m along it)",
                     model->road_path, model->file.format, model->file.s[0],
                     model->file.s[model->file.n - 1]);
        } else {
            snprintf(road_words, sizeof road_words,
                     "the host's road (%d heights a step at road_x_i)", ROAD_QUERIES);
        }
        snprintf(line, sizeof line,
                 "TireInPlane (native) ready in %.3f s (CPU): N = %d, %d coordinates, %d "
                 "contact points (%d on the road), deflection %.4g mm, critical speed %.4g "
                 "m/s, loaded radius %.6g m, %s",
                 (double)(clock() - started) / CLOCKS_PER_SEC, model->m.n_elements, model->ny,
                 model->np, in_contact, model->m.deflection_m * 1e3, model->critical,
                 loaded_radius(model), road_words);
    }
    say(model, MODEL_OK, "logAll", line);
    return MODEL_OK;
}

int model_built_for(const Model* model, const double* values)
{
    int vr;
    if (!model->built) return 0;
    for (vr = 0; vr < SPEC_N_VARIABLES; vr++) {
        if (SPEC_VARIABLES[vr].causality != SPEC_PARAMETER) continue;
        if (memcmp(&model->built_for[vr], &values[vr], sizeof(double)) != 0) return 0;
    }
    return 1;
}

/* -- stepping ---------------------------------------------------------------------------------- */

/* substeps: how the tire cuts a host's step (count, length): whole step_size steps when h is
 * a whole number of them to within the resolution of the host's clock at time_s, else the
 * fewest equal ones no longer than step_size (they end exactly at t + h) */
static long long substeps(double h, double tire_step_s, double time_s, double* length)
{
    double count = nearbyint(h / tire_step_s), at = fabs(time_s) + h;
    double slack = fmin(fmax(1e-9 * h, 2.0 * (nextafter(at, INFINITY) - at)),
                        0.25 * tire_step_s);
    if (count < 1.0) count = 1.0;
    if (fabs(count * tire_step_s - h) <= slack) {
        *length = tire_step_s;
        return (long long)count;
    }
    count = ceil(h / tire_step_s);
    *length = h / count;
    return (long long)count;
}

const char* model_step_problem(const Model* model, double h, char* why, size_t size)
{
    char text[40];
    (void)model;
    if (h >= SPEC_INPLANE_MIN_STEP_S) return NULL;
    py_repr(h, text, size < sizeof text ? size : sizeof text);
    snprintf(why, size, SPEC_MSG_INPLANE_STEP_SHORT, text, SPEC_INPLANE_MIN_STEP_S);
    return why;
}

const char* model_step_refusal(const Model* model) { return model->refusal; }

/* rate_changes: the acceleration and jerk at the communication point from the rates' last
 * two changes (zero without the history) */
static void rate_changes(double rate, double rate_before, double h_before, double change_before,
                         double h_change_before, double* acceleration, double* jerk)
{
    double change;
    *acceleration = *jerk = 0.0;
    if (!(h_before > 0.0)) return;
    change = (rate - rate_before) / h_before;
    *acceleration = change;
    if (!(h_change_before > 0.0)) return;
    *jerk = (change - change_before) / (0.5 * (h_before + h_change_before));
    *acceleration = change + 0.5 * h_before * *jerk;
}

/* input_path: (value, rate, acceleration) at tau into the step of an input given at its start
 * with its rate, on the cubic with the acceleration and jerk of rate_changes */
static void input_path(double value, double rate, double acceleration, double jerk, double tau,
                       double* out)
{
    out[0] = value + tau * (rate + tau * (0.5 * acceleration + tau * jerk / 6.0));
    out[1] = rate + tau * (acceleration + 0.5 * tau * jerk);
    out[2] = acceleration + tau * jerk;
}

static void copy_state(const Model* model, const InPlaneState* from, InPlaneState* to)
{
    size_t ny = (size_t)model->ny, p = (size_t)model->np;
    memcpy(to->y, from->y, ny * sizeof(double));
    memcpy(to->yd, from->yd, ny * sizeof(double));
    memcpy(to->ydd, from->ydd, ny * sizeof(double));
    memcpy(to->e, from->e, p * sizeof(double));
    memcpy(to->slip_sign, from->slip_sign, p * sizeof(double));
    memcpy(to->f_n, from->f_n, p * sizeof(double));
    memcpy(to->contact, from->contact, p * sizeof(int));
    memcpy(to->stick, from->stick, p * sizeof(int));
}

/* InPlaneStepper.checkpoint (the host's samples too: a few hundred); 0, or -1 out of memory */
static int checkpoint(Model* model)
{
    if (position_road_copy(&model->saved_road, &model->road) != 0) return -1;
    memcpy(model->saved_origin, model->origin, sizeof model->origin);
    copy_state(model, &model->now, &model->saved);
    model->saved_steps = model->steps;
    memcpy(model->saved_given, model->given, sizeof model->given);
    memcpy(model->saved_rim, model->rim, sizeof model->rim);
    model->saved_clock[0] = model->rate_given;
    model->saved_clock[1] = model->h_given;
    model->saved_clock[2] = model->elapsed;
    model->saved_clock[3] = model->carry;
    model->saved_clock[4] = model->step.h;
    memcpy(model->saved_accel, model->accel, sizeof model->accel);
    model->saved_accel[3] = model->h_accel;
    model->saved_spin = model->spin_now;
    model->saved_speed = model->speed_now;
    model->saved_ring_spin = model->m.build.ring_spin;
    return 0;
}

static int rollback(Model* model)
{
    int status;
    PositionRoad road = model->road; /* the saved samples back: the two buffers swapped */
    model->road = model->saved_road;
    model->saved_road = road;
    memcpy(model->origin, model->saved_origin, sizeof model->origin);
    status = take_spins(model, model->saved_ring_spin, model->saved_spin, model->saved_speed,
                        model->saved_clock[4]);
    copy_state(model, &model->saved, &model->now);
    model->steps = model->saved_steps;
    memcpy(model->given, model->saved_given, sizeof model->given);
    memcpy(model->rim, model->saved_rim, sizeof model->rim);
    model->rate_given = model->saved_clock[0];
    model->h_given = model->saved_clock[1];
    model->elapsed = model->saved_clock[2];
    model->carry = model->saved_clock[3];
    memcpy(model->accel, model->saved_accel, sizeof model->accel);
    model->h_accel = model->saved_accel[3];
    return status;
}

static void contact_event(Model* model, const double* values)
{
    int in_contact = values[SPEC_VR_IN_CONTACT] != 0.0;
    char line[MESSAGE_SIZE];
    if (in_contact == model->in_contact) return;
    /* losing contact is physics (a unilateral contact): information, not a warning */
    snprintf(line, sizeof line, in_contact ? SPEC_MSG_TOUCH_DOWN : SPEC_MSG_LIFT_OFF,
             model_time(model));
    say(model, MODEL_OK, "logEvents", line);
    model->in_contact = in_contact;
}

/* _take_rim_jump: the rim from where the last step's extension left it to the host's values,
 * its jump taken off the tire's coordinates (the tire's momentum carries on) */
static void take_rim_jump(Model* model)
{
    double dp[2], dv[2];
    int i, ny = model->ny;
    dp[0] = model->given[0] - model->rim[0];
    dp[1] = model->given[2] - model->rim[3];
    dv[0] = model->given[1] - model->rim[1];
    dv[1] = model->given[3] - model->rim[4];
    if (dp[0] == 0.0 && dp[1] == 0.0 && dv[0] == 0.0 && dv[1] == 0.0) return;
    for (i = 0; i < ny; i++) {
        const double* row = model->projection + 2 * (size_t)i;
        model->now.y[i] -= row[0] * dp[0] + row[1] * dp[1];
        model->now.yd[i] -= row[0] * dv[0] + row[1] * dv[1];
    }
}

/* clock.advance: elapsed + h with Kahan compensation */
static void clock_advance(Model* model, double h)
{
    double y = h - model->carry, total = model->elapsed + y;
    model->carry = (total - model->elapsed) - y;
    model->elapsed = total;
}

/* inplane_slave's _extent_warning: said once when a contact point's road leaves the road
 * file's (beyond it the road is level at its end heights), and again after it came back */
static void extent_warning(Model* model)
{
    double x, vx, z, first, last;
    int beyond;
    char line[MESSAGE_SIZE], now[40], at[40];
    wheel_centre(model, &x, &vx, &z);
    road_file_extent(&model->file, &first, &last);
    beyond = x + model->rear_m < first || x + model->front_m > last;
    if (beyond && model->extent_armed) {
        py_repr(model_time(model), now, sizeof now);
        py_repr(x, at, sizeof at);
        snprintf(line, sizeof line, SPEC_MSG_ROAD_EXTENT, now, at, model->road_path, first,
                 last);
        say(model, MODEL_WARNING, "logStatusWarning", line);
    }
    model->extent_armed = !beyond;
}

/* InPlaneStepper.advance_wheel, then advance */
int model_step(Model* model, double step_s, double* values)
{
    double length, accel[3], jerk[3], x[3], z[3], rim_old[6];
    double start_s = model->elapsed;
    long long count = substeps(step_s, model->h, model_time(model), &length), k;
    double torque = values[SPEC_VR_WHEEL_TORQUE], rate_given = 0.0;
    int P = model->np, i, status = 0, known = model->h_given > 0.0;
    double spin_start = 0.0, spin_end = 0.0;
    model->refusal[0] = '\0';
    if (checkpoint(model) != 0) return MODEL_ERROR;
    /* the host's road where the last outputs asked for it, taken before the step */
    if (!model->file_open && position_road_set(&model->road, values + SPEC_VR_ROAD_X_1,
                                               values + SPEC_VR_ROAD_Z_1, ROAD_QUERIES) != 0) {
        rollback(model);
        return MODEL_ERROR;
    }
    if (isnan(model->origin[0])) { /* the coordinates start here */
        model->origin[0] = values[SPEC_VR_WHEEL_X];
        model->origin[1] = road_height(model, values[SPEC_VR_WHEEL_X]);
    }
    /* a driven wheel's spin as the deviation from the built one advance takes */
    if (model->driven) rate_given = values[SPEC_VR_WHEEL_RATE] - model->speed / model->radius;
    if (length != model->step.h &&
        take_spins(model, model->m.build.ring_spin, model->spin_now, model->speed_now,
                   length) != 0) {
        rollback(model);
        snprintf(model->refusal, sizeof model->refusal,
                 "the step could not be built for steps of %g s; nothing changed", length);
        return MODEL_DISCARD;
    }
    {   /* the host's values at the step's start; each position's acceleration over the step
         * is its rate's last change */
        double given[6];
        given[0] = values[SPEC_VR_WHEEL_X] - model->origin[0] - model->speed * model->elapsed;
        given[1] = values[SPEC_VR_WHEEL_VX] - model->speed;
        given[2] = values[SPEC_VR_WHEEL_Z] - model->origin[1] - loaded_radius(model);
        given[3] = values[SPEC_VR_WHEEL_VZ];
        given[4] = given[5] = 0.0; /* the deviation mode's road at the front: not read */
        for (i = 0; i < 3; i++) {
            rate_changes(given[2 * i + 1], model->given[2 * i + 1], model->h_given,
                         model->accel[i], model->h_accel, &accel[i], &jerk[i]);
            /* the last change of the rates, over the step it was made in */
            if (known)
                model->accel[i] = (given[2 * i + 1] - model->given[2 * i + 1]) / model->h_given;
            else
                model->accel[i] = accel[i];
        }
        model->h_accel = model->h_given;
        memcpy(model->given, given, sizeof given);
    }
    take_rim_jump(model);
    if (model->driven) { /* the wheel's spin at the step's start and end */
        double change = known ? (rate_given - model->rate_given) / model->h_given * step_s : 0.0;
        spin_start = model->spin_now + model->now.yd[model->ny - 1];
        spin_end = model->speed / model->radius + rate_given + change;
    }
    input_path(model->given[0], model->given[1], accel[0], jerk[0], 0.0, x);
    input_path(model->given[2], model->given[3], accel[1], jerk[1], 0.0, z);
    for (i = 0; i < 3; i++) {
        model->rim[i] = x[i];
        model->rim[3 + i] = z[i];
    }
    for (k = 1; k <= count; k++) {
        double time, distance, tau = (double)k * length;
        InPlaneState swap;
        model->steps++;
        time = start_s + tau;
        input_path(model->given[0], model->given[1], accel[0], jerk[0], tau, x);
        input_path(model->given[2], model->given[3], accel[1], jerk[1], tau, z);
        memcpy(rim_old, model->rim, sizeof rim_old);
        for (i = 0; i < 3; i++) {
            model->rim[i] = x[i];
            model->rim[3 + i] = z[i];
        }
        /* the ring's step rebuilt at most once a communication step, at its start: the
         * work a step may take is bounded (model_step_work) */
        if (model->free_spin && follow_spin(model, model->now.yd, k == 1) != 0) {
            status = 3;
            break;
        }
        if (model->driven) { /* the turn at the step's end, trapezoidal from the rates */
            double spin = spin_start + (spin_end - spin_start) * ((double)k / (double)count);
            double rate = spin - model->spin_now;
            model->step.psi_new = model->now.y[model->ny - 1] +
                                  0.5 * length * (model->now.yd[model->ny - 1] + rate);
        }
        /* the road under each point where the wheel centre is now, from the origin's height */
        distance = model->speed * time + model->rim[0];
        road_reads(model, model->origin[0] + distance, model->speed_now + model->rim[1]);
        for (i = 0; i < P; i++) {
            model->height[i] = model->height[i] - model->origin[1] - model->rim[3];
            model->rate[i] -= model->rim[4];
        }
        {   /* InPlaneKernel.step: the spin's offsets from the ring's and the tread's */
            double spin = model->spin_now +
                          (model->free_spin ? model->now.yd[model->ny - 1] : 0.0);
            model->step.spin = model->spin_now;
            model->step.dspin = spin - model->m.build.ring_spin;
            model->step.dshare = share(model, (model->speed_now + model->rim[1]) / model->radius) -
                                 model->m.build.ring_share;
            model->step.carry_shift = model->m.build.carry_shift;
        }
        status = inplane_step(&model->step, &model->now, &model->next, model->height,
                              model->rate, torque, rim_old, model->rim, model->work,
                              model->iwork);
        if (status != 0) break;
        swap = model->now;
        model->now = model->next;
        model->next = swap;
        {   /* _check_running: the spin and the road's speed within the built range */
            double spin = model->spin_now +
                          (model->free_spin ? model->now.yd[model->ny - 1] : 0.0);
            double road = model->speed_now + model->rim[1];
            if (!(fabs(spin) <= model->spin_limit)) {
                snprintf(model->refusal, sizeof model->refusal, SPEC_MSG_INPLANE_SPIN_LIMIT,
                         time, spin, model->spin_limit, SPEC_INPLANE_CRITICAL_SPEED_FRACTION,
                         model->critical);
                rollback(model);
                return MODEL_DISCARD;
            }
            if (!(fabs(road) <= model->speed_limit)) {
                snprintf(model->refusal, sizeof model->refusal, SPEC_MSG_INPLANE_SPEED_LIMIT,
                         time, road, model->speed_limit, SPEC_INPLANE_CRITICAL_SPEED_FRACTION,
                         model->critical);
                rollback(model);
                return MODEL_DISCARD;
            }
        }
    }
    if (status != 0) {
        snprintf(model->refusal, sizeof model->refusal,
                 status == 3 ? "step at t = %g s: the step could not be rebuilt at the wheel's "
                               "spin; nothing changed"
                 : status == 1
                     ? "step at t = %g s: the contact and stick sets did not settle in %d "
                       "passes; nothing changed (a shorter step_size settles the sets sooner)"
                     : "step at t = %g s: the contact and stick sets did not give a solvable "
                       "point solve; nothing changed (a shorter step_size settles the sets "
                       "sooner)",
                 start_s + (double)(model->steps - model->saved_steps) * length,
                 SPEC_INPLANE_MAX_SET_PASSES);
        rollback(model);
        return MODEL_DISCARD;
    }
    clock_advance(model, (double)count * length);
    {   /* the force on the rim within MAX_FORCE_LOADS loads */
        double f[3], force;
        rim_force(model, model->now.y, model->now.yd, model->now.ydd, model->spin_now,
                  model->rim, f);
        force = fmax(fabs(f[0]), fabs(f[1]));
        if (!(force <= model->force_limit)) {
            snprintf(model->refusal, sizeof model->refusal, SPEC_MSG_INPLANE_FORCE_LIMIT,
                     model->elapsed, force, SPEC_INPLANE_MAX_FORCE_LOADS, model->load);
            rollback(model);
            return MODEL_DISCARD;
        }
    }
    model->rate_given = rate_given;
    model->h_given = step_s;
    show_outputs(model, values, step_s);
    contact_event(model, values);
    if (model->file_open) extent_warning(model);
    return MODEL_OK;
}

int model_refresh(Model* model, double* values)
{
    /* no feed-through: the outputs are the last step's whatever the inputs now are */
    (void)model;
    (void)values;
    return MODEL_OK;
}

double model_time(const Model* model) { return model->start_time + model->elapsed; }

const TireContract* model_contract(const Model* model)
{
    (void)model;
    return NULL;
}

double model_road_horizon(const Model* model)
{
    (void)model;
    return 0.0;
}

double model_min_step(const Model* model)
{
    (void)model;
    return 0.0;
}

/* core/inplane_contact.py's host_step_work: a host's step costs its count of the tire's
 * steps (step_work each) and at most two rebuilds of the ring's step (rebuild_work) */
int model_step_work(const Model* model, double h, int* n_sub, double* substep, int* work,
                    double* longest)
{
    double length, ny = model->ny, p = model->np;
    long long count = substeps(h, model->h, model_time(model), &length);
    double each = 8.0 * ny * ny + 24.0 * p * ny + floor(p * p * p / 27.0) + 1000.0;
    double rebuilds = 2.0 * (ny * ny * ny + 4.0 * p * ny * ny);
    double per = fmin(each + ceil(rebuilds / (double)count), 2147483647.0);
    *n_sub = count < 2147483647 ? (int)count : 2147483647;
    *substep = length;
    *work = (int)per;
    *longest = fmax(floor((SPEC_MAX_STEP_WORK - rebuilds) / each), 0.0) * model->h;
    return (double)count * each + rebuilds > SPEC_MAX_STEP_WORK;
}

/* -- the model's part of an FMU state --------------------------------------------------------
 * int32: a flag the layer's framing keeps (1), in contact (the last in_contact an event was
 * logged for); then core/inplane_contact.py's InPlaneStepper.state_bytes: its head, doubles
 * (the step's end inputs, the rim, the spins, the clocks, the origin, y, yd, ydd, e, f_n, the
 * host road's samples: none with a road file) and int8 flags (contact, stick, slip sign). */

static size_t n_abs(const Model* model) { return (size_t)model->m.n_dof + 3; }

/* the doubles of a stepper part with ny coordinates, np points, samples road samples and
 * n_dof absolute DOFs */
static size_t stepper_doubles(size_t ny, size_t np, size_t samples, size_t n_dof)
{
    return STEPPER_SCALARS + 3 * ny + 2 * np + 3 * samples + 3 * n_dof;
}

static size_t stepper_size(size_t ny, size_t np, size_t samples, size_t n_dof)
{
    return STEPPER_HEAD + 8 * stepper_doubles(ny, np, samples, n_dof) + 3 * np;
}

size_t model_state_size(const Model* model)
{
    return FLAGS * 4 + stepper_size((size_t)model->ny, (size_t)model->np,
                                    (size_t)position_road_count(&model->road), n_abs(model));
}

static void put(unsigned char** out, const void* value, size_t size)
{
    memcpy(*out, value, size);
    *out += size;
}

static void put_doubles(unsigned char** out, const double* values, int n)
{
    put(out, values, (size_t)n * sizeof(double));
}

void model_state_write(const Model* model, unsigned char* out)
{
    int32_t flag = 1, contact = model->in_contact;
    uint32_t ny = (uint32_t)model->ny, np = (uint32_t)model->np;
    uint32_t samples = (uint32_t)position_road_count(&model->road);
    uint32_t dofs = (uint32_t)n_abs(model);
    int64_t steps = (int64_t)model->steps;
    double spins[3], clocks[5], changes[4];
    const InPlaneState* s = &model->now;
    int i;
    put(&out, &flag, 4);
    put(&out, &contact, 4);
    put(&out, STEPPER_MAGIC, 8);
    put(&out, &ny, 4);
    put(&out, &np, 4);
    put(&out, &samples, 4);
    put(&out, &steps, 8);
    put(&out, &dofs, 4);
    put(&out, &model->fingerprint, 4);
    put_doubles(&out, model->given, 6);
    put_doubles(&out, model->rim, 6);
    spins[0] = model->spin_now;
    spins[1] = model->speed_now;
    spins[2] = model->m.build.ring_spin;
    put_doubles(&out, spins, 3);
    clocks[0] = model->rate_given;
    clocks[1] = model->h_given;
    clocks[2] = model->elapsed;
    clocks[3] = model->carry;
    clocks[4] = model->step.h;
    put_doubles(&out, clocks, 5);
    memcpy(changes, model->accel, sizeof model->accel);
    changes[3] = model->h_accel;
    put_doubles(&out, changes, 4);
    put_doubles(&out, model->origin, 2);
    put_doubles(&out, s->y, model->ny);
    put_doubles(&out, s->yd, model->ny);
    put_doubles(&out, s->ydd, model->ny);
    put_doubles(&out, s->e, model->np);
    put_doubles(&out, s->f_n, model->np);
    for (i = 0; i < (int)samples; i++) { /* as rows (s, z, at) */
        const PositionRoad* road = &model->road;
        double sample[3];
        sample[0] = position_road_s(road)[i];
        sample[1] = position_road_z(road)[i];
        sample[2] = position_road_at(road)[i];
        put_doubles(&out, sample, 3);
    }
    {   /* the coordinates in the tire's own DOFs: to_abs y, y', y'' */
        const double* shapes[3] = {s->y, s->yd, s->ydd};
        const double* to_abs = model->m.terms.to_abs;
        size_t row, n = n_abs(model);
        int g;
        for (g = 0; g < 3; g++)
            for (row = 0; row < n; row++) {
                double v = dot(to_abs + row * (size_t)model->ny, shapes[g], model->ny);
                put_doubles(&out, &v, 1);
            }
    }
    for (i = 0; i < model->np; i++) *out++ = (unsigned char)(s->contact[i] ? 1 : 0);
    for (i = 0; i < model->np; i++) *out++ = (unsigned char)(s->stick[i] ? 1 : 0);
    for (i = 0; i < model->np; i++) {
        signed char sign = (signed char)(s->slip_sign[i] > 0 ? 1 : (s->slip_sign[i] < 0 ? -1 : 0));
        memcpy(out++, &sign, 1);
    }
}

static double get_double(const unsigned char* at, size_t index)
{
    double v;
    memcpy(&v, at + 8 * index, 8);
    return v;
}

/* InPlaneStepper._state_coordinates: a state's y, y', y'' (out: 3 x ny, this model's ny) in
 * this model's coordinates: its own where its basis is this one's (the same fingerprint and
 * size), else its DOFs taken into this basis (least squares on to_abs); 0, or 1 when they lie
 * outside it by more than SPEC_INPLANE_STATE_BASIS_TOLERANCE (off: how far), -1 out of
 * memory */
static int state_coordinates(const Model* model, const unsigned char* doubles, size_t ny_state,
                             size_t np, size_t samples, uint32_t fingerprint, double* out,
                             double* off)
{
    const Memory* mem = &model->host.mem;
    const double* a = model->m.terms.to_abs;
    size_t ny = (size_t)model->ny, n = n_abs(model), g, i, j, k;
    size_t dofs_at = STEPPER_SCALARS + 3 * ny_state + 2 * np + 3 * samples;
    double *lu, *u, worst = 0.0;
    int *pivot, status = 0;
    *off = 0.0;
    if (fingerprint == model->fingerprint && ny_state == ny) {
        for (g = 0; g < 3 * ny; g++) out[g] = get_double(doubles, STEPPER_SCALARS + g);
        return 0;
    }
    lu = (double*)mem_alloc(mem, ny * ny, sizeof(double));
    u = (double*)mem_alloc(mem, n, sizeof(double));
    pivot = (int*)mem_alloc(mem, ny, sizeof(int));
    if (lu == NULL || u == NULL || pivot == NULL) {
        status = -1;
        goto done;
    }
    for (i = 0; i < ny; i++)  /* the normal matrix to_abs^T to_abs */
        for (j = 0; j < ny; j++) {
            double sum = 0.0;
            for (k = 0; k < n; k++) sum += a[k * ny + i] * a[k * ny + j];
            lu[i * ny + j] = sum;
        }
    if (lu_factor(lu, (int)ny, pivot) != 0) {
        status = 1;
        *off = INFINITY;
        goto done;
    }
    for (g = 0; g < 3; g++) {
        double* y = out + g * ny;
        double ring_scale = 1e-12, ring_off = 0.0, turn, turn_off;
        for (k = 0; k < n; k++) u[k] = get_double(doubles, dofs_at + g * n + k);
        for (i = 0; i < ny; i++) {
            double sum = 0.0;
            for (k = 0; k < n; k++) sum += a[k * ny + i] * u[k];
            y[i] = sum;
        }
        lu_solve(lu, (int)ny, pivot, y);
        /* the last DOF is the rim's turn (it grows as the wheel rolls): checked on its own */
        for (k = 0; k + 1 < n; k++) {
            double r = fabs(dot(a + k * ny, y, (int)ny) - u[k]);
            if (r > ring_off) ring_off = r;
            if (fabs(u[k]) > ring_scale) ring_scale = fabs(u[k]);
        }
        turn = fabs(u[n - 1]);
        turn_off = fabs(dot(a + (n - 1) * ny, y, (int)ny) - u[n - 1]) / (turn > 1.0 ? turn : 1.0);
        worst = fmax(worst, fmax(ring_off / ring_scale, turn_off));
    }
    *off = worst;
    status = worst <= SPEC_INPLANE_STATE_BASIS_TOLERANCE ? 0 : 1;
done:
    mem_free(mem, lu);
    mem_free(mem, u);
    mem_free(mem, pivot);
    return status;
}

/* InPlaneStepper._state_meaning_problem: the tire's deformation and the forces the state
 * gives within what a state may hold; 2 with why, or 0 */
static int meaning_problem(const Model* model, const unsigned char* doubles, const double* yyy,
                           size_t ny_state, size_t np, char* why, size_t why_size)
{
    int ny = model->ny, cols = model->free_spin ? ny - 1 : ny, i;
    size_t rows = n_abs(model) - 3, k, at;
    const double *y = yyy, *yd = yyy + ny, *ydd = yyy + 2 * (size_t)ny;
    const double* a = model->m.terms.to_abs;
    double deformation = 0.0, rim[6], f[3], force, point = 0.0, most;
    for (k = 0; k < rows; k++) {
        double v = fabs(dot(a + k * (size_t)ny, y, cols));
        if (v > deformation) deformation = v;
    }
    most = SPEC_INPLANE_STATE_DEFORMATION_FRACTION * model->radius;
    if (!(deformation <= most)) {
        snprintf(why, why_size, "its tire deforms by %.3g m, beyond the %.3g m a state may hold "
                 "(%g of R)", deformation, most, SPEC_INPLANE_STATE_DEFORMATION_FRACTION);
        return 2;
    }
    for (i = 0; i < 6; i++) rim[i] = get_double(doubles, 6 + (size_t)i);
    rim_force(model, y, yd, ydd, get_double(doubles, 12), rim, f);
    force = fmax(fabs(f[0]), fabs(f[1]));
    at = STEPPER_SCALARS + 3 * ny_state;
    for (k = 0; k < np; k++) {
        double e = fabs(model->m.points.kx[k] * get_double(doubles, at + k));
        double fn = fabs(get_double(doubles, at + np + k));
        point = fmax(point, fmax(e, fn));
    }
    if (!(fmax(force, point) <= model->force_limit)) {
        snprintf(why, why_size, "its forces reach %.4g N (on the rim %.4g N, at a point %.4g N), "
                 "beyond %g times the load (%.6g N)", fmax(force, point), force, point,
                 SPEC_INPLANE_MAX_FORCE_LOADS, model->load);
        return 2;
    }
    return 0;
}

int model_state_check(const Model* model, const unsigned char* in, size_t size,
                      const double* values, double time, double start_time, char* why,
                      size_t why_size)
{
    const unsigned char *part = in + FLAGS * 4, *doubles, *flags;
    int32_t flag;
    uint32_t ny, np, samples, dofs, fingerprint;
    int64_t steps;
    size_t n_doubles, i;
    why[0] = '\0';
    if (size < FLAGS * 4 + STEPPER_HEAD) {
        snprintf(why, why_size, SPEC_MSG_STATE_MODEL_SHORT, (unsigned long)size);
        return MODEL_ERROR;
    }
    for (i = 0; i < FLAGS; i++) {
        memcpy(&flag, in + 4 * i, 4);
        if (flag != 0 && flag != 1) {
            snprintf(why, why_size, SPEC_MSG_STATE_MODEL_FLAG, (int)i, (int)flag);
            return MODEL_ERROR;
        }
    }
    if (memcmp(part, STEPPER_MAGIC, 8) != 0) {
        snprintf(why, why_size, "its stepper part is not an in-plane tire's");
        return MODEL_ERROR;
    }
    memcpy(&ny, part + 8, 4);
    memcpy(&np, part + 12, 4);
    memcpy(&samples, part + 16, 4);
    memcpy(&steps, part + 20, 8);
    memcpy(&dofs, part + 28, 4);
    memcpy(&fingerprint, part + 32, 4);
    if (dofs != (uint32_t)n_abs(model) || np != (uint32_t)model->np) {
        snprintf(why, why_size, "its stepper part has %lu DOFs and %lu points, this tire "
                 "%lu and %d", (unsigned long)dofs, (unsigned long)np,
                 (unsigned long)n_abs(model), model->np);
        return MODEL_ERROR;
    }
    if ((samples > 0 && model->file_open) || steps < 0) {
        snprintf(why, why_size, "its stepper part's road or step count does not fit this tire");
        return MODEL_ERROR;
    }
    if (samples > (size - FLAGS * 4) / 24 || samples > SPEC_INPLANE_MAX_ROAD_SAMPLES) {
        snprintf(why, why_size, "its road history holds %lu samples; the tire keeps at most %d "
                 "(one a step over the zone's reach)", (unsigned long)samples,
                 (int)SPEC_INPLANE_MAX_ROAD_SAMPLES);
        return MODEL_ERROR;
    }
    if (!(ny > 0 && ny <= dofs)) {
        snprintf(why, why_size, "its stepper part has %lu coordinates for %lu DOFs",
                 (unsigned long)ny, (unsigned long)dofs);
        return MODEL_ERROR;
    }
    if (size - FLAGS * 4 != stepper_size(ny, np, samples, dofs)) {
        snprintf(why, why_size, "its stepper part has the wrong size");
        return MODEL_ERROR;
    }
    doubles = part + STEPPER_HEAD;
    n_doubles = stepper_doubles(ny, np, samples, dofs);
    for (i = 0; i < n_doubles; i++) {
        /* the origin: both finite, or both NaN before the first step */
        int unset = (i == ORIGIN_AT || i == ORIGIN_AT + 1) &&
                    isnan(get_double(doubles, ORIGIN_AT)) &&
                    isnan(get_double(doubles, ORIGIN_AT + 1));
        if (!isfinite(get_double(doubles, i)) && !unset) {
            snprintf(why, why_size, "its stepper part holds values that are not finite");
            return MODEL_ERROR;
        }
    }
    flags = doubles + 8 * n_doubles;
    for (i = 0; i < 3 * (size_t)np; i++) {
        signed char v;
        memcpy(&v, flags + i, 1);
        if (i < 2 * (size_t)np ? (v != 0 && v != 1) : (v < -1 || v > 1)) {
            snprintf(why, why_size, "its stepper part's contact flags are not flags");
            return MODEL_ERROR;
        }
    }
    {
        double spin = get_double(doubles, 12), speed = get_double(doubles, 13),
               ring_spin = get_double(doubles, 14);
        char a[40], b[40], c[40], d[40];
        if (speed != model->speed) {
            py_repr(speed, a, sizeof a);
            py_repr(model->speed, b, sizeof b);
            snprintf(why, why_size, "its road speed %s m/s is not this tire's %s", a, b);
            return MODEL_ERROR;
        }
        if (!(fabs(spin) <= model->spin_limit) || !(fabs(ring_spin) <= model->spin_limit)) {
            py_repr(fabs(spin) > fabs(ring_spin) ? spin : ring_spin, a, sizeof a);
            snprintf(why, why_size, "its wheel spin %s rad/s is beyond what this tire can hold",
                     a);
            return MODEL_ERROR;
        }
        {   /* the road's samples must read as a profile: distances increasing */
            size_t at = STEPPER_SCALARS + 3 * (size_t)ny + 2 * (size_t)np;
            for (i = 1; i < samples; i++) {
                if (!(get_double(doubles, at + 3 * i) > get_double(doubles, at + 3 * (i - 1)))) {
                    snprintf(why, why_size, "its road's samples are not in order along the road");
                    return MODEL_ERROR;
                }
            }
        }
        {   /* the clock: the tire's elapsed time from the start to the layer's time */
            double h_given = get_double(doubles, 16), elapsed = get_double(doubles, 17),
                   length = get_double(doubles, 19), h_accel = get_double(doubles, 23),
                   stepped = start_time + elapsed;
            if (!(0.0 <= h_given && 0.0 <= h_accel && 0.0 <= elapsed &&
                  SPEC_INPLANE_MIN_STEP_S <= length && length <= model->h)) {
                py_repr(elapsed, a, sizeof a);
                py_repr(h_given, b, sizeof b);
                py_repr(length, c, sizeof c);
                py_repr(model->h, d, sizeof d);
                snprintf(why, why_size, "its clock (elapsed %s s, last step %s s, the tire's "
                         "step %s s) is no clock of this tire (step_size %s s)", a, b, c, d);
                return MODEL_ERROR;
            }
            if (!(fabs(stepped - time) <= fmax(SPEC_TIME_ABS_TOLERANCE_S,
                                              SPEC_TIME_REL_TOLERANCE * fabs(time)) + 1e-9)) {
                py_repr(time, a, sizeof a);
                py_repr(start_time, b, sizeof b);
                py_repr(stepped, c, sizeof c);
                py_repr(start_time, d, sizeof d);
                snprintf(why, why_size, SPEC_MSG_STATE_MODEL_CLOCK, a, b, c, d);
                return MODEL_ERROR;
            }
        }
    }
    {   /* what its coordinates are here */
        double* scratch = (double*)mem_alloc(&model->host.mem, 3 * (size_t)model->ny,
                                             sizeof(double));
        double off = 0.0;
        int status = scratch == NULL ? -1
                                     : state_coordinates(model, doubles, ny, np, samples,
                                                         fingerprint, scratch, &off);
        if (status == 0) status = meaning_problem(model, doubles, scratch, ny, np, why, why_size);
        mem_free(&model->host.mem, scratch);
        if (status < 0) {
            snprintf(why, why_size, "out of memory reading its coordinates");
            return MODEL_ERROR;
        }
        if (status == 2) return MODEL_ERROR; /* why says what it means */
        if (status > 0) {
            snprintf(why, why_size, "its tire's shape lies outside this FMU's reduced basis "
                     "(%.2g of it): it was stepped in a basis built differently (another BLAS, "
                     "thread count or CPU can build the modes otherwise), whose span this build "
                     "does not reproduce; restore it in the process that saved it", off);
            return MODEL_ERROR;
        }
    }
    (void)values;
    return MODEL_OK;
}

void model_state_apply(Model* model, const unsigned char* in)
{
    const unsigned char* part = in + FLAGS * 4;
    const unsigned char *doubles = part + STEPPER_HEAD, *flags;
    uint32_t samples, ny_state, dofs, fingerprint;
    int64_t steps;
    int ny = model->ny, P = model->np, i;
    size_t at = 0;
    InPlaneState* s = &model->now;
    int32_t contact;
    memcpy(&contact, in + 4, 4);
    memcpy(&ny_state, part + 8, 4);
    memcpy(&samples, part + 16, 4);
    memcpy(&steps, part + 20, 8);
    memcpy(&dofs, part + 28, 4);
    memcpy(&fingerprint, part + 32, 4);
    for (i = 0; i < 6; i++) model->given[i] = get_double(doubles, at++);
    for (i = 0; i < 6; i++) model->rim[i] = get_double(doubles, at++);
    {
        double spin = get_double(doubles, at), speed = get_double(doubles, at + 1),
               ring_spin = get_double(doubles, at + 2);
        model->rate_given = get_double(doubles, at + 3);
        model->h_given = get_double(doubles, at + 4);
        model->elapsed = get_double(doubles, at + 5);
        model->carry = get_double(doubles, at + 6);
        at += 7;
        if (take_spins(model, ring_spin, spin, speed, get_double(doubles, at++)) != 0)
            say(model, MODEL_ERROR, "logStatusError",
                "fmi2SetFMUstate: the step could not be rebuilt at the state's spin");
        for (i = 0; i < 3; i++) model->accel[i] = get_double(doubles, at++);
        model->h_accel = get_double(doubles, at++);
        model->origin[0] = get_double(doubles, at++);
        model->origin[1] = get_double(doubles, at++);
    }
    {   /* y, y', y'' here (checked by model_state_check: they fit) */
        double* scratch = (double*)mem_alloc(&model->host.mem, 3 * (size_t)ny, sizeof(double));
        double off;
        if (scratch == NULL ||
            state_coordinates(model, doubles, ny_state, (size_t)P, samples, fingerprint,
                              scratch, &off) != 0) {
            say(model, MODEL_ERROR, "logStatusError",
                "fmi2SetFMUstate: out of memory taking the state's coordinates");
        } else {
            memcpy(s->y, scratch, (size_t)ny * sizeof(double));
            memcpy(s->yd, scratch + ny, (size_t)ny * sizeof(double));
            memcpy(s->ydd, scratch + 2 * (size_t)ny, (size_t)ny * sizeof(double));
        }
        mem_free(&model->host.mem, scratch);
        at += 3 * (size_t)ny_state;
    }
    for (i = 0; i < P; i++) s->e[i] = get_double(doubles, at++);
    for (i = 0; i < P; i++) s->f_n[i] = get_double(doubles, at++);
    {   /* the host's samples, rows (s, z, at) */
        double* rows = (double*)mem_alloc(&model->host.mem, 3 * (size_t)samples, sizeof(double));
        for (i = 0; rows != NULL && i < 3 * (int)samples; i++) rows[i] = get_double(doubles, at + i);
        if (rows == NULL || position_road_restore(&model->road, rows, (int)samples) != 0)
            say(model, MODEL_ERROR, "logStatusError",
                "fmi2SetFMUstate: out of memory restoring the road history");
        mem_free(&model->host.mem, rows);
        at += 3 * (size_t)samples;
    }
    at += 3 * (size_t)dofs; /* the DOFs: read through state_coordinates */
    flags = doubles + 8 * at;
    for (i = 0; i < P; i++) s->contact[i] = flags[i] == 1;
    for (i = 0; i < P; i++) s->stick[i] = flags[P + i] == 1;
    for (i = 0; i < P; i++) {
        signed char sign;
        memcpy(&sign, flags + 2 * P + i, 1);
        s->slip_sign[i] = (double)sign;
    }
    model->steps = (long long)steps;
    model->in_contact = contact;
    model->extent_armed = 1; /* inplane_slave's _restored */
}
