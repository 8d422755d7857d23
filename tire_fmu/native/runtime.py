"""The C half of every native FMU: the FMI 2.0 co-simulation runtime, the same for every export.

It is kept as Python text rather than a ``.c`` file in the package so that an installed
``tire_fmu`` needs no package-data configuration to find it. :mod:`.codegen` writes it out
next to the generated model tables (``tire_model_data.h``), which it includes.
"""

RUNTIME_FILE = "tire_native.c"
DATA_FILE = "tire_model_data.h"

RUNTIME_C = r"""/* tire_native.c: FMI 2.0 co-simulation runtime of a reduced in-plane ring tire
 * (tire_fmu).
 *
 * The same file for every export; the model itself is in tire_model_data.h. The model is in
 * diagonal modal form, one complex mode per conjugate pair (the partner is the conjugate):
 *
 *     q' = diag(lambda) q + B r,      y = static + Re(C q) + D r + E v,
 *
 * with internal inputs r = [rim_z, road_z as each road delay group sees it] and their
 * velocities v. Over a communication step the inputs ramp from r with velocity v, so the step
 * is exact whatever h is:
 *
 *     q(t + h) = e^{lambda h} q + h phi1(lambda h) B r + h^2 phi2(lambda h) B v,
 *
 * and the outputs are read at the end of the step, with r + v h and v. The coefficients depend
 * on h only; a few values of h are cached, so a host that varies its step pays once per h.
 * With speed, the road is recorded at the communication points and read back at t - tau for
 * each delay group by cubic Hermite interpolation (exact for the ramps the step assumes).
 *
 * Reference semantics: tire_fmu.core.simulation.TireSimulator and the Python FMU
 * (tire_fmu.fmu.slave), whose variables, messages and statuses this file mirrors:
 *   - a refused doStep (not initialised, time off the last communication point, h <= 0 or not
 *     finite, a non-finite input) returns fmi2Discard and changes nothing, so the host may fix
 *     the call and retry;
 *   - a refused variable access (unknown reference, wrong type, setting an output, changing a
 *     fixed parameter: the reduced model is compiled in) returns fmi2Error and ignores the value;
 *   - losing contact returns fmi2Warning from that doStep, logged once per episode.
 * Problems (warning and worse) always reach the host's logger; information only with
 * loggingOn or the category logAll.
 *
 * All an instance needs lives in its Instance: no global mutable state, so instances are
 * independent of each other.
 */

#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

typedef enum { TYPE_REAL, TYPE_INTEGER, TYPE_BOOLEAN } VariableType;
typedef enum { CAUSALITY_PARAMETER, CAUSALITY_INPUT, CAUSALITY_OUTPUT } Causality;

typedef struct {
    const char* name;
    VariableType type;
    Causality causality;
    double value;          /* parameters: the export value (Integer and Boolean as numbers) */
    const char* unit;
    const char* reexport;  /* parameters: the export option that sets another value */
} VariableInfo;

/* Inputs and outputs, in value-reference order from VR_FIRST_INPUT and VR_FIRST_OUTPUT. */
enum { RIM_Z, RIM_VZ, ROAD_Z, ROAD_VZ, N_FMU_INPUTS };
enum { RIM_FZ, RIM_FX, CONTACT_FZ, DEFLECTION, N_REAL_OUTPUTS };

#include "tire_model_data.h"

#define N_COLUMNS (2 * N_INPUTS)  /* [r, v]: the step gains act on both */
#define LANES 4          /* N_MODES_PAD is a multiple of it: the mode loops run in whole vectors */
#define CACHE_SIZE 8     /* step sizes whose coefficients are kept */
#define MESSAGE_SIZE 1024
#define NUMBER_SIZE 32   /* a double as text */

/* The stepping loops run over separate arrays; saying so lets the compiler vectorise them. */
#if defined(_MSC_VER)
#define RESTRICT __restrict
#else
#define RESTRICT restrict
#endif

typedef struct { double re, im; } Complex;

typedef enum { PHASE_INSTANTIATED, PHASE_INITIALISING, PHASE_RUNNING, PHASE_TERMINATED } Phase;
#define N_PHASES 4

/* Coefficients of one step size. The gains are stored column by column (input-major), so that
 * adding one input's contribution to every mode is a contiguous loop. */
typedef struct {
    double h;
    double decay_re[N_MODES_PAD], decay_im[N_MODES_PAD];  /* e^{lambda h} */
    double gain_re[N_COLUMNS][N_MODES_PAD];  /* [h phi1 B, h^2 phi2 B], real part */
    double gain_im[N_COLUMNS][N_MODES_PAD];  /* imaginary part */
} StepCoefficients;

/* Road height and velocity at the leading edge, at past communication points (oldest first,
 * from index start of the buffers). */
typedef struct {
    double *t, *z, *v;
    size_t start, count, capacity;
} RoadHistory;

/* Where messages go: the host's logger, and which of them it wants. */
typedef struct {
    fmi2CallbackLogger logger;
    fmi2ComponentEnvironment environment;
    const char* name;  /* the instance name */
    unsigned mask;
} LogTarget;

typedef struct {
    /* the host */
    LogTarget log;
    fmi2CallbackAllocateMemory allocate;
    fmi2CallbackFreeMemory release;
    char* name;

    /* the simulation */
    Phase phase;
    double start_time;
    double time;  /* the last communication point */
    double inputs[N_FMU_INPUTS];
    double outputs[N_REAL_OUTPUTS];
    int in_contact;
    int contact_warning_armed;  /* the next loss of contact is logged */
    int stale;  /* inputs set since the outputs were computed: the next read recomputes them */
    double q_re[N_MODES_PAD], q_im[N_MODES_PAD];
    RoadHistory road;

    /* derived, not part of the FMU state: coefficients per step size, oldest first from
     * cache_next once the cache is full */
    StepCoefficients cache[CACHE_SIZE];
    int cache_count, cache_next;
    int current;        /* entry used by the last step, -1 for none */
    double current_h;   /* the step size that selected it */
} Instance;

/* ---------------------------------------------------------------------------------------- */
/* Logging                                                                                  */

enum {
    LOG_WARNING = 1u << 0,
    LOG_DISCARD = 1u << 1,
    LOG_ERROR = 1u << 2,
    LOG_ALL = 1u << 3,
    LOG_PROBLEMS = LOG_WARNING | LOG_DISCARD | LOG_ERROR,
    LOG_EVERYTHING = LOG_PROBLEMS | LOG_ALL
};

/* Names as in the model description's LogCategories. */
static const char* const LOG_CATEGORY_NAMES[] = {
    "logStatusWarning", "logStatusDiscard", "logStatusError", "logAll"};
#define N_LOG_CATEGORIES 4

static unsigned log_bit(fmi2Status status)
{
    switch (status) {
    case fmi2Warning: return LOG_WARNING;
    case fmi2Discard: return LOG_DISCARD;
    case fmi2Error:
    case fmi2Fatal: return LOG_ERROR;
    default: return LOG_ALL;
    }
}

static const char* log_category(fmi2Status status)
{
    switch (status) {
    case fmi2Warning: return LOG_CATEGORY_NAMES[0];
    case fmi2Discard: return LOG_CATEGORY_NAMES[1];
    case fmi2Error:
    case fmi2Fatal: return LOG_CATEGORY_NAMES[2];
    default: return LOG_CATEGORY_NAMES[3];
    }
}

/* Format the message here and hand it over as "%s": the host's logger treats its message
 * argument as a printf format, and a message must never be read as one. */
static void log_to(const LogTarget* target, fmi2Status status, const char* format, va_list args)
{
    char message[MESSAGE_SIZE];
    if (target->logger == NULL || !(target->mask & log_bit(status))) return;
    vsnprintf(message, sizeof message, format, args);
    target->logger(target->environment, target->name, status, log_category(status), "%s",
                   message);
}

static void log_message(const Instance* inst, fmi2Status status, const char* format, ...)
{
    va_list args;
    va_start(args, format);
    log_to(&inst->log, status, format, args);
    va_end(args);
}

/* Before an instance exists (fmi2Instantiate failing). */
static void log_early(const LogTarget* target, fmi2Status status, const char* format, ...)
{
    va_list args;
    va_start(args, format);
    log_to(target, status, format, args);
    va_end(args);
}

/* A double as Python's repr writes it (the fewest digits that read back to the same value,
 * positional from 1e-4 to 1e16), so messages quote exactly what the host passed, in the
 * words of the Python FMU. */
static const char* number_text(char* out, double x)
{
    int digits, exponent;
    if (isnan(x)) return strcpy(out, "nan");
    if (isinf(x)) return strcpy(out, x > 0 ? "inf" : "-inf");
    for (digits = 1; digits < 17; digits++) {
        snprintf(out, NUMBER_SIZE, "%.*e", digits - 1, x);
        if (strtod(out, NULL) == x) break;
    }
    snprintf(out, NUMBER_SIZE, "%.*e", digits - 1, x);
    exponent = atoi(strchr(out, 'e') + 1);
    if (exponent >= -4 && exponent < 16) {
        snprintf(out, NUMBER_SIZE, "%.*f", digits - 1 - exponent > 0 ? digits - 1 - exponent : 0,
                 x);
        if (strchr(out, '.') == NULL) strcat(out, ".0");
    } else if (digits == 1) {  /* repr writes 1e+16, not 1.e+16 */
        snprintf(out, NUMBER_SIZE, "%.0e", x);
    }
    return out;
}

static const char* value_text(char* out, VariableType type, double value)
{
    if (type == TYPE_BOOLEAN) return value != 0.0 ? "true" : "false";
    if (type == TYPE_INTEGER) {
        snprintf(out, NUMBER_SIZE, "%.0f", value);
        return out;
    }
    return number_text(out, value);
}

/* ---------------------------------------------------------------------------------------- */
/* Complex arithmetic, written out (C99 complex is not portable to every compiler a host may  */
/* build the sources with), following numpy's formulas so that C and Python agree closely.   */

static Complex c_mul(Complex a, Complex b)
{
    Complex r;
    r.re = a.re * b.re - a.im * b.im;
    r.im = a.re * b.im + a.im * b.re;
    return r;
}

/* Smith's division, as numpy divides complex numbers. */
static Complex c_div(Complex a, Complex b)
{
    Complex r;
    double ratio, scale;
    if (fabs(b.re) >= fabs(b.im)) {
        ratio = b.im / b.re;
        scale = 1.0 / (b.re + b.im * ratio);
        r.re = (a.re + a.im * ratio) * scale;
        r.im = (a.im - a.re * ratio) * scale;
    } else {
        ratio = b.re / b.im;
        scale = 1.0 / (b.im + b.re * ratio);
        r.re = (a.re * ratio + a.im) * scale;
        r.im = (a.im * ratio - a.re) * scale;
    }
    return r;
}

static Complex c_real_div(Complex a, double b)
{
    Complex divisor;
    divisor.re = b;
    divisor.im = 0.0;
    return c_div(a, divisor);
}

static Complex c_exp(Complex z)
{
    Complex r;
    double magnitude = exp(z.re);
    r.re = magnitude * cos(z.im);
    r.im = magnitude * sin(z.im);
    return r;
}

/* e^z - 1 without cancellation for small |z|: expm1(x) cos y - 2 sin^2(y/2) + i e^x sin y. */
static Complex c_expm1(Complex z)
{
    Complex r;
    double half_sine = sin(z.im / 2.0);
    r.re = expm1(z.re) * cos(z.im) - 2.0 * half_sine * half_sine;
    r.im = exp(z.re) * sin(z.im);
    return r;
}

/* phi1(z) = (e^z - 1)/z and phi2(z) = (e^z - 1 - z)/z^2; below |z| = PHI_SERIES_LIMIT their
 * Taylor series, where e^z - 1 - z cancels. */
static void phi_functions(Complex z, Complex* phi1, Complex* phi2)
{
    if (hypot(z.re, z.im) < PHI_SERIES_LIMIT) {
        Complex z2 = c_mul(z, z), z3 = c_mul(z2, z);
        Complex a = c_real_div(z, 2.0), b = c_real_div(z2, 6.0), c = c_real_div(z3, 24.0);
        phi1->re = 1.0 + a.re + b.re + c.re;
        phi1->im = a.im + b.im + c.im;
        a = c_real_div(z, 6.0);
        b = c_real_div(z2, 24.0);
        c = c_real_div(z3, 120.0);
        phi2->re = 0.5 + a.re + b.re + c.re;
        phi2->im = a.im + b.im + c.im;
    } else {
        Complex em1 = c_expm1(z), rest;
        *phi1 = c_div(em1, z);
        rest.re = em1.re - z.re;
        rest.im = em1.im - z.im;
        *phi2 = c_div(rest, c_mul(z, z));
    }
}

/* ---------------------------------------------------------------------------------------- */
/* Exact stepping                                                                           */

static void compute_coefficients(StepCoefficients* k, double h)
{
    int i, j;
    k->h = h;
    for (i = 0; i < N_MODES; i++) {
        Complex z, phi1, phi2, g1, g2;
        z.re = EIGEN_RE[i] * h;
        z.im = EIGEN_IM[i] * h;
        phi_functions(z, &phi1, &phi2);
        g1.re = h * phi1.re;
        g1.im = h * phi1.im;
        g2.re = h * h * phi2.re;
        g2.im = h * h * phi2.im;
        {
            Complex decay = c_exp(z);
            k->decay_re[i] = decay.re;
            k->decay_im[i] = decay.im;
        }
        for (j = 0; j < N_INPUTS; j++) {
            Complex b, on_r, on_v;
            b.re = B_RE[i][j];
            b.im = B_IM[i][j];
            on_r = c_mul(g1, b);
            on_v = c_mul(g2, b);
            k->gain_re[j][i] = on_r.re;
            k->gain_im[j][i] = on_r.im;
            k->gain_re[N_INPUTS + j][i] = on_v.re;
            k->gain_im[N_INPUTS + j][i] = on_v.im;
        }
    }
}

static void clear_cache(Instance* inst)
{
    inst->cache_count = 0;
    inst->cache_next = 0;
    inst->current = -1;
    inst->current_h = 0.0;
}

/* The coefficients for a step h taken at time t. A step that differs from a cached one by
 * less than the time axis resolves at t is that step: hosts that compute h as a difference of
 * communication points jitter it in the last bits, and the jitter does not accumulate because
 * the host's clock stays the reference. Cached steps are searched oldest first and the oldest
 * is replaced when the cache is full, as in the Python reference. */
static const StepCoefficients* coefficients_for(Instance* inst, double t, double h)
{
    int n, slot = -1;
    if (inst->current >= 0 && h == inst->current_h) return &inst->cache[inst->current];
    {
        double resolution = SAME_STEP_EPS * (fabs(t) + h);
        int oldest = inst->cache_count < CACHE_SIZE ? 0 : inst->cache_next;
        for (n = 0; n < inst->cache_count; n++) {
            int i = (oldest + n) % CACHE_SIZE;
            if (fabs(h - inst->cache[i].h) <= resolution) {
                slot = i;
                break;
            }
        }
    }
    if (slot < 0) {
        slot = inst->cache_next;
        inst->cache_next = (inst->cache_next + 1) % CACHE_SIZE;
        if (inst->cache_count < CACHE_SIZE) inst->cache_count++;
        compute_coefficients(&inst->cache[slot], h);
    }
    inst->current = slot;
    inst->current_h = h;
    return &inst->cache[slot];
}

/* The three loops of a step, over separate arrays (restrict says so, and lets the compiler
 * vectorise them). They run over N_MODES_PAD, whole groups of LANES; the padding modes have
 * zero coefficients and stay zero. */

/* q = e^{lambda h} q, element-wise and complex */
static void decay_modes(double* RESTRICT q_re, double* RESTRICT q_im,
                        const double* RESTRICT d_re, const double* RESTRICT d_im)
{
    int i;
    for (i = 0; i < N_MODES_PAD; i++) {
        const double re = q_re[i], im = q_im[i];
        q_re[i] = d_re[i] * re - d_im[i] * im;
        q_im[i] = d_re[i] * im + d_im[i] * re;
    }
}

/* q += g1 u1 + g2 u2: inputs are real, so each column adds a real multiple of a complex
 * vector; two columns per pass halve the traffic through q */
static void add_columns(double* RESTRICT q_re, double* RESTRICT q_im,
                        const double* RESTRICT g1_re, const double* RESTRICT g1_im, double u1,
                        const double* RESTRICT g2_re, const double* RESTRICT g2_im, double u2)
{
    int i;
    for (i = 0; i < N_MODES_PAD; i++) {
        q_re[i] += g1_re[i] * u1 + g2_re[i] * u2;
        q_im[i] += g1_im[i] * u1 + g2_im[i] * u2;
    }
}

/* y = Re(C q), one pass over q for all outputs, in LANES partial sums per output:
 * independent additions the processor overlaps, where one running sum would wait for each
 * addition in turn */
static void read_outputs(const double* RESTRICT q_re, const double* RESTRICT q_im,
                         double* RESTRICT y)
{
    double lane[N_REAL_OUTPUTS][LANES] = {{0.0}};
    int i, l, o;
    for (i = 0; i < N_MODES_PAD; i += LANES) {
        for (o = 0; o < N_REAL_OUTPUTS; o++) {
            for (l = 0; l < LANES; l++) {
                lane[o][l] += C_RE[o][i + l] * q_re[i + l] - C_IM[o][i + l] * q_im[i + l];
            }
        }
    }
    for (o = 0; o < N_REAL_OUTPUTS; o++) {
        y[o] = 0.0;
        for (l = 0; l < LANES; l++) y[o] += lane[o][l];
    }
}

/* Advance the modes over the step and read the outputs at its end. u = [r, v] at the start. */
static void advance(Instance* inst, const StepCoefficients* k, const double u[N_COLUMNS])
{
    double y[N_REAL_OUTPUTS];
    int j, o;
    decay_modes(inst->q_re, inst->q_im, k->decay_re, k->decay_im);
    for (j = 0; j < N_INPUTS; j++) {  /* an input and its velocity together */
        add_columns(inst->q_re, inst->q_im, k->gain_re[j], k->gain_im[j], u[j],
                    k->gain_re[N_INPUTS + j], k->gain_im[N_INPUTS + j], u[N_INPUTS + j]);
    }
    read_outputs(inst->q_re, inst->q_im, y);
    for (o = 0; o < N_REAL_OUTPUTS; o++) {
        for (j = 0; j < N_INPUTS; j++) {
            const double v = u[N_INPUTS + j];
            y[o] += D[o][j] * (u[j] + k->h * v) + E[o][j] * v;
        }
        /* the static value last: the deviation keeps its own precision until then */
        inst->outputs[o] = y[o] + STATIC_OUTPUT[o];
    }
}

/* ---------------------------------------------------------------------------------------- */
/* Road delay line                                                                          */

static void free_road(Instance* inst)
{
    if (inst->road.t != NULL) inst->release(inst->road.t);
    if (inst->road.z != NULL) inst->release(inst->road.z);
    if (inst->road.v != NULL) inst->release(inst->road.v);
    memset(&inst->road, 0, sizeof inst->road);
}

/* Make room for `needed` samples after the first kept one; 0 when out of memory (nothing
 * changed then). */
static int reserve_road(Instance* inst, size_t needed)
{
    RoadHistory* road = &inst->road;
    size_t capacity;
    double *t, *z, *v;
    if (road->start + needed <= road->capacity) return 1;
    if (needed <= road->capacity) {  /* room enough once the dropped samples are gone */
        memmove(road->t, road->t + road->start, road->count * sizeof(double));
        memmove(road->z, road->z + road->start, road->count * sizeof(double));
        memmove(road->v, road->v + road->start, road->count * sizeof(double));
        road->start = 0;
        return 1;
    }
    capacity = road->capacity ? road->capacity : 64;
    while (capacity < needed) capacity *= 2;
    t = (double*)inst->allocate(capacity, sizeof(double));
    z = (double*)inst->allocate(capacity, sizeof(double));
    v = (double*)inst->allocate(capacity, sizeof(double));
    if (t == NULL || z == NULL || v == NULL) {
        if (t != NULL) inst->release(t);
        if (z != NULL) inst->release(z);
        if (v != NULL) inst->release(v);
        return 0;
    }
    if (road->count > 0) {
        memcpy(t, road->t + road->start, road->count * sizeof(double));
        memcpy(z, road->z + road->start, road->count * sizeof(double));
        memcpy(v, road->v + road->start, road->count * sizeof(double));
    }
    if (road->t != NULL) inst->release(road->t);
    if (road->z != NULL) inst->release(road->z);
    if (road->v != NULL) inst->release(road->v);
    road->t = t;
    road->z = z;
    road->v = v;
    road->start = 0;
    road->capacity = capacity;
    return 1;
}

/* How many of the n times are <= x (numpy's searchsorted side="right"). */
static size_t count_not_after(const double* times, size_t n, double x)
{
    size_t low = 0, high = n;
    while (low < high) {
        size_t middle = low + (high - low) / 2;
        if (times[middle] <= x) low = middle + 1;
        else high = middle;
    }
    return low;
}

/* Record the road at communication point t; room for one more sample must be reserved. */
static void record_road(Instance* inst, double t, double z, double vz)
{
    RoadHistory* road = &inst->road;
    size_t keep, last;
    /* within the time tolerance of the newest sample is that point again: outputs read there
     * before its step record it first, and hosts hand back their own clock */
    if (road->count > 0 && road->t[road->start + road->count - 1]
                           >= t - fmax(TIME_ABS_TOLERANCE, TIME_REL_TOLERANCE * fabs(t))) {
        /* the same communication point again (a retried step): replace, never duplicate */
        last = road->start + road->count - 1;
        road->z[last] = z;
        road->v[last] = vz;
        return;
    }
    /* keep what the longest delay can still reach, plus the sample just before it */
    keep = count_not_after(road->t + road->start, road->count, t - ROAD_HORIZON);
    keep = keep > 0 ? keep - 1 : 0;
    road->start += keep;
    road->count -= keep;
    last = road->start + road->count;
    road->t[last] = t;
    road->z[last] = z;
    road->v[last] = vz;
    road->count++;
}

/* Road height and slope at a past time: cubic Hermite between communication points, level at
 * the first value before the first one. */
static void road_at(const RoadHistory* road, double x, double* height, double* slope)
{
    const double* t = road->t + road->start;
    const double* z = road->z + road->start;
    const double* v = road->v + road->start;
    size_t n = road->count, i;
    double dt, s, s2, s3, z0, z1, v0, v1;
    if (x < t[0]) {
        *height = z[0];
        *slope = 0.0;
        return;
    }
    if (n == 1) {
        *height = z[0];
        *slope = v[0];
        return;
    }
    /* the interval that holds x, as numpy's clip(searchsorted(t, x, "right") - 1, 0, n - 2) */
    i = count_not_after(t, n, x) - 1;
    if (i > n - 2) i = n - 2;
    dt = t[i + 1] - t[i];
    s = (x - t[i]) / dt;
    z0 = z[i];
    z1 = z[i + 1];
    v0 = v[i] * dt;
    v1 = v[i + 1] * dt;
    s2 = s * s;
    s3 = s * s * s;
    *height = (2 * s3 - 3 * s2 + 1) * z0 + (s3 - 2 * s2 + s) * v0
              + (-2 * s3 + 3 * s2) * z1 + (s3 - s2) * v1;
    *slope = ((6 * s2 - 6 * s) * z0 + (3 * s2 - 4 * s + 1) * v0
              + (-6 * s2 + 6 * s) * z1 + (3 * s2 - 2 * s) * v1) / dt;
}

/* The internal inputs [r, v] at communication point t. */
static void internal_inputs(Instance* inst, double t, double u[N_COLUMNS])
{
    int j;
    u[0] = inst->inputs[RIM_Z];
    u[N_INPUTS] = inst->inputs[RIM_VZ];
    if (!ROAD_DELAYED) {  /* at rest the whole patch sees the road at once */
        for (j = 1; j < N_INPUTS; j++) {
            u[j] = inst->inputs[ROAD_Z];
            u[N_INPUTS + j] = inst->inputs[ROAD_VZ];
        }
        return;
    }
    record_road(inst, t, inst->inputs[ROAD_Z], inst->inputs[ROAD_VZ]);
    for (j = 1; j < N_INPUTS; j++) {
        road_at(&inst->road, t - INPUT_DELAY[j], &u[j], &u[N_INPUTS + j]);
    }
}

/* Outputs at the current communication point for the inputs set there, the state left alone.
 * A step reports its outputs at its end with the inputs ramped from its start; once the host
 * sets the inputs of the new point, the direct feedthrough (the contact spring and damper on
 * the road, the sidewall on the rim) uses those: the contact damper alone passes about
 * 1.7e4 N s/m of road velocity straight to the contact force. */
static void refresh_outputs(Instance* inst)
{
    double u[N_COLUMNS], y[N_REAL_OUTPUTS];
    char a[NUMBER_SIZE];
    int i, j, o, bad = 0;
    inst->stale = 0;
    for (i = 0; i < N_FMU_INPUTS; i++) bad |= !isfinite(inst->inputs[i]);
    if (bad) {
        log_message(inst, fmi2Warning, "outputs kept from the last step: non-finite input");
        return;
    }
    if (ROAD_DELAYED && !reserve_road(inst, inst->road.count + 1)) {
        log_message(inst, fmi2Error, "outputs kept from the last step at t = %s s: out of "
                    "memory for the road history", number_text(a, inst->time));
        return;
    }
    internal_inputs(inst, inst->time, u);
    read_outputs(inst->q_re, inst->q_im, y);
    for (o = 0; o < N_REAL_OUTPUTS; o++) {
        for (j = 0; j < N_INPUTS; j++) y[o] += D[o][j] * u[j] + E[o][j] * u[N_INPUTS + j];
        inst->outputs[o] = y[o] + STATIC_OUTPUT[o];
    }
    inst->in_contact = inst->outputs[CONTACT_FZ] > 0.0;
}

/* ---------------------------------------------------------------------------------------- */
/* Instance lifecycle                                                                       */

/* The state of a fresh instance: at rest in static equilibrium, nothing recorded. */
static void start_over(Instance* inst)
{
    int i;
    inst->phase = PHASE_INSTANTIATED;
    inst->start_time = 0.0;
    inst->time = 0.0;
    for (i = 0; i < N_FMU_INPUTS; i++) inst->inputs[i] = 0.0;
    for (i = 0; i < N_REAL_OUTPUTS; i++) inst->outputs[i] = STATIC_OUTPUT[i];
    inst->in_contact = STATIC_OUTPUT[CONTACT_FZ] > 0.0;
    inst->contact_warning_armed = 1;
    inst->stale = 0;
    memset(inst->q_re, 0, sizeof inst->q_re);
    memset(inst->q_im, 0, sizeof inst->q_im);
    inst->road.start = 0;
    inst->road.count = 0;
    clear_cache(inst);
}

static void* default_allocate(size_t count, size_t size) { return calloc(count, size); }

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions* functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn)
{
    Instance* inst;
    LogTarget log;
    const char* name = instanceName != NULL ? instanceName : "";
    (void)fmuResourceLocation;
    (void)visible;
    log.logger = functions != NULL ? functions->logger : NULL;
    log.environment = functions != NULL ? functions->componentEnvironment : NULL;
    log.name = name;
    log.mask = LOG_EVERYTHING;
    if (fmuType != fmi2CoSimulation) {
        log_early(&log, fmi2Error, "fmi2Instantiate: %s is a co-simulation FMU only (it has "
                    "no model-exchange interface)", MODEL_IDENTIFIER);
        return NULL;
    }
    if (fmuGUID == NULL || strcmp(fmuGUID, MODEL_GUID) != 0) {
        log_early(&log, fmi2Error, "fmi2Instantiate: GUID %s does not match this binary's "
                    "%s: the modelDescription.xml and the binary come from different exports",
                    fmuGUID != NULL ? fmuGUID : "(null)", MODEL_GUID);
        return NULL;
    }
    {
        /* FMI 2.0 hosts pass calloc and free; fall back to them when a host passes none */
        fmi2CallbackAllocateMemory allocate =
            functions != NULL && functions->allocateMemory != NULL ? functions->allocateMemory
                                                                   : default_allocate;
        fmi2CallbackFreeMemory release =
            functions != NULL && functions->freeMemory != NULL ? functions->freeMemory : free;
        inst = (Instance*)allocate(1, sizeof(Instance));
        if (inst == NULL) {
            log_early(&log, fmi2Error, "fmi2Instantiate: out of memory (%lu bytes)",
                        (unsigned long)sizeof(Instance));
            return NULL;
        }
        inst->name = (char*)allocate(strlen(name) + 1, 1);
        if (inst->name == NULL) {
            release(inst);
            log_early(&log, fmi2Error, "fmi2Instantiate: out of memory");
            return NULL;
        }
        strcpy(inst->name, name);
        inst->allocate = allocate;
        inst->release = release;
    }
    inst->log = log;
    inst->log.name = inst->name;
    inst->log.mask = loggingOn ? LOG_EVERYTHING : LOG_PROBLEMS;
    start_over(inst);
    log_message(inst, fmi2OK, "%s instantiated: %s", MODEL_IDENTIFIER, MODEL_SUMMARY);
    return inst;
}

void fmi2FreeInstance(fmi2Component c)
{
    Instance* inst = (Instance*)c;
    fmi2CallbackFreeMemory release;
    if (inst == NULL) return;
    release = inst->release;
    free_road(inst);
    release(inst->name);
    release(inst);
}

const char* fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }

const char* fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[])
{
    Instance* inst = (Instance*)c;
    unsigned mask = 0;
    size_t i;
    int k;
    if (inst == NULL) return fmi2Error;
    if (!loggingOn) {
        inst->log.mask = LOG_PROBLEMS;  /* a host must still learn why a call failed */
        return fmi2OK;
    }
    if (nCategories == 0) {
        inst->log.mask = LOG_EVERYTHING;
        return fmi2OK;
    }
    for (i = 0; i < nCategories; i++) {
        for (k = 0; k < N_LOG_CATEGORIES; k++) {
            if (categories[i] != NULL && strcmp(categories[i], LOG_CATEGORY_NAMES[k]) == 0) break;
        }
        if (k == N_LOG_CATEGORIES) {
            log_message(inst, fmi2Error, "fmi2SetDebugLogging: unknown log category '%s'; known: "
                        "logStatusWarning, logStatusDiscard, logStatusError, logAll; logging "
                        "unchanged", categories[i] != NULL ? categories[i] : "(null)");
            return fmi2Error;
        }
        mask |= k == 3 ? (unsigned)LOG_EVERYTHING : 1u << k;
    }
    inst->log.mask = mask;
    return fmi2OK;
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined,
                               fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    Instance* inst = (Instance*)c;
    char text[NUMBER_SIZE];
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    if (inst == NULL) return fmi2Error;
    if (!isfinite(startTime)) {
        log_message(inst, fmi2Error, "fmi2SetupExperiment: start time %s s must be finite",
                    number_text(text, startTime));
        return fmi2Error;
    }
    inst->start_time = startTime;  /* takes effect when initialisation ends */
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    Instance* inst = (Instance*)c;
    if (inst == NULL) return fmi2Error;
    if (inst->phase == PHASE_INSTANTIATED) inst->phase = PHASE_INITIALISING;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    Instance* inst = (Instance*)c;
    int i;
    if (inst == NULL) return fmi2Error;
    if (inst->phase != PHASE_INSTANTIATED && inst->phase != PHASE_INITIALISING) {
        log_message(inst, fmi2Error, "fmi2ExitInitializationMode: the FMU is not being "
                    "initialised (it is %s); call fmi2Reset to start over",
                    inst->phase == PHASE_RUNNING ? "running" : "terminated");
        return fmi2Error;
    }
    /* the model is compiled in: initialising only places the tire in static equilibrium */
    inst->time = inst->start_time;
    for (i = 0; i < N_REAL_OUTPUTS; i++) inst->outputs[i] = STATIC_OUTPUT[i];
    inst->in_contact = STATIC_OUTPUT[CONTACT_FZ] > 0.0;
    inst->contact_warning_armed = 1;
    memset(inst->q_re, 0, sizeof inst->q_re);
    memset(inst->q_im, 0, sizeof inst->q_im);
    inst->road.start = 0;
    inst->road.count = 0;
    inst->phase = PHASE_RUNNING;
    /* inputs set during initialisation feed through on the first read */
    inst->stale = 0;
    for (i = 0; i < N_FMU_INPUTS; i++) inst->stale |= inst->inputs[i] != 0.0;
    log_message(inst, fmi2OK, "%s ready: %s", MODEL_IDENTIFIER, MODEL_SUMMARY);
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c)
{
    Instance* inst = (Instance*)c;
    if (inst == NULL) return fmi2Error;
    inst->phase = PHASE_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c)
{
    Instance* inst = (Instance*)c;
    if (inst == NULL) return fmi2Error;
    start_over(inst);
    return fmi2OK;
}

/* ---------------------------------------------------------------------------------------- */
/* Stepping                                                                                 */

static const char* why_not_running(const Instance* inst)
{
    if (inst->phase == PHASE_TERMINATED) return "the FMU was terminated (fmi2Terminate)";
    return "the FMU is not initialised (call fmi2ExitInitializationMode)";
}

static fmi2Status refuse_step(const Instance* inst, double t, const char* why)
{
    char text[NUMBER_SIZE];
    log_message(inst, fmi2Discard, "doStep at t = %s s refused: %s", number_text(text, t), why);
    return fmi2Discard;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentCommunicationPoint)
{
    Instance* inst = (Instance*)c;
    const double t = currentCommunicationPoint, h = communicationStepSize;
    const StepCoefficients* k;
    double u[N_COLUMNS], contact_force;
    char why[MESSAGE_SIZE / 2], a[NUMBER_SIZE], b[NUMBER_SIZE];
    int i, bad = 0;
    (void)noSetFMUStatePriorToCurrentCommunicationPoint;
    if (inst == NULL) return fmi2Error;
    if (inst->phase != PHASE_RUNNING) return refuse_step(inst, t, why_not_running(inst));
    if (t != inst->time
        && fabs(t - inst->time) > fmax(TIME_ABS_TOLERANCE, TIME_REL_TOLERANCE * fabs(inst->time))) {
        snprintf(why, sizeof why, "the last communication point is t = %s s, and a step must "
                 "start there (roll back with fmi2SetFMUstate to step from an earlier time); "
                 "state unchanged", number_text(a, inst->time));
        return refuse_step(inst, t, why);
    }
    if (!(h > 0.0 && isfinite(h))) {
        snprintf(why, sizeof why, "step size h = %s s: must be finite and > 0; state unchanged",
                 number_text(a, h));
        return refuse_step(inst, t, why);
    }
    for (i = 0; i < N_FMU_INPUTS; i++) bad |= !isfinite(inst->inputs[i]);
    if (bad) {
        size_t used = (size_t)snprintf(why, sizeof why, "non-finite input:");
        for (i = 0; i < N_FMU_INPUTS; i++) {
            if (isfinite(inst->inputs[i]) || used >= sizeof why) continue;
            used += (size_t)snprintf(why + used, sizeof why - used, "%s %s = %s",
                                     used > strlen("non-finite input:") ? "," : "",
                                     VARIABLES[VR_FIRST_INPUT + i].name,
                                     number_text(b, inst->inputs[i]));
        }
        if (used < sizeof why) snprintf(why + used, sizeof why - used, "; state unchanged");
        return refuse_step(inst, t, why);
    }
    if (ROAD_DELAYED && !reserve_road(inst, inst->road.count + 1)) {
        log_message(inst, fmi2Error, "doStep at t = %s s failed: out of memory for the road "
                    "history (%lu samples); state unchanged", number_text(a, t),
                    (unsigned long)inst->road.count);
        return fmi2Error;
    }

    k = coefficients_for(inst, t, h);
    internal_inputs(inst, t, u);
    advance(inst, k, u);
    inst->time = t + h;  /* from the host's clock, so no drift accumulates here */
    inst->stale = 0;

    contact_force = inst->outputs[CONTACT_FZ];
    inst->in_contact = contact_force > 0.0;
    if (contact_force < 0.0) {
        if (inst->contact_warning_armed) {
            inst->contact_warning_armed = 0;
            snprintf(a, sizeof a, "%.9g", inst->time);
            snprintf(b, sizeof b, "%.6g", contact_force);
            log_message(inst, fmi2Warning, "t = %s s: contact force %s N < 0: the linear contact "
                        "pulls on the road, so the tire has lost contact (in_contact = false) "
                        "and the forces are not physical until it returns; logged once until "
                        "contact returns", a, b);
            return fmi2Warning;
        }
    } else if (!inst->contact_warning_armed) {
        inst->contact_warning_armed = 1;
    }
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    Instance* inst = (Instance*)c;
    if (inst == NULL) return fmi2Error;
    log_message(inst, fmi2Error, "fmi2CancelStep: doStep always completes before it returns "
                "(canRunAsynchronuously = false); nothing to cancel");
    return fmi2Error;
}

/* ---------------------------------------------------------------------------------------- */
/* Variables                                                                                */

static const char* const TYPE_NAMES[] = {"Real", "Integer", "Boolean"};

/* The variable behind vr if it exists and has the type; otherwise log and return NULL. */
static const VariableInfo* checked_variable(const Instance* inst, fmi2ValueReference vr,
                                            VariableType type, const char* function)
{
    const VariableInfo* v;
    if (vr >= N_VARIABLES) {
        log_message(inst, fmi2Error, "%s: value reference %u does not exist (%s has %d "
                    "variables); ignored", function, (unsigned)vr, MODEL_IDENTIFIER,
                    N_VARIABLES);
        return NULL;
    }
    v = &VARIABLES[vr];
    if (v->type != type) {
        log_message(inst, fmi2Error, "%s: %s is a%s %s variable; use fmi2%s%s; ignored",
                    function, v->name, v->type == TYPE_INTEGER ? "n" : "", TYPE_NAMES[v->type],
                    strncmp(function, "fmi2Get", 7) == 0 ? "Get" : "Set", TYPE_NAMES[v->type]);
        return NULL;
    }
    return v;
}

static double variable_value(const Instance* inst, fmi2ValueReference vr)
{
    const VariableInfo* v = &VARIABLES[vr];
    if (v->causality == CAUSALITY_PARAMETER) return v->value;
    if (v->causality == CAUSALITY_INPUT) return inst->inputs[vr - VR_FIRST_INPUT];
    if (vr == VR_IN_CONTACT) return inst->in_contact ? 1.0 : 0.0;
    return inst->outputs[vr - VR_FIRST_OUTPUT];
}

static fmi2Status get_values(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                             VariableType type, const char* function, double out[])
{
    Instance* inst = (Instance*)c;
    fmi2Status status = fmi2OK;
    size_t i;
    if (inst == NULL) return fmi2Error;
    if (n > 0 && (vr == NULL || out == NULL)) return fmi2Error;
    if (inst->stale) refresh_outputs(inst);
    for (i = 0; i < n; i++) {
        if (checked_variable(inst, vr[i], type, function) == NULL) {
            out[i] = 0.0;
            status = fmi2Error;
        } else {
            out[i] = variable_value(inst, vr[i]);
        }
    }
    return status;
}

/* Set one value; parameters may only be "set" to the value the FMU was exported with. */
static fmi2Status set_value(Instance* inst, fmi2ValueReference vr, VariableType type,
                            const char* function, double value)
{
    const VariableInfo* v = checked_variable(inst, vr, type, function);
    char given[NUMBER_SIZE], exported[NUMBER_SIZE];
    if (v == NULL) return fmi2Error;
    if (v->causality == CAUSALITY_OUTPUT) {
        log_message(inst, fmi2Error, "%s: %s is an output; ignored", function, v->name);
        return fmi2Error;
    }
    if (v->causality == CAUSALITY_INPUT) {
        inst->inputs[vr - VR_FIRST_INPUT] = value;  /* doStep checks it is finite */
        inst->stale = inst->phase == PHASE_RUNNING;
        return fmi2OK;
    }
    if (type == TYPE_BOOLEAN ? (value != 0.0) == (v->value != 0.0) : value == v->value) {
        return fmi2OK;  /* the export value itself: nothing changes */
    }
    log_message(inst, fmi2Error, "%s: %s = %s%s%s refused: this FMU was exported for %s = %s%s%s "
                "and its reduced model is compiled in; re-export it with the value you need "
                "(tire-fmu export --format fmu OUT.fmu, option %s) or use TireModal.fmu, which "
                "builds its model at initialisation; value unchanged", function, v->name,
                value_text(given, type, value), *v->unit ? " " : "", v->unit, v->name,
                value_text(exported, type, v->value), *v->unit ? " " : "", v->unit,
                v->reexport);
    return fmi2Error;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[])
{
    Instance* inst = (Instance*)c;
    size_t i;
    /* the host's usual call, the four forces in order, without per-value checks */
    if (inst != NULL && nvr == N_REAL_OUTPUTS && vr != NULL && value != NULL
        && vr[0] == VR_FIRST_OUTPUT && vr[1] == VR_FIRST_OUTPUT + 1
        && vr[2] == VR_FIRST_OUTPUT + 2 && vr[3] == VR_FIRST_OUTPUT + 3) {
        if (inst->stale) refresh_outputs(inst);
        for (i = 0; i < N_REAL_OUTPUTS; i++) value[i] = inst->outputs[i];
        return fmi2OK;
    }
    return get_values(c, vr, nvr, TYPE_REAL, "fmi2GetReal", value);
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[])
{
    fmi2Status status = fmi2OK, one;
    double number;
    size_t i;
    if (nvr > 0 && (vr == NULL || value == NULL)) return fmi2Error;
    for (i = 0; i < nvr; i++) {
        one = get_values(c, &vr[i], 1, TYPE_INTEGER, "fmi2GetInteger", &number);
        value[i] = (fmi2Integer)number;
        if (one > status) status = one;
    }
    return status;
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[])
{
    fmi2Status status = fmi2OK, one;
    double number;
    size_t i;
    if (nvr > 0 && (vr == NULL || value == NULL)) return fmi2Error;
    for (i = 0; i < nvr; i++) {
        one = get_values(c, &vr[i], 1, TYPE_BOOLEAN, "fmi2GetBoolean", &number);
        value[i] = number != 0.0 ? fmi2True : fmi2False;
        if (one > status) status = one;
    }
    return status;
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[])
{
    Instance* inst = (Instance*)c;
    size_t i;
    (void)vr;
    if (inst == NULL) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    for (i = 0; i < nvr; i++) value[i] = "";
    log_message(inst, fmi2Error, "fmi2GetString: %s has no String variables", MODEL_IDENTIFIER);
    return fmi2Error;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[])
{
    Instance* inst = (Instance*)c;
    fmi2Status status = fmi2OK, one;
    size_t i;
    if (inst == NULL) return fmi2Error;
    if (nvr > 0 && (vr == NULL || value == NULL)) return fmi2Error;
    /* the host's usual call, the four inputs in order */
    if (nvr == N_FMU_INPUTS && vr[0] == VR_FIRST_INPUT && vr[1] == VR_FIRST_INPUT + 1
        && vr[2] == VR_FIRST_INPUT + 2 && vr[3] == VR_FIRST_INPUT + 3) {
        for (i = 0; i < N_FMU_INPUTS; i++) inst->inputs[i] = value[i];
        inst->stale = inst->phase == PHASE_RUNNING;
        return fmi2OK;
    }
    for (i = 0; i < nvr; i++) {
        one = set_value(inst, vr[i], TYPE_REAL, "fmi2SetReal", value[i]);
        if (one > status) status = one;
    }
    return status;
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[])
{
    Instance* inst = (Instance*)c;
    fmi2Status status = fmi2OK, one;
    size_t i;
    if (inst == NULL) return fmi2Error;
    if (nvr > 0 && (vr == NULL || value == NULL)) return fmi2Error;
    for (i = 0; i < nvr; i++) {
        one = set_value(inst, vr[i], TYPE_INTEGER, "fmi2SetInteger", (double)value[i]);
        if (one > status) status = one;
    }
    return status;
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[])
{
    Instance* inst = (Instance*)c;
    fmi2Status status = fmi2OK, one;
    size_t i;
    if (inst == NULL) return fmi2Error;
    if (nvr > 0 && (vr == NULL || value == NULL)) return fmi2Error;
    for (i = 0; i < nvr; i++) {
        one = set_value(inst, vr[i], TYPE_BOOLEAN, "fmi2SetBoolean", value[i] ? 1.0 : 0.0);
        if (one > status) status = one;
    }
    return status;
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[])
{
    Instance* inst = (Instance*)c;
    (void)vr;
    (void)value;
    if (inst == NULL) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    log_message(inst, fmi2Error, "fmi2SetString: %s has no String variables; ignored",
                MODEL_IDENTIFIER);
    return fmi2Error;
}

/* ---------------------------------------------------------------------------------------- */
/* FMU state. A state is its own serialized bytes, so getting, setting, serializing and     */
/* deserializing share one format and one set of checks. Doubles are stored as this         */
/* platform writes them, with a byte-order mark: a state belongs to the binary that wrote it. */

#define STATE_MAGIC "TIRESTAT"
#define STATE_FORMAT_VERSION 1u
#define STATE_BYTE_ORDER 0x01020304u
#define STATE_GUID_SIZE 48

typedef struct {
    size_t size;
    unsigned char bytes[1];  /* size bytes follow */
} StateBlob;

/* Writes into data when it is not NULL, and counts the bytes either way. */
typedef struct {
    unsigned char* data;
    size_t used;
} Writer;

static void put(Writer* w, const void* value, size_t size)
{
    if (w->data != NULL) memcpy(w->data + w->used, value, size);
    w->used += size;
}

static void put_u32(Writer* w, unsigned long value)
{
    unsigned int x = (unsigned int)value;
    put(w, &x, 4);
}

static void put_i32(Writer* w, int value) { put(w, &value, 4); }

static void put_f64(Writer* w, double value) { put(w, &value, 8); }

static size_t write_state(const Instance* inst, unsigned char* data)
{
    Writer w;
    char guid[STATE_GUID_SIZE];
    const RoadHistory* road = &inst->road;
    unsigned long long count = (unsigned long long)road->count;
    int i;
    w.data = data;
    w.used = 0;
    memset(guid, 0, sizeof guid);
    strncpy(guid, MODEL_GUID, sizeof guid - 1);
    put(&w, STATE_MAGIC, 8);
    put_u32(&w, STATE_FORMAT_VERSION);
    put_u32(&w, STATE_BYTE_ORDER);
    put(&w, guid, sizeof guid);
    put_u32(&w, N_MODES);
    put_u32(&w, N_INPUTS);
    put_i32(&w, (int)inst->phase);
    put_i32(&w, inst->in_contact);
    put_i32(&w, inst->contact_warning_armed);
    put_i32(&w, 0);  /* keeps the doubles 8-byte aligned in the blob */
    put_f64(&w, inst->start_time);
    put_f64(&w, inst->time);
    for (i = 0; i < N_FMU_INPUTS; i++) put_f64(&w, inst->inputs[i]);
    for (i = 0; i < N_REAL_OUTPUTS; i++) put_f64(&w, inst->outputs[i]);
    for (i = 0; i < N_MODES; i++) put_f64(&w, inst->q_re[i]);
    for (i = 0; i < N_MODES; i++) put_f64(&w, inst->q_im[i]);
    put(&w, &count, 8);
    if (road->count > 0) {
        put(&w, road->t + road->start, road->count * sizeof(double));
        put(&w, road->z + road->start, road->count * sizeof(double));
        put(&w, road->v + road->start, road->count * sizeof(double));
    }
    return w.used;
}

typedef struct {
    const unsigned char* data;
    size_t size, used;
} Reader;

static int take(Reader* r, void* value, size_t size)
{
    if (r->size - r->used < size) return 0;
    memcpy(value, r->data + r->used, size);
    r->used += size;
    return 1;
}

/* Why the bytes are not a state of this FMU, or NULL when they are. The decoded header goes
 * to phase and road_count. */
static const char* check_state(const unsigned char* data, size_t size, int* phase,
                               size_t* road_count)
{
    Reader r;
    char magic[8], guid[STATE_GUID_SIZE];
    unsigned int version, order, modes, inputs;
    int flags[4];
    unsigned long long count;
    size_t fixed, i;
    double number, previous;
    r.data = data;
    r.size = size;
    r.used = 0;
    if (data == NULL || !take(&r, magic, 8) || memcmp(magic, STATE_MAGIC, 8) != 0)
        return "it is not a tire_fmu native FMU state";
    if (!take(&r, &version, 4) || version != STATE_FORMAT_VERSION)
        return "it has an unknown state format version";
    if (!take(&r, &order, 4) || order != STATE_BYTE_ORDER)
        return "it was written on a platform with another byte order";
    if (!take(&r, guid, sizeof guid) || guid[sizeof guid - 1] != '\0'
        || strcmp(guid, MODEL_GUID) != 0)
        return "it belongs to another FMU (its GUID differs)";
    if (!take(&r, &modes, 4) || !take(&r, &inputs, 4) || modes != N_MODES || inputs != N_INPUTS)
        return "its model has another size";
    for (i = 0; i < 4; i++) {
        if (!take(&r, &flags[i], 4)) return "it is truncated";
    }
    if (flags[0] < 0 || flags[0] >= N_PHASES) return "it names an unknown phase";
    fixed = r.used + 8 * (2 + N_FMU_INPUTS + N_REAL_OUTPUTS + 2 * N_MODES);
    if (size < fixed + 8) return "it is truncated";
    r.used = fixed;
    take(&r, &count, 8);
    if (count > (size - r.used) / 24 || size - r.used != 24 * count)
        return "its road history does not match its size";
    /* times of the road history must be finite and increasing, as recorded */
    previous = -HUGE_VAL;
    for (i = 0; i < (size_t)count; i++) {
        memcpy(&number, data + r.used + 8 * i, 8);
        if (!isfinite(number) || number <= previous) return "its road history is corrupt";
        previous = number;
    }
    *phase = flags[0];
    *road_count = (size_t)count;
    return NULL;
}

/* Restore a checked state; 0 (and nothing changed) when the road history cannot be held. */
static int read_state(Instance* inst, const unsigned char* data, size_t size)
{
    Reader r;
    int phase, flags[4], i;
    size_t count;
    unsigned long long stored;
    if (check_state(data, size, &phase, &count) != NULL) return 0;
    if (!reserve_road(inst, count)) return 0;
    r.data = data;
    r.size = size;
    r.used = 8 + 4 + 4 + STATE_GUID_SIZE + 4 + 4;
    for (i = 0; i < 4; i++) take(&r, &flags[i], 4);
    inst->phase = (Phase)flags[0];
    inst->in_contact = flags[1];
    inst->contact_warning_armed = flags[2];
    inst->stale = 0;  /* the state's outputs belong to its inputs */
    take(&r, &inst->start_time, 8);
    take(&r, &inst->time, 8);
    for (i = 0; i < N_FMU_INPUTS; i++) take(&r, &inst->inputs[i], 8);
    for (i = 0; i < N_REAL_OUTPUTS; i++) take(&r, &inst->outputs[i], 8);
    for (i = 0; i < N_MODES; i++) take(&r, &inst->q_re[i], 8);
    for (i = 0; i < N_MODES; i++) take(&r, &inst->q_im[i], 8);
    take(&r, &stored, 8);
    if (count > 0) {
        take(&r, inst->road.t + inst->road.start, count * sizeof(double));
        take(&r, inst->road.z + inst->road.start, count * sizeof(double));
        take(&r, inst->road.v + inst->road.start, count * sizeof(double));
    }
    inst->road.count = count;
    return 1;
}

static StateBlob* new_blob(const Instance* inst, size_t size)
{
    StateBlob* blob = (StateBlob*)inst->allocate(1, offsetof(StateBlob, bytes) + size);
    if (blob != NULL) blob->size = size;
    return blob;
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* FMUstate)
{
    Instance* inst = (Instance*)c;
    StateBlob* blob;
    size_t size;
    if (inst == NULL || FMUstate == NULL) return fmi2Error;
    size = write_state(inst, NULL);
    blob = (StateBlob*)*FMUstate;
    if (blob == NULL || blob->size != size) {  /* FMI 2.0: a given state is overwritten */
        if (blob != NULL) inst->release(blob);
        *FMUstate = NULL;
        blob = new_blob(inst, size);
        if (blob == NULL) {
            log_message(inst, fmi2Error, "fmi2GetFMUstate: out of memory (%lu bytes)",
                        (unsigned long)size);
            return fmi2Error;
        }
    }
    write_state(inst, blob->bytes);
    *FMUstate = blob;
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
    Instance* inst = (Instance*)c;
    const StateBlob* blob = (const StateBlob*)FMUstate;
    const char* why;
    int phase;
    size_t count;
    if (inst == NULL) return fmi2Error;
    why = blob == NULL ? "it is NULL" : check_state(blob->bytes, blob->size, &phase, &count);
    if (why != NULL) {
        log_message(inst, fmi2Error, "fmi2SetFMUstate refused: %s; state unchanged", why);
        return fmi2Error;
    }
    if (!read_state(inst, blob->bytes, blob->size)) {
        log_message(inst, fmi2Error, "fmi2SetFMUstate: out of memory for the road history");
        return fmi2Error;
    }
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* FMUstate)
{
    Instance* inst = (Instance*)c;
    if (inst == NULL || FMUstate == NULL) return fmi2Error;
    if (*FMUstate != NULL) inst->release(*FMUstate);
    *FMUstate = NULL;
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t* size)
{
    Instance* inst = (Instance*)c;
    if (inst == NULL || FMUstate == NULL || size == NULL) return fmi2Error;
    *size = ((const StateBlob*)FMUstate)->size;
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[],
                                 size_t size)
{
    Instance* inst = (Instance*)c;
    const StateBlob* blob = (const StateBlob*)FMUstate;
    if (inst == NULL || blob == NULL || serializedState == NULL) return fmi2Error;
    if (size < blob->size) {
        log_message(inst, fmi2Error, "fmi2SerializeFMUstate: the buffer has %lu bytes, the state "
                    "needs %lu (ask fmi2SerializedFMUstateSize)", (unsigned long)size,
                    (unsigned long)blob->size);
        return fmi2Error;
    }
    memcpy(serializedState, blob->bytes, blob->size);
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[],
                                   size_t size, fmi2FMUstate* FMUstate)
{
    Instance* inst = (Instance*)c;
    const char* why;
    StateBlob* blob;
    int phase;
    size_t count;
    if (inst == NULL || FMUstate == NULL) return fmi2Error;
    why = check_state((const unsigned char*)serializedState, size, &phase, &count);
    if (why != NULL) {
        log_message(inst, fmi2Error, "fmi2DeSerializeFMUstate refused: %s", why);
        return fmi2Error;
    }
    if (*FMUstate != NULL) inst->release(*FMUstate);
    *FMUstate = NULL;
    blob = new_blob(inst, size);
    if (blob == NULL) {
        log_message(inst, fmi2Error, "fmi2DeSerializeFMUstate: out of memory (%lu bytes)",
                    (unsigned long)size);
        return fmi2Error;
    }
    memcpy(blob->bytes, serializedState, size);
    *FMUstate = blob;
    return fmi2OK;
}

/* ---------------------------------------------------------------------------------------- */
/* What this FMU does not provide (its capability flags say so)                            */

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown[],
                                        size_t nUnknown, const fmi2ValueReference vKnown[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[])
{
    Instance* inst = (Instance*)c;
    (void)vUnknown;
    (void)nUnknown;
    (void)vKnown;
    (void)nKnown;
    (void)dvKnown;
    (void)dvUnknown;
    if (inst == NULL) return fmi2Error;
    log_message(inst, fmi2Error, "fmi2GetDirectionalDerivative: not provided "
                "(providesDirectionalDerivative = false)");
    return fmi2Error;
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                       size_t nvr, const fmi2Integer order[],
                                       const fmi2Real value[])
{
    Instance* inst = (Instance*)c;
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    if (inst == NULL) return fmi2Error;
    log_message(inst, fmi2Error, "fmi2SetRealInputDerivatives: not supported "
                "(canInterpolateInputs = false); set the velocity inputs rim_vz and road_vz "
                "instead, the inputs ramp with them over the step");
    return fmi2Error;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t nvr, const fmi2Integer order[],
                                        fmi2Real value[])
{
    Instance* inst = (Instance*)c;
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    if (inst == NULL) return fmi2Error;
    log_message(inst, fmi2Error, "fmi2GetRealOutputDerivatives: not provided "
                "(maxOutputDerivativeOrder = 0)");
    return fmi2Error;
}

static fmi2Status no_status(Instance* inst, const char* function)
{
    if (inst == NULL) return fmi2Error;
    log_message(inst, fmi2Discard, "%s: no such status (doStep never returns fmi2Pending)",
                function);
    return fmi2Discard;
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status* value)
{
    (void)s;
    (void)value;
    return no_status((Instance*)c, "fmi2GetStatus");
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real* value)
{
    Instance* inst = (Instance*)c;
    if (inst != NULL && value != NULL && s == fmi2LastSuccessfulTime) {
        *value = inst->time;
        return fmi2OK;
    }
    return no_status(inst, "fmi2GetRealStatus");
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer* value)
{
    (void)s;
    (void)value;
    return no_status((Instance*)c, "fmi2GetIntegerStatus");
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean* value)
{
    Instance* inst = (Instance*)c;
    if (inst != NULL && value != NULL && s == fmi2Terminated) {
        /* a refused step ends nothing: the host may fix its call and retry */
        *value = inst->phase == PHASE_TERMINATED ? fmi2True : fmi2False;
        return fmi2OK;
    }
    return no_status(inst, "fmi2GetBooleanStatus");
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String* value)
{
    (void)s;
    (void)value;
    return no_status((Instance*)c, "fmi2GetStringStatus");
}
"""
