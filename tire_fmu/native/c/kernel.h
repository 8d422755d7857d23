/* kernel.h: the step of the tire, for any builder's contract (contract.h).
 *
 * One kernel steps the tire for both FMUs: the native FMU hands it the contract its C builder
 * made, the Python FMU the one the Python core made (through ctypes, tire_fmu/native/kernel.py).
 * It copies what it needs of the contract, so the builder's arrays may go once it is made.
 * The algorithm is tire_fmu/core/kernel_numpy.py's, the readable reference: the ring stepped
 * exactly in its free modal basis with the rim and the contact forces ramped over each
 * substep, the contact forces solved at the end of each substep from the substep's own
 * interface flexibility (active set, then projected Gauss-Seidel). Outputs: rim_Fz, rim_Fx,
 * contact_Fz, deflection, contact_length, tread_deflection. The clock is the time since the
 * start, its steps summed with compensation (core/clock.py).
 *
 * The road, one of two ways (a kernel reads it one way from its first step on):
 * - by time (kernel_step, kernel_outputs_with; inputs rim_z, rim_vz, road_z, road_vz): the
 *   road's height at the contact zone's front given at each communication point, its history
 *   read through each point's window delays (road.c);
 * - by position (kernel_set_road, then kernel_step_at, kernel_outputs_at; inputs rim_z,
 *   rim_vz, x, vx): the road a sampled profile along it (road_samples.h), the wheel centre at x
 *   along it moving at vx; each contact point reads the mean height over its window of road
 *   [x + window_lo_m, x + window_hi_m] (contract.h) and that mean's rate at vx, at the
 *   communication point and at the end of every substep, where x is on its extension over
 *   the step (core/host_inputs.py, as the rim's z): the road is resolved at the substep's
 *   travel, whatever the host's step. */
#ifndef TIRE_KERNEL_H
#define TIRE_KERNEL_H

#include <stddef.h>

#include "tire.h" /* numerics.h first: contract.h uses its types */
#include "contract.h"

#define KERNEL_N_INPUTS 4
#define KERNEL_N_OUTPUTS 6
/* what a step reports: the outputs, then the time, then 1 where the footprint touches an end
 * of the contact zone (a report is one array, so a host's step is one call) */
#define KERNEL_REPORT (KERNEL_N_OUTPUTS + 2)
#define KERNEL_REPORT_TIME KERNEL_N_OUTPUTS
#define KERNEL_REPORT_ZONE_EDGE (KERNEL_N_OUTPUTS + 1)

typedef struct TireKernel TireKernel;

/* status of the kernel's calls */
enum { KERNEL_OK = 0, KERNEL_NO_MEMORY = -1, KERNEL_BAD_CONTRACT = -2, KERNEL_REFUSED = -3 };

/* the inputs of a step with the road by position: rim_z, rim_vz, then these */
#define KERNEL_INPUT_X 2  /* x (m): the wheel centre's position along the road */
#define KERNEL_INPUT_VX 3 /* vx (m/s): its rate */

/* why a step is refused, as bits (0: it is not): h not finite and > 0, shorter than the
 * shortest step the contract takes, or not resolved by a clock of doubles at the kernel's
 * time; input i not finite or beyond its limit (bit 3 + i: SPEC_MAX_DISPLACEMENT_M,
 * SPEC_MAX_VELOCITY_M_S, x SPEC_MAX_ROAD_POSITION_M); more sub-steps than the work one step
 * may take (SPEC_MAX_STEP_WORK); the kernel reads the road the other way (kernel_step on a
 * kernel with a road by position, kernel_step_at on one without) */
enum { KERNEL_BAD_H = 1, KERNEL_SHORT_H = 2, KERNEL_UNRESOLVED_H = 4, KERNEL_BAD_INPUT = 8,
       KERNEL_LONG_H = 128, KERNEL_OTHER_ROAD = 256 };
int kernel_step_problems(const TireKernel* kernel, double h, const double inputs[KERNEL_N_INPUTS]);
int kernel_step_at_problems(const TireKernel* kernel, double h,
                            const double inputs[KERNEL_N_INPUTS]);

/* a kernel for the contract, at time start_time; KERNEL_BAD_CONTRACT for another version or
 * an inconsistent layout (why says which) */
int kernel_create(const TireContract* contract, const Memory* mem, double start_time,
                  TireKernel** out, char* why, size_t why_size);
void kernel_destroy(TireKernel* kernel);
/* kernel_create with calloc and free (for hosts that bring no allocator); NULL with why */
TireKernel* kernel_new(const TireContract* contract, double start_time, char* why,
                       size_t why_size);
void kernel_reset(TireKernel* kernel, double start_time);
/* one communication step of h from kernel_time with the inputs at kernel_time; the report
 * (KERNEL_REPORT values, or NULL) at the new time. KERNEL_REFUSED, nothing changed, for a step
 * kernel_step_problems finds fault with. */
int kernel_step(TireKernel* kernel, double h, const double inputs[KERNEL_N_INPUTS],
                double report[KERNEL_REPORT]);
/* the outputs at kernel_time for inputs given there (the forces re-solved for them) */
int kernel_outputs_with(TireKernel* kernel, const double inputs[KERNEL_N_INPUTS],
                        double report[KERNEL_REPORT]);

/* The road by position: n >= 0 samples, positions s (m, finite, increasing), heights z (m,
 * within SPEC_MAX_STATE_DISPLACEMENT_M) and the running integral at of z from s[0] (m^2,
 * trapezoids), linear between samples and level beyond them (none: level at 0). The kernel
 * reads the arrays in place at every substep: they must stay unchanged and alive until the
 * next kernel_set_road or kernel_destroy; call it again after changing them (a host's road
 * that grows). From the first call on the kernel steps with kernel_step_at (kernel_reset keeps
 * the road). KERNEL_REFUSED with why (may be NULL), nothing changed, for bad samples or a
 * kernel that has stepped with the road by time (since its last reset or state). */
int kernel_set_road(TireKernel* kernel, const double* s, const double* z, const double* at,
                    int n, char* why, size_t why_size);
int kernel_road_on(const TireKernel* kernel);  /* 1: the road by position */
/* kernel_step and kernel_outputs_with with the road by position: inputs rim_z, rim_vz, x, vx
 * at kernel_time (x extended over the step with its rate's history as rim_z is) */
int kernel_step_at(TireKernel* kernel, double h, const double inputs[KERNEL_N_INPUTS],
                   double report[KERNEL_REPORT]);
int kernel_outputs_at(TireKernel* kernel, const double inputs[KERNEL_N_INPUTS],
                      double report[KERNEL_REPORT]);
/* where the road was read last: the x of the last step's end, or of kernel_outputs_at */
double kernel_road_position(const TireKernel* kernel);

void kernel_outputs(const TireKernel* kernel, double outputs[KERNEL_N_OUTPUTS]);
double kernel_time(const TireKernel* kernel);         /* start + time since it */
double kernel_start_time(const TireKernel* kernel);
double kernel_elapsed(const TireKernel* kernel);       /* time since the start */
double kernel_min_step(const TireKernel* kernel);     /* shortest step it takes (s) */
double kernel_horizon(const TireKernel* kernel);  /* road delay to the last point (s) */
int kernel_in_contact(const TireKernel* kernel);
int kernel_at_zone_edge(const TireKernel* kernel);
long kernel_solver_fallbacks(const TireKernel* kernel);
/* tests: solve every contact problem by the projected Gauss-Seidel fallback (its own check) */
void kernel_set_fallback_only(TireKernel* kernel, int on);
int kernel_cached_steps(const TireKernel* kernel);   /* step sizes with coefficients kept */
int kernel_delay_line_on(const TireKernel* kernel);  /* the road read by its delay line */
/* the forces on each contact point at kernel_time (N), n_points values */
void kernel_forces(const TireKernel* kernel, double* forces);

/* the kernel's state, as bytes (the layout is in kernel.c) */
size_t kernel_state_size(const TireKernel* kernel);
void kernel_state_write(TireKernel* kernel, unsigned char* out);
/* KERNEL_OK, or KERNEL_BAD_CONTRACT with why (nothing changed then) */
int kernel_state_check(const TireKernel* kernel, const unsigned char* in, size_t size,
                       char* why, size_t why_size);
int kernel_state_apply(TireKernel* kernel, const unsigned char* in);
/* what state bytes (checked) hold: their time (start + since), start, outputs */
double kernel_state_time(const unsigned char* in);
double kernel_state_start(const unsigned char* in);
void kernel_state_outputs(const unsigned char* in, double outputs[KERNEL_N_OUTPUTS]);

#endif
