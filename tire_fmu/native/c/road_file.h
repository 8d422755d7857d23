/* road_file.h: a road file read into the road the tire reads by position, in C for the native
 * FMUs: an OpenCRG file (.crg: KRBI, KDBI, LRFI, LDFI) along its reference line at a lateral
 * offset, or a two-column profile (distance m, height m).
 *
 * The C of tire_fmu/road_files.py, with its rules and its messages: the profile's knots are
 * the file's cross sections (an OpenCRG grid interpolated between the long sections either
 * side of the offset as the ASAM OpenCRG C API interpolates it, plus the reference line's
 * height, the banking and the modifiers' shift), linear between knots, level at the end
 * heights beyond them (the C API's default border mode). tests/test_road_files.py holds the
 * two readers equal, and both equal to the ASAM C API (through pycrg).
 *
 * No allocation is sized by a file's field before the field is checked against the limits
 * below and against the file's size. Every refusal is a sentence in why, naming the file and
 * what is wrong. */
#ifndef TIRE_ROAD_FILE_H
#define TIRE_ROAD_FILE_H

#include <stddef.h>

#include "tire.h"

/* road_files.py's limits (a test holds them equal) */
#define ROAD_FILE_MAX_BYTES 1073741824L      /* MAX_ROAD_FILE_BYTES */
#define ROAD_FILE_MAX_HEADER_BYTES 1048576L  /* MAX_CRG_HEADER_BYTES */
#define ROAD_FILE_MAX_KNOTS 10000000L        /* MAX_CROSS_SECTIONS */
#define ROAD_FILE_MAX_CHANNELS 100000L       /* MAX_CRG_CHANNELS */
#define ROAD_FILE_MAX_ABS_HEIGHT_M 1.0e4     /* MAX_ABS_HEIGHT_M */
#define ROAD_FILE_MAX_ABS_DISTANCE_M 1.0e7   /* MAX_ABS_DISTANCE_M */
#define ROAD_FILE_MIN_INCREMENT_M 1.0e-6     /* MIN_INCREMENT_M */
#define ROAD_FILE_V_BORDER_M 1.0e-8          /* V_BORDER_TOLERANCE_M */
#define ROAD_FILE_HEADER_TOLERANCE_M 1.0e-6  /* HEADER_TOLERANCE_M */
#define ROAD_FILE_MAX_PROFILE_BYTES 536870912L /* MAX_PROFILE_FILE_BYTES */

enum {
    ROAD_FILE_OK = 0,
    ROAD_FILE_UNREADABLE = 1,  /* missing, a folder, cannot be read, too large */
    ROAD_FILE_MALFORMED = 2,   /* not what its format says (truncated, NaN, wrong header) */
    ROAD_FILE_UNSUPPORTED = 3, /* a valid file this reader does not take (its message says
                                  what is supported) */
    ROAD_FILE_NO_MEMORY = 4,
    ROAD_FILE_BAD_ARGUMENT = 5 /* a NULL pointer, a non-finite lateral offset */
};

/* The road along the file: read only once opened. */
typedef struct {
    size_t n;              /* knots, >= 2 */
    double* s;             /* distance along the road (m; an OpenCRG file's u), increasing */
    double* z;             /* height (m) */
    double* area;          /* the integral of z from s[0] to each knot (m^2) */
    double lateral_offset_m; /* v of the track read (OpenCRG), 0 for a profile */
    double height_shift_m; /* what the OpenCRG modifiers added to every height (m) */
    char format[8];        /* "KRBI", "KDBI", "LRFI", "LDFI" or "profile" */
    const Memory* mem;     /* what the arrays came from */
} RoadFile;

/* Read path (an OpenCRG file: a .crg name or a text starting with $CT, $ROAD_CRG or
 * $KD_DEFINITION, read at lateral_offset_m; else a profile, whose lateral offset must be 0)
 * into *road (mem NULL: calloc and free). On a problem returns its status, *road is left
 * empty (road_file_free may still be called) and why (why_size > 0) holds the sentence. */
int road_file_open(const char* path, double lateral_offset_m, const Memory* mem,
                   RoadFile* road, char* why, size_t why_size);

/* The height (m) at s (m): linear between knots, level at the end heights beyond them. */
double road_file_height(const RoadFile* road, double s_m);
/* dz/ds at s: the slope of the segment s lies on (the one after a knot), 0 beyond the ends. */
double road_file_slope(const RoadFile* road, double s_m);
/* The integral of the height from s[0] to s (m^2), the level road's beyond the ends. */
double road_file_integral(const RoadFile* road, double s_m);
/* The mean height over [s_lo, s_hi] from the exact integral; the height at s_lo when
 * s_hi <= s_lo. */
double road_file_mean(const RoadFile* road, double s_lo_m, double s_hi_m);
/* The distances the file covers: s[0] and s[n - 1]. */
void road_file_extent(const RoadFile* road, double* first_m, double* last_m);
void road_file_free(RoadFile* road);

#endif
