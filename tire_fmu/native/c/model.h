/* model.h: what the generic FMI 2.0 co-simulation layer (fmi2_layer.c) needs of a model, and
 * what it offers the model. The layer owns the variable values (one double per value
 * reference, Integer and Boolean ones exact), the lifecycle, the time, the call checks and the
 * FMU-state framing; the model builds itself from the parameter values, steps, recomputes its
 * outputs for new inputs, and writes and reads its own part of an FMU state. */
#ifndef TIRE_MODEL_H
#define TIRE_MODEL_H

#include <stddef.h>

#include "tire.h" /* numerics.h first: contract.h uses its types */
#include "contract.h"

/* the FMI statuses the model returns (the values of fmi2Status) */
enum { MODEL_OK = 0, MODEL_WARNING = 1, MODEL_DISCARD = 2, MODEL_ERROR = 3 };

typedef struct {
    Memory mem;
    void* layer;
    /* status: an fmi2Status; category: a log category of the model description */
    void (*log)(void* layer, int status, const char* category, const char* message);
    /* a String variable's value (its value reference; "" when unset) */
    const char* (*string)(void* layer, int vr);
} ModelHost;

typedef struct Model Model;

Model* model_create(const ModelHost* host);
void model_destroy(Model* model);
/* the values the outputs show before initialisation (after instantiate, reset, a set) */
void model_preview(const double* values, double* out_values);
/* build from the parameters in values; outputs written into values. MODEL_ERROR after logging
 * every problem (nothing changed then) */
int model_initialise(Model* model, const double* values, double start_time, double* out_values);
/* why the model cannot take a step of h by a rule of its own (into why, returned), or NULL:
 * the layer then refuses the step and nothing changes */
const char* model_step_problem(const Model* model, double h, char* why, size_t size);
/* one communication step from model_time to + h with the inputs in values: MODEL_OK;
 * MODEL_DISCARD when the model refused the step as it went and undid it (nothing changed:
 * model_step_refusal says why); MODEL_ERROR when it failed (out of memory) */
int model_step(Model* model, double h, double* values);
const char* model_step_refusal(const Model* model);
/* the outputs at model_time for the inputs in values (direct feedthrough) */
int model_refresh(Model* model, double* values);
/* the model's clock: start + the compensated sum of its steps (it never takes the host's t) */
double model_time(const Model* model);
/* the step contract the model was built into (NULL before it is built) */
const TireContract* model_contract(const Model* model);
/* how long the road takes from the zone front to its last node (s; 0 at rest) */
double model_road_horizon(const Model* model);
/* the shortest step it takes (s): SPEC_MIN_CORRECTED_STEP_S for a ring truncated with static
 * correction, else 0 */
double model_min_step(const Model* model);
/* whether a step of h takes more work than a step may (SPEC_MAX_STEP_WORK): its sub-steps,
 * their length and work, and the longest step that does not */
int model_step_work(const Model* model, double h, int* n_sub, double* substep, int* work,
                    double* longest);
/* does the model hold a built simulator for exactly these parameter values? */
int model_built_for(const Model* model, const double* values);
/* its part of an FMU state */
size_t model_state_size(const Model* model);
void model_state_write(const Model* model, unsigned char* out);
/* MODEL_OK, or MODEL_ERROR with why (every problem; nothing changed then): the part must
 * mean a state of this model, at the layer's time and start time, showing the layer's
 * values as its outputs */
int model_state_check(const Model* model, const unsigned char* in, size_t size,
                      const double* values, double time, double start_time, char* why,
                      size_t why_size);
void model_state_apply(Model* model, const unsigned char* in);

#endif
