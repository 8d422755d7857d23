/* The cheapest co-simulation FMU with the native tire FMU's interface (4 Real inputs, 5 Real
 * outputs, value references 0-8): doStep copies, so a host loop through it measures the
 * host's own call cost. benchmarks/bench_native.py builds it. */
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

typedef struct {
    double values[10];
    double time;
} Trivial;

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid,
                              fmi2String location, const fmi2CallbackFunctions* functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn)
{
    (void)name; (void)type; (void)guid; (void)location; (void)functions; (void)visible;
    (void)loggingOn;
    return calloc(1, sizeof(Trivial));
}
void fmi2FreeInstance(fmi2Component c) { free(c); }
const char* fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char* fmi2GetVersion(void) { return fmi2Version; }
fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String k[])
{ (void)c; (void)on; (void)n; (void)k; return fmi2OK; }
fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean a, fmi2Real b, fmi2Real start,
                               fmi2Boolean d, fmi2Real e)
{ (void)a; (void)b; (void)d; (void)e; ((Trivial*)c)->time = start; return fmi2OK; }
fmi2Status fmi2EnterInitializationMode(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2ExitInitializationMode(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2Terminate(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2Reset(fmi2Component c) { memset(c, 0, sizeof(Trivial)); return fmi2OK; }
fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real v[])
{
    size_t i;
    for (i = 0; i < n; i++) {
        if (vr[i] >= 10) return fmi2Error;
        v[i] = ((Trivial*)c)->values[vr[i]];
    }
    return fmi2OK;
}
fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                       const fmi2Real v[])
{
    size_t i;
    for (i = 0; i < n; i++) {
        if (vr[i] >= 10) return fmi2Error;
        ((Trivial*)c)->values[vr[i]] = v[i];
    }
    return fmi2OK;
}
fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean prior)
{
    Trivial* s = (Trivial*)c;
    int i;
    (void)prior;
    if (t != t || !(h > 0)) return fmi2Error;
    for (i = 0; i < 4; i++) s->values[4 + i] = s->values[i];
    s->values[8] = s->values[0] + s->values[2];
    s->time = t + h;
    return fmi2OK;
}
#define NOT_HERE(...) { (void)c; return fmi2Error; }
fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          fmi2Integer v[]) { (void)vr; (void)n; (void)v; NOT_HERE() }
fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          fmi2Boolean v[]) { (void)vr; (void)n; (void)v; NOT_HERE() }
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                         fmi2String v[]) { (void)vr; (void)n; (void)v; NOT_HERE() }
fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          const fmi2Integer v[]) { (void)vr; (void)n; (void)v; NOT_HERE() }
fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          const fmi2Boolean v[]) { (void)vr; (void)n; (void)v; NOT_HERE() }
fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                         const fmi2String v[]) { (void)vr; (void)n; (void)v; NOT_HERE() }
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* s) { (void)s; NOT_HERE() }
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s) { (void)s; NOT_HERE() }
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* s) { (void)s; NOT_HERE() }
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t* n)
{ (void)s; (void)n; NOT_HERE() }
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t n)
{ (void)s; (void)b; (void)n; NOT_HERE() }
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte b[], size_t n,
                                   fmi2FMUstate* s) { (void)s; (void)b; (void)n; NOT_HERE() }
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference a[], size_t b,
                                        const fmi2ValueReference d[], size_t e,
                                        const fmi2Real f[], fmi2Real g[])
{ (void)a; (void)b; (void)d; (void)e; (void)f; (void)g; NOT_HERE() }
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer o[], const fmi2Real v[])
{ (void)vr; (void)n; (void)o; (void)v; NOT_HERE() }
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t n, const fmi2Integer o[], fmi2Real v[])
{ (void)vr; (void)n; (void)o; (void)v; NOT_HERE() }
fmi2Status fmi2CancelStep(fmi2Component c) { NOT_HERE() }
fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind k, fmi2Status* v)
{ (void)k; (void)v; NOT_HERE() }
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind k, fmi2Real* v)
{ (void)k; *v = ((Trivial*)c)->time; return fmi2OK; }
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind k, fmi2Integer* v)
{ (void)k; (void)v; NOT_HERE() }
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind k, fmi2Boolean* v)
{ (void)k; *v = fmi2False; (void)c; return fmi2OK; }
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind k, fmi2String* v)
{ (void)k; (void)v; NOT_HERE() }
