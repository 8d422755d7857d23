/* pythonfmu_guard.c: the binary of a pythonfmu FMU on Linux, in front of pythonfmu's wrapper.
 *
 * pythonfmu 0.7 ships one generic C++ wrapper (libpythonfmu-export.so) that every FMU it
 * builds uses as its binary. The build (tire_fmu/fmu/builder.py) puts that wrapper into the
 * FMU as binaries/linux64/pythonfmu-export.so and this file, compiled, as the FMU's binary.
 * Every fmi2 function is forwarded to the wrapper; this layer changes only what the wrapper
 * gets wrong (read from pythonfmu 0.7.0's src/pythonfmu/{fmi2.cpp,PySlaveInstance.cpp,
 * PyState.hpp}):
 *
 * - Statuses. The wrapper returns fmi2Error only for its own C++ failures and turns a slave's
 *   refused step into fmi2Discard with "terminated" set, so a host such as fmpy silently stops
 *   with a truncated result. Here a call returns the most severe status of the messages the
 *   slave logged during it when that is fmi2Error or worse; warnings are logged and do not
 *   change the status. A refused step without an error message stays fmi2Discard (and then
 *   asks the host to terminate, as pythonfmu does). fmi2LastSuccessfulTime is the end of the
 *   last step that returned fmi2OK (the start time before the first), not the refused time.
 * - Messages. The wrapper hands its messages to the host as printf formats: the slave escapes
 *   its own, and the wrapper's own texts (category NULL) are escaped here. The wrapper is
 *   always instantiated with logging on, so the statuses above can be seen; this layer then
 *   applies the host's loggingOn and categories: warnings and worse always reach the host,
 *   other messages only with logging on.
 * - The resource location. The wrapper decodes only "%20" in the URI, so a folder whose path
 *   holds any other escaped character ('%' itself, non-ASCII) is not found, and the wrapper
 *   then calls a NULL Python class (SIGSEGV in fmi2Instantiate). Here the URI is decoded in
 *   full and checked, and a location the wrapper would misread is refused with a message.
 * - Process exit. The wrapper keeps its interpreter guard in a static std::shared_ptr and
 *   releases it again from an ELF destructor. Its <regex> code has STB_GNU_UNIQUE symbols, so
 *   glibc never unloads it: at exit the static destructor frees the guard first, then the ELF
 *   destructor writes to the freed block (valgrind: "invalid read" in
 *   finalizePythonInterpreter under _dl_fini), which corrupts the heap and sometimes aborts
 *   ("corrupted double-linked list"). Here the guard is released once at exit, before the
 *   wrapper's static destructors run, so both later calls find it empty.
 * - Arguments. NULL pointers, a component after a fatal error (the wrapper has then released
 *   its Python objects and would crash on the next call), FMU states this FMU did not make,
 *   and a serialization buffer of the wrong size are refused with fmi2Error and a message
 *   instead of being passed on.
 * - A process without Python. The wrapper needs the Python C API from the process; without
 *   it fmi2Instantiate is refused with a message and NULL. Some hosts drop both: ecos's
 *   proxyfmu runs each FMU in a process of its own with a no-op logger, ignores the NULL and
 *   every later fmi2Error, and showed all outputs as 0.0. So this refusal is also written
 *   once to stderr, and fmi2GetReal on a NULL component fills its values with NaN (still
 *   returning fmi2Error), so that a host that reads them anyway gets no plausible zeros.
 */

#define _GNU_SOURCE
#include <dlfcn.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "fmi2Functions.h"

#define WRAPPER_FILE "pythonfmu-export.so"
#define PATH_SIZE 4096
#define MESSAGE_SIZE (2 * PATH_SIZE + 1024)

/* -- the wrapper ------------------------------------------------------------------------- */

static struct {
    void *handle;
    fmi2InstantiateTYPE *Instantiate;
    fmi2FreeInstanceTYPE *FreeInstance;
    fmi2SetupExperimentTYPE *SetupExperiment;
    fmi2EnterInitializationModeTYPE *EnterInitializationMode;
    fmi2ExitInitializationModeTYPE *ExitInitializationMode;
    fmi2TerminateTYPE *Terminate;
    fmi2ResetTYPE *Reset;
    fmi2GetRealTYPE *GetReal;
    fmi2GetIntegerTYPE *GetInteger;
    fmi2GetBooleanTYPE *GetBoolean;
    fmi2GetStringTYPE *GetString;
    fmi2SetRealTYPE *SetReal;
    fmi2SetIntegerTYPE *SetInteger;
    fmi2SetBooleanTYPE *SetBoolean;
    fmi2SetStringTYPE *SetString;
    fmi2GetFMUstateTYPE *GetFMUstate;
    fmi2SetFMUstateTYPE *SetFMUstate;
    fmi2FreeFMUstateTYPE *FreeFMUstate;
    fmi2SerializedFMUstateSizeTYPE *SerializedFMUstateSize;
    fmi2SerializeFMUstateTYPE *SerializeFMUstate;
    fmi2DeSerializeFMUstateTYPE *DeSerializeFMUstate;
    fmi2GetDirectionalDerivativeTYPE *GetDirectionalDerivative;
    fmi2SetRealInputDerivativesTYPE *SetRealInputDerivatives;
    fmi2GetRealOutputDerivativesTYPE *GetRealOutputDerivatives;
    fmi2DoStepTYPE *DoStep;
    fmi2CancelStepTYPE *CancelStep;
    fmi2GetStatusTYPE *GetStatus;
    fmi2GetRealStatusTYPE *GetRealStatus;
    fmi2GetIntegerStatusTYPE *GetIntegerStatus;
    fmi2GetBooleanStatusTYPE *GetBooleanStatus;
    fmi2GetStringStatusTYPE *GetStringStatus;
    void (*finalizePythonInterpreter)(void);
} wrapper;

static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
static char load_error[MESSAGE_SIZE];
static int exit_release_registered;
static int python_refusal_printed;

/* FMU states handed out (by fmi2GetFMUstate and fmi2DeSerializeFMUstate) and not yet freed:
 * any instance of this FMU may set them, nothing else is passed to the wrapper. */
static fmi2FMUstate *states;
static size_t n_states, states_capacity;

typedef struct {
    fmi2Component inner;             /* the wrapper's component */
    fmi2CallbackFunctions host;      /* the host's callbacks */
    fmi2CallbackFunctions callbacks; /* the wrapper's: our logger, this instance as environment */
    char name[256];
    int logging_on;
    char **categories; /* NULL: every category */
    size_t n_categories;
    fmi2Status worst; /* the most severe status logged during the current call */
    int dead;         /* the wrapper returned fmi2Fatal: only fmi2FreeInstance is safe */
    double last_successful_time;
    int wants_to_terminate;
} Instance;

/* -- messages ---------------------------------------------------------------------------- */

static const char *status_category(fmi2Status status)
{
    switch (status) {
        case fmi2Warning: return "logStatusWarning";
        case fmi2Discard: return "logStatusDiscard";
        case fmi2Error: return "logStatusError";
        case fmi2Fatal: return "logStatusFatal";
        default: return "logAll";
    }
}

/* text as an FMI message: printf's '%' and the variable-reference escape '#' doubled */
static char *as_format(const char *text)
{
    size_t n = 0;
    for (const char *p = text; *p; p++) n += (*p == '%' || *p == '#') ? 2 : 1;
    char *out = malloc(n + 1);
    if (out == NULL) return NULL;
    char *q = out;
    for (const char *p = text; *p; p++) {
        *q++ = *p;
        if (*p == '%' || *p == '#') *q++ = *p;
    }
    *q = '\0';
    return out;
}

static int wanted(const Instance *g, fmi2Status status, const char *category)
{
    if (status >= fmi2Warning && status <= fmi2Fatal) return 1;
    if (!g->logging_on) return 0;
    if (g->categories == NULL) return 1;
    for (size_t i = 0; i < g->n_categories; i++) {
        if (strcmp(g->categories[i], "logAll") == 0 || strcmp(g->categories[i], category) == 0)
            return 1;
    }
    return 0;
}

/* what the wrapper gets as its logger: note the status, forward what the host wants */
static void guard_logger(fmi2ComponentEnvironment environment, fmi2String instance,
                         fmi2Status status, fmi2String category, fmi2String message, ...)
{
    Instance *g = (Instance *)environment;
    if (g == NULL) return;
    if (status > g->worst && status <= fmi2Fatal) g->worst = status;
    const char *name = category != NULL ? category : status_category(status);
    if (g->host.logger == NULL || !wanted(g, status, name)) return;
    if (message == NULL) message = "";
    if (category != NULL) { /* the slave's message, already a format (see slave.py) */
        g->host.logger(g->host.componentEnvironment, instance, status, name, message);
        return;
    }
    char *format = as_format(message); /* the wrapper's own text */
    g->host.logger(g->host.componentEnvironment, instance, status, name,
                   format != NULL ? format : "(a message was lost: out of memory)");
    free(format);
}

/* a message of this layer, counted like the slave's */
static void say(Instance *g, fmi2Status status, const char *format, ...)
{
    char text[MESSAGE_SIZE];
    va_list args;
    va_start(args, format);
    vsnprintf(text, sizeof text, format, args);
    va_end(args);
    guard_logger(g, g->name, status, NULL, text);
}

/* -- loading the wrapper ----------------------------------------------------------------- */

static void release_python_state(void)
{
    /* see the file comment: empties the wrapper's static guard before its destructors run */
    if (wrapper.finalizePythonInterpreter != NULL) wrapper.finalizePythonInterpreter();
}

#define RESOLVE(symbol)                                                                       \
    if ((*(void **)&wrapper.symbol = dlsym(handle, "fmi2" #symbol)) == NULL) missing = "fmi2" #symbol;

static int load_wrapper(void)
{
    pthread_mutex_lock(&lock);
    if (wrapper.handle == NULL && load_error[0] == '\0') {
        Dl_info self;
        char path[PATH_SIZE];
        /* our own file (a static function's address: exported names may be interposed) */
        if (dladdr((void *)&load_wrapper, &self) == 0 || self.dli_fname == NULL) {
            snprintf(load_error, sizeof load_error, "cannot find the FMU's own binary");
        } else {
            const char *slash = strrchr(self.dli_fname, '/');
            int folder = slash != NULL ? (int)(slash - self.dli_fname + 1) : 0;
            snprintf(path, sizeof path, "%.*s%s", folder, self.dli_fname, WRAPPER_FILE);
            void *handle = dlopen(path, RTLD_NOW | RTLD_LOCAL);
            if (handle == NULL) {
                snprintf(load_error, sizeof load_error, "cannot load pythonfmu's wrapper %s (%s)",
                         path, dlerror());
            } else {
                const char *missing = NULL;
                RESOLVE(Instantiate) RESOLVE(FreeInstance) RESOLVE(SetupExperiment)
                RESOLVE(EnterInitializationMode) RESOLVE(ExitInitializationMode)
                RESOLVE(Terminate) RESOLVE(Reset) RESOLVE(GetReal) RESOLVE(GetInteger)
                RESOLVE(GetBoolean) RESOLVE(GetString) RESOLVE(SetReal) RESOLVE(SetInteger)
                RESOLVE(SetBoolean) RESOLVE(SetString) RESOLVE(GetFMUstate) RESOLVE(SetFMUstate)
                RESOLVE(FreeFMUstate) RESOLVE(SerializedFMUstateSize) RESOLVE(SerializeFMUstate)
                RESOLVE(DeSerializeFMUstate) RESOLVE(GetDirectionalDerivative)
                RESOLVE(SetRealInputDerivatives) RESOLVE(GetRealOutputDerivatives)
                RESOLVE(DoStep) RESOLVE(CancelStep) RESOLVE(GetStatus) RESOLVE(GetRealStatus)
                RESOLVE(GetIntegerStatus) RESOLVE(GetBooleanStatus) RESOLVE(GetStringStatus)
                *(void **)&wrapper.finalizePythonInterpreter =
                    dlsym(handle, "finalizePythonInterpreter");
                if (missing != NULL) {
                    snprintf(load_error, sizeof load_error, "pythonfmu's wrapper %s lacks %s",
                             path, missing);
                } else {
                    wrapper.handle = handle;
                }
            }
        }
    }
    int loaded = wrapper.handle != NULL;
    pthread_mutex_unlock(&lock);
    return loaded;
}

static void register_exit_release(void)
{
    /* After the first instance exists, so that it runs before the static destructors of the
     * wrapper and of the libraries the slave imported (atexit handlers run last-in first-out);
     * the binary is linked -z nodelete, so the handler stays mapped until then. */
    pthread_mutex_lock(&lock);
    if (!exit_release_registered && wrapper.finalizePythonInterpreter != NULL) {
        exit_release_registered = atexit(release_python_state) == 0;
    }
    pthread_mutex_unlock(&lock);
}

/* -- the resource location --------------------------------------------------------------- */

static int hex_digit(char c)
{
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

/* The folder a file URI (or a plain absolute path) names, decoded, or NULL with a message. */
static char *resource_folder(Instance *g, const char *location)
{
    const char *path = location;
    int encoded = 1;
    if (strncmp(location, "file://", 7) == 0) {
        path = location + 7;
        if (strncmp(path, "localhost/", 10) == 0) path += 9;
        if (path[0] != '/') {
            say(g, fmi2Error, "fmi2Instantiate: resource location '%s' is not a local folder "
                "(file:///path expected)", location);
            return NULL;
        }
    } else if (strncmp(location, "file:/", 6) == 0) {
        path = location + 5;
    } else if (location[0] == '/') {
        encoded = 0; /* a plain path, taken as it is */
    } else {
        say(g, fmi2Error, "fmi2Instantiate: resource location '%s' is not a file URI "
            "(file:///path expected)", location);
        return NULL;
    }
    char *folder = malloc(strlen(path) + 1);
    if (folder == NULL) return NULL;
    char *q = folder;
    for (const char *p = path; *p; p++) {
        if (encoded && *p == '%') {
            int high = hex_digit(p[1]), low = high < 0 ? -1 : hex_digit(p[2]);
            if (low < 0 || (high == 0 && low == 0)) {
                say(g, fmi2Error, "fmi2Instantiate: resource location '%s' has a bad escape "
                    "at '%.3s'", location, p);
                free(folder);
                return NULL;
            }
            *q++ = (char)(high * 16 + low);
            p += 2;
        } else {
            *q++ = *p;
        }
    }
    *q = '\0';
    /* the wrapper replaces every "%20" by a space and drops the first "file://" */
    if (strstr(folder, "%20") != NULL || strstr(folder, "file://") != NULL) {
        say(g, fmi2Error, "fmi2Instantiate: the FMU's folder '%s' contains '%s', which "
            "pythonfmu's wrapper would misread; extract the FMU into another folder", folder,
            strstr(folder, "%20") != NULL ? "%20" : "file://");
        free(folder);
        return NULL;
    }
    char module_list[PATH_SIZE];
    struct stat info;
    snprintf(module_list, sizeof module_list, "%s/slavemodule.txt", folder);
    if (stat(module_list, &info) != 0 || !S_ISREG(info.st_mode)) {
        say(g, fmi2Error, "fmi2Instantiate: resource location '%s' is not this FMU's resources "
            "folder (it has no slavemodule.txt)", location);
        free(folder);
        return NULL;
    }
    return folder;
}

/* -- FMU states -------------------------------------------------------------------------- */

static int state_known(fmi2FMUstate state)
{
    int known = 0;
    pthread_mutex_lock(&lock);
    for (size_t i = 0; i < n_states && !known; i++) known = states[i] == state;
    pthread_mutex_unlock(&lock);
    return known;
}

static int remember_state(fmi2FMUstate state)
{
    int ok = 1;
    pthread_mutex_lock(&lock);
    if (n_states == states_capacity) {
        size_t capacity = states_capacity ? 2 * states_capacity : 16;
        fmi2FMUstate *grown = realloc(states, capacity * sizeof *grown);
        if (grown == NULL) {
            ok = 0;
        } else {
            states = grown;
            states_capacity = capacity;
        }
    }
    if (ok) states[n_states++] = state;
    pthread_mutex_unlock(&lock);
    return ok;
}

static void forget_state(fmi2FMUstate state)
{
    pthread_mutex_lock(&lock);
    for (size_t i = 0; i < n_states; i++) {
        if (states[i] == state) {
            states[i] = states[--n_states];
            break;
        }
    }
    pthread_mutex_unlock(&lock);
}

/* -- calls ------------------------------------------------------------------------------- */

/* The status a call returns: the wrapper's, made an error when the slave logged one. */
static fmi2Status finish(Instance *g, fmi2Status status)
{
    if (status == fmi2Fatal) {
        g->dead = 1;
        return fmi2Fatal;
    }
    if (g->worst >= fmi2Error && status < g->worst) return g->worst;
    return status;
}

#define BEGIN(c, function)                                                                     \
    Instance *g = (Instance *)(c);                                                            \
    if (g == NULL) return fmi2Error;                                                          \
    g->worst = fmi2OK;                                                                        \
    if (g->dead) {                                                                            \
        say(g, fmi2Fatal, "%s refused: an earlier call failed fatally, so this instance can "  \
            "only be freed", function);                                                       \
        return fmi2Fatal;                                                                     \
    }

#define NEED(condition, function, what)                                                        \
    if (!(condition)) {                                                                       \
        say(g, fmi2Error, "%s refused: %s", function, what);                                  \
        return fmi2Error;                                                                     \
    }

#define ARRAYS(function, n, vr, value)                                                         \
    NEED((n) == 0 || ((vr) != NULL && (value) != NULL), function,                              \
         "a value-reference or value array is NULL")

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }

const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn)
{
    Instance *g = calloc(1, sizeof *g);
    if (g == NULL) return NULL;
    if (functions != NULL) g->host = *functions;
    g->logging_on = loggingOn;
    snprintf(g->name, sizeof g->name, "%s", instanceName != NULL ? instanceName : "");
    char *folder = NULL;
    if (instanceName == NULL || fmuGUID == NULL || fmuResourceLocation == NULL) {
        say(g, fmi2Error, "fmi2Instantiate refused: the %s is NULL", instanceName == NULL
            ? "instance name" : fmuGUID == NULL ? "GUID" : "resource location");
    } else if (fmuType != fmi2CoSimulation) {
        say(g, fmi2Error, "fmi2Instantiate refused: this FMU supports co-simulation only");
    } else if ((folder = resource_folder(g, fmuResourceLocation)) != NULL) {
        if (!load_wrapper()) {
            static const char *why = "fmi2Instantiate refused: %s. A pythonfmu FMU runs the "
                "host's own Python: the host must be a Python process (or have loaded "
                "libpython3 globally) with the packages in resources/requirements.txt";
            say(g, fmi2Error, why, load_error);
            pthread_mutex_lock(&lock);
            int first = !python_refusal_printed;
            python_refusal_printed = 1;
            pthread_mutex_unlock(&lock);
            if (first) { /* for hosts that drop the FMU's log (see the file comment) */
                fprintf(stderr, "%s: ", instanceName);
                fprintf(stderr, why, load_error);
                fputc('\n', stderr);
                fflush(stderr);
            }
        } else {
            g->callbacks = g->host;
            g->callbacks.logger = guard_logger;
            g->callbacks.componentEnvironment = g;
            g->inner = wrapper.Instantiate(instanceName, fmuType, fmuGUID, folder,
                                           &g->callbacks, visible, fmi2True);
        }
    }
    free(folder);
    if (g->inner == NULL) {
        free(g);
        return NULL;
    }
    register_exit_release();
    return g;
}

void fmi2FreeInstance(fmi2Component c)
{
    Instance *g = (Instance *)c;
    if (g == NULL) return;
    g->worst = fmi2OK;
    if (!g->dead) wrapper.FreeInstance(g->inner); /* after a fatal error: leak, not crash */
    for (size_t i = 0; i < g->n_categories; i++) free(g->categories[i]);
    free(g->categories);
    free(g);
}

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[])
{
    BEGIN(c, "fmi2SetDebugLogging")
    NEED(nCategories == 0 || categories != NULL, "fmi2SetDebugLogging",
         "the category array is NULL")
    for (size_t i = 0; i < nCategories; i++) {
        NEED(categories[i] != NULL, "fmi2SetDebugLogging", "a category is NULL")
    }
    char **copied = NULL;
    if (nCategories > 0) {
        copied = calloc(nCategories, sizeof *copied);
        NEED(copied != NULL, "fmi2SetDebugLogging", "out of memory")
        for (size_t i = 0; i < nCategories; i++) copied[i] = strdup(categories[i]);
    }
    for (size_t i = 0; i < g->n_categories; i++) free(g->categories[i]);
    free(g->categories);
    g->categories = copied;
    g->n_categories = nCategories;
    g->logging_on = loggingOn;
    return fmi2OK;
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined,
                               fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    BEGIN(c, "fmi2SetupExperiment")
    fmi2Status status = finish(g, wrapper.SetupExperiment(g->inner, toleranceDefined, tolerance,
                                                          startTime, stopTimeDefined, stopTime));
    if (status == fmi2OK) g->last_successful_time = startTime;
    return status;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    BEGIN(c, "fmi2EnterInitializationMode")
    return finish(g, wrapper.EnterInitializationMode(g->inner));
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    BEGIN(c, "fmi2ExitInitializationMode")
    return finish(g, wrapper.ExitInitializationMode(g->inner));
}

fmi2Status fmi2Terminate(fmi2Component c)
{
    BEGIN(c, "fmi2Terminate")
    return finish(g, wrapper.Terminate(g->inner));
}

fmi2Status fmi2Reset(fmi2Component c)
{
    BEGIN(c, "fmi2Reset")
    fmi2Status status = finish(g, wrapper.Reset(g->inner));
    if (status == fmi2OK) {
        g->last_successful_time = 0.0;
        g->wants_to_terminate = 0;
    }
    return status;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[])
{
    if (c == NULL && value != NULL) { /* no instance (fmi2Instantiate refused): no values */
        for (size_t i = 0; i < nvr; i++) value[i] = NAN;
    }
    BEGIN(c, "fmi2GetReal")
    ARRAYS("fmi2GetReal", nvr, vr, value)
    return finish(g, wrapper.GetReal(g->inner, vr, nvr, value));
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[])
{
    BEGIN(c, "fmi2GetInteger")
    ARRAYS("fmi2GetInteger", nvr, vr, value)
    return finish(g, wrapper.GetInteger(g->inner, vr, nvr, value));
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[])
{
    BEGIN(c, "fmi2GetBoolean")
    ARRAYS("fmi2GetBoolean", nvr, vr, value)
    return finish(g, wrapper.GetBoolean(g->inner, vr, nvr, value));
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[])
{
    BEGIN(c, "fmi2GetString")
    ARRAYS("fmi2GetString", nvr, vr, value)
    return finish(g, wrapper.GetString(g->inner, vr, nvr, value));
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[])
{
    BEGIN(c, "fmi2SetReal")
    ARRAYS("fmi2SetReal", nvr, vr, value)
    return finish(g, wrapper.SetReal(g->inner, vr, nvr, value));
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[])
{
    BEGIN(c, "fmi2SetInteger")
    ARRAYS("fmi2SetInteger", nvr, vr, value)
    return finish(g, wrapper.SetInteger(g->inner, vr, nvr, value));
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[])
{
    BEGIN(c, "fmi2SetBoolean")
    ARRAYS("fmi2SetBoolean", nvr, vr, value)
    return finish(g, wrapper.SetBoolean(g->inner, vr, nvr, value));
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[])
{
    BEGIN(c, "fmi2SetString")
    ARRAYS("fmi2SetString", nvr, vr, value)
    for (size_t i = 0; i < nvr; i++) {
        NEED(value[i] != NULL, "fmi2SetString", "a string is NULL")
    }
    return finish(g, wrapper.SetString(g->inner, vr, nvr, value));
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    BEGIN(c, "fmi2GetFMUstate")
    NEED(FMUstate != NULL, "fmi2GetFMUstate", "the state pointer is NULL")
    if (*FMUstate != NULL && state_known(*FMUstate)) { /* an update: the old one goes */
        forget_state(*FMUstate);
        wrapper.FreeFMUstate(g->inner, FMUstate);
    }
    fmi2FMUstate state = NULL;
    fmi2Status status = finish(g, wrapper.GetFMUstate(g->inner, &state));
    if (status <= fmi2Warning && state != NULL && !remember_state(state)) {
        wrapper.FreeFMUstate(g->inner, &state);
        say(g, fmi2Error, "fmi2GetFMUstate refused: out of memory");
        state = NULL;
        status = fmi2Error;
    }
    *FMUstate = state;
    return status;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
    BEGIN(c, "fmi2SetFMUstate")
    NEED(state_known(FMUstate), "fmi2SetFMUstate",
         "the state was not made by this FMU, or it was freed")
    return finish(g, wrapper.SetFMUstate(g->inner, FMUstate));
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    BEGIN(c, "fmi2FreeFMUstate")
    if (FMUstate == NULL || *FMUstate == NULL) return fmi2OK;
    NEED(state_known(*FMUstate), "fmi2FreeFMUstate",
         "the state was not made by this FMU, or it was freed already")
    forget_state(*FMUstate);
    fmi2Status status = finish(g, wrapper.FreeFMUstate(g->inner, FMUstate));
    *FMUstate = NULL;
    return status;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size)
{
    BEGIN(c, "fmi2SerializedFMUstateSize")
    NEED(size != NULL, "fmi2SerializedFMUstateSize", "the size pointer is NULL")
    NEED(state_known(FMUstate), "fmi2SerializedFMUstateSize",
         "the state was not made by this FMU, or it was freed")
    return finish(g, wrapper.SerializedFMUstateSize(g->inner, FMUstate, size));
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serialized[],
                                 size_t size)
{
    BEGIN(c, "fmi2SerializeFMUstate")
    NEED(state_known(FMUstate), "fmi2SerializeFMUstate",
         "the state was not made by this FMU, or it was freed")
    size_t needed = 0;
    fmi2Status status = finish(g, wrapper.SerializedFMUstateSize(g->inner, FMUstate, &needed));
    if (status > fmi2Warning) return status;
    /* the wrapper copies `size` bytes out of a buffer of `needed` */
    if (size < needed || (needed > 0 && serialized == NULL)) {
        say(g, fmi2Error, "fmi2SerializeFMUstate refused: the buffer holds %zu bytes and the "
            "state needs %zu (ask fmi2SerializedFMUstateSize)", serialized == NULL ? 0 : size,
            needed);
        return fmi2Error;
    }
    return finish(g, wrapper.SerializeFMUstate(g->inner, FMUstate, serialized, needed));
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serialized[], size_t size,
                                   fmi2FMUstate *FMUstate)
{
    BEGIN(c, "fmi2DeSerializeFMUstate")
    NEED(FMUstate != NULL, "fmi2DeSerializeFMUstate", "the state pointer is NULL")
    NEED(size == 0 || serialized != NULL, "fmi2DeSerializeFMUstate", "the byte array is NULL")
    fmi2FMUstate state = NULL;
    fmi2Status status = finish(g, wrapper.DeSerializeFMUstate(g->inner,
                                                              size ? serialized : "", size,
                                                              &state));
    if (status <= fmi2Warning && state != NULL && !remember_state(state)) {
        wrapper.FreeFMUstate(g->inner, &state);
        say(g, fmi2Error, "fmi2DeSerializeFMUstate refused: out of memory");
        state = NULL;
        status = fmi2Error;
    }
    *FMUstate = state;
    return status;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[])
{
    BEGIN(c, "fmi2GetDirectionalDerivative")
    return finish(g, wrapper.GetDirectionalDerivative(g->inner, vUnknown_ref, nUnknown,
                                                      vKnown_ref, nKnown, dvKnown, dvUnknown));
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                       size_t nvr, const fmi2Integer order[],
                                       const fmi2Real value[])
{
    BEGIN(c, "fmi2SetRealInputDerivatives")
    return finish(g, wrapper.SetRealInputDerivatives(g->inner, vr, nvr, order, value));
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t nvr, const fmi2Integer order[], fmi2Real value[])
{
    BEGIN(c, "fmi2GetRealOutputDerivatives")
    return finish(g, wrapper.GetRealOutputDerivatives(g->inner, vr, nvr, order, value));
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    BEGIN(c, "fmi2DoStep")
    fmi2Status status = finish(g, wrapper.DoStep(g->inner, currentCommunicationPoint,
                                                 communicationStepSize,
                                                 noSetFMUStatePriorToCurrentPoint));
    if (status == fmi2OK) {
        g->last_successful_time = currentCommunicationPoint + communicationStepSize;
    } else if (status == fmi2Discard) {
        g->wants_to_terminate = 1;
    }
    return status;
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    BEGIN(c, "fmi2CancelStep")
    return finish(g, wrapper.CancelStep(g->inner));
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{
    BEGIN(c, "fmi2GetStatus")
    NEED(value != NULL, "fmi2GetStatus", "the value pointer is NULL")
    return finish(g, wrapper.GetStatus(g->inner, s, value));
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    BEGIN(c, "fmi2GetRealStatus")
    NEED(value != NULL, "fmi2GetRealStatus", "the value pointer is NULL")
    if (s == fmi2LastSuccessfulTime) {
        *value = g->last_successful_time;
        return fmi2OK;
    }
    return finish(g, wrapper.GetRealStatus(g->inner, s, value));
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value)
{
    BEGIN(c, "fmi2GetIntegerStatus")
    NEED(value != NULL, "fmi2GetIntegerStatus", "the value pointer is NULL")
    return finish(g, wrapper.GetIntegerStatus(g->inner, s, value));
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value)
{
    BEGIN(c, "fmi2GetBooleanStatus")
    NEED(value != NULL, "fmi2GetBooleanStatus", "the value pointer is NULL")
    if (s == fmi2Terminated) {
        *value = g->wants_to_terminate ? fmi2True : fmi2False;
        return fmi2OK;
    }
    return finish(g, wrapper.GetBooleanStatus(g->inner, s, value));
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
{
    BEGIN(c, "fmi2GetStringStatus")
    NEED(value != NULL, "fmi2GetStringStatus", "the value pointer is NULL")
    return finish(g, wrapper.GetStringStatus(g->inner, s, value));
}
