/* fmi2_layer.c: the generic FMI 2.0 co-simulation layer (no tire in it; see model.h).
 *
 * Which call is allowed in which phase is one table (CALLS) checked by one macro (ENTER) at
 * the top of every function, as the Reference-FMUs keep it. A refused call logs why (status
 * error, category logStatusError) and changes nothing. Every message is formatted here and
 * handed to the host as the argument of a constant "%s" format: a host's logger treats its
 * format as printf's, so no text, host-given or computed, is ever read as one.
 *
 * Statuses (docs/native.md): fmi2Error for every refused call (a call the phase does not
 * allow, an unknown value reference or wrong type, setting an output or a fixed parameter after
 * initialisation, a non-finite input, a doStep at another time than the last communication
 * point or with NaN, h <= 0, a step or start time the clock cannot resolve, bad parameters at
 * fmi2ExitInitializationMode, an FMU state that is damaged, of another FMU, holds non-finite
 * values or does not mean a state of this tire); fmi2Warning from the doStep whose
 * footprint first reaches the end of the contact zone; fmi2OK otherwise (losing contact
 * included: it is the physics of a unilateral contact). */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "model.h"
#include "spec.h"
#include "export.h"

/* export.h holds one start value per variable of spec.h */
typedef char export_matches_spec[sizeof EXPORT_START_VALUES / sizeof EXPORT_START_VALUES[0]
                                 == SPEC_N_VARIABLES ? 1 : -1];

#define MESSAGE_SIZE 2048

typedef enum {
    PHASE_INSTANTIATED = 1,
    PHASE_INITIALISATION = 2,
    PHASE_RUNNING = 4,
    PHASE_TERMINATED = 8
} Phase;

#define ANY_PHASE (PHASE_INSTANTIATED | PHASE_INITIALISATION | PHASE_RUNNING | PHASE_TERMINATED)

typedef enum {
    CALL_SET_DEBUG_LOGGING, CALL_SETUP_EXPERIMENT, CALL_ENTER_INITIALIZATION,
    CALL_EXIT_INITIALIZATION, CALL_TERMINATE, CALL_RESET, CALL_GET, CALL_SET,
    CALL_FMU_STATE, CALL_DIRECTIONAL_DERIVATIVE, CALL_INPUT_DERIVATIVES,
    CALL_OUTPUT_DERIVATIVES, CALL_DO_STEP, CALL_CANCEL_STEP, CALL_STATUS
} Call;

/* FMI 2.0, section 4.2.4 (the co-simulation state machine) */
static const struct {
    const char* name;
    unsigned phases;
} CALLS[] = {
    {"fmi2SetDebugLogging", ANY_PHASE},
    {"fmi2SetupExperiment", PHASE_INSTANTIATED},
    {"fmi2EnterInitializationMode", PHASE_INSTANTIATED},
    {"fmi2ExitInitializationMode", PHASE_INITIALISATION},
    {"fmi2Terminate", PHASE_RUNNING},
    {"fmi2Reset", ANY_PHASE},
    {"fmi2Get*", PHASE_INITIALISATION | PHASE_RUNNING | PHASE_TERMINATED},
    {"fmi2Set*", PHASE_INSTANTIATED | PHASE_INITIALISATION | PHASE_RUNNING},
    {"the FMU state functions", ANY_PHASE},
    {"fmi2GetDirectionalDerivative", PHASE_INITIALISATION | PHASE_RUNNING | PHASE_TERMINATED},
    {"fmi2SetRealInputDerivatives", PHASE_INSTANTIATED | PHASE_INITIALISATION | PHASE_RUNNING},
    {"fmi2GetRealOutputDerivatives", PHASE_RUNNING | PHASE_TERMINATED},
    {"fmi2DoStep", PHASE_RUNNING},
    {"fmi2CancelStep", PHASE_RUNNING},
    {"fmi2Get*Status", PHASE_RUNNING | PHASE_TERMINATED},
};

typedef struct {
    fmi2CallbackLogger logger;
    fmi2ComponentEnvironment environment;
    char* name;
    Memory mem;
    int logging_on;
    unsigned categories;  /* bit i: SPEC_LOG_CATEGORIES[i] */
    Phase phase;
    const char* broken;   /* an internal failure, what it was (NULL: none): only a reset helps */
    double time, start_time;
    int stale;            /* inputs set since the outputs were computed */
    double values[SPEC_N_VARIABLES];
    Model* model;
} Instance;

static const char* phase_text(Phase phase)
{
    switch (phase) {
    case PHASE_INSTANTIATED: return "instantiated (fmi2EnterInitializationMode comes next)";
    case PHASE_INITIALISATION: return "in initialization mode (fmi2ExitInitializationMode "
                                      "comes next)";
    case PHASE_RUNNING: return "running (initialised; fmi2Reset starts over)";
    default: return "terminated (fmi2Reset starts over)";
    }
}

static int category_index(const char* category)
{
    int i;
    for (i = 0; i < SPEC_N_LOG_CATEGORIES; i++) {
        if (strcmp(category, SPEC_LOG_CATEGORIES[i]) == 0) return i;
    }
    return SPEC_N_LOG_CATEGORIES - 1;
}

/* problems (warning and worse) always reach the host's logger; information only with
 * loggingOn and its category (or logAll) enabled */
static void deliver(const Instance* inst, fmi2Status status, const char* category,
                    const char* message)
{
    if (inst->logger == NULL) return;
    if (status == fmi2OK) {
        unsigned all = 1u << (SPEC_N_LOG_CATEGORIES - 1);
        if (!inst->logging_on) return;
        if (!(inst->categories & (all | (1u << category_index(category))))) return;
    }
    inst->logger(inst->environment, inst->name, status, category, "%s", message);
}

static void log_message(const Instance* inst, fmi2Status status, const char* format, ...)
{
    char message[MESSAGE_SIZE];
    va_list args;
    va_start(args, format);
    vsnprintf(message, sizeof message, format, args);
    va_end(args);
    deliver(inst, status, status == fmi2OK ? "logAll"
                      : status == fmi2Warning ? "logStatusWarning" : "logStatusError",
            message);
}

static void model_log(void* layer, int status, const char* category, const char* message)
{
    deliver((const Instance*)layer, (fmi2Status)status, category, message);
}

static int allowed(Instance* inst, Call call)
{
    if (inst->broken && call != CALL_RESET && call != CALL_FMU_STATE &&
        call != CALL_SET_DEBUG_LOGGING) {
        log_message(inst, fmi2Error, "%s refused: the FMU failed earlier (%s); reset it or "
                    "set an FMU state", CALLS[call].name, inst->broken);
        return 0;
    }
    if (CALLS[call].phases & (unsigned)inst->phase) return 1;
    log_message(inst, fmi2Error, "%s refused: the FMU is %s; nothing changed",
                CALLS[call].name, phase_text(inst->phase));
    return 0;
}

#define ENTER(call)                                    \
    Instance* inst = (Instance*)c;                     \
    if (inst == NULL) return fmi2Error;                \
    if (!allowed(inst, call)) return fmi2Error

static void number(char* text, double x) { py_repr(x, text, 40); }

/* -- instances ----------------------------------------------------------------------------------- */

static void* default_allocate(size_t count, size_t size) { return calloc(count, size); }

static void start_values(Instance* inst)
{
    memcpy(inst->values, EXPORT_START_VALUES, sizeof inst->values);
    model_preview(inst->values, inst->values);
    inst->phase = PHASE_INSTANTIATED;
    inst->time = inst->start_time = 0.0;
    inst->stale = 0;
    inst->broken = 0;
}

static ModelHost host_of(Instance* inst)
{
    ModelHost host;
    host.mem = inst->mem;
    host.layer = inst;
    host.log = model_log;
    return host;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions* functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn)
{
    Instance probe, *inst;
    const char* name = instanceName != NULL ? instanceName : "";
    ModelHost host;
    (void)fmuResourceLocation;
    (void)visible;
    memset(&probe, 0, sizeof probe);
    probe.logger = functions != NULL ? functions->logger : NULL;
    probe.environment = functions != NULL ? functions->componentEnvironment : NULL;
    probe.name = (char*)name;
    if (fmuType != fmi2CoSimulation) {
        log_message(&probe, fmi2Error, "fmi2Instantiate refused: %s is a co-simulation FMU "
                    "(it has no model-exchange interface)", EXPORT_MODEL_IDENTIFIER);
        return NULL;
    }
    if (fmuGUID == NULL || strcmp(fmuGUID, EXPORT_GUID) != 0) {
        log_message(&probe, fmi2Error, "fmi2Instantiate refused: GUID %s is not this binary's "
                    "%s (the modelDescription.xml and the binary come from different exports)",
                    fmuGUID != NULL ? fmuGUID : "(null)", EXPORT_GUID);
        return NULL;
    }
    probe.mem.allocate = functions != NULL && functions->allocateMemory != NULL
                             ? functions->allocateMemory : default_allocate;
    probe.mem.release = functions != NULL && functions->freeMemory != NULL
                            ? functions->freeMemory : free;
    inst = (Instance*)probe.mem.allocate(1, sizeof(Instance));
    if (inst == NULL) {
        log_message(&probe, fmi2Error, "fmi2Instantiate: out of memory");
        return NULL;
    }
    *inst = probe;
    inst->name = (char*)inst->mem.allocate(strlen(name) + 1, 1);
    if (inst->name == NULL) {
        inst->mem.release(inst);
        log_message(&probe, fmi2Error, "fmi2Instantiate: out of memory");
        return NULL;
    }
    memcpy(inst->name, name, strlen(name) + 1);
    inst->logging_on = loggingOn ? 1 : 0;
    inst->categories = ~0u;
    start_values(inst);
    host = host_of(inst);
    inst->model = model_create(&host);
    if (inst->model == NULL) {
        log_message(&probe, fmi2Error, "fmi2Instantiate: out of memory");
        inst->mem.release(inst->name);
        inst->mem.release(inst);
        return NULL;
    }
    return inst;
}

void fmi2FreeInstance(fmi2Component c)
{
    Instance* inst = (Instance*)c;
    fmi2CallbackFreeMemory release;
    if (inst == NULL) return;
    release = inst->mem.release;
    model_destroy(inst->model);
    release(inst->name);
    release(inst);
}

const char* fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }

const char* fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[])
{
    unsigned mask = 0;
    size_t i;
    ENTER(CALL_SET_DEBUG_LOGGING);
    if (nCategories > 0 && categories == NULL) {
        log_message(inst, fmi2Error, "fmi2SetDebugLogging refused: %lu categories but no "
                    "array; logging unchanged", (unsigned long)nCategories);
        return fmi2Error;
    }
    for (i = 0; i < nCategories; i++) {
        int k;
        for (k = 0; k < SPEC_N_LOG_CATEGORIES; k++) {
            if (categories[i] != NULL && strcmp(categories[i], SPEC_LOG_CATEGORIES[k]) == 0) break;
        }
        if (k == SPEC_N_LOG_CATEGORIES) {
            log_message(inst, fmi2Error, "fmi2SetDebugLogging refused: unknown log category "
                        "'%s' (known: logEvents, logStatusWarning, logStatusError, logAll); "
                        "logging unchanged", categories[i] != NULL ? categories[i] : "(null)");
            return fmi2Error;
        }
        mask |= 1u << k;
    }
    inst->logging_on = loggingOn ? 1 : 0;
    inst->categories = nCategories == 0 ? ~0u : mask;
    return fmi2OK;
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined,
                               fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    char a[40], b[40];
    ENTER(CALL_SETUP_EXPERIMENT);
    (void)tolerance;
    if (!isfinite(startTime)) {
        number(a, startTime);
        log_message(inst, fmi2Error, "fmi2SetupExperiment refused: startTime = %s s: must be "
                    "finite; nothing changed", a);
        return fmi2Error;
    }
    if (!clock_resolves(startTime, SPEC_MAX_STEP_S)) {
        char text[512];
        number(a, startTime);
        snprintf(text, sizeof text, SPEC_MSG_START_UNRESOLVED, a,
                 clock_resolved_until(SPEC_MAX_STEP_S) - SPEC_MAX_STEP_S, SPEC_MAX_STEP_S);
        log_message(inst, fmi2Error, "fmi2SetupExperiment refused: %s; nothing changed", text);
        return fmi2Error;
    }
    if (stopTimeDefined && !(stopTime >= startTime)) {
        number(a, stopTime);
        number(b, startTime);
        log_message(inst, fmi2Error, "fmi2SetupExperiment refused: stopTime = %s s: must be "
                    ">= startTime = %s s; nothing changed", a, b);
        return fmi2Error;
    }
    (void)toleranceDefined;
    inst->start_time = startTime;
    inst->time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    ENTER(CALL_ENTER_INITIALIZATION);
    inst->phase = PHASE_INITIALISATION;
    return fmi2OK;
}

static int any_input_set(const double* values)
{
    int i;
    for (i = 0; i < SPEC_BLOCK_N_INPUTS; i++) {
        if (values[SPEC_BLOCK_INPUTS_FIRST + i] != 0.0) return 1;
    }
    return 0;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    ENTER(CALL_EXIT_INITIALIZATION);
    if (model_initialise(inst->model, inst->values, inst->start_time, inst->values) != MODEL_OK) {
        log_message(inst, fmi2Error, "fmi2ExitInitializationMode refused: the parameters "
                    "listed above cannot build the model; the FMU stays in initialization "
                    "mode (set valid parameters and call fmi2ExitInitializationMode again, or "
                    "reset it)");
        return fmi2Error;
    }
    inst->phase = PHASE_RUNNING;
    inst->time = inst->start_time;
    inst->stale = any_input_set(inst->values);  /* inputs set before feed through */
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c)
{
    ENTER(CALL_TERMINATE);
    inst->phase = PHASE_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c)
{
    ModelHost host;
    Model* fresh;
    ENTER(CALL_RESET);
    host = host_of(inst);
    fresh = model_create(&host);
    if (fresh == NULL) {
        log_message(inst, fmi2Error, "fmi2Reset: out of memory");
        return fmi2Error;
    }
    model_destroy(inst->model);
    inst->model = fresh;
    start_values(inst);
    return fmi2OK;
}

/* -- variables ----------------------------------------------------------------------------------- */

static const char* type_name(SpecType type)
{
    return type == SPEC_REAL ? "Real" : type == SPEC_INTEGER ? "Integer" : "Boolean";
}

/* why vr cannot be used as type (NULL when it can) */
/* The largest magnitude an input may have: a position (m) or a rate (m/s). NaN fails the
 * comparison with it, so one test refuses both. */
static double input_limit(const SpecVariable* v)
{
    return v->unit[0] == 'm' && v->unit[1] == '/' ? SPEC_MAX_VELOCITY_M_S
                                                   : SPEC_MAX_DISPLACEMENT_M;
}

static const char* reference_problem(const Instance* inst, fmi2ValueReference vr, SpecType type,
                                     char* why, size_t size)
{
    (void)inst;
    if (vr >= SPEC_N_VARIABLES) {
        snprintf(why, size, "value reference %u does not exist (%s has %d variables)",
                 (unsigned)vr, EXPORT_MODEL_IDENTIFIER, SPEC_N_VARIABLES);
        return why;
    }
    if (SPEC_VARIABLES[vr].type != type) {
        snprintf(why, size, "%s has FMI type %s: use fmi2Get%s and fmi2Set%s",
                 SPEC_VARIABLES[vr].name, type_name(SPEC_VARIABLES[vr].type),
                 type_name(SPEC_VARIABLES[vr].type), type_name(SPEC_VARIABLES[vr].type));
        return why;
    }
    return NULL;
}

static fmi2Status refresh(Instance* inst)
{
    if (inst->stale && inst->phase == PHASE_RUNNING) {
        if (model_refresh(inst->model, inst->values) != MODEL_OK) {
            inst->broken = "out of memory";
            return fmi2Error;
        }
        inst->stale = 0;
    }
    return fmi2OK;
}

static fmi2Status get_values(Instance* inst, const char* call, const fmi2ValueReference vr[],
                             size_t nvr, SpecType type, double* out)
{
    char why[256];
    size_t i;
    if (nvr > 0 && vr == NULL) {
        log_message(inst, fmi2Error, "%s refused: %lu values but no value references", call,
                    (unsigned long)nvr);
        return fmi2Error;
    }
    for (i = 0; i < nvr; i++) {
        if (reference_problem(inst, vr[i], type, why, sizeof why) != NULL) {
            log_message(inst, fmi2Error, "%s refused: %s", call, why);
            return fmi2Error;
        }
    }
    if (refresh(inst) != fmi2OK) return fmi2Error;
    for (i = 0; i < nvr; i++) out[i] = inst->values[vr[i]];
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[])
{
    ENTER(CALL_GET);
    if (nvr > 0 && value == NULL) return fmi2Error;
    return get_values(inst, "fmi2GetReal", vr, nvr, SPEC_REAL, value);
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[])
{
    double out[SPEC_N_VARIABLES];
    size_t i, done;
    ENTER(CALL_GET);
    if (nvr > 0 && value == NULL) return fmi2Error;
    for (done = 0; done < nvr; done += SPEC_N_VARIABLES) {
        size_t count = nvr - done < SPEC_N_VARIABLES ? nvr - done : SPEC_N_VARIABLES;
        if (get_values(inst, "fmi2GetInteger", vr + done, count, SPEC_INTEGER, out) != fmi2OK) {
            return fmi2Error;
        }
        for (i = 0; i < count; i++) value[done + i] = (fmi2Integer)out[i];
    }
    return fmi2OK;
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[])
{
    double out[SPEC_N_VARIABLES];
    size_t i, done;
    ENTER(CALL_GET);
    if (nvr > 0 && value == NULL) return fmi2Error;
    for (done = 0; done < nvr; done += SPEC_N_VARIABLES) {
        size_t count = nvr - done < SPEC_N_VARIABLES ? nvr - done : SPEC_N_VARIABLES;
        if (get_values(inst, "fmi2GetBoolean", vr + done, count, SPEC_BOOLEAN, out) != fmi2OK) {
            return fmi2Error;
        }
        for (i = 0; i < count; i++) value[done + i] = out[i] != 0.0 ? fmi2True : fmi2False;
    }
    return fmi2OK;
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[])
{
    ENTER(CALL_GET);
    (void)vr;
    (void)value;
    if (nvr == 0) return fmi2OK;
    log_message(inst, fmi2Error, "fmi2GetString refused: %s has no String variables",
                EXPORT_MODEL_IDENTIFIER);
    return fmi2Error;
}

/* set every value or, if one is refused, none */
static fmi2Status set_values(Instance* inst, const char* call, const fmi2ValueReference vr[],
                             size_t nvr, SpecType type, const double* in)
{
    char why[256], text[40];
    size_t i;
    int inputs = 0;
    if (nvr > 0 && (vr == NULL || in == NULL)) {
        log_message(inst, fmi2Error, "%s refused: %lu values but no arrays", call,
                    (unsigned long)nvr);
        return fmi2Error;
    }
    for (i = 0; i < nvr; i++) {
        const SpecVariable* v;
        if (reference_problem(inst, vr[i], type, why, sizeof why) != NULL) {
            log_message(inst, fmi2Error, "%s refused: %s; nothing changed", call, why);
            return fmi2Error;
        }
        v = &SPEC_VARIABLES[vr[i]];
        if (v->causality == SPEC_INPUT && fabs(in[i]) <= input_limit(v)) continue;  /* hot */
        /* as the Python FMU shows it (parameters.value_text) */
        if (type == SPEC_BOOLEAN) {
            snprintf(text, sizeof text, "%s", in[i] != 0.0 ? "True" : "False");
        } else if (type == SPEC_INTEGER) {
            snprintf(text, sizeof text, "%d", (int)in[i]);
        } else {
            value_text(in[i], v->unit, text, sizeof text);
        }
        if (v->causality == SPEC_OUTPUT) {
            log_message(inst, fmi2Error, "%s refused: %s = %s: it is an output; nothing "
                        "changed", call, v->name, text);
            return fmi2Error;
        }
        if (v->causality == SPEC_PARAMETER && inst->phase == PHASE_RUNNING) {
            log_message(inst, fmi2Error, "%s refused: %s = %s: parameters are fixed after "
                        "initialisation (they define the model built there); reset the FMU "
                        "to change them; nothing changed", call, v->name, text);
            return fmi2Error;
        }
        if (v->causality == SPEC_INPUT && !(fabs(in[i]) <= input_limit(v))) {
            double limit = input_limit(v);
            number(text, in[i]);  /* as the core's StepError shows it: repr, then the unit */
            log_message(inst, fmi2Error, "%s refused: %s = %s %s: must be in [-%g, %g] %s; "
                        "nothing changed", call, v->name, text, v->unit, limit, limit,
                        v->unit);
            return fmi2Error;
        }
    }
    for (i = 0; i < nvr; i++) {
        inst->values[vr[i]] = in[i];
        if (SPEC_VARIABLES[vr[i]].causality == SPEC_INPUT) inputs = 1;
        else if (vr[i] == SPEC_VR_LOAD && inst->phase != PHASE_RUNNING) {
            model_preview(inst->values, inst->values);
        }
    }
    if (inputs && inst->phase == PHASE_RUNNING) inst->stale = 1;
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[])
{
    ENTER(CALL_SET);
    return set_values(inst, "fmi2SetReal", vr, nvr, SPEC_REAL, value);
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[])
{
    double in[SPEC_N_VARIABLES];
    size_t i;
    ENTER(CALL_SET);
    if (nvr > SPEC_N_VARIABLES || (nvr > 0 && value == NULL)) {
        log_message(inst, fmi2Error, "fmi2SetInteger refused: %lu values for %d variables",
                    (unsigned long)nvr, SPEC_N_VARIABLES);
        return fmi2Error;
    }
    for (i = 0; i < nvr; i++) in[i] = (double)value[i];
    return set_values(inst, "fmi2SetInteger", vr, nvr, SPEC_INTEGER, in);
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[])
{
    double in[SPEC_N_VARIABLES];
    size_t i;
    ENTER(CALL_SET);
    if (nvr > SPEC_N_VARIABLES || (nvr > 0 && value == NULL)) {
        log_message(inst, fmi2Error, "fmi2SetBoolean refused: %lu values for %d variables",
                    (unsigned long)nvr, SPEC_N_VARIABLES);
        return fmi2Error;
    }
    for (i = 0; i < nvr; i++) in[i] = value[i] ? 1.0 : 0.0;
    return set_values(inst, "fmi2SetBoolean", vr, nvr, SPEC_BOOLEAN, in);
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[])
{
    ENTER(CALL_SET);
    (void)vr;
    (void)value;
    if (nvr == 0) return fmi2OK;
    log_message(inst, fmi2Error, "fmi2SetString refused: %s has no String variables",
                EXPORT_MODEL_IDENTIFIER);
    return fmi2Error;
}

/* -- stepping ------------------------------------------------------------------------------------- */

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    char t[40], h[40], now[40];
    int status;
    double tolerance;
    ENTER(CALL_DO_STEP);
    (void)noSetFMUStatePriorToCurrentPoint;
    tolerance = fmax(SPEC_TIME_ABS_TOLERANCE_S, SPEC_TIME_REL_TOLERANCE * fabs(inst->time));
    if (!(fabs(currentCommunicationPoint - inst->time) <= tolerance &&
          communicationStepSize > 0.0 && communicationStepSize <= SPEC_MAX_STEP_S)) {
        number(t, currentCommunicationPoint);  /* the texts only for a refusal */
        number(h, communicationStepSize);
    }
    if (!isfinite(currentCommunicationPoint)) {
        log_message(inst, fmi2Error, "fmi2DoStep(t = %s s, h = %s s) refused: t must be "
                    "finite; nothing changed", t, h);
        return fmi2Error;
    }
    if (!(fabs(currentCommunicationPoint - inst->time) <= tolerance)) {
        number(now, inst->time);
        log_message(inst, fmi2Error, "fmi2DoStep(t = %s s, h = %s s) refused: t must be the "
                    "last communication point t = %s s (roll back with fmi2SetFMUstate to "
                    "step from an earlier time); nothing changed", t, h, now);
        return fmi2Error;
    }
    {   /* the Python FMU's checks, in its words */
        double h_value = communicationStepSize, reach = model_road_horizon(inst->model);
        if (!(0.0 < h_value && h_value <= SPEC_MAX_STEP_S)) {
            log_message(inst, fmi2Error, "fmi2DoStep(t = %s s, h = %s s) refused: step size h "
                        "= %s s: must be in (0, %g] s; nothing changed", t, h, h,
                        SPEC_MAX_STEP_S);
            return fmi2Error;
        }
        if (!(reach / h_value <= SPEC_MAX_DELAY_STEPS)) {
            number(t, currentCommunicationPoint);
            number(h, h_value);
            log_message(inst, fmi2Error, "fmi2DoStep(t = %s s, h = %s s) refused: step size h "
                        "= %s s: must be at least %.3g s at this speed: the road reaches the "
                        "contact zone's last node %.3g s after its front, and the FMU keeps at "
                        "most %d steps of its history; nothing changed", t, h, h,
                        reach / SPEC_MAX_DELAY_STEPS, reach, SPEC_MAX_DELAY_STEPS);
            return fmi2Error;
        }
        if (h_value < model_min_step(inst->model)) {
            char why[MESSAGE_SIZE];
            number(t, currentCommunicationPoint);
            number(h, h_value);
            snprintf(why, sizeof why, SPEC_MSG_SHORT_STEP_CORRECTED, h,
                     model_min_step(inst->model));
            log_message(inst, fmi2Error, "fmi2DoStep(t = %s s, h = %s s) refused: %s; nothing "
                        "changed", t, h, why);
            return fmi2Error;
        }
    }
    if (!clock_resolves(inst->time, communicationStepSize)) {
        char text[512];
        double spacing = nextafter(fabs(inst->time) + communicationStepSize, INFINITY)
                         - (fabs(inst->time) + communicationStepSize);
        number(t, currentCommunicationPoint);
        number(h, communicationStepSize);
        number(now, inst->time);
        snprintf(text, sizeof text, SPEC_MSG_CLOCK_RESOLUTION, h, now, spacing, spacing,
                 clock_resolved_until(communicationStepSize));
        log_message(inst, fmi2Error, "fmi2DoStep(t = %s s, h = %s s) refused: %s; nothing "
                    "changed", t, h, text);
        return fmi2Error;
    }
    {   /* more work than a step may take (core/simulator.py: the kernel's rule) */
        int n_sub, work;
        double substep, longest;
        if (model_step_work(inst->model, communicationStepSize, &n_sub, &substep, &work,
                            &longest)) {
            char why[MESSAGE_SIZE];
            number(t, currentCommunicationPoint);
            number(h, communicationStepSize);
            snprintf(why, sizeof why, SPEC_MSG_LONG_STEP, h, n_sub, substep, work,
                     SPEC_MAX_STEP_WORK, longest);
            log_message(inst, fmi2Error, "fmi2DoStep(t = %s s, h = %s s) refused: %s; nothing "
                        "changed", t, h, why);
            return fmi2Error;
        }
    }
    /* the model's own clock goes on: the host's t, within rounding of it, would bring its
     * clock's rounding into the road history (core/clock.py) */
    status = model_step(inst->model, communicationStepSize, inst->values);
    if (status == MODEL_ERROR) {
        inst->broken = "out of memory";
        return fmi2Error;
    }
    inst->stale = 0;
    inst->time = model_time(inst->model);
    {
        int i;
        for (i = 0; i < SPEC_BLOCK_N_OUTPUTS; i++) {
            if (!isfinite(inst->values[SPEC_BLOCK_OUTPUTS_FIRST + i])) {
                number(t, currentCommunicationPoint);
                log_message(inst, fmi2Error, "the step from t = %s s gave non-finite outputs; "
                            "reset the FMU or set an FMU state", t);
                inst->broken = "a step gave non-finite outputs";
                return fmi2Error;
            }
        }
    }
    return status == MODEL_WARNING ? fmi2Warning : fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    ENTER(CALL_CANCEL_STEP);
    log_message(inst, fmi2Error, "fmi2CancelStep refused: no step is pending (fmi2DoStep "
                "always completes)");
    return fmi2Error;
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status* value)
{
    ENTER(CALL_STATUS);
    if (s == fmi2DoStepStatus && value != NULL) {
        *value = fmi2OK;
        return fmi2OK;
    }
    log_message(inst, fmi2Error, "fmi2GetStatus refused: status kind %d has no fmi2Status "
                "value (use fmi2GetRealStatus or fmi2GetBooleanStatus)", (int)s);
    return fmi2Error;
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real* value)
{
    ENTER(CALL_STATUS);
    if (s == fmi2LastSuccessfulTime && value != NULL) {
        *value = inst->time;  /* the last communication point reached */
        return fmi2OK;
    }
    log_message(inst, fmi2Error, "fmi2GetRealStatus refused: status kind %d is not "
                "fmi2LastSuccessfulTime", (int)s);
    return fmi2Error;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer* value)
{
    ENTER(CALL_STATUS);
    (void)value;
    log_message(inst, fmi2Error, "fmi2GetIntegerStatus refused: status kind %d has no Integer "
                "value", (int)s);
    return fmi2Error;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean* value)
{
    ENTER(CALL_STATUS);
    if (s == fmi2Terminated && value != NULL) {
        *value = inst->phase == PHASE_TERMINATED ? fmi2True : fmi2False;
        return fmi2OK;
    }
    log_message(inst, fmi2Error, "fmi2GetBooleanStatus refused: status kind %d is not "
                "fmi2Terminated", (int)s);
    return fmi2Error;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String* value)
{
    ENTER(CALL_STATUS);
    (void)value;
    log_message(inst, fmi2Error, "fmi2GetStringStatus refused: status kind %d has no String "
                "value", (int)s);
    return fmi2Error;
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                       size_t nvr, const fmi2Integer order[],
                                       const fmi2Real value[])
{
    ENTER(CALL_INPUT_DERIVATIVES);
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    log_message(inst, fmi2Error, "fmi2SetRealInputDerivatives refused: the FMU cannot "
                "interpolate inputs (canInterpolateInputs = false); set rim_vz and road_vz");
    return fmi2Error;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t nvr, const fmi2Integer order[],
                                        fmi2Real value[])
{
    ENTER(CALL_OUTPUT_DERIVATIVES);
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    log_message(inst, fmi2Error, "fmi2GetRealOutputDerivatives refused: "
                "maxOutputDerivativeOrder = 0");
    return fmi2Error;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[])
{
    ENTER(CALL_DIRECTIONAL_DERIVATIVE);
    (void)vUnknown_ref;
    (void)nUnknown;
    (void)vKnown_ref;
    (void)nKnown;
    (void)dvKnown;
    (void)dvUnknown;
    log_message(inst, fmi2Error, "fmi2GetDirectionalDerivative refused: the FMU provides no "
                "directional derivatives");
    return fmi2Error;
}

/* -- FMU states ------------------------------------------------------------------------------------
 * One byte string, the same as an FMUstate and serialized: magic (8), version (u32), phase
 * (u32), GUID (48, NUL padded), total size (u64), time, start time (f64), stale (u32),
 * reserved (u32), the variable values (f64 each), the model's part size (u64) and bytes, then a
 * 64-bit FNV-1a checksum of everything before it. Every byte is covered by the checksum. */

#define STATE_GUID_BYTES 48
#define STATE_HEAD (8 + 4 + 4 + STATE_GUID_BYTES + 8 + 8 + 8 + 4 + 4)
#define STATE_VALUES (8 * SPEC_N_VARIABLES)
#define STATE_FIXED (STATE_HEAD + STATE_VALUES + 8 + 8)

static void put(unsigned char** p, const void* data, size_t size)
{
    memcpy(*p, data, size);
    *p += size;
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* FMUstate)
{
    size_t model_size, total;
    unsigned char *bytes, *p;
    uint32_t u;
    uint64_t size64, hash;
    char guid[STATE_GUID_BYTES];
    ENTER(CALL_FMU_STATE);
    if (FMUstate == NULL) {
        log_message(inst, fmi2Error, "fmi2GetFMUstate refused: no place for the state");
        return fmi2Error;
    }
    if (refresh(inst) != fmi2OK) return fmi2Error;
    model_size = inst->phase == PHASE_RUNNING || inst->phase == PHASE_TERMINATED
                     ? model_state_size(inst->model) : 0;
    total = STATE_FIXED + model_size;
    bytes = (unsigned char*)inst->mem.allocate(total, 1);
    if (bytes == NULL) {
        log_message(inst, fmi2Error, "fmi2GetFMUstate: out of memory (%lu bytes)",
                    (unsigned long)total);
        return fmi2Error;
    }
    p = bytes;
    put(&p, SPEC_STATE_MAGIC, 8);
    u = SPEC_STATE_VERSION;
    put(&p, &u, 4);
    u = (uint32_t)inst->phase;
    put(&p, &u, 4);
    memset(guid, 0, sizeof guid);
    strncpy(guid, EXPORT_GUID, sizeof guid - 1);
    put(&p, guid, sizeof guid);
    size64 = (uint64_t)total;
    put(&p, &size64, 8);
    put(&p, &inst->time, 8);
    put(&p, &inst->start_time, 8);
    u = (uint32_t)inst->stale;
    put(&p, &u, 4);
    u = 0;
    put(&p, &u, 4);
    put(&p, inst->values, STATE_VALUES);
    size64 = (uint64_t)model_size;
    put(&p, &size64, 8);
    if (model_size > 0) model_state_write(inst->model, p);
    p += model_size;
    hash = fnv1a(FNV_OFFSET, bytes, (size_t)(p - bytes));
    put(&p, &hash, 8);
    if (*FMUstate != NULL) inst->mem.release(*FMUstate);  /* the host hands back its own */
    *FMUstate = bytes;
    return fmi2OK;
}

/* checks everything but the model part; the total size when the bytes are a state */
static size_t state_problem(const Instance* inst, const unsigned char* bytes, size_t size,
                            char* why, size_t why_size)
{
    uint32_t version, phase, stale;
    uint64_t total, model_size, hash;
    char guid[STATE_GUID_BYTES + 1];
    double time, start;
    int vr;
    if (bytes == NULL) {
        snprintf(why, why_size, "no state given");
        return 0;
    }
    if (size < STATE_FIXED || memcmp(bytes, SPEC_STATE_MAGIC, 8) != 0) {
        snprintf(why, why_size, "it is not a state of this FMU (%s)",
                 size < STATE_FIXED ? "too short" : "no state header");
        return 0;
    }
    memcpy(&version, bytes + 8, 4);
    memcpy(&phase, bytes + 12, 4);
    memcpy(guid, bytes + 16, STATE_GUID_BYTES);
    guid[STATE_GUID_BYTES] = '\0';
    memcpy(&total, bytes + 16 + STATE_GUID_BYTES, 8);
    if (total != size) {
        snprintf(why, why_size, "it says it has %lu bytes, but %lu were given",
                 (unsigned long)total, (unsigned long)size);
        return 0;
    }
    memcpy(&hash, bytes + size - 8, 8);
    if (hash != fnv1a(FNV_OFFSET, bytes, size - 8)) {
        snprintf(why, why_size, "it is damaged: its checksum does not match");
        return 0;
    }
    if (version != SPEC_STATE_VERSION) {
        snprintf(why, why_size, "its format version is %u, this FMU reads %d", (unsigned)version,
                 SPEC_STATE_VERSION);
        return 0;
    }
    if (strcmp(guid, EXPORT_GUID) != 0) {
        snprintf(why, why_size, "it belongs to the FMU with GUID %s, not this one (%s)", guid,
                 EXPORT_GUID);
        return 0;
    }
    if (phase != PHASE_INSTANTIATED && phase != PHASE_INITIALISATION &&
        phase != PHASE_RUNNING && phase != PHASE_TERMINATED) {
        snprintf(why, why_size, "its phase %u is not one of this FMU's", (unsigned)phase);
        return 0;
    }
    memcpy(&time, bytes + 16 + STATE_GUID_BYTES + 8, 8);
    memcpy(&start, bytes + 16 + STATE_GUID_BYTES + 16, 8);
    memcpy(&stale, bytes + 16 + STATE_GUID_BYTES + 24, 4);
    if (!isfinite(time) || !isfinite(start) || stale > 1) {
        snprintf(why, why_size, "its time %g s, start time %g s or flags are not valid", time,
                 start);
        return 0;
    }
    if (!clock_resolves(start, SPEC_MAX_STEP_S)) {
        char a[40], text[512];
        number(a, start);
        snprintf(text, sizeof text, SPEC_MSG_START_UNRESOLVED, a,
                 clock_resolved_until(SPEC_MAX_STEP_S) - SPEC_MAX_STEP_S, SPEC_MAX_STEP_S);
        snprintf(why, why_size, "its %s", text);
        return 0;
    }
    if ((phase == PHASE_INSTANTIATED || phase == PHASE_INITIALISATION) && time != start) {
        char a[40], b[40];
        number(a, time);
        number(b, start);
        snprintf(why, why_size, "its time is %s s before initialisation, not its start time %s "
                 "s", a, b);
        return 0;
    }
    for (vr = 0; vr < SPEC_N_VARIABLES; vr++) {
        double v;
        memcpy(&v, bytes + STATE_HEAD + 8 * (size_t)vr, 8);
        if (!isfinite(v) || (SPEC_VARIABLES[vr].type == SPEC_INTEGER &&
                             (v != floor(v) || fabs(v) > 2147483647.0)) ||
            (SPEC_VARIABLES[vr].type == SPEC_BOOLEAN && v != 0.0 && v != 1.0)) {
            snprintf(why, why_size, "its value of %s is not a valid %s", SPEC_VARIABLES[vr].name,
                     type_name(SPEC_VARIABLES[vr].type));
            return 0;
        }
    }
    memcpy(&model_size, bytes + STATE_HEAD + STATE_VALUES, 8);
    if (model_size != size - STATE_FIXED) {
        snprintf(why, why_size, "its model part has the wrong size");
        return 0;
    }
    if ((phase == PHASE_RUNNING || phase == PHASE_TERMINATED) != (model_size > 0)) {
        snprintf(why, why_size, "its model part does not fit its phase");
        return 0;
    }
    (void)inst;
    return size;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
    const unsigned char* bytes = (const unsigned char*)FMUstate;
    char why[1536];
    uint64_t total = 0;
    uint32_t phase, stale;
    double values[SPEC_N_VARIABLES], time, start;
    const unsigned char* model_part;
    size_t model_size;
    Model* model;
    ENTER(CALL_FMU_STATE);
    if (bytes != NULL && memcmp(bytes, SPEC_STATE_MAGIC, 8) == 0) {
        memcpy(&total, bytes + 16 + STATE_GUID_BYTES, 8);
    }
    if (state_problem(inst, bytes, (size_t)total, why, sizeof why) == 0) {
        log_message(inst, fmi2Error, "fmi2SetFMUstate refused: %s; nothing changed", why);
        return fmi2Error;
    }
    memcpy(&phase, bytes + 12, 4);
    memcpy(&time, bytes + 16 + STATE_GUID_BYTES + 8, 8);
    memcpy(&start, bytes + 16 + STATE_GUID_BYTES + 16, 8);
    memcpy(&stale, bytes + 16 + STATE_GUID_BYTES + 24, 4);
    memcpy(values, bytes + STATE_HEAD, STATE_VALUES);
    model_part = bytes + STATE_HEAD + STATE_VALUES + 8;
    model_size = (size_t)total - STATE_FIXED;
    model = inst->model;
    if (model_size > 0 && !model_built_for(inst->model, values)) {
        /* a state of other parameters, or set into a fresh instance: build its model */
        ModelHost host = host_of(inst);
        double scratch[SPEC_N_VARIABLES];
        model = model_create(&host);
        memcpy(scratch, values, sizeof scratch);
        if (model == NULL || model_initialise(model, values, start, scratch) != MODEL_OK) {
            model_destroy(model);
            log_message(inst, fmi2Error, "fmi2SetFMUstate refused: its parameters do not build "
                        "a model (logged above); nothing changed");
            return fmi2Error;
        }
    }
    if (model_size > 0 &&
        model_state_check(model, model_part, model_size, values, time, start, why,
                          sizeof why) != MODEL_OK) {
        if (model != inst->model) model_destroy(model);
        log_message(inst, fmi2Error, "fmi2SetFMUstate refused: %s; nothing changed", why);
        return fmi2Error;
    }
    if (model != inst->model) {
        model_destroy(inst->model);
        inst->model = model;
    }
    if (model_size > 0) model_state_apply(inst->model, model_part);
    memcpy(inst->values, values, sizeof values);
    inst->phase = (Phase)phase;
    inst->time = time;
    inst->start_time = start;
    inst->stale = (int)stale;
    inst->broken = 0;
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* FMUstate)
{
    ENTER(CALL_FMU_STATE);
    if (FMUstate != NULL && *FMUstate != NULL) {
        inst->mem.release(*FMUstate);
        *FMUstate = NULL;
    }
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t* size)
{
    uint64_t total;
    ENTER(CALL_FMU_STATE);
    if (FMUstate == NULL || size == NULL ||
        memcmp(FMUstate, SPEC_STATE_MAGIC, 8) != 0) {
        log_message(inst, fmi2Error, "fmi2SerializedFMUstateSize refused: not a state of this "
                    "FMU");
        return fmi2Error;
    }
    memcpy(&total, (const unsigned char*)FMUstate + 16 + STATE_GUID_BYTES, 8);
    *size = (size_t)total;
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[],
                                 size_t size)
{
    uint64_t total;
    ENTER(CALL_FMU_STATE);
    if (FMUstate == NULL || serializedState == NULL ||
        memcmp(FMUstate, SPEC_STATE_MAGIC, 8) != 0) {
        log_message(inst, fmi2Error, "fmi2SerializeFMUstate refused: not a state of this FMU");
        return fmi2Error;
    }
    memcpy(&total, (const unsigned char*)FMUstate + 16 + STATE_GUID_BYTES, 8);
    if (size < total) {
        log_message(inst, fmi2Error, "fmi2SerializeFMUstate refused: %lu bytes given, the state "
                    "needs %lu", (unsigned long)size, (unsigned long)total);
        return fmi2Error;
    }
    memcpy(serializedState, FMUstate, (size_t)total);
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[],
                                   size_t size, fmi2FMUstate* FMUstate)
{
    char why[512];
    unsigned char* copy;
    ENTER(CALL_FMU_STATE);
    if (FMUstate == NULL ||
        state_problem(inst, (const unsigned char*)serializedState, size, why, sizeof why) == 0) {
        log_message(inst, fmi2Error, "fmi2DeSerializeFMUstate refused: %s",
                    FMUstate == NULL ? "no place for the state" : why);
        return fmi2Error;
    }
    copy = (unsigned char*)inst->mem.allocate(size, 1);
    if (copy == NULL) {
        log_message(inst, fmi2Error, "fmi2DeSerializeFMUstate: out of memory");
        return fmi2Error;
    }
    memcpy(copy, serializedState, size);
    *FMUstate = copy;
    return fmi2OK;
}
