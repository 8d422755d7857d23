/* tire_model.c: the tire as a model of the generic FMI layer (model.h).
 *
 * At initialisation: the parameters are checked as the Python FMU checks them (the core's
 * validation: tire data, operating point, truncation, then what needs the model: the critical
 * speed, the contact zone, the load the footprint can carry), every problem is logged with the
 * same text, and only then the model is built: zone, free ring for the speed (order by order),
 * the static footprint for the load by active-set continuation, the road windows, the
 * simulator. The message templates and every tolerance come from spec.h. */
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "contract_pack.h"
#include "kernel.h"
#include "model.h"
#include "model_problems.h"
#include "spec.h"

#define PI 3.14159265358979323846
#define MESSAGE_SIZE 1024

struct Model {
    ModelHost host;
    int built;
    double built_for[SPEC_N_VARIABLES];
    Tire tire;
    int n_elements, linear;
    double speed, critical;
    Ring ring;
    Zone zone;
    FootprintPath path;
    Footprint footprint;
    Windows windows;
    double* compliance;
    TireContract contract;  /* what the step kernel reads */
    TireKernel* kernel;     /* the step: kernel.c, the Python FMU's too */
    int zone_warning_armed;
    int in_contact;
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
    kernel_destroy(model->kernel);
    model->kernel = NULL;
    contract_free(&model->contract, mem);
    footprint_path_free(&model->path, mem);
    footprint_free(&model->footprint, mem);
    windows_free(&model->windows, mem);
    zone_free(&model->zone, mem);
    ring_free(&model->ring, mem);
    mem_free(mem, model->compliance);
    model->compliance = NULL;
    model->built = 0;
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

static void tire_from_values(const double* values, Tire* t)
{
    t->R = values[SPEC_VR_R];
    t->b = values[SPEC_VR_B];
    t->inflation_pressure = values[SPEC_VR_INFLATION_PRESSURE];
    t->rhoA = values[SPEC_VR_RHOA];
    t->m_s = values[SPEC_VR_M_S];
    t->k_r1 = values[SPEC_VR_K_R1];
    t->k_r2 = values[SPEC_VR_K_R2];
    t->EI = values[SPEC_VR_EI];
    t->k_cw = values[SPEC_VR_K_CW];
    t->alpha = values[SPEC_VR_ALPHA];
    t->beta = values[SPEC_VR_BETA];
    t->sidewall_shear = values[SPEC_VR_SIDEWALL_SHEAR];
    t->sidewall_max_order = values[SPEC_VR_SIDEWALL_MAX_ORDER];
    t->sidewall_pressure_exponent = values[SPEC_VR_SIDEWALL_PRESSURE_EXPONENT];
    t->reference_pressure = values[SPEC_VR_REFERENCE_PRESSURE];
}

/* what the Python FMU checks before it builds: truncation, tire data, operating point; the
 * count of problems beyond the truncation's (with none, the model is still built, for the
 * problems only the model finds) */
static int plain_problems(const double* values, Problems* p)
{
    char text[64];
    int truncation_problems;
    double f_max = values[SPEC_VR_F_MAX];
    double n_modes = values[SPEC_VR_N_MODES];
    if (f_max != 0.0 && !(0 < f_max && f_max <= SPEC_F_MAX_LIMIT_HZ)) {
        value_text(f_max, "Hz", text, sizeof text);
        PROBLEM(p, SPEC_MSG_F_MAX_RANGE, text, SPEC_F_MAX_LIMIT_HZ);
    }
    if (n_modes != 0.0 && !(1 <= n_modes && n_modes <= SPEC_N_MODES_LIMIT)) {
        PROBLEM(p, SPEC_MSG_N_MODES_RANGE, (int)n_modes, SPEC_N_MODES_LIMIT);
    }
    truncation_problems = p->count;
    tire_field_problems(values, p);
    {
        double n = values[SPEC_VR_N_ELEMENTS];
        if (!(SPEC_MIN_ELEMENTS <= n && n <= SPEC_MAX_ELEMENTS)) {
            PROBLEM(p, SPEC_MSG_ELEMENTS_RANGE, (int)n, SPEC_MIN_ELEMENTS, SPEC_MAX_ELEMENTS);
        }
    }
    {
        static const struct {
            int vr;
            const char *name, *unit;
        } op[2] = {{SPEC_VR_LOAD, "load", "N"}, {SPEC_VR_SPEED, "speed", "m/s"}};
        int i;
        for (i = 0; i < 2; i++) {
            double value = values[op[i].vr];
            if (!isfinite(value) || value < 0) {
                value_text(value, op[i].unit, text, sizeof text);
                PROBLEM(p, SPEC_MSG_NOT_NONNEGATIVE, op[i].name, text, op[i].unit);
            } else if (op[i].vr == SPEC_VR_SPEED && 0 < value &&
                       value < SPEC_MIN_ROLLING_SPEED_M_S) {
                value_text(value, op[i].unit, text, sizeof text);
                PROBLEM(p, SPEC_MSG_MIN_ROLLING_SPEED, text, SPEC_MIN_ROLLING_SPEED_M_S);
            }
        }
    }
    {   /* parameters.point_spacing_range_problems */
        double spacing = values[SPEC_VR_CONTACT_POINT_SPACING];
        if (!(SPEC_MIN_POINT_SPACING_M <= spacing && spacing <= SPEC_MAX_POINT_SPACING_M)) {
            char allowed[64];
            snprintf(allowed, sizeof allowed, SPEC_MSG_POINT_SPACING_ALLOWED,
                     SPEC_MIN_POINT_SPACING_M, SPEC_MAX_POINT_SPACING_M);
            add_problem(p, "contact_point_spacing", spacing, "m", allowed,
                        SPEC_MSG_POINT_SPACING_REASON);
        }
    }
    return p->count - truncation_problems;
}

static const char* field_unit(const char* name)
{
    int i;
    for (i = 0; i < SPEC_N_TIRE_FIELDS; i++) {
        if (strcmp(SPEC_TIRE_FIELDS[i].name, name) == 0) return SPEC_TIRE_FIELDS[i].unit;
    }
    return "";
}

/* the stiff local terms of parameters._stiff_terms, in its order; bound: the field's value at
 * which the term reaches limit, or NAN when no value of the field alone would do */
#define N_STIFF_TERMS 4
static double stiff_term(const Tire* t, double ds, int which, double limit, double* bound)
{
    double above;
    switch (which) {
    case 0:
        above = limit - t->k_r1;
        *bound = above > 0 ? above : NAN;
        return t->k_r1 + t->k_cw;
    case 1:
        *bound = limit * pow(ds, 4) / 16.0;
        return 16.0 * t->EI / pow(ds, 4);
    case 2:
        *bound = limit * ds * ds / (4.0 * t->b * t->R);
        return 4.0 * t->inflation_pressure * t->b * t->R / (ds * ds);
    default:
        above = (limit - t->k_r1 - t->k_r2) * ds * ds / 4.0;
        *bound = above > 0 ? above : NAN;
        return t->k_r1 + t->k_r2 + 4.0 * t->sidewall_shear / (ds * ds);
    }
}

static const char* const STIFF_FIELDS[N_STIFF_TERMS] = {"k_cw", "EI", "inflation_pressure",
                                                         "sidewall_shear"};
static const char* const STIFF_WHAT[N_STIFF_TERMS] = {
    SPEC_MSG_STIFF_TERM_K_CW, SPEC_MSG_STIFF_TERM_EI, SPEC_MSG_STIFF_TERM_INFLATION_PRESSURE,
    SPEC_MSG_STIFF_TERM_SIDEWALL_SHEAR};

static double field_value(const Tire* t, const char* name)
{
    if (strcmp(name, "k_cw") == 0) return t->k_cw;
    if (strcmp(name, "EI") == 0) return t->EI;
    if (strcmp(name, "inflation_pressure") == 0) return t->inflation_pressure;
    if (strcmp(name, "sidewall_shear") == 0) return t->sidewall_shear;
    if (strcmp(name, "k_r1") == 0) return t->k_r1;
    if (strcmp(name, "k_r2") == 0) return t->k_r2;
    if (strcmp(name, "m_s") == 0) return t->m_s;
    if (strcmp(name, "rhoA") == 0) return t->rhoA;
    return NAN;
}

/* parameters.conditioning_problems: whether double precision resolves the static response;
 * 1 with the problem added when it does not */
static int conditioning_problem(const Tire* t, int n_elements, Problems* p)
{
    Tire reference;
    double ds = t->R * 2.0 * PI / n_elements, support, limit, stiffness = -1, bound = NAN;
    double reference_support, too_stiff, other, needed, unused;
    char reason[MESSAGE_SIZE], allowed[256];
    const char* weak;
    int i, stiffest = 0;
    support = t->k_r1 * t->k_r2 / (t->k_r1 + t->k_r2);
    limit = SPEC_MAX_STIFFNESS_RATIO * support;
    for (i = 0; i < N_STIFF_TERMS; i++) {
        double b, k = stiff_term(t, ds, i, limit, &b);
        if (k > stiffness) {
            stiffness = k;
            bound = b;
            stiffest = i;
        }
    }
    if (stiffness <= limit) return 0;
    {   /* the default tire (GL073A): the start values of the spec's table */
        double defaults[SPEC_N_VARIABLES];
        for (i = 0; i < SPEC_N_VARIABLES; i++) defaults[i] = SPEC_VARIABLES[i].start;
        tire_from_values(defaults, &reference);
    }
    reference_support = reference.k_r1 * reference.k_r2 / (reference.k_r1 + reference.k_r2);
    too_stiff = stiffness / stiff_term(&reference, ds, stiffest, limit, &unused);
    snprintf(reason, sizeof reason, SPEC_MSG_CONDITIONING_REASON, support,
             SPEC_MAX_STIFFNESS_RATIO, STIFF_WHAT[stiffest], stiffness);
    if (too_stiff >= reference_support / support && !isnan(bound)) {
        const char* unit = field_unit(STIFF_FIELDS[stiffest]);
        snprintf(allowed, sizeof allowed, SPEC_MSG_CONDITIONING_STIFF_ALLOWED, bound, unit);
        add_problem(p, STIFF_FIELDS[stiffest], field_value(t, STIFF_FIELDS[stiffest]), unit,
                    allowed, reason);
        return 1;
    }
    if (t->k_r2 <= t->k_r1) {
        weak = "k_r2";
        other = t->k_r1;
    } else {
        weak = "k_r1";
        other = t->k_r2;
    }
    needed = stiffness / SPEC_MAX_STIFFNESS_RATIO;
    if (other > needed) {
        snprintf(allowed, sizeof allowed, SPEC_MSG_CONDITIONING_WEAK_ALLOWED,
                 needed * other / (other - needed));
    } else {
        snprintf(allowed, sizeof allowed, SPEC_MSG_CONDITIONING_WEAK_LARGER, needed);
    }
    add_problem(p, weak, field_value(t, weak), field_unit(weak), allowed, reason);
    return 1;
}

/* the fastest modes of the tire, by stiffness over mass (model.check_resolved's candidates) */
static const char* const RESOLVED_FIELDS[3] = {"m_s", "rhoA", "EI"};
static const char* const RESOLVED_WAYS[3] = {SPEC_MSG_RESOLVED_WAY_M_S, SPEC_MSG_RESOLVED_WAY_RHOA,
                                             SPEC_MSG_RESOLVED_WAY_EI};
static const char* const RESOLVED_WHATS[3] = {SPEC_MSG_RESOLVED_WHAT_M_S,
                                              SPEC_MSG_RESOLVED_WHAT_RHOA,
                                              SPEC_MSG_RESOLVED_WHAT_EI};

static int fastest_modes(const Tire* t, int n_elements, double* ratio)
{
    double ratios[3], step = 2 * PI / n_elements;
    int i, which = 0;
    ratios[0] = (t->k_r1 + t->k_r2) / t->m_s;
    ratios[1] = (t->k_r1 + t->k_cw) / t->rhoA;
    ratios[2] = t->EI * 16 / pow(step * t->R, 4) / t->rhoA;
    for (i = 1; i < 3; i++) {
        if (ratios[i] > ratios[which]) which = i;
    }
    *ratio = ratios[which];
    return which;
}

static void ring_problem(const Tire* t, int n_elements, Problems* p)
{
    double ratio;
    int which = fastest_modes(t, n_elements, &ratio);
    PROBLEM(p, SPEC_MSG_RING_NOT_COMPUTED, RESOLVED_WHATS[which], ratio, RESOLVED_FIELDS[which],
            RESOLVED_WAYS[which]);
}

/* model.check_resolved on the free ring's modes (its rigid rotation, eigenvalue 0, left out);
 * 1 with the problem added when double precision does not resolve them */
static int resolved_problem(const Tire* t, const Ring* ring, int n_elements, Problems* p)
{
    double slow = INFINITY, fast = 0, ratio;
    char spread[64], allowed[512], reason[512];
    int i, finite = 1, count = 0, which;
    for (i = 0; i < ring->n_modes; i++) {
        double magnitude = cx_abs(ring->lam[i]);
        if (ring->lam[i].re == 0.0 && ring->lam[i].im == 0.0) continue;
        if (!isfinite(magnitude)) finite = 0;
        if (magnitude < slow) slow = magnitude;
        if (magnitude > fast) fast = magnitude;
        count++;
    }
    if (count == 0 || (finite && fast <= SPEC_MAX_EIGENVALUE_SPREAD * slow)) return 0;
    which = fastest_modes(t, n_elements, &ratio);
    if (slow > 0 && finite) {
        snprintf(spread, sizeof spread, SPEC_MSG_RESOLVED_SPREAD, fast / slow);
    } else {
        snprintf(spread, sizeof spread, "%s", SPEC_MSG_RESOLVED_SPREAD_UNBOUNDED);
    }
    snprintf(allowed, sizeof allowed, SPEC_MSG_RESOLVED_ALLOWED, RESOLVED_WAYS[which], spread,
             SPEC_MAX_EIGENVALUE_SPREAD);
    snprintf(reason, sizeof reason, SPEC_MSG_RESOLVED_REASON, RESOLVED_WHATS[which], ratio,
             t->beta);
    add_problem(p, RESOLVED_FIELDS[which], field_value(t, RESOLVED_FIELDS[which]),
                field_unit(RESOLVED_FIELDS[which]), allowed, reason);
    return 1;
}

/* a contact the step cannot afford (contact_dynamics.build_contact_model): sub-steps below
 * SPEC_MIN_SUBSTEP_S, or a millisecond of more work than a step may take */
static int contact_problem(const Tire* t, const Ring* ring, const Zone* zone, int n_elements,
                           Problems* p)
{
    double rate = sqrt(t->k_cw / t->rhoA), substep = fmin(SPEC_MAX_SUBSTEP_S, 1.0 / rate);
    double per_interval = ceil(SPEC_WORK_INTERVAL_S / substep * (1 - 1e-12));
    int work = contract_substep_work(ring->n_modes, ring->n_orders, zone->n_zone,
                                     zone->n_points, zone->n_support, ring->truncated);
    char allowed[256], reason[256];
    if (1.0 / rate < SPEC_MIN_SUBSTEP_S) {
        snprintf(allowed, sizeof allowed, SPEC_MSG_SUBSTEP_ALLOWED,
                 t->rhoA / (SPEC_MIN_SUBSTEP_S * SPEC_MIN_SUBSTEP_S), t->rhoA);
        snprintf(reason, sizeof reason, SPEC_MSG_SUBSTEP_REASON, SPEC_MIN_SUBSTEP_S);
    } else if (per_interval * work > SPEC_MAX_STEP_WORK) {
        double most = SPEC_MAX_STEP_WORK / (double)work / SPEC_WORK_INTERVAL_S;
        snprintf(allowed, sizeof allowed, SPEC_MSG_STIFF_CONTACT_ALLOWED, t->rhoA * most * most,
                 t->rhoA, n_elements);
        snprintf(reason, sizeof reason, SPEC_MSG_STIFF_CONTACT_REASON, (int)per_interval, work,
                 SPEC_MAX_STEP_WORK);
    } else {
        return 0;
    }
    add_problem(p, "k_cw", t->k_cw, field_unit("k_cw"), allowed, reason);
    return 1;
}

/* -- initialisation ------------------------------------------------------------------------- */

static int build(Model* model, const double* values, Problems* p, char* warning)
{
    const Memory* mem = &model->host.mem;
    Tire* tire = &model->tire;
    int n = (int)values[SPEC_VR_N_ELEMENTS], half, per_node, status;
    double speed = values[SPEC_VR_SPEED], load = values[SPEC_VR_LOAD], spin;
    Truncation truncation;
    Footprint limit;
    char text[64];
    warning[0] = '\0';
    tire_from_values(values, tire);
    model->n_elements = n;
    model->speed = speed;
    model->linear = values[SPEC_VR_LINEAR_CONTACT] != 0.0;
    if (conditioning_problem(tire, n, p)) return MODEL_ERROR;
    model->critical = critical_speed(tire, n);
    if (speed >= model->critical && values[SPEC_VR_ALLOW_SUPERCRITICAL] == 0.0) {
        value_text(speed, "m/s", text, sizeof text);
        PROBLEM(p, SPEC_MSG_SUPERCRITICAL, text, model->critical, n);
        return MODEL_ERROR;
    }
    if (SPEC_CRITICAL_SPEED_WARNING_FRACTION * model->critical <= speed &&
        speed < model->critical) {
        snprintf(warning, MESSAGE_SIZE, SPEC_MSG_NEAR_CRITICAL, speed,
                 100 * speed / model->critical, model->critical, n);
    }
    if (zone_length_problem(tire->R, n, values[SPEC_VR_CONTACT_ZONE_LENGTH], p))
        return MODEL_ERROR;
    half = zone_half_count(tire->R, n, values[SPEC_VR_CONTACT_ZONE_LENGTH]);
    if (point_count_problem(tire->R, n, half, values[SPEC_VR_CONTACT_POINT_SPACING], &per_node,
                            p)) {
        return MODEL_ERROR;
    }
    spin = speed / tire->R;
    /* a truncation already refused builds the whole ring: for the other problems only */
    truncation.f_max_hz = p->count ? 0.0 : values[SPEC_VR_F_MAX];
    truncation.n_modes = p->count ? 0 : (int)values[SPEC_VR_N_MODES];
    truncation.static_correction = values[SPEC_VR_STATIC_CORRECTION] != 0.0;
    if (zone_build(&model->zone, mem, n, tire->R, tire->k_cw, tire->beta, half, per_node) != 0) {
        goto memory;
    }
    /* the ring is read at the zone nodes: the carrying nodes and, with points between them,
     * two more each side (every point's stencil inside) */
    status = ring_build(&model->ring, mem, tire, n, spin, model->zone.half, &truncation);
    if (status != 0) {
        ring_problem(tire, n, p);
        return MODEL_ERROR;
    }
    model->compliance = (double*)mem_alloc(mem, (size_t)(model->zone.n_zone * model->zone.n_zone),
                                           sizeof(double));
    if (model->compliance == NULL) goto memory;
    ring_compliance(&model->ring, model->compliance);
    status = footprint_path(&model->path, mem, &model->zone, model->compliance,
                            SPEC_MAX_DEFLECTION_FRACTION * tire->R);
    if (status == -2) {
        PROBLEM(p, "the footprint continuation did not terminate (a degenerate contact path); "
                   "report the tire data");
        return MODEL_ERROR;
    }
    if (status != 0) goto memory;
    if (footprint_alloc(&limit, mem, &model->zone) != 0) goto memory;
    max_credible_load(&model->path, &model->zone, SPEC_MAX_PATCH_FRACTION * (2.0 * PI * tire->R),
                      &limit);
    if (load > limit.load) {
        char reason[256];
        if (limit.touches_edge) {
            snprintf(reason, sizeof reason, "%s", SPEC_MSG_LOAD_REASON_ZONE);
        } else {
            snprintf(reason, sizeof reason, SPEC_MSG_LOAD_REASON_LENGTH,
                     SPEC_MAX_PATCH_FRACTION * (2.0 * PI * tire->R));
        }
        value_text(load, "N", text, sizeof text);
        PROBLEM(p, SPEC_MSG_LOAD_RANGE, text, limit.load, limit.load, limit.deflection * 1e3,
                reason);
        footprint_free(&limit, mem);
        return MODEL_ERROR;
    }
    footprint_free(&limit, mem);
    if (resolved_problem(tire, &model->ring, n, p)) return MODEL_ERROR;
    if (contact_problem(tire, &model->ring, &model->zone, n, p)) return MODEL_ERROR;
    if (footprint_alloc(&model->footprint, mem, &model->zone) != 0) goto memory;
    if (footprint_at_load(&model->path, &model->zone, load, &model->footprint) != 0) {
        PROBLEM(p, "load = %g N needs a rim deflection beyond %g m", load,
                model->path.max_deflection);
        return MODEL_ERROR;
    }
    if (windows_build(&model->windows, mem, &model->zone, model->footprint.deflection, speed) !=
        0) {
        goto memory;
    }
    /* the step kernel's contract: the contact is sub-stepped at 1/sqrt(k_cw/rhoA) at most
     * (contact_dynamics.build_contact_model) */
    if (contract_pack(&model->contract, mem, &model->ring, &model->zone, &model->footprint,
                      &model->windows, model->compliance, model->footprint.deflection,
                      fmin(SPEC_MAX_SUBSTEP_S, 1.0 / sqrt(tire->k_cw / tire->rhoA)),
                      model->linear, speed,
                      model->ring.truncated ? SPEC_MIN_CORRECTED_STEP_S : 0.0) != 0) {
        goto memory;
    }
    {
        char why[256];
        if (kernel_create(&model->contract, mem, 0.0, &model->kernel, why, sizeof why) != 0) {
            PROBLEM(p, "the step kernel refused the model: %s", why);
            return MODEL_ERROR;
        }
    }
    return MODEL_OK;
memory:
    PROBLEM(p, "out of memory while building the model (N = %d)", n);
    return MODEL_ERROR;
}

static void show_outputs(Model* model, double* values)
{
    int i;
    double outputs[KERNEL_N_OUTPUTS];
    kernel_outputs(model->kernel, outputs);
    for (i = 0; i < SPEC_BLOCK_N_OUTPUTS; i++) values[SPEC_BLOCK_OUTPUTS_FIRST + i] = outputs[i];
    values[SPEC_BLOCK_IN_CONTACT] = kernel_in_contact(model->kernel) ? 1.0 : 0.0;
}

int model_initialise(Model* model, const double* values, double start_time, double* out_values)
{
    Problems problems;
    char warning[MESSAGE_SIZE], line[MESSAGE_SIZE + 64];
    clock_t started = clock();
    int status, i;
    problems.count = 0;
    model_clear(model);
    status = plain_problems(values, &problems) ? MODEL_ERROR
             : build(model, values, &problems, warning);
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
    if (warning[0] != '\0') say(model, MODEL_WARNING, "logStatusWarning", warning);
    model->built = 1;
    memcpy(model->built_for, values, sizeof model->built_for);
    kernel_reset(model->kernel, start_time);
    model->zone_warning_armed = 1;
    show_outputs(model, out_values);
    model->in_contact = kernel_in_contact(model->kernel);
    snprintf(line, sizeof line,
             "ready in %.3f s (CPU): N = %d, %d of %d ring modes, %d contact-zone nodes, "
             "%d contact points (%d per node), "
             "footprint %.3g cm at %.6g N, deflection %.4g mm, vertical stiffness %.6g N/m, "
             "critical speed %.4g m/s, %s contact",
             (double)(clock() - started) / CLOCKS_PER_SEC, model->n_elements,
             model->ring.n_modes, model->ring.total_modes, model->zone.n_zone,
             model->zone.n_points, model->zone.per_node,
             model->footprint.length * 100, model->footprint.load,
             model->footprint.deflection * 1e3, model->footprint.tangent, model->critical,
             model->linear ? "linear" : "unilateral");
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

static int after_step(Model* model, double* values)
{
    char line[MESSAGE_SIZE];
    int status = MODEL_OK, in_contact;
    show_outputs(model, values);
    in_contact = kernel_in_contact(model->kernel);
    if (in_contact != model->in_contact) {
        /* losing contact is physics (a unilateral contact): information, not a warning */
        snprintf(line, sizeof line, in_contact ? SPEC_MSG_TOUCH_DOWN : SPEC_MSG_LIFT_OFF,
                 kernel_time(model->kernel));
        say(model, MODEL_OK, "logEvents", line);
        model->in_contact = in_contact;
    }
    if (kernel_at_zone_edge(model->kernel)) {
        if (model->zone_warning_armed) {
            model->zone_warning_armed = 0;
            /* logged as a warning, but the step is OK, as in the Python FMU (whose wrapper
             * cannot return fmi2Warning from a step): a strict host must not end a ride run
             * because the footprint touched the zone's end for a moment */
            snprintf(line, sizeof line, SPEC_MSG_ZONE_EDGE, kernel_time(model->kernel));
            say(model, MODEL_WARNING, "logStatusWarning", line);
        }
    } else {
        model->zone_warning_armed = 1;
    }
    return status;
}

int model_step(Model* model, double h, double* values)
{
    const double* inputs = values + SPEC_BLOCK_INPUTS_FIRST;
    int status = kernel_step(model->kernel, h, inputs, NULL);
    if (status != KERNEL_OK) {
        /* the layer checked h and the inputs with the kernel's rules: a refusal is a bug */
        say(model, MODEL_ERROR, "logStatusError", status == KERNEL_REFUSED
            ? "fmi2DoStep: the step kernel refused a step the FMU's checks passed"
            : "fmi2DoStep: out of memory");
        return MODEL_ERROR;
    }
    return after_step(model, values);
}

/* the layer's checks are the radial model's rules: it has none of its own, and never
 * refuses a step as it goes */
const char* model_step_problem(const Model* model, double h, char* why, size_t size)
{
    (void)model;
    (void)h;
    (void)why;
    (void)size;
    return NULL;
}

const char* model_step_refusal(const Model* model)
{
    (void)model;
    return "";
}

int model_refresh(Model* model, double* values)
{
    if (kernel_outputs_with(model->kernel, values + SPEC_BLOCK_INPUTS_FIRST, NULL) != KERNEL_OK) {
        say(model, MODEL_ERROR, "logStatusError", "out of memory recomputing the outputs");
        return MODEL_ERROR;
    }
    show_outputs(model, values);
    return MODEL_OK;
}

double model_time(const Model* model) { return kernel_time(model->kernel); }

const TireContract* model_contract(const Model* model)
{
    return model->built ? &model->contract : NULL;
}

double model_road_horizon(const Model* model) { return kernel_horizon(model->kernel); }

double model_min_step(const Model* model) { return kernel_min_step(model->kernel); }

int model_step_work(const Model* model, double h, int* n_sub, double* substep, int* work,
                    double* longest)
{
    double count;
    *substep = model->contract.substep_s;
    *work = model->contract.substep_work;
    count = ceil(h / *substep * (1 - SPEC_SUBSTEP_SLACK));
    *n_sub = count < 2147483647.0 ? (int)count : 2147483647;
    *longest = floor((double)SPEC_MAX_STEP_WORK / *work) * *substep;
    return count * *work > SPEC_MAX_STEP_WORK;
}

/* -- the model's part of an FMU state --------------------------------------------------------
 * int32: zone warning armed, in contact; then the step kernel's state (kernel.c: its layout,
 * and what it must mean to be set). */

#define FLAGS SPEC_STATE_MODEL_FLAGS

size_t model_state_size(const Model* model) { return FLAGS * 4 + kernel_state_size(model->kernel); }

static void put_int(unsigned char** out, int value)
{
    int32_t v = (int32_t)value;
    memcpy(*out, &v, 4);
    *out += 4;
}

static int get_int(const unsigned char* in, int index)
{
    int32_t v;
    memcpy(&v, in + 4 * index, 4);
    return (int)v;
}

void model_state_write(const Model* model, unsigned char* out)
{
    put_int(&out, model->zone_warning_armed);
    put_int(&out, model->in_contact);
    kernel_state_write(model->kernel, out);
}

/* the problems found so far, "; " between them (as the core joins them) */
static void add_why(char* why, size_t why_size, const char* text)
{
    size_t used = strlen(why);
    if (used + 2 >= why_size) return;
    snprintf(why + used, why_size - used, "%s%s", used ? "; " : "", text);
}

int model_state_check(const Model* model, const unsigned char* in, size_t size,
                      const double* values, double time, double start_time, char* why,
                      size_t why_size)
{
    const unsigned char* kernel_part = in + FLAGS * 4;
    int i;
    why[0] = '\0';
    if (size < FLAGS * 4) {
        snprintf(why, why_size, SPEC_MSG_STATE_MODEL_SHORT, (unsigned long)size);
        return MODEL_ERROR;
    }
    for (i = 0; i < FLAGS; i++) {
        if (get_int(in, i) != 0 && get_int(in, i) != 1) {
            snprintf(why, why_size, SPEC_MSG_STATE_MODEL_FLAG, i, get_int(in, i));
            return MODEL_ERROR;
        }
    }
    if (kernel_state_check(model->kernel, kernel_part, size - FLAGS * 4, why, why_size) !=
        KERNEL_OK) {
        return MODEL_ERROR;
    }
    {   /* the FMU's part against the kernel's: one time, one start, the outputs it shows */
        char text[512], a[40], b[40], c[40], d[40];
        double outputs[KERNEL_N_OUTPUTS];
        int wrong = 0;
        if (kernel_state_start(kernel_part) != start_time ||
            kernel_state_time(kernel_part) != time) {
            py_repr(time, a, sizeof a);
            py_repr(start_time, b, sizeof b);
            py_repr(kernel_state_time(kernel_part), c, sizeof c);
            py_repr(kernel_state_start(kernel_part), d, sizeof d);
            snprintf(text, sizeof text, SPEC_MSG_STATE_MODEL_CLOCK, a, b, c, d);
            add_why(why, why_size, text);
        }
        kernel_state_outputs(kernel_part, outputs);
        for (i = 0; i < SPEC_BLOCK_N_OUTPUTS; i++) {
            if (values[SPEC_BLOCK_OUTPUTS_FIRST + i] != outputs[i]) wrong = 1;
        }
        /* (the model's own in-contact flag is the last one it logged an event for, which
         * outputs read after new inputs, before a step, may have left behind) */
        if (values[SPEC_BLOCK_IN_CONTACT] != (outputs[2] > 0.0 ? 1.0 : 0.0)) wrong = 1;
        if (wrong) add_why(why, why_size, SPEC_MSG_STATE_MODEL_OUTPUTS);
    }
    return why[0] == '\0' ? MODEL_OK : MODEL_ERROR;
}

void model_state_apply(Model* model, const unsigned char* in)
{
    model->zone_warning_armed = get_int(in, 0);
    model->in_contact = get_int(in, 1);
    if (kernel_state_apply(model->kernel, in + FLAGS * 4) != KERNEL_OK) {
        say(model, MODEL_ERROR, "logStatusError",
            "fmi2SetFMUstate: out of memory restoring the road history");
    }
}
