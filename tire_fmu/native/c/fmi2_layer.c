/* fmi2_layer.c: the generic FMI 2.0 co-simulation layer (no tire in it; see model.h).
 *
 * Which call is allowed in which phase is one table, SPEC_CALLS in spec.h (generated from
 * tire_fmu/fmu/spec.py's CALLS, which the Python FMU's slave reads too), checked by one macro
 * (ENTER) at the top of every function, as the Reference-FMUs keep it. A refused call logs why
 * (status error, category logStatusError) with the spec's texts and changes nothing. Every
 * message is formatted here and handed to the host as the argument of a constant "%s"
 * format: a host's logger treats its format as printf's, so no text, host-given or computed,
 * is ever read as one.
 *
 * Statuses (docs/native.md): fmi2Error for every refused call (a call the phase does not
 * allow, an unknown value reference or wrong type, setting an output or a fixed parameter after
 * initialisation, an input that is not finite or beyond its limit, a doStep at another time
 * than the last communication point or with NaN, h <= 0, a step or start time the clock cannot
 * resolve, bad parameters at fmi2ExitInitializationMode (then the error state), an FMU state
 * that is damaged, of another FMU, or does not mean a state of this tire); fmi2OK otherwise
 * (losing contact and the footprint at the end of the zone included: the one is physics, the
 * other a warning logged once). */
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
typedef char export_strings_match_spec[sizeof EXPORT_START_STRINGS /
                                       sizeof EXPORT_START_STRINGS[0] == SPEC_N_VARIABLES
                                       ? 1 : -1];

#define MESSAGE_SIZE 2048

typedef struct {
    fmi2CallbackLogger logger;
    fmi2ComponentEnvironment environment;
    char* name;
    Memory mem;
    int logging_on;
    unsigned categories;  /* bit i: SPEC_LOG_CATEGORIES[i] */
    int phase;            /* SPEC_PHASE_... */
    char* reason;         /* in the error phase: why (NULL: none given) */
    double time, start_time;
    int stale;            /* inputs set since the outputs were computed */
    double values[SPEC_N_VARIABLES];
    /* the String variables' values (NULL: the export's start value), those the model was
     * built with, and while a state's model is built the state's (string_view) */
    char* strings[SPEC_N_VARIABLES];
    char* built_strings[SPEC_N_VARIABLES];
    char* const* string_view;
    Model* model;
    /* while the model builds: whether its parameter problems are collected, them ("; "
     * between them), how many, and whether its messages reach the host */
    int collecting;
    char* problems;
    int n_problems, quiet;
} Instance;

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

/* a formatted text of any length: in `fixed` when it fits, else in memory of the host's
 * (released with release_text) */
static char* format_text(const Instance* inst, char* fixed, size_t size, const char* format,
                         va_list args)
{
    va_list again;
    int needed;
    char* text;
    va_copy(again, args);
    needed = vsnprintf(fixed, size, format, args);
    if (needed < 0 || (size_t)needed < size) {
        va_end(again);
        return fixed;
    }
    text = (char*)inst->mem.allocate((size_t)needed + 1, 1);
    if (text == NULL) {  /* the start of it, then */
        va_end(again);
        return fixed;
    }
    vsnprintf(text, (size_t)needed + 1, format, again);
    va_end(again);
    return text;
}

static void release_text(const Instance* inst, char* text, const char* fixed)
{
    if (text != fixed) inst->mem.release(text);
}

static char* new_text(const Instance* inst, const char* format, ...)
{
    char fixed[MESSAGE_SIZE], *text, *copy;
    va_list args;
    va_start(args, format);
    text = format_text(inst, fixed, sizeof fixed, format, args);
    va_end(args);
    if (text != fixed) return text;
    copy = (char*)inst->mem.allocate(strlen(fixed) + 1, 1);
    if (copy != NULL) memcpy(copy, fixed, strlen(fixed) + 1);
    return copy;
}

static void log_message(const Instance* inst, fmi2Status status, const char* format, ...)
{
    char fixed[MESSAGE_SIZE], *message;
    va_list args;
    va_start(args, format);
    message = format_text(inst, fixed, sizeof fixed, format, args);
    va_end(args);
    deliver(inst, status, status == fmi2OK ? "logAll"
                      : status == fmi2Warning ? "logStatusWarning" : "logStatusError",
            message);
    release_text(inst, message, fixed);
}

/* a refused call: SPEC_MSG_REFUSED (the call, why; nothing changed) */
static fmi2Status refuse(const Instance* inst, const char* call, const char* why)
{
    log_message(inst, fmi2Error, SPEC_MSG_REFUSED, call, why);
    return fmi2Error;
}

static void append_problem(Instance* inst, const char* text)
{
    size_t used = inst->problems ? strlen(inst->problems) : 0, size = used + strlen(text) + 3;
    char* grown = (char*)inst->mem.allocate(size, 1);
    if (grown == NULL) return;
    if (inst->problems) {
        memcpy(grown, inst->problems, used);
        memcpy(grown + used, "; ", 2);
        used += 2;
        inst->mem.release(inst->problems);
    }
    memcpy(grown + used, text, strlen(text) + 1);
    inst->problems = grown;
    inst->n_problems++;
}

/* the model's messages; while it builds, its parameter problems (SPEC_MSG_PROBLEM_LINE) are
 * also collected for the reason of a refusal */
static void model_log(void* layer, int status, const char* category, const char* message)
{
    Instance* inst = (Instance*)layer;
    int number, count, offset = -1;
    if (inst->collecting && status >= fmi2Error &&
        sscanf(message, "parameter problem %d/%d: %n", &number, &count, &offset) == 2 &&
        offset > 0) {
        append_problem(inst, message + offset);
    }
    if (!inst->quiet) deliver(inst, (fmi2Status)status, category, message);
}

static void start_collecting(Instance* inst, int quiet)
{
    inst->collecting = 1;
    inst->problems = NULL;
    inst->n_problems = 0;
    inst->quiet = quiet;
}

static void stop_collecting(Instance* inst)
{
    if (inst->problems) inst->mem.release(inst->problems);
    inst->problems = NULL;
    inst->n_problems = 0;
    inst->collecting = inst->quiet = 0;
}

static void set_reason(Instance* inst, char* reason)
{
    if (inst->reason) inst->mem.release(inst->reason);
    inst->reason = reason;
}

/* an internal failure: the error state, with why, logged (SPEC_MSG_FAILED) */
static fmi2Status fail(Instance* inst, const char* what, const char* cause)
{
    inst->phase = SPEC_PHASE_ERROR;
    set_reason(inst, new_text(inst, SPEC_MSG_FAILED, what, cause));
    log_message(inst, fmi2Error, "%s", inst->reason ? inst->reason : SPEC_MSG_ERROR_STATE);
    return fmi2Error;
}

static int allowed(Instance* inst, SpecCall call)
{
    if (SPEC_CALLS[call].phases & (1u << inst->phase)) return 1;
    if (inst->phase == SPEC_PHASE_ERROR) {
        refuse(inst, SPEC_CALLS[call].name, inst->reason ? inst->reason : SPEC_MSG_ERROR_STATE);
    } else {
        char why[512];
        snprintf(why, sizeof why, SPEC_MSG_PHASE, SPEC_PHASE_TEXT[inst->phase]);
        refuse(inst, SPEC_CALLS[call].name, why);
    }
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
    inst->phase = SPEC_PHASE_INSTANTIATED;
    inst->time = inst->start_time = 0.0;
    inst->stale = 0;
    set_reason(inst, NULL);
}

/* a String variable's value in texts (NULL: its start value) */
static const char* text_of(char* const* texts, int vr)
{
    if (texts[vr] != NULL) return texts[vr];
    return EXPORT_START_STRINGS[vr] != NULL ? EXPORT_START_STRINGS[vr] : "";
}

static const char* string_of(const Instance* inst, int vr)
{
    return text_of(inst->string_view != NULL ? inst->string_view : inst->strings, vr);
}

/* ModelHost.string: a String parameter's value as the model is built with it */
static const char* layer_string(void* layer, int vr) { return string_of((Instance*)layer, vr); }

static char* copy_text(Instance* inst, const char* text)
{
    size_t n = strlen(text) + 1;
    char* copy = (char*)inst->mem.allocate(n, 1);
    if (copy != NULL) memcpy(copy, text, n);
    return copy;
}

static void release_strings(Instance* inst, char** strings)
{
    int vr;
    for (vr = 0; vr < SPEC_N_VARIABLES; vr++) {
        if (strings[vr] != NULL) inst->mem.release(strings[vr]);
        strings[vr] = NULL;
    }
}

/* strings[] := copies of the texts (NULL entries, the start values, stay NULL); 0, or -1 out
 * of memory (nothing changed) */
static int take_strings(Instance* inst, char** strings, char* const* texts)
{
    char* copies[SPEC_N_VARIABLES];
    int vr;
    for (vr = 0; vr < SPEC_N_VARIABLES; vr++) {
        copies[vr] = NULL;
        if (texts[vr] == NULL) continue;
        copies[vr] = copy_text(inst, texts[vr]);
        if (copies[vr] == NULL) {
            release_strings(inst, copies);
            return -1;
        }
    }
    release_strings(inst, strings);
    memcpy(strings, copies, sizeof copies);
    return 0;
}

static ModelHost host_of(Instance* inst)
{
    ModelHost host;
    host.mem = inst->mem;
    host.layer = inst;
    host.log = model_log;
    host.string = layer_string;
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
    probe.mem.allocate = functions != NULL && functions->allocateMemory != NULL
                             ? functions->allocateMemory : default_allocate;
    probe.mem.release = functions != NULL && functions->freeMemory != NULL
                            ? functions->freeMemory : free;
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
    release_strings(inst, inst->strings);
    release_strings(inst, inst->built_strings);
    set_reason(inst, NULL);
    stop_collecting(inst);
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
    ENTER(SPEC_CALL_SET_DEBUG_LOGGING);
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
    char a[40], b[40], why[512];
    const char* call = "fmi2SetupExperiment";
    ENTER(SPEC_CALL_SETUP_EXPERIMENT);
    number(a, startTime);
    if (!isfinite(startTime)) {
        snprintf(why, sizeof why, SPEC_MSG_START_NOT_FINITE, a);
        return refuse(inst, call, why);
    }
    if (!clock_resolves(startTime, SPEC_MAX_STEP_S)) {
        snprintf(why, sizeof why, SPEC_MSG_START_UNRESOLVED, a,
                 clock_resolved_until(SPEC_MAX_STEP_S) - SPEC_MAX_STEP_S, SPEC_MAX_STEP_S);
        return refuse(inst, call, why);
    }
    if (stopTimeDefined && !(isfinite(stopTime) && stopTime >= startTime)) {
        number(b, stopTime);
        snprintf(why, sizeof why, SPEC_MSG_STOP_TIME, b, a);
        return refuse(inst, call, why);
    }
    if (toleranceDefined && !(isfinite(tolerance) && tolerance > 0.0)) {
        number(b, tolerance);
        snprintf(why, sizeof why, SPEC_MSG_TOLERANCE, b);
        return refuse(inst, call, why);
    }
    inst->start_time = startTime;
    inst->time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    ENTER(SPEC_CALL_ENTER_INITIALIZATION_MODE);
    inst->phase = SPEC_PHASE_INITIALISATION;
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
    int status;
    ENTER(SPEC_CALL_EXIT_INITIALIZATION_MODE);
    start_collecting(inst, 0);
    status = model_initialise(inst->model, inst->values, inst->start_time, inst->values);
    if (status == MODEL_OK && take_strings(inst, inst->built_strings, inst->strings) != 0) {
        model_destroy(inst->model);
        inst->model = NULL;
        stop_collecting(inst);
        return fail(inst, SPEC_MSG_OUTPUTS_FAILED, SPEC_MSG_OUT_OF_MEMORY);
    }
    if (status != MODEL_OK) {
        /* no model to step: FMI's error state, every later refusal saying why */
        inst->phase = SPEC_PHASE_ERROR;
        set_reason(inst, new_text(inst, SPEC_MSG_PARAMETERS_REFUSED,
                                  inst->n_problems,
                                  inst->problems ? inst->problems : ""));
        stop_collecting(inst);
        log_message(inst, fmi2Error, SPEC_MSG_EXIT_REFUSED,
                    inst->reason ? inst->reason : SPEC_MSG_ERROR_STATE);
        return fmi2Error;
    }
    stop_collecting(inst);
    inst->phase = SPEC_PHASE_RUNNING;
    inst->time = inst->start_time;
    inst->stale = any_input_set(inst->values);  /* inputs set before feed through */
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c)
{
    ENTER(SPEC_CALL_TERMINATE);
    inst->phase = SPEC_PHASE_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c)
{
    ModelHost host;
    Model* fresh;
    ENTER(SPEC_CALL_RESET);
    host = host_of(inst);
    fresh = model_create(&host);
    if (fresh == NULL) {
        log_message(inst, fmi2Error, "fmi2Reset: out of memory");
        return fmi2Error;
    }
    model_destroy(inst->model);
    inst->model = fresh;
    release_strings(inst, inst->strings);
    release_strings(inst, inst->built_strings);
    start_values(inst);
    return fmi2OK;
}

/* -- variables ----------------------------------------------------------------------------------- */

static const char* type_name(SpecType type)
{
    return type == SPEC_REAL      ? "Real"
           : type == SPEC_INTEGER ? "Integer"
           : type == SPEC_STRING  ? "String"
                                  : "Boolean";
}

/* why input v cannot take x (SPEC_MSG_INPUT_RANGE), or NULL: beyond the largest magnitude
 * its row carries (the Python FMUs' rule, interface.input_limit: by name, else by unit). NaN
 * fails the comparison with it, so one test refuses both. */
static const char* input_problem(const SpecVariable* v, double x, char* why, size_t size)
{
    char text[40];
    double limit = v->limit;
    if (fabs(x) <= limit) return NULL;
    number(text, x);  /* as the core's StepError shows it: repr, then the unit */
    snprintf(why, size, SPEC_MSG_INPUT_RANGE, v->name, text, v->unit, limit, limit, v->unit);
    return why;
}

/* why vr cannot be used as type (NULL when it can) */
static const char* reference_problem(fmi2ValueReference vr, SpecType type, char* why,
                                     size_t size)
{
    if (vr >= SPEC_N_VARIABLES) {
        snprintf(why, size, SPEC_MSG_REFERENCE_MISSING, (unsigned)vr, EXPORT_MODEL_IDENTIFIER,
                 SPEC_N_VARIABLES);
        return why;
    }
    if (SPEC_VARIABLES[vr].type != type) {
        const char* name = type_name(SPEC_VARIABLES[vr].type);
        snprintf(why, size, SPEC_MSG_REFERENCE_TYPE, (unsigned)vr, SPEC_VARIABLES[vr].name,
                 name, name, name);
        return why;
    }
    return NULL;
}

static fmi2Status refresh(Instance* inst)
{
    if (inst->stale && inst->phase == SPEC_PHASE_RUNNING) {
        if (model_refresh(inst->model, inst->values) != MODEL_OK) {
            return fail(inst, SPEC_MSG_OUTPUTS_FAILED, SPEC_MSG_OUT_OF_MEMORY);
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
    if (nvr > 0 && (vr == NULL || out == NULL)) {
        log_message(inst, fmi2Error, "%s refused: %lu values but no arrays", call,
                    (unsigned long)nvr);
        return fmi2Error;
    }
    for (i = 0; i < nvr; i++) {
        if (reference_problem(vr[i], type, why, sizeof why) != NULL) {
            return refuse(inst, call, why);
        }
    }
    if (refresh(inst) != fmi2OK) return fmi2Error;
    for (i = 0; i < nvr; i++) out[i] = inst->values[vr[i]];
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[])
{
    ENTER(SPEC_CALL_GET_REAL);
    return get_values(inst, "fmi2GetReal", vr, nvr, SPEC_REAL, value);
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[])
{
    double out[SPEC_N_VARIABLES];
    size_t i, done;
    ENTER(SPEC_CALL_GET_INTEGER);
    if (nvr > 0 && value == NULL) return get_values(inst, "fmi2GetInteger", vr, nvr,
                                                    SPEC_INTEGER, NULL);
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
    ENTER(SPEC_CALL_GET_BOOLEAN);
    if (nvr > 0 && value == NULL) return get_values(inst, "fmi2GetBoolean", vr, nvr,
                                                    SPEC_BOOLEAN, NULL);
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
    char why[256];
    size_t i;
    ENTER(SPEC_CALL_GET_STRING);
    if (nvr == 0) return fmi2OK;
    if (SPEC_N_STRINGS == 0) {
        snprintf(why, sizeof why, SPEC_MSG_NO_STRINGS, EXPORT_MODEL_IDENTIFIER);
        return refuse(inst, "fmi2GetString", why);
    }
    if (vr == NULL || value == NULL) {
        log_message(inst, fmi2Error, "fmi2GetString refused: %lu values but no arrays",
                    (unsigned long)nvr);
        return fmi2Error;
    }
    for (i = 0; i < nvr; i++) {
        if (reference_problem(vr[i], SPEC_STRING, why, sizeof why) != NULL) {
            return refuse(inst, "fmi2GetString", why);
        }
    }
    for (i = 0; i < nvr; i++) value[i] = string_of(inst, (int)vr[i]);
    return fmi2OK;
}

/* set every value or, if one is refused, none */
static fmi2Status set_values(Instance* inst, const char* call, const fmi2ValueReference vr[],
                             size_t nvr, SpecType type, const double* in)
{
    char why[512], text[40];
    size_t i;
    int inputs = 0;
    if (nvr > 0 && (vr == NULL || in == NULL)) {
        log_message(inst, fmi2Error, "%s refused: %lu values but no arrays", call,
                    (unsigned long)nvr);
        return fmi2Error;
    }
    for (i = 0; i < nvr; i++) {
        const SpecVariable* v;
        if (reference_problem(vr[i], type, why, sizeof why) != NULL) {
            return refuse(inst, call, why);
        }
        v = &SPEC_VARIABLES[vr[i]];
        if (v->causality == SPEC_INPUT) {
            if (input_problem(v, in[i], why, sizeof why) != NULL) return refuse(inst, call, why);
            continue;
        }
        /* as the Python FMU shows it (parameters.value_text) */
        if (type == SPEC_BOOLEAN) {
            snprintf(text, sizeof text, "%s", in[i] != 0.0 ? "True" : "False");
        } else if (type == SPEC_INTEGER) {
            snprintf(text, sizeof text, "%d", (int)in[i]);
        } else {
            value_text(in[i], v->unit, text, sizeof text);
        }
        if (v->causality == SPEC_OUTPUT) {
            snprintf(why, sizeof why, SPEC_MSG_OUTPUT_SET, v->name, text);
            return refuse(inst, call, why);
        }
        if (v->causality == SPEC_PARAMETER && inst->phase == SPEC_PHASE_RUNNING) {
            snprintf(why, sizeof why, SPEC_MSG_PARAMETER_FIXED, v->name, text);
            return refuse(inst, call, why);
        }
    }
    for (i = 0; i < nvr; i++) {
        inst->values[vr[i]] = in[i];
        if (SPEC_VARIABLES[vr[i]].causality == SPEC_INPUT) inputs = 1;
        else if (vr[i] == SPEC_VR_LOAD && inst->phase != SPEC_PHASE_RUNNING) {
            model_preview(inst->values, inst->values);
        }
    }
    if (inputs && inst->phase == SPEC_PHASE_RUNNING) inst->stale = 1;
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[])
{
    ENTER(SPEC_CALL_SET_REAL);
    return set_values(inst, "fmi2SetReal", vr, nvr, SPEC_REAL, value);
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[])
{
    double in[SPEC_N_VARIABLES];
    size_t i;
    ENTER(SPEC_CALL_SET_INTEGER);
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
    ENTER(SPEC_CALL_SET_BOOLEAN);
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
    char why[512], *texts[SPEC_N_VARIABLES];
    size_t i;
    int k;
    ENTER(SPEC_CALL_SET_STRING);
    if (nvr == 0) return fmi2OK;
    if (SPEC_N_STRINGS == 0) {
        snprintf(why, sizeof why, SPEC_MSG_NO_STRINGS, EXPORT_MODEL_IDENTIFIER);
        return refuse(inst, "fmi2SetString", why);
    }
    if (vr == NULL || value == NULL) {
        log_message(inst, fmi2Error, "fmi2SetString refused: %lu values but no arrays",
                    (unsigned long)nvr);
        return fmi2Error;
    }
    for (i = 0; i < nvr; i++) {
        const SpecVariable* v;
        char text[256];
        if (reference_problem(vr[i], SPEC_STRING, why, sizeof why) != NULL) {
            return refuse(inst, "fmi2SetString", why);
        }
        v = &SPEC_VARIABLES[vr[i]];
        snprintf(text, sizeof text, "'%s'", value[i] != NULL ? value[i] : "");
        if (v->causality == SPEC_OUTPUT) {
            snprintf(why, sizeof why, SPEC_MSG_OUTPUT_SET, v->name, text);
            return refuse(inst, "fmi2SetString", why);
        }
        if (v->causality == SPEC_PARAMETER && inst->phase == SPEC_PHASE_RUNNING) {
            snprintf(why, sizeof why, SPEC_MSG_PARAMETER_FIXED, v->name, text);
            return refuse(inst, "fmi2SetString", why);
        }
    }
    /* every value or none: the new texts in a copy of the strings, then swapped in */
    for (k = 0; k < SPEC_N_VARIABLES; k++) texts[k] = inst->strings[k];
    for (i = 0; i < nvr; i++) texts[vr[i]] = (char*)(value[i] != NULL ? value[i] : "");
    if (take_strings(inst, inst->strings, texts) != 0) {
        return refuse(inst, "fmi2SetString", SPEC_MSG_OUT_OF_MEMORY);
    }
    return fmi2OK;
}

/* -- stepping ------------------------------------------------------------------------------------- */

/* a step that failed: its message is written only then (the shortest round-trip text of t
 * takes several printf and strtod calls, a few microseconds of every step if made ahead) */
static fmi2Status step_failed(Instance* inst, double t, const char* why)
{
    char text[40], call[128];
    number(text, t);
    snprintf(call, sizeof call, SPEC_MSG_STEP_FAILED, text);
    return fail(inst, call, why);
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    char t[40], h[40], now[40], call[128], why[MESSAGE_SIZE];
    int status, i;
    double tolerance, reach, h_value = communicationStepSize;
    ENTER(SPEC_CALL_DO_STEP);
    (void)noSetFMUStatePriorToCurrentPoint;
    tolerance = fmax(SPEC_TIME_ABS_TOLERANCE_S, SPEC_TIME_REL_TOLERANCE * fabs(inst->time));
    reach = model_road_horizon(inst->model);
    /* the checks of the Python FMU, in its order and words (a NaN fails every comparison) */
    if (!(fabs(currentCommunicationPoint - inst->time) <= tolerance && 0.0 < h_value &&
          h_value <= SPEC_MAX_STEP_S && reach / h_value <= SPEC_MAX_DELAY_STEPS &&
          h_value >= model_min_step(inst->model) && clock_resolves(inst->time, h_value))) {
        number(t, currentCommunicationPoint);  /* the texts only for a refusal */
        number(h, h_value);
        snprintf(call, sizeof call, SPEC_MSG_STEP_CALL, t, h);
        if (!(fabs(currentCommunicationPoint - inst->time) <= tolerance)) {
            number(now, inst->time);
            snprintf(why, sizeof why, SPEC_MSG_NOT_LAST_POINT, t, now);
        } else if (!(0.0 < h_value && h_value <= SPEC_MAX_STEP_S)) {
            snprintf(why, sizeof why, SPEC_MSG_STEP_RANGE, h, SPEC_MAX_STEP_S);
        } else if (!(reach / h_value <= SPEC_MAX_DELAY_STEPS)) {
            snprintf(why, sizeof why, SPEC_MSG_STEP_DELAY, h, reach / SPEC_MAX_DELAY_STEPS,
                     reach, SPEC_MAX_DELAY_STEPS);
        } else if (h_value < model_min_step(inst->model)) {
            snprintf(why, sizeof why, SPEC_MSG_SHORT_STEP_CORRECTED, h,
                     model_min_step(inst->model));
        } else {
            double spacing = nextafter(fabs(inst->time) + h_value, INFINITY)
                             - (fabs(inst->time) + h_value);
            number(now, inst->time);
            snprintf(why, sizeof why, SPEC_MSG_CLOCK_RESOLUTION, h, now, spacing, spacing,
                     clock_resolved_until(h_value));
        }
        return refuse(inst, call, why);
    }
    {   /* more work than a step may take (core/simulator.py: the kernel's rule) */
        int n_sub, work;
        double substep, longest;
        if (model_step_work(inst->model, communicationStepSize, &n_sub, &substep, &work,
                            &longest)) {
            number(t, currentCommunicationPoint);
            number(h, communicationStepSize);
            snprintf(call, sizeof call, SPEC_MSG_STEP_CALL, t, h);
            snprintf(why, sizeof why, SPEC_MSG_LONG_STEP, h, n_sub, substep, work,
                     SPEC_MAX_STEP_WORK, longest);
            return refuse(inst, call, why);
        }
    }
    if (model_step_problem(inst->model, h_value, why, sizeof why) != NULL) {
        number(t, currentCommunicationPoint);
        number(h, h_value);
        snprintf(call, sizeof call, SPEC_MSG_STEP_CALL, t, h);
        return refuse(inst, call, why);
    }
    /* the model's own clock goes on: the host's t, within rounding of it, would bring its
     * clock's rounding into the road history (core/clock.py) */
    status = model_step(inst->model, communicationStepSize, inst->values);
    if (status == MODEL_DISCARD) {  /* refused and undone by the model: nothing changed */
        number(t, currentCommunicationPoint);
        number(h, h_value);
        snprintf(call, sizeof call, SPEC_MSG_STEP_CALL, t, h);
        return refuse(inst, call, model_step_refusal(inst->model));
    }
    if (status == MODEL_ERROR) {
        return step_failed(inst, currentCommunicationPoint, SPEC_MSG_OUT_OF_MEMORY);
    }
    for (i = 0; i < SPEC_BLOCK_N_OUTPUTS; i++) {
        if (!isfinite(inst->values[SPEC_BLOCK_OUTPUTS_FIRST + i])) {
            return step_failed(inst, currentCommunicationPoint, SPEC_MSG_NOT_FINITE_OUTPUTS);
        }
    }
    inst->stale = 0;
    inst->time = model_time(inst->model);
    /* the footprint at the zone's end is logged as a warning, but the step is OK, as in the
     * Python FMU (whose wrapper cannot return fmi2Warning from a step): a strict host must
     * not end a ride run because the footprint touched the zone's end for a moment */
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    ENTER(SPEC_CALL_CANCEL_STEP);
    return refuse(inst, "fmi2CancelStep", SPEC_MSG_NO_STEP_PENDING);
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status* value)
{
    ENTER(SPEC_CALL_GET_STATUS);
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
    ENTER(SPEC_CALL_GET_REAL_STATUS);
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
    ENTER(SPEC_CALL_GET_INTEGER_STATUS);
    (void)value;
    log_message(inst, fmi2Error, "fmi2GetIntegerStatus refused: status kind %d has no Integer "
                "value", (int)s);
    return fmi2Error;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean* value)
{
    ENTER(SPEC_CALL_GET_BOOLEAN_STATUS);
    if (s == fmi2Terminated && value != NULL) {
        *value = inst->phase == SPEC_PHASE_TERMINATED ? fmi2True : fmi2False;
        return fmi2OK;
    }
    log_message(inst, fmi2Error, "fmi2GetBooleanStatus refused: status kind %d is not "
                "fmi2Terminated", (int)s);
    return fmi2Error;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String* value)
{
    ENTER(SPEC_CALL_GET_STRING_STATUS);
    (void)value;
    log_message(inst, fmi2Error, "fmi2GetStringStatus refused: status kind %d has no String "
                "value", (int)s);
    return fmi2Error;
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                       size_t nvr, const fmi2Integer order[],
                                       const fmi2Real value[])
{
    ENTER(SPEC_CALL_SET_REAL_INPUT_DERIVATIVES);
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
    ENTER(SPEC_CALL_GET_REAL_OUTPUT_DERIVATIVES);
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
    ENTER(SPEC_CALL_GET_DIRECTIONAL_DERIVATIVE);
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
 * One byte string, the same as an FMUstate and serialized, in the layout of spec.py's
 * STATE_LAYOUT (docs/fmu.md): magic (8), version (u32), phase (u32), GUID (48, NUL padded),
 * total size (u64), time, start time (f64), stale (u32), the error reason's size (u32), the
 * variable values (f64 each), the model's part size (u64) and bytes, the reason, then a
 * CRC-32 of everything before it. The Python FMU writes and reads the same bytes. */

#define STATE_VALUES (8 * SPEC_N_VARIABLES)
#define STATE_FIXED (SPEC_STATE_HEAD + STATE_VALUES + 8 + 4)
#define AT_SIZE (16 + SPEC_STATE_GUID_BYTES)
#define AT_TIME (AT_SIZE + 8)

static uint32_t state_crc(const unsigned char* bytes, size_t size)
{
    unsigned long crc = 0xfffffffful;
    size_t i;
    for (i = 0; i < size; i++) crc = SPEC_CRC32_TABLE[(crc ^ bytes[i]) & 0xff] ^ (crc >> 8);
    return (uint32_t)(crc ^ 0xfffffffful);
}

static void put(unsigned char** p, const void* data, size_t size)
{
    memcpy(*p, data, size);
    *p += size;
}

/* the bytes of the String values as a state holds them: each, then a NUL */
static size_t strings_size(const Instance* inst)
{
    size_t total = 0;
    int vr;
    for (vr = 0; vr < SPEC_N_VARIABLES; vr++)
        if (SPEC_VARIABLES[vr].type == SPEC_STRING) total += strlen(string_of(inst, vr)) + 1;
    return total;
}

/* whether the bytes are one NUL-ended UTF-8 text per String variable (state_strings) */
static int strings_valid(const unsigned char* bytes, size_t size)
{
    size_t i = 0, texts = 0;
    while (i < size) {
        unsigned char c = bytes[i];
        int more = c < 0x80 ? 0 : (c & 0xe0) == 0xc0 ? 1 : (c & 0xf0) == 0xe0 ? 2
                 : (c & 0xf8) == 0xf0 ? 3 : -1;
        if (more < 0 || (more == 1 && c < 0xc2) || i + (size_t)more >= size) return 0;
        for (i++; more > 0; more--, i++)
            if ((bytes[i] & 0xc0) != 0x80) return 0;
        if (c == 0) texts++;
    }
    return (size == 0 || bytes[size - 1] == 0) && texts == SPEC_N_STRINGS;
}

/* texts[vr] := the state's String values (pointers into its bytes), the rest NULL */
static void state_texts(const unsigned char* bytes, char** texts)
{
    int vr;
    for (vr = 0; vr < SPEC_N_VARIABLES; vr++) {
        texts[vr] = NULL;
        if (SPEC_VARIABLES[vr].type != SPEC_STRING) continue;
        texts[vr] = (char*)bytes;
        bytes += strlen((const char*)bytes) + 1;
    }
}

static int same_strings(char* const* a, char* const* b)
{
    int vr;
    for (vr = 0; vr < SPEC_N_VARIABLES; vr++) {
        if (SPEC_VARIABLES[vr].type == SPEC_STRING && strcmp(text_of(a, vr), text_of(b, vr)) != 0)
            return 0;
    }
    return 1;
}

static int has_model_part(int phase)
{
    return phase == SPEC_PHASE_RUNNING || phase == SPEC_PHASE_TERMINATED;
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* FMUstate)
{
    size_t model_size, reason_size, texts_size, total;
    unsigned char *bytes, *p;
    int vr;
    uint32_t u;
    uint64_t size64;
    char guid[SPEC_STATE_GUID_BYTES];
    ENTER(SPEC_CALL_GET_FMUSTATE);
    if (FMUstate == NULL) {
        log_message(inst, fmi2Error, "fmi2GetFMUstate refused: no place for the state");
        return fmi2Error;
    }
    if (refresh(inst) != fmi2OK) return fmi2Error;
    model_size = has_model_part(inst->phase) ? model_state_size(inst->model) : 0;
    reason_size = inst->phase == SPEC_PHASE_ERROR && inst->reason ? strlen(inst->reason) : 0;
    texts_size = strings_size(inst);
    total = STATE_FIXED + model_size + texts_size + reason_size;
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
    u = (uint32_t)reason_size;
    put(&p, &u, 4);
    u = (uint32_t)texts_size;
    put(&p, &u, 4);
    put(&p, inst->values, STATE_VALUES);
    size64 = (uint64_t)model_size;
    put(&p, &size64, 8);
    if (model_size > 0) model_state_write(inst->model, p);
    p += model_size;
    for (vr = 0; vr < SPEC_N_VARIABLES; vr++) {
        if (SPEC_VARIABLES[vr].type == SPEC_STRING) {
            const char* text = string_of(inst, vr);
            put(&p, text, strlen(text) + 1);
        }
    }
    if (reason_size > 0) put(&p, inst->reason, reason_size);
    u = state_crc(bytes, (size_t)(p - bytes));
    put(&p, &u, 4);
    if (*FMUstate != NULL) inst->mem.release(*FMUstate);  /* the host hands back its own */
    *FMUstate = bytes;
    return fmi2OK;
}

/* checks everything but the model part (in spec.py's order and words, as the Python FMU);
 * the total size when the bytes are a state */
static size_t state_problem(const unsigned char* bytes, size_t size, char* why,
                            size_t why_size)
{
    uint32_t version, phase, stale, reason_size, texts_size, crc;
    uint64_t total, model_size;
    char guid[SPEC_STATE_GUID_BYTES + 1], a[40], b[40];
    double time, start;
    int vr;
    if (bytes == NULL || size < STATE_FIXED || memcmp(bytes, SPEC_STATE_MAGIC, 8) != 0) {
        snprintf(why, why_size, SPEC_MSG_STATE_NOT_OURS,
                 bytes == NULL || size < STATE_FIXED ? SPEC_MSG_STATE_TOO_SHORT
                                                     : SPEC_MSG_STATE_NO_HEADER);
        return 0;
    }
    memcpy(&version, bytes + 8, 4);
    memcpy(&phase, bytes + 12, 4);
    memcpy(guid, bytes + 16, SPEC_STATE_GUID_BYTES);
    guid[SPEC_STATE_GUID_BYTES] = '\0';
    memcpy(&total, bytes + AT_SIZE, 8);
    if (total != size) {
        snprintf(why, why_size, SPEC_MSG_STATE_SIZE, (unsigned long)total, (unsigned long)size);
        return 0;
    }
    memcpy(&crc, bytes + size - 4, 4);
    if (crc != state_crc(bytes, size - 4)) {
        snprintf(why, why_size, "%s", SPEC_MSG_STATE_DAMAGED);
        return 0;
    }
    if (version != SPEC_STATE_VERSION) {
        snprintf(why, why_size, SPEC_MSG_STATE_VERSION, (unsigned)version, SPEC_STATE_VERSION);
        return 0;
    }
    if (strcmp(guid, EXPORT_GUID) != 0) {
        snprintf(why, why_size, SPEC_MSG_STATE_GUID, guid, EXPORT_GUID);
        return 0;
    }
    if (phase >= SPEC_N_PHASES) {
        snprintf(why, why_size, SPEC_MSG_STATE_PHASE, (unsigned)phase);
        return 0;
    }
    memcpy(&time, bytes + AT_TIME, 8);
    memcpy(&start, bytes + AT_TIME + 8, 8);
    memcpy(&stale, bytes + AT_TIME + 16, 4);
    memcpy(&reason_size, bytes + AT_TIME + 20, 4);
    memcpy(&texts_size, bytes + AT_TIME + 24, 4);
    if (!isfinite(time) || !isfinite(start) || stale > 1) {
        number(a, time);
        number(b, start);
        snprintf(why, why_size, SPEC_MSG_STATE_CLOCK, a, b);
        return 0;
    }
    if (!clock_resolves(start, SPEC_MAX_STEP_S)) {
        char text[512];
        number(a, start);
        snprintf(text, sizeof text, SPEC_MSG_START_UNRESOLVED, a,
                 clock_resolved_until(SPEC_MAX_STEP_S) - SPEC_MAX_STEP_S, SPEC_MAX_STEP_S);
        snprintf(why, why_size, SPEC_MSG_STATE_START, text);
        return 0;
    }
    if ((phase == SPEC_PHASE_INSTANTIATED || phase == SPEC_PHASE_INITIALISATION) &&
        time != start) {
        number(a, time);
        number(b, start);
        snprintf(why, why_size, SPEC_MSG_STATE_BEFORE_INIT, a, b);
        return 0;
    }
    for (vr = 0; vr < SPEC_N_VARIABLES; vr++) {
        const SpecVariable* v = &SPEC_VARIABLES[vr];
        double x;
        memcpy(&x, bytes + SPEC_STATE_HEAD + 8 * (size_t)vr, 8);
        if (v->causality == SPEC_INPUT) {
            char text[512];
            if (input_problem(v, x, text, sizeof text) != NULL) {
                snprintf(why, why_size, SPEC_MSG_STATE_INPUT, text);
                return 0;
            }
        } else if ((v->type == SPEC_INTEGER &&
                    !(x == floor(x) && fabs(x) <= 2147483647.0)) ||
                   (v->type == SPEC_BOOLEAN && x != 0.0 && x != 1.0) ||
                   (v->causality == SPEC_OUTPUT && !isfinite(x))) {
            /* a Real parameter holds whatever a set gave it: checked when it is used */
            snprintf(why, why_size, SPEC_MSG_STATE_VALUE, v->name, type_name(v->type));
            return 0;
        }
    }
    memcpy(&model_size, bytes + SPEC_STATE_HEAD + STATE_VALUES, 8);
    /* (the sizes of the model part and the reason fill what the header leaves, exactly; no
     * sum that could wrap around) */
    if (reason_size > size - STATE_FIXED || texts_size > size - STATE_FIXED - reason_size ||
        model_size != size - STATE_FIXED - reason_size - texts_size) {
        snprintf(why, why_size, "%s", SPEC_MSG_STATE_MODEL_SIZE);
        return 0;
    }
    if (!strings_valid(bytes + SPEC_STATE_HEAD + STATE_VALUES + 8 + model_size, texts_size)) {
        snprintf(why, why_size, "%s", SPEC_MSG_STATE_STRINGS);
        return 0;
    }
    if (has_model_part((int)phase) != (model_size > 0)) {
        snprintf(why, why_size, "%s", SPEC_MSG_STATE_MODEL_PHASE);
        return 0;
    }
    if ((phase == SPEC_PHASE_ERROR) != (reason_size > 0)) {
        if (phase == SPEC_PHASE_ERROR) snprintf(why, why_size, "%s", SPEC_MSG_STATE_NO_REASON);
        else snprintf(why, why_size, SPEC_MSG_STATE_REASON_PHASE,
                      SPEC_PHASE_NAME[phase]);
        return 0;
    }
    if (memchr(bytes + size - 4 - reason_size, '\0', reason_size) != NULL) {
        snprintf(why, why_size, "%s", SPEC_MSG_STATE_REASON_NUL);
        return 0;
    }
    return size;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
    const unsigned char* bytes = (const unsigned char*)FMUstate;
    char why[MESSAGE_SIZE];
    uint64_t total = 0;
    uint32_t phase, stale, reason_size, texts_size;
    double values[SPEC_N_VARIABLES], time, start;
    const unsigned char* model_part;
    size_t model_size;
    char* reason = NULL;
    char* texts[SPEC_N_VARIABLES];
    Model* model;
    ENTER(SPEC_CALL_SET_FMUSTATE);
    if (bytes != NULL && memcmp(bytes, SPEC_STATE_MAGIC, 8) == 0) {
        memcpy(&total, bytes + AT_SIZE, 8);
    }
    if (state_problem(bytes, (size_t)total, why, sizeof why) == 0) {
        return refuse(inst, "fmi2SetFMUstate", why);
    }
    memcpy(&phase, bytes + 12, 4);
    memcpy(&time, bytes + AT_TIME, 8);
    memcpy(&start, bytes + AT_TIME + 8, 8);
    memcpy(&stale, bytes + AT_TIME + 16, 4);
    memcpy(&reason_size, bytes + AT_TIME + 20, 4);
    memcpy(&texts_size, bytes + AT_TIME + 24, 4);
    memcpy(values, bytes + SPEC_STATE_HEAD, STATE_VALUES);
    model_part = bytes + SPEC_STATE_HEAD + STATE_VALUES + 8;
    model_size = (size_t)total - STATE_FIXED - reason_size - texts_size;
    state_texts(model_part + model_size, texts);
    model = inst->model;
    if (model_size > 0 && (!model_built_for(inst->model, values) ||
                           !same_strings(texts, inst->built_strings))) {
        /* a state of other parameters, or set into a fresh instance: build its model (its
         * messages unlogged, its problems the reason of the refusal) */
        ModelHost host = host_of(inst);
        double scratch[SPEC_N_VARIABLES];
        int built;
        model = model_create(&host);
        memcpy(scratch, values, sizeof scratch);
        start_collecting(inst, 1);
        inst->string_view = texts;  /* the model is built with the state's String values */
        built = model != NULL && model_initialise(model, values, start, scratch) == MODEL_OK;
        inst->string_view = NULL;
        if (!built) {
            char* text = new_text(inst, SPEC_MSG_STATE_PARAMETERS,
                                  inst->problems ? inst->problems : SPEC_MSG_OUT_OF_MEMORY);
            stop_collecting(inst);
            model_destroy(model);
            refuse(inst, "fmi2SetFMUstate", text ? text : SPEC_MSG_OUT_OF_MEMORY);
            if (text) inst->mem.release(text);
            return fmi2Error;
        }
        stop_collecting(inst);
    }
    if (model_size > 0 &&
        model_state_check(model, model_part, model_size, values, time, start, why,
                          sizeof why) != MODEL_OK) {
        if (model != inst->model) model_destroy(model);
        return refuse(inst, "fmi2SetFMUstate", why);
    }
    if (reason_size > 0) {
        reason = (char*)inst->mem.allocate((size_t)reason_size + 1, 1);
        if (reason == NULL) {
            if (model != inst->model) model_destroy(model);
            return refuse(inst, "fmi2SetFMUstate", SPEC_MSG_OUT_OF_MEMORY);
        }
        memcpy(reason, model_part + model_size + texts_size, reason_size);
    }
    if (take_strings(inst, inst->strings, texts) != 0 ||
        (model_size > 0 && take_strings(inst, inst->built_strings, texts) != 0)) {
        if (model != inst->model) model_destroy(model);
        if (reason != NULL) inst->mem.release(reason);
        return refuse(inst, "fmi2SetFMUstate", SPEC_MSG_OUT_OF_MEMORY);
    }
    if (model != inst->model) {
        model_destroy(inst->model);
        inst->model = model;
    }
    if (model_size > 0) model_state_apply(inst->model, model_part);
    memcpy(inst->values, values, sizeof values);
    inst->phase = (int)phase;
    inst->time = time;
    inst->start_time = start;
    inst->stale = (int)stale;
    set_reason(inst, reason);
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* FMUstate)
{
    ENTER(SPEC_CALL_FREE_FMUSTATE);
    if (FMUstate != NULL && *FMUstate != NULL) {
        inst->mem.release(*FMUstate);
        *FMUstate = NULL;
    }
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t* size)
{
    uint64_t total;
    ENTER(SPEC_CALL_SERIALIZED_FMUSTATE_SIZE);
    if (FMUstate == NULL || size == NULL ||
        memcmp(FMUstate, SPEC_STATE_MAGIC, 8) != 0) {
        log_message(inst, fmi2Error, "fmi2SerializedFMUstateSize refused: not a state of this "
                    "FMU");
        return fmi2Error;
    }
    memcpy(&total, (const unsigned char*)FMUstate + AT_SIZE, 8);
    *size = (size_t)total;
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[],
                                 size_t size)
{
    uint64_t total;
    ENTER(SPEC_CALL_SERIALIZE_FMUSTATE);
    if (FMUstate == NULL || serializedState == NULL ||
        memcmp(FMUstate, SPEC_STATE_MAGIC, 8) != 0) {
        log_message(inst, fmi2Error, "fmi2SerializeFMUstate refused: not a state of this FMU");
        return fmi2Error;
    }
    memcpy(&total, (const unsigned char*)FMUstate + AT_SIZE, 8);
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
    char why[MESSAGE_SIZE];
    unsigned char* copy;
    ENTER(SPEC_CALL_DE_SERIALIZE_FMUSTATE);
    if (FMUstate == NULL) {
        return refuse(inst, "fmi2DeSerializeFMUstate", "no place for the state");
    }
    if (state_problem((const unsigned char*)serializedState, size, why, sizeof why) == 0) {
        return refuse(inst, "fmi2DeSerializeFMUstate", why);
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
