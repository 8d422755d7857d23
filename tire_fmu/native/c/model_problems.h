/* model_problems.h: how a model of the layer (tire_model.c, inplane_tire_model.c) collects its
 * parameter problems, in the core's words and all at once: a list of lines, one a problem, each
 * as the core's parameters.render writes it. Header-only (static inline): each model is its own
 * translation unit, and the layer knows nothing of it. */
#ifndef TIRE_MODEL_PROBLEMS_H
#define TIRE_MODEL_PROBLEMS_H

#include <stdio.h>

#include "spec.h"

#define MAX_PROBLEMS 48
#define PROBLEM_SIZE 1024

typedef struct {
    int count;
    char text[MAX_PROBLEMS][PROBLEM_SIZE];
} Problems;

char* next_problem(Problems* p);

#define PROBLEM(p, ...)                                                \
    do {                                                               \
        char* slot_ = next_problem(p);                                 \
        if (slot_ != NULL) snprintf(slot_, PROBLEM_SIZE, __VA_ARGS__); \
    } while (0)

/* the value reference of a variable by name, -1 for none */
int variable_index(const char* name);

/* one problem as the core renders it (parameters.render): name = value: must be allowed
 * (reason) */
void add_problem(Problems* p, const char* name, double value, const char* unit,
                 const char* allowed, const char* reason);

/* FieldSpec.problem for each of n fields (a table of spec.h: SPEC_TIRE_FIELDS,
 * SPEC_INPLANE_FIELDS), values by value reference: every one out of its range; returns how
 * many */
int field_problems(const SpecField* fields, int n, const double* values, Problems* p);

/* parameters.tire_problems: every tire field out of its range (SPEC_TIRE_FIELDS, in the
 * core's order) and, with none, the sidewall's pressure law; returns how many */
int tire_field_problems(const double* values, Problems* p);

/* contact.zone_problems: the contact zone's length on this mesh (in (0, 2R tan 60deg], at
 * least one node either side of the centre), named contact_zone_length; 1 with the problem
 * added, else 0 */
int zone_length_problem(double radius, int n_elements, double length, Problems* p);

/* contact.point_spacing_problems: the contact points the spacing makes on this mesh and zone
 * (carry nodes either side of the centre), named contact_point_spacing; 1 with the problem
 * added when more than SPEC_MAX_CONTACT_POINTS, else 0 with the points per node in
 * *per_node */
int point_count_problem(double radius, int n_elements, int carry, double spacing,
                        int* per_node, Problems* p);

#endif
