/* contract_shim.c: the native FMU's C builder outside the FMI layer, for tests: build the model
 * from parameter values (by value reference, as the FMU holds them) and hand back its step
 * contract, so that tests/test_contract.py compares it with the Python core's. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "model.h"
#include "spec.h"

typedef struct {
    char* text;
    size_t size;
} Log;

static void collect(void* layer, int status, const char* category, const char* message)
{
    Log* log = (Log*)layer;
    size_t used = strlen(log->text);
    (void)category;
    if (status >= MODEL_ERROR && used + strlen(message) + 2 < log->size) {
        strcat(log->text, message);
        strcat(log->text, "\n");
    }
}

/* the model (free it with shim_free) and its contract in *out; NULL with the problems in text
 * when the parameters are refused */
void* shim_build(const double* values, TireContract* out, char* text, size_t size)
{
    static Log log;
    ModelHost host;
    Model* model;
    double* scratch = (double*)calloc(SPEC_N_VARIABLES, sizeof(double));
    text[0] = '\0';
    log.text = text;
    log.size = size;
    host.mem.allocate = calloc;
    host.mem.release = free;
    host.layer = &log;
    host.log = collect;
    model = model_create(&host);
    memcpy(scratch, values, sizeof(double) * SPEC_N_VARIABLES);
    if (model == NULL || model_initialise(model, values, 0.0, scratch) != MODEL_OK) {
        free(scratch);
        model_destroy(model);
        return NULL;
    }
    free(scratch);
    *out = *model_contract(model);
    return model;
}

void shim_free(void* model) { model_destroy((Model*)model); }
