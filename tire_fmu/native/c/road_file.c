/* road_file.c: road files (OpenCRG and two-column profiles) read into the road the tire reads
 * by position; the C of tire_fmu/road_files.py, with its rules and its sentences (road_file.h).
 *
 * Written from the OpenCRG format's description and the behaviour of the ASAM C API
 * (evaluation in crgEvaluv2z, reference line in calcRefLineZ, modifiers' shift), not from its
 * code. Numbers are parsed independently of the C locale (a host may set one whose decimal
 * point is a comma). */
#include <errno.h>
#include <locale.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "road_file.h"

#define LINE_CHARS 4096 /* header lines longer than this are cut here (the C API cuts too) */
#define RECORD_BYTES 80
#define N_WANTED 6      /* track j, j + 1, reference point j, j + 1, slope, banking */

/* -- sentences ------------------------------------------------------------------------------ */

static int fail(char* why, size_t size, int status, const char* path, const char* format, ...)
{
    if (why != NULL && size > 0) {
        int used = snprintf(why, size, "%s: ", path);
        if (used >= 0 && (size_t)used < size) {
            va_list args;
            va_start(args, format);
            vsnprintf(why + used, size - (size_t)used, format, args);
            va_end(args);
        }
    }
    return status;
}

/* -- numbers, as road_files.py's _NUMBER and _INTEGER read them ------------------------------ */

static int is_space(char c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}

static int is_digit(char c) { return c >= '0' && c <= '9'; }

/* Length of the number at text (after blanks, which *skip counts), 0 if none: an optional
 * sign, digits with an optional point and digits (or a point and digits), an optional
 * exponent. integer: digits only. */
static size_t number_length(const char* text, size_t* skip, int integer)
{
    size_t i = 0, start, digits = 0;
    while (is_space(text[i])) i++;
    *skip = start = i;
    if (text[i] == '+' || text[i] == '-') i++;
    while (is_digit(text[i])) { i++; digits++; }
    if (integer) return digits ? i - start : 0;
    if (text[i] == '.') {
        size_t after = 0;
        i++;
        while (is_digit(text[i])) { i++; after++; }
        if (digits == 0 && after == 0) return 0;
    } else if (digits == 0) {
        return 0;
    }
    if (text[i] == 'e' || text[i] == 'E') {
        size_t e = i + 1;
        if (text[e] == '+' || text[e] == '-') e++;
        if (is_digit(text[e])) {
            while (is_digit(text[e])) e++;
            i = e;
        }
    }
    return i - start;
}

/* The number of length characters at text, read as C reads it in the "C" locale. */
static double number_value(const char* text, size_t length)
{
    char buffer[512];
    const char* point = localeconv()->decimal_point;
    size_t i;
    if (length >= sizeof buffer) length = sizeof buffer - 1;
    memcpy(buffer, text, length);
    buffer[length] = '\0';
    if (point != NULL && point[0] != '\0' && point[0] != '.' && point[1] == '\0')
        for (i = 0; i < length; i++)
            if (buffer[i] == '.') buffer[i] = point[0];
    return strtod(buffer, NULL);
}

/* -- lines --------------------------------------------------------------------------------- */

/* The next line of stream into line (at most LINE_CHARS - 1 characters kept, the rest of a
 * longer line read and dropped), trailing '\r' removed; -1 at the end of the stream. */
static long next_line(FILE* stream, char* line, long* offset)
{
    long length = 0, kept = 0;
    int c;
    while ((c = getc(stream)) != EOF) {
        (*offset)++;
        if (c == '\n') break;
        if (kept < LINE_CHARS - 1) line[kept++] = (char)c;
        length++;
    }
    if (c == EOF && length == 0) return -1;
    while (kept > 0 && line[kept - 1] == '\r') kept--;
    line[kept] = '\0';
    return kept;
}

static const char* skip_spaces(const char* text)
{
    while (*text == ' ') text++;
    return text;
}

static int starts_with_nocase(const char* text, const char* prefix)
{
    while (*prefix) {
        char a = *text, b = *prefix;
        if (a >= 'a' && a <= 'z') a = (char)(a - 'a' + 'A');
        if (b >= 'a' && b <= 'z') b = (char)(b - 'a' + 'A');
        if (a != b) return 0;
        text++;
        prefix++;
    }
    return 1;
}

/* -- the OpenCRG header --------------------------------------------------------------------- */

enum { SEC_NONE, SEC_COMMENT, SEC_ROAD, SEC_OPTS, SEC_MODS, SEC_KD, SEC_FILE, SEC_DATA,
       SEC_OTHER };

static int line_tag(const char* line)
{
    static const char* tags[] = {"$ROAD_CRG_MODS", "$ROAD_CRG_OPTS", "$ROAD_CRG_FILE",
                                 "$ROAD_CRG", "$CT", "$KD_DEFINITION", "$$$$", "$"};
    static const int sections[] = {SEC_MODS, SEC_OPTS, SEC_FILE, SEC_ROAD, SEC_COMMENT, SEC_KD,
                                   SEC_DATA, SEC_NONE};
    const char* text = skip_spaces(line);
    size_t k;
    for (k = 0; k < sizeof tags / sizeof tags[0]; k++)
        if (starts_with_nocase(text, tags[k])) return sections[k];
    return SEC_OTHER;
}

static const char* ROAD_KEYS[] = {
    "reference_line_start_u", "reference_line_start_x", "reference_line_start_y",
    "reference_line_start_z", "reference_line_start_phi", "reference_line_start_b",
    "reference_line_start_s", "reference_line_end_u", "reference_line_end_x",
    "reference_line_end_y", "reference_line_end_z", "reference_line_end_phi",
    "reference_line_end_b", "reference_line_end_s", "reference_line_increment",
    "long_section_v_right", "long_section_v_left", "long_section_v_increment",
    "reference_line_offset_x", "reference_line_offset_y", "reference_line_offset_z",
    "reference_line_offset_phi"};
enum { R_START_U, R_START_X, R_START_Y, R_START_Z, R_START_PHI, R_START_B, R_START_S, R_END_U,
       R_END_X, R_END_Y, R_END_Z, R_END_PHI, R_END_B, R_END_S, R_INCREMENT, R_V_RIGHT,
       R_V_LEFT, R_V_INCREMENT, R_COUNT = 22 };

static const char* OPTION_KEYS[] = {
    "border_mode_u", "border_offset_u", "border_mode_v", "border_offset_v",
    "border_smooth_ubeg", "border_smooth_uend", "refline_continuation", "refline_search_far",
    "refline_search_close", "refline_search_ufrac", "refline_search_u", "warn_msgs",
    "warn_curv_local", "warn_curv_global", "log_msgs", "log_eval_freq", "log_eval",
    "log_hist_freq", "log_hist", "log_stat_freq", "log_stat", "check_eps", "check_inc",
    "check_tol"};
enum { O_MODE_U, O_OFFSET_U, O_MODE_V, O_OFFSET_V, O_SMOOTH_BEG, O_SMOOTH_END, O_COUNT = 24 };

static const char* MODIFIER_KEYS[] = {
    "scale_z_grid", "scale_slope", "scale_banking", "scale_length", "scale_width",
    "scale_curvature", "grid_nan_mode", "grid_nan_offset", "refline_rotcenter_x",
    "refline_rotcenter_y", "refline_offset_phi", "refline_offset_x", "refline_offset_y",
    "refline_offset_z", "refpoint_u_fraction", "refpoint_u_offset", "refpoint_u",
    "refpoint_v_fraction", "refpoint_v_offset", "refpoint_v", "refpoint_x", "refpoint_y",
    "refpoint_z", "refpoint_phi"};
enum { M_SCALE_Z, M_SCALE_SLOPE, M_SCALE_BANK, M_SCALE_LENGTH, M_SCALE_WIDTH, M_SCALE_CURV,
       M_NAN_MODE, M_NAN_OFFSET, M_ROT_X, M_ROT_Y, M_OFF_PHI, M_OFF_X, M_OFF_Y, M_OFF_Z,
       M_U_FRACTION, M_U_OFFSET, M_U, M_V_FRACTION, M_V_OFFSET, M_V, M_X, M_Y, M_Z, M_PHI,
       M_COUNT };

typedef struct {
    char kind;  /* 'z', 's' slope, 'b' banking, 'p' heading */
    double v;   /* a long section's v, or its number */
} Channel;

typedef struct {
    double road[R_COUNT];
    int road_given[R_COUNT];
    double options[O_COUNT];
    int options_given[O_COUNT];
    double mods[M_COUNT];
    int mods_given[M_COUNT];
    int has_mods;
    char format[8];
    Channel* channels;
    long n_channels, capacity;
    int by_number, by_position;
    long data_offset;
} Header;

static int match_key(const char* line, const char** keys, int count)
{
    const char* text = skip_spaces(line);
    int k;
    for (k = 0; k < count; k++)
        if (starts_with_nocase(text, keys[k])) return k;
    return -1;
}

static int header_value(const char* path, long number, const char* line, const char* key,
                        int integer, double* value, char* why, size_t size)
{
    const char* equals = strchr(line, '=');
    size_t skip = 0, length = equals ? number_length(equals + 1, &skip, integer) : 0;
    const char* shown = line;
    size_t shown_length = strlen(line);
    if (length == 0) {
        while (*shown == ' ' || *shown == '\t') { shown++; shown_length--; }
        while (shown_length > 0 && is_space(shown[shown_length - 1])) shown_length--;
        return fail(why, size, ROAD_FILE_MALFORMED, path,
                    "line %ld: %s: no number after '=' in '%.*s'", number, key,
                    (int)shown_length, shown);
    }
    *value = number_value(equals + 1 + skip, length);
    if (!isfinite(*value))
        return fail(why, size, ROAD_FILE_MALFORMED, path, "line %ld: %s = %.*s: not finite",
                    number, key, (int)length, equals + 1 + skip);
    return ROAD_FILE_OK;
}

/* name of a D: line, lower case, its blanks collapsed and trimmed; unit likewise */
static void channel_parts(const char* text, char* name, size_t name_size, char* unit,
                          size_t unit_size)
{
    const char* end = strchr(text, '!');
    const char* comma = strchr(text, ',');
    size_t limit = end ? (size_t)(end - text) : strlen(text);
    size_t n = 0, i, name_end = comma && (size_t)(comma - text) < limit ? (size_t)(comma - text)
                                                                       : limit;
    int space = 0;
    for (i = 0; i < name_end && n + 1 < name_size; i++) {
        char c = text[i];
        if (is_space(c)) { space = n > 0; continue; }
        if (space) { name[n++] = ' '; space = 0; if (n + 1 >= name_size) break; }
        name[n++] = (char)((c >= 'A' && c <= 'Z') ? c - 'A' + 'a' : c);
    }
    name[n] = '\0';
    n = 0;
    if (name_end < limit) {
        size_t last;
        i = name_end + 1;
        while (i < limit && is_space(text[i])) i++;
        last = limit;
        while (last > i && is_space(text[last - 1])) last--;
        for (; i < last && n + 1 < unit_size; i++) {
            char c = text[i];
            unit[n++] = (char)((c >= 'A' && c <= 'Z') ? c - 'A' + 'a' : c);
        }
    }
    unit[n] = '\0';
}

static int add_channel(const char* path, long number, const char* text, Header* h,
                       const Memory* mem, char* why, size_t size)
{
    char name[LINE_CHARS], unit[LINE_CHARS], definition[LINE_CHARS];
    const char* bang = strchr(text, '!');
    size_t def_length = bang ? (size_t)(bang - text) : strlen(text);
    Channel channel;
    channel.kind = 'z';
    channel.v = NAN;
    while (def_length > 0 && is_space(text[def_length - 1])) def_length--;
    {
        size_t start = 0;
        while (start < def_length && is_space(text[start])) start++;
        snprintf(definition, sizeof definition, "%.*s", (int)(def_length - start), text + start);
    }
    channel_parts(text, name, sizeof name, unit, sizeof unit);
    if (strncmp(name, "long section", 12) == 0) {
        const char* rest = name + 12;
        size_t skip, length;
        while (*rest == ' ') rest++;
        if (strncmp(unit, "m", 1) != 0)
            return fail(why, size, ROAD_FILE_MALFORMED, path,
                        "line %ld: long section '%s': its unit must be m, not '%s'", number,
                        rest, unit);
        if (strncmp(rest, "at v", 4) == 0) {
            const char* equals = strchr(rest, '=');
            length = equals ? number_length(equals + 1, &skip, 0) : 0;
            if (length == 0 || !isfinite(number_value(equals + 1 + skip, length)))
                return fail(why, size, ROAD_FILE_MALFORMED, path,
                            "line %ld: 'long section %s': no position after 'at v ='", number,
                            rest);
            channel.v = number_value(equals + 1 + skip, length);
            h->by_position = 1;
        } else {
            length = number_length(rest, &skip, 0);
            channel.v = length ? number_value(rest + skip, length) : NAN;
            if (length == 0 || !(channel.v == floor(channel.v)))
                return fail(why, size, ROAD_FILE_MALFORMED, path,
                            "line %ld: 'long section %s': a long section is 'long section N' "
                            "or 'long section at v = V'", number, rest);
            h->by_number = 1;
        }
    } else if (strncmp(name, "reference line", 14) == 0) {
        const char* what = name + 14;
        const char* expected = NULL;
        while (*what == ' ') what++;
        if (strcmp(what, "slope") == 0) { channel.kind = 's'; expected = "m/m"; }
        else if (strcmp(what, "banking") == 0) { channel.kind = 'b'; expected = "m/m"; }
        else if (strcmp(what, "phi") == 0) { channel.kind = 'p'; expected = "rad"; }
        else if (strcmp(what, "x") == 0 || strcmp(what, "y") == 0 || strcmp(what, "u") == 0)
            return fail(why, size, ROAD_FILE_UNSUPPORTED, path,
                        "line %ld: a reference line given by its %s values is not supported: "
                        "u runs from reference_line_start_u by reference_line_increment (a "
                        "heading channel, 'reference line phi', may bend it)", number, what);
        if (expected == NULL)
            return fail(why, size, ROAD_FILE_UNSUPPORTED, path,
                        "line %ld: channel '%s': not an OpenCRG channel read here (long section "
                        "N, long section at v = V, reference line slope, banking or phi)",
                        number, definition);
        if (strncmp(unit, expected, strlen(expected)) != 0)
            return fail(why, size, ROAD_FILE_MALFORMED, path,
                        "line %ld: reference line %s: its unit must be %s, not '%s'", number,
                        what, expected, unit);
    } else {
        return fail(why, size, ROAD_FILE_UNSUPPORTED, path,
                    "line %ld: channel '%s': not an OpenCRG channel read here (long section N, "
                    "long section at v = V, reference line slope, banking or phi)", number,
                    definition);
    }
    if (h->n_channels >= h->capacity) {
        long grown = h->capacity ? 2 * h->capacity : 64;
        Channel* more;
        if (grown > ROAD_FILE_MAX_CHANNELS) grown = ROAD_FILE_MAX_CHANNELS;
        more = (Channel*)mem_alloc(mem, (size_t)grown, sizeof(Channel));
        if (more == NULL) return fail(why, size, ROAD_FILE_NO_MEMORY, path, "out of memory");
        if (h->n_channels) memcpy(more, h->channels, (size_t)h->n_channels * sizeof(Channel));
        mem_free(mem, h->channels);
        h->channels = more;
        h->capacity = grown;
    }
    h->channels[h->n_channels++] = channel;
    return ROAD_FILE_OK;
}

static int checked_header(const char* path, Header* h, char* why, size_t size)
{
    long k, z = 0, kinds[3] = {0, 0, 0};
    const char* kind_names[3] = {"slope", "bank", "phi"};
    const char kind_codes[3] = {'s', 'b', 'p'};
    double increment;
    if (h->format[0] == '\0')
        return fail(why, size, ROAD_FILE_MALFORMED, path,
                    "no data format in $KD_DEFINITION (a line #:KRBI, #:KDBI, #:LRFI or "
                    "#:LDFI)");
    if (h->by_number && h->by_position)
        return fail(why, size, ROAD_FILE_MALFORMED, path,
                    "long sections given both by number and by position (at v =): use one way");
    for (k = 0; k < h->n_channels; k++) {
        int j;
        if (h->channels[k].kind == 'z') z++;
        for (j = 0; j < 3; j++)
            if (h->channels[k].kind == kind_codes[j]) kinds[j]++;
    }
    if (z < 2)
        return fail(why, size, ROAD_FILE_MALFORMED, path,
                    "fewer than 2 long sections (D:long section ... lines): no road to "
                    "interpolate");
    for (k = 0; k < 3; k++)
        if (kinds[k] > 1)
            return fail(why, size, ROAD_FILE_MALFORMED, path,
                        "more than one reference line %s channel", kind_names[k]);
    if (!h->road_given[R_INCREMENT])
        return fail(why, size, ROAD_FILE_MALFORMED, path,
                    "no reference_line_increment in $ROAD_CRG (the spacing of the cross "
                    "sections along u)");
    increment = h->road[R_INCREMENT];
    if (!(increment >= ROAD_FILE_MIN_INCREMENT_M && increment <= 1e3))
        return fail(why, size, ROAD_FILE_MALFORMED, path,
                    "reference_line_increment = %g m: must be in [%g, 1000] m", increment,
                    ROAD_FILE_MIN_INCREMENT_M);
    if (h->options_given[O_MODE_U] && h->options[O_MODE_U] != 2.0)
        return fail(why, size, ROAD_FILE_UNSUPPORTED, path,
                    "border_mode_u = %g: only 2 (keep the last height beyond the road's ends, "
                    "the default) is supported", h->options[O_MODE_U]);
    {
        const int keys[3] = {O_OFFSET_U, O_SMOOTH_BEG, O_SMOOTH_END};
        for (k = 0; k < 3; k++)
            if (h->options_given[keys[k]] && h->options[keys[k]] != 0.0)
                return fail(why, size, ROAD_FILE_UNSUPPORTED, path,
                            "%s = %g: not supported (the road is level at its end heights "
                            "beyond its ends)", OPTION_KEYS[keys[k]], h->options[keys[k]]);
    }
    if (h->has_mods) {
        char scaling[256] = "";
        int by_ref = 0, by_off = 0;
        for (k = M_SCALE_Z; k <= M_SCALE_WIDTH; k++)
            if (h->mods_given[k]) {
                if (scaling[0]) strcat(scaling, ", ");
                strcat(scaling, MODIFIER_KEYS[k]);
            }
        if (scaling[0])
            return fail(why, size, ROAD_FILE_UNSUPPORTED, path,
                        "modifier %s: scaling modifiers are not supported: apply them and save "
                        "the road first (pyopencrg: road.apply_mods(), then road.save(...))",
                        scaling);
        for (k = M_U_FRACTION; k <= M_PHI; k++)
            if (k != M_U_OFFSET && k != M_V_OFFSET && h->mods_given[k]) by_ref = 1;
        for (k = M_OFF_PHI; k <= M_OFF_Z; k++)
            if (h->mods_given[k]) by_off = 1;
        if (by_ref && by_off)
            return fail(why, size, ROAD_FILE_UNSUPPORTED, path,
                        "modifiers refpoint_* and refline_offset_* together: the OpenCRG C API "
                        "refuses them, give one kind");
        if (h->mods_given[M_U] && h->mods_given[M_U_FRACTION])
            return fail(why, size, ROAD_FILE_MALFORMED, path,
                        "modifiers refpoint_u and refpoint_u_fraction together: give one");
        if (h->mods_given[M_V] && h->mods_given[M_V_FRACTION])
            return fail(why, size, ROAD_FILE_MALFORMED, path,
                        "modifiers refpoint_v and refpoint_v_fraction together: give one");
    }
    return ROAD_FILE_OK;
}

static int read_header(const char* path, FILE* stream, long file_bytes, Header* h,
                       const Memory* mem, char* why, size_t size)
{
    char line[LINE_CHARS];
    int section = SEC_NONE;
    long number = 0, offset = 0, length;
    long comment_end_line = 0;
    char comment_end[LINE_CHARS] = "";
    while (offset < ROAD_FILE_MAX_HEADER_BYTES
           && (length = next_line(stream, line, &offset)) >= 0) {
        const char* stripped = skip_spaces(line);
        int status = ROAD_FILE_OK, key;
        double value;
        number++;
        if (offset > ROAD_FILE_MAX_HEADER_BYTES) break;  /* the line runs past the header */
        if (section == SEC_COMMENT) {
            if (line[0] == '$') {
                int tag = line_tag(line);
                section = SEC_NONE;
                if (tag == SEC_MODS || tag == SEC_OPTS || tag == SEC_FILE || tag == SEC_ROAD
                    || tag == SEC_COMMENT || tag == SEC_KD) {
                    const char* text = line;
                    size_t n = strlen(text);
                    while (*text == ' ' || *text == '\t') { text++; n--; }
                    while (n > 0 && is_space(text[n - 1])) n--;
                    comment_end_line = number;
                    snprintf(comment_end, sizeof comment_end, "%.*s", (int)n, text);
                }
            }
            continue;
        }
        if (*stripped == '\0' || *stripped == '*') continue;
        if (section == SEC_NONE) {
            int tag = line_tag(line);
            if (tag == SEC_DATA) {
                h->data_offset = offset;
                return checked_header(path, h, why, size);
            }
            if (tag == SEC_FILE)
                return fail(why, size, ROAD_FILE_UNSUPPORTED, path,
                            "line %ld: $ROAD_CRG_FILE (a road in several files) is not "
                            "supported: give one file", number);
            if (tag == SEC_OTHER) continue;
            if (tag == SEC_MODS) {
                h->has_mods = 1;
                memset(h->mods_given, 0, sizeof h->mods_given);
            }
            if (tag == SEC_OPTS) memset(h->options_given, 0, sizeof h->options_given);
            section = tag;
            continue;
        }
        if (*stripped == '$') {
            section = SEC_NONE;
        } else if (section == SEC_ROAD) {
            key = match_key(line, ROAD_KEYS, R_COUNT);
            if (key >= 0) {
                status = header_value(path, number, line, ROAD_KEYS[key], 0, &value, why, size);
                h->road[key] = value;
                h->road_given[key] = 1;
            }
        } else if (section == SEC_OPTS) {
            key = match_key(line, OPTION_KEYS, O_COUNT);
            if (key >= 0) {
                status = header_value(path, number, line, OPTION_KEYS[key],
                                      strncmp(OPTION_KEYS[key], "border_mode", 11) == 0,
                                      &value, why, size);
                h->options[key] = value;
                h->options_given[key] = 1;
            }
        } else if (section == SEC_MODS) {
            key = match_key(line, MODIFIER_KEYS, M_COUNT);
            if (key >= 0) {
                status = header_value(path, number, line, MODIFIER_KEYS[key],
                                      key == M_NAN_MODE, &value, why, size);
                h->mods[key] = value;
                h->mods_given[key] = 1;
            }
        } else if (section == SEC_KD) {
            if (stripped[0] == '#' && stripped[1] == ':') {
                char format[5];
                size_t i;
                for (i = 0; i < 4 && stripped[2 + i] != '\0'; i++) {
                    char c = stripped[2 + i];
                    format[i] = (char)((c >= 'a' && c <= 'z') ? c - 'a' + 'A' : c);
                }
                format[i] = '\0';
                if (strcmp(format, "KRBI") && strcmp(format, "KDBI") && strcmp(format, "LRFI")
                    && strcmp(format, "LDFI"))
                    return fail(why, size, ROAD_FILE_UNSUPPORTED, path,
                                "line %ld: data format '%.*s': supported are KRBI and KDBI "
                                "(binary, single and double precision) and LRFI and LDFI "
                                "(text)", number, (int)i, stripped + 2);
                memcpy(h->format, format, 5);
            } else if ((stripped[0] == 'D' || stripped[0] == 'd') && stripped[1] == ':') {
                if (h->n_channels >= ROAD_FILE_MAX_CHANNELS)
                    return fail(why, size, ROAD_FILE_MALFORMED, path,
                                "more than %ld channels (D: lines)", ROAD_FILE_MAX_CHANNELS);
                status = add_channel(path, number, stripped + 2, h, mem, why, size);
            }
        }
        if (status != ROAD_FILE_OK) return status;
    }
    if (comment_end_line)
        return fail(why, size, ROAD_FILE_MALFORMED, path,
                    "not an OpenCRG file: no data section (a line of '$$$$' after the closed "
                    "$ROAD_CRG and $KD_DEFINITION blocks) %s (line %ld, '%s', only ends the "
                    "$CT block before it: the OpenCRG loader needs a line '$' between)",
                    file_bytes <= ROAD_FILE_MAX_HEADER_BYTES ? "in the file"
                    : "in its first 1048576 bytes", comment_end_line, comment_end);
    return fail(why, size, ROAD_FILE_MALFORMED, path,
                "not an OpenCRG file: no data section (a line of '$$$$' after the closed "
                "$ROAD_CRG and $KD_DEFINITION blocks) %s",
                file_bytes <= ROAD_FILE_MAX_HEADER_BYTES ? "in the file"
                : "in its first 1048576 bytes");
}

/* -- the OpenCRG data ----------------------------------------------------------------------- */

typedef struct {
    long rows;
    double start_u, increment;
    int wanted[N_WANTED];    /* channel indices, -1: none */
    double* column[N_WANTED];
} Data;

static int text_field_allowed(const char* field, size_t chars)
{
    size_t i;
    for (i = 0; i < chars; i++)
        if (!strchr("0123456789+-.eEdD ", field[i]) || field[i] == '\0') return 0;
    return 1;
}

static double text_value(const char* field, size_t chars)
{
    if (text_field_allowed(field, chars)) {
        char buffer[32];
        size_t skip, length;
        memcpy(buffer, field, chars);
        buffer[chars] = '\0';
        length = number_length(buffer, &skip, 0);
        return length ? number_value(buffer + skip, length) : 0.0;
    }
    if (chars == 10 && memcmp(field, "**unused**", 10) == 0) return 0.0;
    return NAN;
}

static double big_endian(const unsigned char* bytes, int width)
{
    unsigned char host[8];
    unsigned int probe = 1;
    int little = *(unsigned char*)&probe == 1, i;
    for (i = 0; i < width; i++) host[i] = bytes[little ? width - 1 - i : i];
    if (width == 4) {
        float f;
        memcpy(&f, host, 4);
        return (double)f;
    } else {
        double d;
        memcpy(&d, host, 8);
        return d;
    }
}

static int allocate_columns(Data* d, const Memory* mem, const char* path, char* why,
                            size_t size)
{
    int k;
    for (k = 0; k < N_WANTED; k++) {
        if (d->wanted[k] < 0) continue;
        d->column[k] = (double*)mem_alloc(mem, (size_t)d->rows, sizeof(double));
        if (d->column[k] == NULL)
            return fail(why, size, ROAD_FILE_NO_MEMORY, path, "out of memory");
    }
    return ROAD_FILE_OK;
}

static int read_binary(const char* path, FILE* stream, long file_bytes, const Header* h,
                       Data* d, const Memory* mem, char* why, size_t size)
{
    int width = h->format[1] == 'D' ? 8 : 4;
    long record = h->n_channels * width, available = file_bytes - h->data_offset, row;
    double count, end;
    unsigned char* buffer;
    int status, k;
    if (!h->road_given[R_END_U])
        return fail(why, size, ROAD_FILE_MALFORMED, path,
                    "no reference_line_end_u in $ROAD_CRG: a binary file's cross sections are "
                    "counted from it");
    end = h->road[R_END_U];
    count = (end - d->start_u) / d->increment + 0.5;
    if (!(count >= 1.0 && count < (double)ROAD_FILE_MAX_KNOTS))
        return fail(why, size, ROAD_FILE_MALFORMED, path,
                    "reference_line_start_u = %g, end_u = %g by %g m: %.6g increments; must "
                    "make 2 to %ld cross sections", d->start_u, end, d->increment, count - 0.5,
                    ROAD_FILE_MAX_KNOTS);
    d->rows = (long)count + 1;
    if (available < d->rows * record) {
        long held = available > 0 ? available : 0;
        return fail(why, size, ROAD_FILE_MALFORMED, path,
                    "truncated: the header declares %ld cross sections of %ld %s values (%ld "
                    "bytes of data), the file holds %ld bytes (%ld cross sections)", d->rows,
                    h->n_channels, h->format, d->rows * record, held, held / record);
    }
    if (available - d->rows * record >= RECORD_BYTES)
        return fail(why, size, ROAD_FILE_MALFORMED, path,
                    "%ld bytes of data beyond the %ld cross sections reference_line_start_u, "
                    "end_u and increment declare (at most %d bytes of padding): the header "
                    "does not match the data", available - d->rows * record, d->rows,
                    RECORD_BYTES - 1);
    status = allocate_columns(d, mem, path, why, size);
    if (status != ROAD_FILE_OK) return status;
    buffer = (unsigned char*)mem_alloc(mem, (size_t)record, 1);
    if (buffer == NULL) return fail(why, size, ROAD_FILE_NO_MEMORY, path, "out of memory");
    if (fseek(stream, h->data_offset, SEEK_SET) != 0) {
        mem_free(mem, buffer);
        return fail(why, size, ROAD_FILE_UNREADABLE, path, "cannot be read: %s",
                    strerror(errno));
    }
    for (row = 0; row < d->rows; row++) {
        if (fread(buffer, 1, (size_t)record, stream) != (size_t)record) {
            mem_free(mem, buffer);
            return fail(why, size, ROAD_FILE_UNREADABLE, path, "cannot be read: %s",
                        strerror(errno));
        }
        for (k = 0; k < N_WANTED; k++)
            if (d->wanted[k] >= 0)
                d->column[k][row] = big_endian(buffer + (long)d->wanted[k] * width, width);
    }
    mem_free(mem, buffer);
    return ROAD_FILE_OK;
}

/* The next record of a text data section into record (its first capacity - 1 characters,
 * lines joined, each line's trailing '\r' removed, blank lines skipped); its full length in
 * *length; 0 at the end of the data, -1 when the data end inside the record (*lines: the
 * lines it had). */
static int next_record(FILE* stream, long lines_per_record, char* record, size_t capacity,
                       size_t* length, long* lines)
{
    long got = 0;
    *length = 0;
    *lines = 0;
    while (got < lines_per_record) {
        size_t line_start = *length, kept_end = *length, n = 0;
        int c, any = 0;
        while ((c = getc(stream)) != EOF && c != '\n') {
            any = 1;
            if (*length < capacity - 1) record[*length] = (char)c;
            (*length)++;
            n++;
            if (c != '\r') kept_end = *length;
        }
        *length = kept_end;  /* trailing '\r' dropped */
        if (*length > line_start) {
            got++;
        } else if (c == EOF) {
            break;
        }
        (void)any;
        (void)n;
        if (c == EOF) break;
    }
    if (*length < capacity) record[*length] = '\0';
    else record[capacity - 1] = '\0';
    *lines = got;
    if (got == 0) return 0;
    return got == lines_per_record ? 1 : -1;
}

static int read_text(const char* path, FILE* stream, const Header* h, Data* d,
                     const Memory* mem, char* why, size_t size)
{
    long chars = h->format[1] == 'D' ? 20 : 10, per_line = h->format[1] == 'D' ? 4 : 8;
    long lines_per_record = (h->n_channels + per_line - 1) / per_line;
    long needed = h->n_channels * chars, rows = 0, got, row;
    size_t capacity = (size_t)needed + 1, length;
    char* record;
    int status, k;
    double end, last;
    record = (char*)mem_alloc(mem, capacity, 1);
    if (record == NULL) return fail(why, size, ROAD_FILE_NO_MEMORY, path, "out of memory");
    /* first: count the records and check each holds its values */
    if (fseek(stream, h->data_offset, SEEK_SET) != 0) {
        mem_free(mem, record);
        return fail(why, size, ROAD_FILE_UNREADABLE, path, "cannot be read: %s",
                    strerror(errno));
    }
    for (;;) {
        int more = next_record(stream, lines_per_record, record, capacity, &length, &got);
        if (more == 0) break;
        if (more < 0) {
            mem_free(mem, record);
            return fail(why, size, ROAD_FILE_MALFORMED, path,
                        "truncated: the last cross section has %ld of its %ld lines (%ld values "
                        "of %ld characters, %ld a line)", got, lines_per_record, h->n_channels,
                        chars, per_line);
        }
        if (rows >= ROAD_FILE_MAX_KNOTS) {
            mem_free(mem, record);
            return fail(why, size, ROAD_FILE_MALFORMED, path, "more than %ld cross sections",
                        ROAD_FILE_MAX_KNOTS);
        }
        if ((long)length < needed) {
            mem_free(mem, record);
            return fail(why, size, ROAD_FILE_MALFORMED, path,
                        "cross section %ld holds %ld characters: %ld values of %ld characters "
                        "need %ld (truncated or not %s)", rows + 1, (long)length,
                        h->n_channels, chars, needed, h->format);
        }
        rows++;
    }
    if (rows < 2) {
        mem_free(mem, record);
        return fail(why, size, ROAD_FILE_MALFORMED, path,
                    "%ld cross sections of data: a road needs 2", rows);
    }
    d->rows = rows;
    end = h->road[R_END_U];
    last = d->start_u + (double)(rows - 1) * d->increment;
    if (h->road_given[R_END_U] && fabs(end - last) > 0.5 * d->increment) {
        mem_free(mem, record);
        return fail(why, size, ROAD_FILE_MALFORMED, path,
                    "the data hold %ld cross sections, to u = %g m, but reference_line_end_u = "
                    "%g m: truncated, or the header is wrong", rows, last, end);
    }
    status = allocate_columns(d, mem, path, why, size);
    if (status == ROAD_FILE_OK && fseek(stream, h->data_offset, SEEK_SET) != 0)
        status = fail(why, size, ROAD_FILE_UNREADABLE, path, "cannot be read: %s",
                      strerror(errno));
    for (row = 0; status == ROAD_FILE_OK && row < rows; row++) {
        next_record(stream, lines_per_record, record, capacity, &length, &got);
        for (k = 0; k < N_WANTED; k++)
            if (d->wanted[k] >= 0)
                d->column[k][row] = text_value(record + (long)d->wanted[k] * chars,
                                               (size_t)chars);
    }
    mem_free(mem, record);
    return status;
}

/* -- from the grid to the road -------------------------------------------------------------- */

typedef struct {
    long n;          /* long sections */
    double* v;       /* their v, right to left */
    long* channel;   /* the channel of each */
} Sections;

static int compare_channels(const void* a, const void* b)
{
    const double x = ((const double*)a)[0], y = ((const double*)b)[0];
    return (x > y) - (x < y);
}

static int long_sections(const char* path, const Header* h, Sections* s, const Memory* mem,
                         char* why, size_t size)
{
    long k, n = 0;
    double* pairs;
    for (k = 0; k < h->n_channels; k++) n += h->channels[k].kind == 'z';
    s->n = n;
    s->v = (double*)mem_alloc(mem, (size_t)n, sizeof(double));
    s->channel = (long*)mem_alloc(mem, (size_t)n, sizeof(long));
    pairs = (double*)mem_alloc(mem, (size_t)(2 * n), sizeof(double));
    if (s->v == NULL || s->channel == NULL || pairs == NULL) {
        mem_free(mem, pairs);
        return fail(why, size, ROAD_FILE_NO_MEMORY, path, "out of memory");
    }
    n = 0;
    for (k = 0; k < h->n_channels; k++)
        if (h->channels[k].kind == 'z') {
            pairs[2 * n] = h->channels[k].v;
            pairs[2 * n + 1] = (double)k;
            n++;
        }
    qsort(pairs, (size_t)n, 2 * sizeof(double), compare_channels);
    for (k = 0; k < n; k++) s->channel[k] = (long)pairs[2 * k + 1];
    if (h->by_number) {
        double increment, right;
        for (k = 0; k < n; k++)
            if (pairs[2 * k] != (double)(k + 1)) {
                mem_free(mem, pairs);
                return fail(why, size, ROAD_FILE_MALFORMED, path,
                            "long sections numbered other than 1 to %ld, each once", n);
            }
        mem_free(mem, pairs);
        if (!h->road_given[R_V_INCREMENT])
            return fail(why, size, ROAD_FILE_MALFORMED, path,
                        "long sections by number need long_section_v_increment in $ROAD_CRG");
        increment = h->road[R_V_INCREMENT];
        if (!(increment >= ROAD_FILE_MIN_INCREMENT_M && increment <= 1e3))
            return fail(why, size, ROAD_FILE_MALFORMED, path,
                        "long_section_v_increment = %g m: must be in [%g, 1000] m", increment,
                        ROAD_FILE_MIN_INCREMENT_M);
        right = h->road_given[R_V_RIGHT] ? h->road[R_V_RIGHT] : 0.0;
        for (k = 0; k < n; k++) s->v[k] = right + increment * (double)k;
    } else {
        for (k = 0; k < n; k++) s->v[k] = pairs[2 * k];
        mem_free(mem, pairs);
        for (k = 0; k + 1 < n; k++)
            if (s->v[k + 1] - s->v[k] < ROAD_FILE_MIN_INCREMENT_M)
                return fail(why, size, ROAD_FILE_MALFORMED, path,
                            "long sections at v = %g and %g m: closer than %g m", s->v[k],
                            s->v[k + 1], ROAD_FILE_MIN_INCREMENT_M);
    }
    if (h->road_given[R_V_RIGHT] && fabs(h->road[R_V_RIGHT] - s->v[0])
                                        > ROAD_FILE_HEADER_TOLERANCE_M)
        return fail(why, size, ROAD_FILE_MALFORMED, path,
                    "long_section_v_right = %g m, but the long sections' right edge is at v = "
                    "%g m", h->road[R_V_RIGHT], s->v[0]);
    if (h->road_given[R_V_LEFT] && fabs(h->road[R_V_LEFT] - s->v[n - 1])
                                       > ROAD_FILE_HEADER_TOLERANCE_M)
        return fail(why, size, ROAD_FILE_MALFORMED, path,
                    "long_section_v_left = %g m, but the long sections' left edge is at v = "
                    "%g m", h->road[R_V_LEFT], s->v[n - 1]);
    for (k = 0; k < n; k++)
        if (fabs(s->v[k]) > ROAD_FILE_MAX_ABS_DISTANCE_M)
            return fail(why, size, ROAD_FILE_MALFORMED, path, "long sections beyond %g m",
                        ROAD_FILE_MAX_ABS_DISTANCE_M);
    return ROAD_FILE_OK;
}

/* (j, f): v between long sections j and j + 1 at fraction f, as the C API finds them */
static void v_weights(const Header* h, const Sections* s, double v, long* j, double* f)
{
    long n = s->n;
    if (h->by_number) {
        double fraction = (v - s->v[0]) / h->road[R_V_INCREMENT];
        long index;
        if (fraction < 0.0) { *j = 0; *f = 0.0; return; }
        index = (long)fraction;
        if (index >= n - 1) { *j = n - 2; *f = 1.0; return; }
        *j = index;
        *f = fraction - (double)index;
    } else {
        long lo = 0, hi = n;  /* the last k with v[k] <= v, clipped to [0, n - 2] */
        double fraction;
        while (lo < hi) {
            long mid = lo + (hi - lo) / 2;
            if (s->v[mid] <= v) lo = mid + 1;
            else hi = mid;
        }
        lo -= 1;
        if (lo < 0) lo = 0;
        if (lo > n - 2) lo = n - 2;
        fraction = (v - s->v[lo]) / (s->v[lo + 1] - s->v[lo]);
        *j = lo;
        *f = fraction < 0.0 ? 0.0 : fraction > 1.0 ? 1.0 : fraction;
    }
}

/* column slots of Data */
enum { W_TRACK, W_TRACK_NEXT, W_REF, W_REF_NEXT, W_SLOPE, W_BANK };

static int section_heights(const char* path, const Data* d, int slot, long j, double f,
                           double v, const char* what, double* out, char* why, size_t size)
{
    const double* near = d->column[slot];
    const double* far = d->column[slot + 1];
    long row, pass;
    for (pass = 0; pass < 2; pass++) {
        const double* values = pass == 0 ? near : far;
        long k = j + pass;
        if ((pass == 0 && f == 1.0) || (pass == 1 && f == 0.0)) continue;
        for (row = 0; row < d->rows; row++)
            if (!isfinite(values[row]))
                return fail(why, size, ROAD_FILE_MALFORMED, path,
                            "no height (NaN) in long section %ld at u = %g m (cross section "
                            "%ld), which %s at v = %g m reads", k + 1,
                            d->start_u + (double)row * d->increment, row + 1, what, v);
        for (row = 0; row < d->rows; row++)
            if (fabs(values[row]) > ROAD_FILE_MAX_ABS_HEIGHT_M)
                return fail(why, size, ROAD_FILE_MALFORMED, path,
                            "height %.6g m in long section %ld at u = %g m (cross section "
                            "%ld), which %s at v = %g m reads: beyond %g m, no road (a "
                            "damaged file?)", values[row], k + 1,
                            d->start_u + (double)row * d->increment, row + 1, what, v,
                            ROAD_FILE_MAX_ABS_HEIGHT_M);
    }
    for (row = 0; row < d->rows; row++)
        out[row] = f == 0.0 ? near[row] : f == 1.0 ? far[row]
                                                   : near[row] + f * (far[row] - near[row]);
    return ROAD_FILE_OK;
}

static int reference_line(const char* path, const Header* h, const Data* d, double* height,
                          char* why, size_t size)
{
    long n = d->rows, k;
    double start_slope = h->road_given[R_START_S] ? h->road[R_START_S] : 0.0;
    double start_z = h->road_given[R_START_Z] ? h->road[R_START_Z] : 0.0;
    const double* channel = d->wanted[W_SLOPE] >= 0 ? d->column[W_SLOPE] : NULL;
    double increment = d->increment;
    if (channel == NULL && start_slope == 0.0) {
        for (k = 0; k < n; k++) height[k] = start_z;
        return ROAD_FILE_OK;
    }
    if (channel != NULL)
        for (k = 1; k < n; k++)
            if (!isfinite(channel[k]))
                return fail(why, size, ROAD_FILE_MALFORMED, path,
                            "no reference line slope (NaN) at cross section %ld", k + 1);
#define SLOPE(k) (channel != NULL ? channel[k] : start_slope)
    if (!h->road_given[R_END_Z]) {
        height[0] = start_z;
        for (k = 0; k < n - 1; k++) height[k + 1] = height[k] + SLOPE(k + 1) * increment;
        return ROAD_FILE_OK;
    }
    height[n - 1] = h->road[R_END_Z];
    for (k = n - 1; k > 0; k--) height[k - 1] = height[k] - SLOPE(k) * increment;
    height[0] = start_z;
    for (k = 0; k < n - 2; k++) {
        double fraction = (double)k / (double)(n - 1);
        height[k + 1] = (1.0 - fraction) * (height[k] + SLOPE(k + 1) * increment)
                        + fraction * height[k + 1];
    }
#undef SLOPE
    return ROAD_FILE_OK;
}

static int banking(const char* path, const Header* h, const Data* d, const Sections* s,
                   int* has_bank, char* why, size_t size)
{
    double first, last;
    long k;
    int channel = d->wanted[W_BANK] >= 0;
    double start_b = h->road_given[R_START_B] ? h->road[R_START_B] : 0.0;
    double end_b = h->road_given[R_END_B] ? h->road[R_END_B] : 0.0;
    *has_bank = channel || start_b != 0.0 || end_b != 0.0;
    if (!*has_bank) return ROAD_FILE_OK;
    if (h->by_number) {
        first = h->road_given[R_V_RIGHT] ? h->road[R_V_RIGHT] : 0.0;
    } else {
        double smallest = INFINITY, largest = -INFINITY;
        for (k = 0; k + 1 < s->n; k++) {
            double gap = s->v[k + 1] - s->v[k];
            if (gap < smallest) smallest = gap;
            if (gap > largest) largest = gap;
        }
        first = (largest - smallest) / smallest < 1e-3 ? s->v[0]
                : h->road_given[R_V_RIGHT] ? h->road[R_V_RIGHT] : 0.0;
    }
    last = h->road_given[R_V_LEFT] ? h->road[R_V_LEFT] : 0.0;
    if (fabs(first - s->v[0]) > ROAD_FILE_HEADER_TOLERANCE_M
        || fabs(last - s->v[s->n - 1]) > ROAD_FILE_HEADER_TOLERANCE_M)
        return fail(why, size, ROAD_FILE_MALFORMED, path,
                    "a banked road needs long_section_v_right and long_section_v_left at its "
                    "outer long sections (v = %g and %g m): the OpenCRG C API clamps v to them "
                    "for the banking", s->v[0], s->v[s->n - 1]);
    if (channel)
        for (k = 0; k < d->rows; k++)
            if (!isfinite(d->column[W_BANK][k]))
                return fail(why, size, ROAD_FILE_MALFORMED, path,
                            "no banking (NaN) at cross section %ld", k + 1);
    return ROAD_FILE_OK;
}

static double bank_at(const Header* h, const Data* d, long row)
{
    if (d->wanted[W_BANK] >= 0) return d->column[W_BANK][row];
    return h->road_given[R_START_B] ? h->road[R_START_B] : 0.0;
}

static int row_heights(const char* path, const Header* h, const Data* d, const Sections* s,
                       const double* reference, int has_bank, int slot, long j, double f,
                       double v, const char* what, double* out, char* why, size_t size)
{
    long row;
    double clamped = v < s->v[0] ? s->v[0] : v > s->v[s->n - 1] ? s->v[s->n - 1] : v;
    int status = section_heights(path, d, slot, j, f, v, what, out, why, size);
    if (status != ROAD_FILE_OK) return status;
    for (row = 0; row < d->rows; row++) {
        out[row] = out[row] + reference[row];
        if (has_bank) out[row] = out[row] + bank_at(h, d, row) * clamped;
    }
    return ROAD_FILE_OK;
}

static double at_u(const double* heights, long n, double first, double increment, double u)
{
    double fraction = (u - first) / increment;
    long k;
    if (fraction <= 0.0) return heights[0];
    k = (long)fraction;
    if (k >= n - 1) return heights[n - 1];
    fraction -= (double)k;
    return heights[k] + fraction * (heights[k + 1] - heights[k]);
}

/* the reference point's v (refpoint modifiers, or OpenCRG's defaults), and whether there is
 * one */
static int reference_point(const Header* h, const Sections* s, double* v)
{
    int by_ref = 0, by_off = 0, k;
    if (!h->has_mods) { *v = 0.0; return 1; }
    for (k = M_U_FRACTION; k <= M_PHI; k++)
        if (k != M_U_OFFSET && k != M_V_OFFSET && h->mods_given[k]) by_ref = 1;
    for (k = M_OFF_PHI; k <= M_OFF_Z; k++)
        if (h->mods_given[k]) by_off = 1;
    (void)by_off;
    if (!by_ref) return 0;
    if (h->mods_given[M_V]) *v = h->mods[M_V];
    else if (h->mods_given[M_V_FRACTION])
        *v = s->v[0] + h->mods[M_V_FRACTION] * (s->v[s->n - 1] - s->v[0])
             + (h->mods_given[M_V_OFFSET] ? h->mods[M_V_OFFSET] : 0.0);
    else *v = 0.0;
    return 1;
}

static double reference_point_u(const Header* h, const Data* d)
{
    double first = d->start_u, last = d->start_u + (double)(d->rows - 1) * d->increment;
    if (h->has_mods && h->mods_given[M_U]) return h->mods[M_U];
    if (!h->has_mods) return first;
    return first + (h->mods_given[M_U_FRACTION] ? h->mods[M_U_FRACTION] : 0.0) * (last - first)
           + (h->mods_given[M_U_OFFSET] ? h->mods[M_U_OFFSET] : 0.0);
}

static int read_crg(const char* path, FILE* stream, long file_bytes, double lateral_offset_m,
                    const Memory* mem, RoadFile* road, char* why, size_t size)
{
    Header h;
    Sections s;
    Data d;
    double v, ref_v = 0.0, ref_f = 0.0, shift = 0.0;
    double *reference = NULL, *heights = NULL, *ref_heights = NULL;
    long j = 0, ref_j = 0, k;
    int status, has_ref, has_bank = 0;
    memset(&h, 0, sizeof h);
    memset(&s, 0, sizeof s);
    memset(&d, 0, sizeof d);
    for (k = 0; k < N_WANTED; k++) d.wanted[k] = -1;
    status = read_header(path, stream, file_bytes, &h, mem, why, size);
    if (status == ROAD_FILE_OK) status = long_sections(path, &h, &s, mem, why, size);
    if (status == ROAD_FILE_OK
        && !(s.v[0] - ROAD_FILE_V_BORDER_M <= lateral_offset_m
             && lateral_offset_m <= s.v[s.n - 1] + ROAD_FILE_V_BORDER_M))
        status = fail(why, size, ROAD_FILE_MALFORMED, path,
                      "lateral offset %g m: outside the road's width, v from %g to %g m",
                      lateral_offset_m, s.v[0], s.v[s.n - 1]);
    if (status == ROAD_FILE_OK) {
        double f = 0.0;
        v = lateral_offset_m < s.v[0] ? s.v[0]
            : lateral_offset_m > s.v[s.n - 1] ? s.v[s.n - 1] : lateral_offset_m;
        v_weights(&h, &s, v, &j, &f);
        d.wanted[W_TRACK] = (int)s.channel[j];
        d.wanted[W_TRACK_NEXT] = (int)s.channel[j + 1];
        has_ref = reference_point(&h, &s, &ref_v);
        if (has_ref) {
            v_weights(&h, &s, ref_v, &ref_j, &ref_f);
            d.wanted[W_REF] = (int)s.channel[ref_j];
            d.wanted[W_REF_NEXT] = (int)s.channel[ref_j + 1];
        }
        for (k = 0; k < h.n_channels; k++) {
            if (h.channels[k].kind == 's') d.wanted[W_SLOPE] = (int)k;
            if (h.channels[k].kind == 'b') d.wanted[W_BANK] = (int)k;
        }
        d.start_u = h.road_given[R_START_U] ? h.road[R_START_U] : 0.0;
        d.increment = h.road[R_INCREMENT];
        status = h.format[2] == 'B'
                 ? read_binary(path, stream, file_bytes, &h, &d, mem, why, size)
                 : read_text(path, stream, &h, &d, mem, why, size);
        if (status == ROAD_FILE_OK
            && (fabs(d.start_u) > ROAD_FILE_MAX_ABS_DISTANCE_M
                || fabs(d.start_u + (double)(d.rows - 1) * d.increment)
                       > ROAD_FILE_MAX_ABS_DISTANCE_M))
            status = fail(why, size, ROAD_FILE_MALFORMED, path,
                          "u from %g m over %ld cross sections: beyond %g m", d.start_u, d.rows,
                          ROAD_FILE_MAX_ABS_DISTANCE_M);
        if (status == ROAD_FILE_OK) {
            reference = (double*)mem_alloc(mem, (size_t)d.rows, sizeof(double));
            heights = (double*)mem_alloc(mem, (size_t)d.rows, sizeof(double));
            ref_heights = (double*)mem_alloc(mem, (size_t)d.rows, sizeof(double));
            if (reference == NULL || heights == NULL || ref_heights == NULL)
                status = fail(why, size, ROAD_FILE_NO_MEMORY, path, "out of memory");
        }
        if (status == ROAD_FILE_OK) status = reference_line(path, &h, &d, reference, why, size);
        if (status == ROAD_FILE_OK) status = banking(path, &h, &d, &s, &has_bank, why, size);
        if (status == ROAD_FILE_OK)
            status = row_heights(path, &h, &d, &s, reference, has_bank, W_TRACK, j, f, v,
                                 "the tire's track", heights, why, size);
        if (status == ROAD_FILE_OK && has_ref) {
            status = row_heights(path, &h, &d, &s, reference, has_bank, W_REF, ref_j, ref_f,
                                 ref_v, "the reference point (refpoint, OpenCRG's default: the "
                                 "start of the reference line)", ref_heights, why, size);
            if (status == ROAD_FILE_OK)
                shift = (h.has_mods && h.mods_given[M_Z] ? h.mods[M_Z] : 0.0)
                        - at_u(ref_heights, d.rows, d.start_u, d.increment,
                               reference_point_u(&h, &d));
        } else if (status == ROAD_FILE_OK && h.has_mods) {
            for (k = M_OFF_PHI; k <= M_OFF_Z; k++)
                if (h.mods_given[k]) shift = h.mods_given[M_OFF_Z] ? h.mods[M_OFF_Z] : 0.0;
        }
        if (status == ROAD_FILE_OK) {
            for (k = 0; k < d.rows; k++) {
                heights[k] = heights[k] + shift;
                if (!(fabs(heights[k]) <= ROAD_FILE_MAX_ABS_HEIGHT_M)) {
                    status = fail(why, size, ROAD_FILE_MALFORMED, path,
                                  "heights beyond %g m along v = %g m",
                                  ROAD_FILE_MAX_ABS_HEIGHT_M, v);
                    break;
                }
            }
        }
        if (status == ROAD_FILE_OK) {
            road->n = (size_t)d.rows;
            road->s = reference;  /* reused for the distances */
            road->z = heights;
            reference = heights = NULL;
            for (k = 0; k < d.rows; k++) road->s[k] = d.start_u + d.increment * (double)k;
            road->lateral_offset_m = v;
            road->height_shift_m = shift;
            memcpy(road->format, h.format, 5);
        }
    }
    for (k = 0; k < N_WANTED; k++) mem_free(mem, d.column[k]);
    mem_free(mem, h.channels);
    mem_free(mem, s.v);
    mem_free(mem, s.channel);
    mem_free(mem, reference);
    mem_free(mem, heights);
    mem_free(mem, ref_heights);
    return status;
}

/* -- profiles ------------------------------------------------------------------------------- */

/* a whole field as a number (as Python's float reads it), 1; 0 when it is none; non-finite
 * spellings (nan, inf) read as such */
static int field_number(const char* field, size_t n, double* value)
{
    size_t skip, length;
    char buffer[64];
    const char* words[] = {"nan", "+nan", "-nan", "inf", "+inf", "-inf", "infinity",
                           "+infinity", "-infinity"};
    size_t k;
    if (n >= sizeof buffer) n = sizeof buffer - 1;
    memcpy(buffer, field, n);
    buffer[n] = '\0';
    for (k = 0; k < sizeof words / sizeof words[0]; k++) {
        size_t i = 0;
        while (words[k][i] && buffer[i]
               && ((buffer[i] >= 'A' && buffer[i] <= 'Z') ? buffer[i] - 'A' + 'a' : buffer[i])
                      == words[k][i])
            i++;
        if (words[k][i] == '\0' && buffer[i] == '\0') {
            *value = words[k][strlen(words[k]) - 1] == 'n' ? NAN
                     : (buffer[0] == '-' ? -INFINITY : INFINITY);
            return 1;
        }
    }
    length = number_length(buffer, &skip, 0);
    if (length == 0 || skip != 0 || length != n) return 0;
    *value = number_value(buffer, length);
    return 1;
}

static int is_separator(char c) { return c == ',' || is_space(c); }

static int read_profile(const char* path, FILE* stream, const Memory* mem, RoadFile* road,
                        char* why, size_t size)
{
    char line[LINE_CHARS];
    long number = 0, offset = 0, n = 0, capacity = 0, last_line = 0;
    int header_allowed = 1, status = ROAD_FILE_OK, first = 1;
    double *s = NULL, *z = NULL;
    while (status == ROAD_FILE_OK && next_line(stream, line, &offset) >= 0) {
        char* content = line;
        char* hash;
        size_t length;
        const char* fields[3];
        size_t lengths[3];
        int count = 0;
        double distance, height;
        int ok_distance, ok_height;
        number++;
        if (first) {  /* a UTF-8 byte-order mark is no part of the text */
            first = 0;
            if ((unsigned char)content[0] == 0xEF && (unsigned char)content[1] == 0xBB
                && (unsigned char)content[2] == 0xBF)
                content += 3;
        }
        hash = strchr(content, '#');
        if (hash) *hash = '\0';
        while (is_space(*content)) content++;
        length = strlen(content);
        while (length > 0 && is_space(content[length - 1])) content[--length] = '\0';
        if (length == 0) continue;
        {
            size_t i = 0;
            while (i < length) {
                size_t start;
                while (i < length && is_separator(content[i])) i++;
                if (i >= length) break;
                start = i;
                while (i < length && !is_separator(content[i])) i++;
                if (count < 3) {
                    fields[count] = content + start;
                    lengths[count] = i - start;
                }
                count++;
            }
        }
        if (count != 2) {
            status = fail(why, size, ROAD_FILE_MALFORMED, path,
                          "line %ld: %d values in '%.60s': a profile line holds two, distance "
                          "(m) and height (m)", number, count, content);
            break;
        }
        ok_distance = field_number(fields[0], lengths[0], &distance);
        ok_height = field_number(fields[1], lengths[1], &height);
        if (!ok_distance || !ok_height) {
            if (header_allowed && !ok_distance && !ok_height) {
                header_allowed = 0;
                continue;
            }
            status = fail(why, size, ROAD_FILE_MALFORMED, path,
                          "line %ld: '%.60s': not two numbers (distance m, height m)", number,
                          content);
            break;
        }
        header_allowed = 0;
        if (!isfinite(distance) || !isfinite(height)) {
            status = fail(why, size, ROAD_FILE_MALFORMED, path,
                          "line %ld: '%.60s': distance and height must be finite", number,
                          content);
            break;
        }
        if (fabs(distance) > ROAD_FILE_MAX_ABS_DISTANCE_M
            || fabs(height) > ROAD_FILE_MAX_ABS_HEIGHT_M) {
            status = fail(why, size, ROAD_FILE_MALFORMED, path,
                          "line %ld: '%.60s': beyond %g m along or %g m high", number, content,
                          ROAD_FILE_MAX_ABS_DISTANCE_M, ROAD_FILE_MAX_ABS_HEIGHT_M);
            break;
        }
        if (n > 0 && distance <= s[n - 1]) {
            status = fail(why, size, ROAD_FILE_MALFORMED, path,
                          "line %ld: distance %.15g m after %.15g m (line %ld): distances must "
                          "strictly increase", number, distance, s[n - 1], last_line);
            break;
        }
        if (n >= ROAD_FILE_MAX_KNOTS) {
            status = fail(why, size, ROAD_FILE_MALFORMED, path, "more than %ld points",
                          ROAD_FILE_MAX_KNOTS);
            break;
        }
        if (n >= capacity) {  /* grows with what was read, never with a declared size */
            long grown = capacity ? 2 * capacity : 1024;
            double *more_s, *more_z;
            if (grown > ROAD_FILE_MAX_KNOTS) grown = ROAD_FILE_MAX_KNOTS;
            more_s = (double*)mem_alloc(mem, (size_t)grown, sizeof(double));
            more_z = (double*)mem_alloc(mem, (size_t)grown, sizeof(double));
            if (more_s == NULL || more_z == NULL) {
                mem_free(mem, more_s);
                mem_free(mem, more_z);
                status = fail(why, size, ROAD_FILE_NO_MEMORY, path, "out of memory");
                break;
            }
            if (n) {
                memcpy(more_s, s, (size_t)n * sizeof(double));
                memcpy(more_z, z, (size_t)n * sizeof(double));
            }
            mem_free(mem, s);
            mem_free(mem, z);
            s = more_s;
            z = more_z;
            capacity = grown;
        }
        s[n] = distance;
        z[n] = height;
        n++;
        last_line = number;
    }
    if (status == ROAD_FILE_OK && ferror(stream))
        status = fail(why, size, ROAD_FILE_UNREADABLE, path, "cannot be read: %s",
                      strerror(errno));
    if (status == ROAD_FILE_OK && n < 2)
        status = fail(why, size, ROAD_FILE_MALFORMED, path,
                      "%ld points: a road profile needs at least 2 lines of distance (m) and "
                      "height (m)", n);
    if (status != ROAD_FILE_OK) {
        mem_free(mem, s);
        mem_free(mem, z);
        return status;
    }
    road->n = (size_t)n;
    road->s = s;
    road->z = z;
    road->lateral_offset_m = 0.0;
    road->height_shift_m = 0.0;
    memcpy(road->format, "profile", 8);
    return ROAD_FILE_OK;
}

/* -- the road --------------------------------------------------------------------------------- */

static int looks_like_crg(const char* path, FILE* stream)
{
    size_t n = strlen(path), i = 0, got;
    char head[256];
    const char* tags[] = {"$CT", "$ROAD_CRG", "$KD_DEFINITION"};
    if (n >= 4 && path[n - 4] == '.' && starts_with_nocase(path + n - 3, "crg")) return 1;
    got = fread(head, 1, sizeof head - 1, stream);
    head[got] = '\0';
    rewind(stream);
    while (i < got && (head[i] == ' ' || head[i] == '\t' || head[i] == '\r' || head[i] == '\n'))
        i++;
    for (n = 0; n < 3; n++)
        if (starts_with_nocase(head + i, tags[n])) return 1;
    return 0;
}

int road_file_open(const char* path, double lateral_offset_m, const Memory* mem,
                   RoadFile* road, char* why, size_t why_size)
{
    FILE* stream;
    long file_bytes;
    int status, crg;
    size_t k;
    char probe;
    if (why != NULL && why_size > 0) why[0] = '\0';
    if (road == NULL || path == NULL) {
        if (why != NULL && why_size > 0) snprintf(why, why_size, "road_file_open: no road or path");
        return ROAD_FILE_BAD_ARGUMENT;
    }
    memset(road, 0, sizeof *road);
    road->mem = mem != NULL ? mem : mem_default();
    mem = road->mem;
    if (!isfinite(lateral_offset_m))
        return fail(why, why_size, ROAD_FILE_BAD_ARGUMENT, path,
                    "lateral offset %g m: must be a finite number", lateral_offset_m);
    errno = 0;
    stream = fopen(path, "rb");
    if (stream == NULL)
        return fail(why, why_size, ROAD_FILE_UNREADABLE, path, "cannot be read: %s",
                    strerror(errno));
    errno = 0;
    if (fread(&probe, 1, 1, stream) != 1 && ferror(stream)) {
        int code = errno;
        fclose(stream);
        if (code == EISDIR)
            return fail(why, why_size, ROAD_FILE_UNREADABLE, path,
                        "is a folder, not a road file");
        return fail(why, why_size, ROAD_FILE_UNREADABLE, path, "cannot be read: %s",
                    strerror(code));
    }
    if (fseek(stream, 0, SEEK_END) != 0 || (file_bytes = ftell(stream)) < 0) {
        fclose(stream);
        return fail(why, why_size, ROAD_FILE_UNREADABLE, path,
                    "cannot be read: its size is unknown (more than the %ld bytes a road "
                    "file may hold?)", ROAD_FILE_MAX_BYTES);
    }
    rewind(stream);
    crg = looks_like_crg(path, stream);
    if (file_bytes > (crg ? ROAD_FILE_MAX_BYTES : ROAD_FILE_MAX_PROFILE_BYTES)) {
        fclose(stream);
        return fail(why, why_size, ROAD_FILE_UNREADABLE, path,
                    "%ld bytes: more than the %ld bytes a road file may hold", file_bytes,
                    crg ? ROAD_FILE_MAX_BYTES : ROAD_FILE_MAX_PROFILE_BYTES);
    }
    if (crg) {
        status = read_crg(path, stream, file_bytes, lateral_offset_m, mem, road, why, why_size);
    } else if (lateral_offset_m != 0.0) {
        status = fail(why, why_size, ROAD_FILE_BAD_ARGUMENT, path,
                      "a profile file has no width: the lateral offset %g m applies to OpenCRG "
                      "files only (leave it 0)", lateral_offset_m);
    } else {
        status = read_profile(path, stream, mem, road, why, why_size);
    }
    fclose(stream);
    if (status == ROAD_FILE_OK) {
        road->area = (double*)mem_alloc(mem, road->n, sizeof(double));
        if (road->area == NULL) {
            road_file_free(road);
            return fail(why, why_size, ROAD_FILE_NO_MEMORY, path, "out of memory");
        }
        road->area[0] = 0.0;
        for (k = 1; k < road->n; k++)
            road->area[k] = road->area[k - 1]
                            + 0.5 * (road->s[k] - road->s[k - 1]) * (road->z[k] + road->z[k - 1]);
    } else {
        road_file_free(road);
    }
    return status;
}

/* the knot s follows (the last k with s[k] <= s), clipped to [0, n - 2] */
static size_t segment(const RoadFile* road, double s_m)
{
    size_t lo = 0, hi = road->n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (road->s[mid] <= s_m) lo = mid + 1;
        else hi = mid;
    }
    if (lo == 0) return 0;
    lo -= 1;
    return lo > road->n - 2 ? road->n - 2 : lo;
}

static double segment_slope(const RoadFile* road, size_t k)
{
    return (road->z[k + 1] - road->z[k]) / (road->s[k + 1] - road->s[k]);
}

double road_file_height(const RoadFile* road, double s_m)
{
    size_t k = segment(road, s_m);
    double inside = s_m < road->s[0] ? road->s[0] : s_m > road->s[road->n - 1]
                                                     ? road->s[road->n - 1] : s_m;
    return road->z[k] + segment_slope(road, k) * (inside - road->s[k]);
}

double road_file_slope(const RoadFile* road, double s_m)
{
    if (s_m < road->s[0] || s_m > road->s[road->n - 1]) return 0.0;
    return segment_slope(road, segment(road, s_m));
}

double road_file_integral(const RoadFile* road, double s_m)
{
    size_t k = segment(road, s_m);
    double inside = s_m < road->s[0] ? road->s[0] : s_m > road->s[road->n - 1]
                                                     ? road->s[road->n - 1] : s_m;
    double slope = segment_slope(road, k), past = inside - road->s[k];
    double height = road->z[k] + slope * past;
    return road->area[k] + (road->z[k] + 0.5 * slope * past) * past + (s_m - inside) * height;
}

double road_file_mean(const RoadFile* road, double s_lo_m, double s_hi_m)
{
    double width = s_hi_m - s_lo_m;
    if (width <= 0.0) return road_file_height(road, s_lo_m);
    return (road_file_integral(road, s_hi_m) - road_file_integral(road, s_lo_m)) / width;
}

void road_file_extent(const RoadFile* road, double* first_m, double* last_m)
{
    if (first_m) *first_m = road->s[0];
    if (last_m) *last_m = road->s[road->n - 1];
}

void road_file_free(RoadFile* road)
{
    const Memory* mem;
    if (road == NULL) return;
    mem = road->mem != NULL ? road->mem : mem_default();
    mem_free(mem, road->s);
    mem_free(mem, road->z);
    mem_free(mem, road->area);
    road->s = road->z = road->area = NULL;
    road->n = 0;
}
