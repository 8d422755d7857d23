/* A minimal FMI 2.0 co-simulation host for the tests: loads the FMU's binary with
 * LoadLibrary/GetProcAddress (Windows) or dlopen/dlsym, reads commands from a file, prints
 * the outputs after each step with %.17g, and every status and log line.
 *
 *   host BINARY GUID COMMANDS
 *
 * Commands, one per line:
 *   real VR VALUE | integer VR VALUE | boolean VR 0|1   set a variable (any phase)
 *   string VR TEXT                                       set a String (TEXT: the rest of the
 *                                                        line)
 *   getstring VR                                         print fmi2GetString of it
 *   init                                                 setup, enter and exit initialisation
 *   step T H                                             doStep, then print the outputs
 *                                                        (the block spec.h of the FMU's
 *                                                        sources names: radial or in-plane)
 *   save                                                 fmi2GetFMUstate, serialise it, free
 *                                                        it (the bytes kept)
 *   restore                                              deserialise the bytes saved, set
 *                                                        that state and free it
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <stdarg.h>

#ifdef _WIN32
#include <windows.h>
#define LOAD(path) (void*)LoadLibraryA(path)
#define SYMBOL(lib, name) (void*)GetProcAddress((HMODULE)(lib), name)
#else
#include <dlfcn.h>
#define LOAD(path) dlopen(path, RTLD_NOW | RTLD_LOCAL)
#define SYMBOL(lib, name) dlsym(lib, name)
#endif

#include "fmi2Functions.h"
#include "spec.h" /* the FMU's own (sources/ on the include path): its outputs' block */

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    char text[4096];
    va_list args;
    (void)env;
    va_start(args, message);
    vsnprintf(text, sizeof text, message, args);
    va_end(args);
    printf("log %s %d %s %s\n", name, (int)status, category, text);
}

#define GET(type, name) type name = (type)SYMBOL(lib, #name); if (!name) { printf("missing %s\n", #name); return 2; }

int main(int argc, char** argv)
{
    void* lib;
    char line[512];
    FILE* commands;
    fmi2Component c;
    fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    fmi2ValueReference outputs[SPEC_BLOCK_N_OUTPUTS];
    int k;
    for (k = 0; k < SPEC_BLOCK_N_OUTPUTS; k++) outputs[k] = SPEC_BLOCK_OUTPUTS_FIRST + k;
    if (argc != 4) {
        printf("usage: host BINARY GUID COMMANDS\n");
        return 2;
    }
    lib = LOAD(argv[1]);
    if (!lib) {
        printf("cannot load %s\n", argv[1]);
        return 2;
    }
    {
        GET(fmi2InstantiateTYPE*, fmi2Instantiate)
        GET(fmi2SetupExperimentTYPE*, fmi2SetupExperiment)
        GET(fmi2EnterInitializationModeTYPE*, fmi2EnterInitializationMode)
        GET(fmi2ExitInitializationModeTYPE*, fmi2ExitInitializationMode)
        GET(fmi2SetRealTYPE*, fmi2SetReal)
        GET(fmi2SetIntegerTYPE*, fmi2SetInteger)
        GET(fmi2SetBooleanTYPE*, fmi2SetBoolean)
        GET(fmi2GetRealTYPE*, fmi2GetReal)
        GET(fmi2DoStepTYPE*, fmi2DoStep)
        GET(fmi2TerminateTYPE*, fmi2Terminate)
        GET(fmi2FreeInstanceTYPE*, fmi2FreeInstance)
        GET(fmi2SetStringTYPE*, fmi2SetString)
        GET(fmi2GetStringTYPE*, fmi2GetString)
        GET(fmi2GetFMUstateTYPE*, fmi2GetFMUstate)
        GET(fmi2SetFMUstateTYPE*, fmi2SetFMUstate)
        GET(fmi2FreeFMUstateTYPE*, fmi2FreeFMUstate)
        GET(fmi2SerializedFMUstateSizeTYPE*, fmi2SerializedFMUstateSize)
        GET(fmi2SerializeFMUstateTYPE*, fmi2SerializeFMUstate)
        GET(fmi2DeSerializeFMUstateTYPE*, fmi2DeSerializeFMUstate)
        fmi2Byte* saved = NULL;
        size_t saved_size = 0;
        c = fmi2Instantiate("host", fmi2CoSimulation, argv[2], "", &callbacks, fmi2False, fmi2True);
        if (!c) {
            printf("instantiate failed\n");
            return 1;
        }
        commands = fopen(argv[3], "r");
        if (!commands) return 2;
        while (fgets(line, sizeof line, commands)) {
            char word[32];
            unsigned vr;
            double x, y;
            int status = 0, i;
            if (sscanf(line, "%31s", word) != 1) continue;
            if (strcmp(word, "real") == 0 && sscanf(line, "%*s %u %lf", &vr, &x) == 2) {
                fmi2ValueReference r = vr;
                status = fmi2SetReal(c, &r, 1, &x);
            } else if (strcmp(word, "integer") == 0 && sscanf(line, "%*s %u %lf", &vr, &x) == 2) {
                fmi2ValueReference r = vr;
                fmi2Integer v = (fmi2Integer)x;
                status = fmi2SetInteger(c, &r, 1, &v);
            } else if (strcmp(word, "boolean") == 0 && sscanf(line, "%*s %u %lf", &vr, &x) == 2) {
                fmi2ValueReference r = vr;
                fmi2Boolean v = x != 0.0;
                status = fmi2SetBoolean(c, &r, 1, &v);
            } else if (strcmp(word, "string") == 0 && sscanf(line, "%*s %u %n", &vr, &i) == 1) {
                fmi2ValueReference r = vr;
                fmi2String text = line + i;
                line[strcspn(line, "\r\n")] = '\0';
                status = fmi2SetString(c, &r, 1, &text);
            } else if (strcmp(word, "getstring") == 0 && sscanf(line, "%*s %u", &vr) == 1) {
                fmi2ValueReference r = vr;
                fmi2String got = NULL;
                status = fmi2GetString(c, &r, 1, &got);
                printf("string %s\n", got != NULL ? got : "(null)");
            } else if (strcmp(word, "save") == 0) {
                fmi2FMUstate state = NULL;
                status = fmi2GetFMUstate(c, &state);
                status |= fmi2SerializedFMUstateSize(c, state, &saved_size) << 4;
                free(saved);
                saved = (fmi2Byte*)malloc(saved_size);
                if (saved == NULL) return 2;
                status |= fmi2SerializeFMUstate(c, state, saved, saved_size) << 8;
                status |= fmi2FreeFMUstate(c, &state) << 12;
            } else if (strcmp(word, "restore") == 0 && saved != NULL) {
                fmi2FMUstate state = NULL;
                status = fmi2DeSerializeFMUstate(c, saved, saved_size, &state);
                status |= fmi2SetFMUstate(c, state) << 4;
                status |= fmi2FreeFMUstate(c, &state) << 8;
            } else if (strcmp(word, "init") == 0) {
                status = fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0);
                status |= fmi2EnterInitializationMode(c) << 4;
                status |= fmi2ExitInitializationMode(c) << 8;
            } else if (strcmp(word, "step") == 0 && sscanf(line, "%*s %lf %lf", &x, &y) == 2) {
                double values[SPEC_BLOCK_N_OUTPUTS];
                status = fmi2DoStep(c, x, y, fmi2True);
                fmi2GetReal(c, outputs, SPEC_BLOCK_N_OUTPUTS, values);
                printf("out");
                for (i = 0; i < SPEC_BLOCK_N_OUTPUTS; i++) printf(" %.17g", values[i]);
                printf("\n");
            } else {
                continue;
            }
            printf("status %s %d\n", word, status);
        }
        fclose(commands);
        free(saved);
        fmi2Terminate(c);
        fmi2FreeInstance(c);
    }
    return 0;
}
