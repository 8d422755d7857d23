/* model_problems.c: the parameter problems of a model of the layer (model_problems.h). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "model_problems.h"
#include "numerics.h"
#include "spec.h"
#include "tire.h"

#define PI 3.14159265358979323846

char* next_problem(Problems* p)
{
    if (p->count >= MAX_PROBLEMS) return NULL;
    return p->text[p->count++];
}

/* the value reference of a variable by name, -1 for none */
int variable_index(const char* name)
{
    int vr;
    for (vr = 0; vr < SPEC_N_VARIABLES; vr++) {
        if (strcmp(SPEC_VARIABLES[vr].name, name) == 0) return vr;
    }
    return -1;
}

/* one problem as the core renders it (parameters.render): name = value: must be allowed
 * (reason) */
void add_problem(Problems* p, const char* name, double value, const char* unit,
                 const char* allowed, const char* reason)
{
    char text[64], line[PROBLEM_SIZE / 2]; /* and the reason at most the other half */
    value_text(value, unit, text, sizeof text);
    snprintf(line, sizeof line, SPEC_MSG_PROBLEM, name, text, allowed);
    if (reason != NULL && reason[0] != '\0') {
        PROBLEM(p, SPEC_MSG_REASON, line, reason);
    } else {
        PROBLEM(p, "%s", line);
    }
}

int field_problems(const SpecField* fields, int n, const double* values, Problems* p)
{
    char text[64];
    int field, count = 0;
    for (field = 0; field < n; field++) {
        const SpecField* f = &fields[field];
        double value = values[variable_index(f->name)];
        int below;
        if (!isfinite(value)) {
            py_repr(value, text, sizeof text);
            PROBLEM(p, SPEC_MSG_FIELD_NOT_FINITE, f->name, text, f->range_text, f->description);
            count++;
            continue;
        }
        below = f->low_inclusive ? value < f->low : value <= f->low;
        if (below || value > f->high) {
            value_text(value, f->unit, text, sizeof text);
            PROBLEM(p, f->integer ? SPEC_MSG_FIELD_INTEGER : SPEC_MSG_FIELD_RANGE, f->name, text,
                    f->range_text, f->description);
            count++;
        } else if (f->integer && value != floor(value)) {
            value_text(value, f->unit, text, sizeof text);
            PROBLEM(p, SPEC_MSG_FIELD_INTEGER, f->name, text, f->range_text, f->description);
            count++;
        }
    }
    return count;
}

/* parameters.tire_problems: every tire field out of its range (SPEC_TIRE_FIELDS, in the
 * core's order) and, with none, the sidewall's pressure law; returns how many */
int tire_field_problems(const double* values, Problems* p)
{
    char text[64];
    int count = field_problems(SPEC_TIRE_FIELDS, SPEC_N_TIRE_FIELDS, values, p);
    if (count == 0 && values[SPEC_VR_SIDEWALL_PRESSURE_EXPONENT] > 0.0 &&
        values[SPEC_VR_INFLATION_PRESSURE] < SPEC_MIN_LAW_PRESSURE_PA) {
        value_text(values[SPEC_VR_INFLATION_PRESSURE], "Pa", text, sizeof text);
        PROBLEM(p, SPEC_MSG_PRESSURE_LAW, text, SPEC_MIN_LAW_PRESSURE_PA,
                values[SPEC_VR_SIDEWALL_PRESSURE_EXPONENT]);
        count++;
    }
    return count;
}

int zone_length_problem(double radius, int n_elements, double length, Problems* p)
{
    double limit = 2 * radius * tan(SPEC_MAX_ZONE_HALF_ANGLE), dtheta = 2.0 * PI / n_elements;
    char text[64];
    value_text(length, "m", text, sizeof text);
    if (!(isfinite(length) && 0 < length && length <= limit)) {
        PROBLEM(p, SPEC_MSG_ZONE_RANGE, text, limit);
        return 1;
    }
    if (atan(0.5 * length / radius) < dtheta) {
        PROBLEM(p, SPEC_MSG_ZONE_TOO_SHORT, text, 2 * radius * tan(dtheta), n_elements);
        return 1;
    }
    return 0;
}

int point_count_problem(double radius, int n_elements, int carry, double spacing,
                        int* per_node, Problems* p)
{
    double arc = radius * (2.0 * PI / n_elements), points;
    int carrying = 2 * carry + 1, most;
    char allowed[128], reason[256];
    *per_node = points_per_node(arc, spacing);
    points = (double)carrying * *per_node;
    if (points <= SPEC_MAX_CONTACT_POINTS) return 0;
    most = SPEC_MAX_CONTACT_POINTS / carrying;
    if (most < 1) most = 1;
    most -= 1 - most % 2;  /* odd */
    {   /* the smallest spacing allowed, rounded up to 4 digits (as printed, it holds) */
        double smallest = arc / (most > 1 ? most : 1), step = pow(10.0, floor(log10(smallest)) - 3);
        snprintf(allowed, sizeof allowed, SPEC_MSG_POINTS_ALLOWED, ceil(smallest / step) * step);
    }
    snprintf(reason, sizeof reason, SPEC_MSG_POINTS_REASON, *per_node, carrying, (int)points,
             SPEC_MAX_CONTACT_POINTS);
    add_problem(p, "contact_point_spacing", spacing, "m", allowed, reason);
    return 1;
}
