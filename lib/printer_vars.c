/*
 * Variables of the start/end G-code macros (docs/gcode.md, "Printer
 * profiles"): the profile's fields for the keys ampath maps (so that options
 * that change them change the G-code consistently), every other `.ini` key
 * from p->vars as written, and the runtime variables PrusaSlicer sets for a
 * job (amp_printer_job). The `.ini` does not record types: a value is a list
 * of numbers when every comma-separated piece is one, a list of strings when
 * it is quoted ("a";"b") or has semicolons and no spaces, else one string
 * with C-style escapes (as PrusaSlicer writes them).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "printer_internal.h"

/* ---------------------------------------------------------------- storing */

/* Offset of the entry of @p key in p->vars, or p->vars_len when absent. */
static size_t vars_find(const amp_printer *p, const char *key, size_t kn)
{
    size_t at = 0;
    while (at < p->vars_len) {
        const char *k = p->vars + at;
        size_t klen = strlen(k), vlen = strlen(k + klen + 1);
        if (klen == kn && memcmp(k, key, kn) == 0)
            return at;
        at += klen + vlen + 2;
    }
    return p->vars_len;
}

void amp_pr_vars_set(amp_printer *p, const char *key, size_t kn, const char *val, size_t vn)
{
    size_t at = vars_find(p, key, kn), room;
    char *d;
    if (at < p->vars_len) { /* a later file's key replaces the earlier one, as in the slicers */
        size_t len = strlen(p->vars + at) + 1;
        len += strlen(p->vars + at + len) + 1;
        memmove(p->vars + at, p->vars + at + len, p->vars_len - at - len);
        p->vars_len -= len;
    }
    room = sizeof p->vars - p->vars_len;
    d = p->vars + p->vars_len;
    if (kn + vn + 2 <= room) {
        memcpy(d, key, kn);
        d[kn] = '\0';
        memcpy(d + kn + 1, val, vn);
        d[kn + 1 + vn] = '\0';
        p->vars_len += kn + vn + 2;
        return;
    }
    p->n_vars_dropped++;
    if (kn + 3 <= room) { /* the name alone, marked: a macro naming it is told why it has no value */
        memcpy(d, key, kn);
        d[kn] = '\0';
        d[kn + 1] = '\001';
        d[kn + 2] = '\0';
        p->vars_len += kn + 3;
    }
}

/* The value of @p key in p->vars (NUL-terminated), NULL when absent. */
static const char *vars_get(const amp_printer *p, const char *key, size_t kn)
{
    size_t at = vars_find(p, key, kn);
    return at < p->vars_len ? p->vars + at + kn + 1 : NULL;
}

/* ---------------------------------------------------------------- values as the .ini writes them */

int amp_pr_number(const char *s, size_t n, amp_pr_val *v)
{
    char buf[64];
    size_t k = 0, digits = 0;
    if (n == 0 || n >= sizeof buf)
        return 0;
    if (s[k] == '+' || s[k] == '-')
        k++;
    for (; k < n && s[k] >= '0' && s[k] <= '9'; k++)
        digits++;
    if (k < n && s[k] == '.')
        for (k++; k < n && s[k] >= '0' && s[k] <= '9'; k++)
            digits++;
    if (digits == 0)
        return 0;
    if (k < n && (s[k] == 'e' || s[k] == 'E')) {
        size_t e0;
        k++;
        if (k < n && (s[k] == '+' || s[k] == '-'))
            k++;
        for (e0 = k; k < n && s[k] >= '0' && s[k] <= '9'; k++)
            ;
        if (k == e0)
            return 0;
    }
    if (k != n)
        return 0;
    /* strtod on a copy that is checked first: it would also take hexadecimal, inf and nan */
    memcpy(buf, s, n);
    buf[n] = '\0';
    v->t = MV_NUM;
    v->d = strtod(buf, NULL);
    return isfinite(v->d);
}

enum { RAW_SCALAR, RAW_NUMBERS, RAW_QUOTED, RAW_LIST };

static int is_space(char ch) { return ch == ' ' || ch == '\t'; }

/* Piece @p s..e trimmed of blanks. */
static void trim(const char **s, const char **e)
{
    while (*s < *e && is_space(**s))
        (*s)++;
    while (*e > *s && is_space((*e)[-1]))
        (*e)--;
}

/* Which of the shapes the slicers write a value in (see the top of the file). */
static int raw_shape(const char *v)
{
    const char *s = v;
    if (*v == '"')
        return RAW_QUOTED;
    for (;;) {
        const char *e = strchr(s, ','), *a = s, *b;
        amp_pr_val x;
        b = e ? e : s + strlen(s);
        trim(&a, &b);
        if (!((b - a == 3 && memcmp(a, "nil", 3) == 0) || amp_pr_number(a, (size_t)(b - a), &x)))
            break;
        if (!e)
            return RAW_NUMBERS;
        s = e + 1;
    }
    return strchr(v, ';') && !strchr(v, ' ') ? RAW_LIST : RAW_SCALAR;
}

/* Number of values. */
static size_t raw_count(const char *v, int shape)
{
    size_t n = 1;
    const char *s;
    int quoted = 0;
    if (shape == RAW_SCALAR)
        return 1;
    for (s = v; *s; s++) {
        if (shape == RAW_QUOTED && *s == '\\' && s[1])
            s++;
        else if (shape == RAW_QUOTED && *s == '"')
            quoted = !quoted;
        else if (!quoted && *s == (shape == RAW_NUMBERS ? ',' : ';'))
            n++;
    }
    return n;
}

/* The string s..e with C-style escapes resolved (`\n`, `\r`, `\t`, else the character), in the arena if any. */
static amp_status unescape(amp_pr_ctx *c, const char *s, const char *e, amp_pr_val *v)
{
    char *d;
    size_t k = 0;
    v->t = MV_STR;
    v->s = s;
    v->n = (size_t)(e - s);
    if (!memchr(s, '\\', v->n))
        return AMP_OK;
    if (!(d = amp_pr_alloc(c, v->n)))
        return c->st;
    for (; s < e; s++) {
        char ch = *s;
        if (ch == '\\' && s + 1 < e) {
            ch = *++s;
            ch = ch == 'n' ? '\n' : ch == 'r' ? '\r' : ch == 't' ? '\t' : ch;
        }
        d[k++] = ch;
    }
    v->s = d;
    v->n = k;
    return AMP_OK;
}

/* Value @p k of a list: its piece s..e (quotes of a quoted string removed). */
static void raw_piece(const char *v, int shape, size_t k, const char **s, const char **e)
{
    char sep = shape == RAW_NUMBERS ? ',' : ';';
    const char *p = v;
    int quoted = 0;
    for (; k > 0 && *p; p++) {
        if (shape == RAW_QUOTED && *p == '\\' && p[1])
            p++;
        else if (shape == RAW_QUOTED && *p == '"')
            quoted = !quoted;
        else if (!quoted && *p == sep)
            k--;
    }
    *s = p;
    for (quoted = 0; *p && (quoted || *p != sep); p++) {
        if (shape == RAW_QUOTED && *p == '\\' && p[1])
            p++;
        else if (shape == RAW_QUOTED && *p == '"')
            quoted = !quoted;
    }
    *e = p;
    trim(s, e);
    if (shape == RAW_QUOTED && *e - *s >= 2 && **s == '"' && (*e)[-1] == '"')
        (*s)++, (*e)--;
}

/* Keys PrusaSlicer keeps as integers (the temperatures): the rest of the numbers are decimals. */
static int int_key(const char *name, size_t n)
{
    static const char *const keys[] = {"temperature", "first_layer_temperature", "bed_temperature",
                                       "first_layer_bed_temperature", "nozzle_temperature",
                                       "nozzle_temperature_initial_layer", "hot_plate_temp",
                                       "hot_plate_temp_initial_layer", "disable_fan_first_layers"};
    size_t i;
    for (i = 0; i < sizeof keys / sizeof keys[0]; i++)
        if (strlen(keys[i]) == n && memcmp(keys[i], name, n) == 0)
            return 1;
    return 0;
}

/* Value @p k (< its count) of the raw `.ini` value @p raw of key @p name. */
static amp_status raw_value(amp_pr_ctx *c, const char *name, size_t n, const char *raw, int shape, size_t k,
                            amp_pr_val *v)
{
    const char *s, *e;
    if (shape == RAW_SCALAR)
        return unescape(c, raw, raw + strlen(raw), v);
    raw_piece(raw, shape, k, &s, &e);
    if (shape != RAW_NUMBERS)
        return unescape(c, s, e, v);
    if (e - s == 3 && memcmp(s, "nil", 3) == 0) {
        v->t = MV_NIL;
        return AMP_OK;
    }
    amp_pr_number(s, (size_t)(e - s), v);
    if (int_key(name, n) && v->d == (double)(long long)v->d && v->d >= -AMP_PR_INT_MAX && v->d <= AMP_PR_INT_MAX) {
        v->t = MV_INT;
        v->i = (long long)v->d;
    }
    return AMP_OK;
}

/* ---------------------------------------------------------------- the profile's fields */

enum { F_TEMP, F_TEMP1, F_BED, F_BED1, F_NOZZLE, F_FILAMENT, F_LAYER, F_LAYER1, F_HEIGHT, F_TRAVEL, F_RETRACT,
       F_RETRACT_SPEED, F_LIFT, F_BEFORE, F_MULT, F_FAN_OFF, F_MODEL, F_FLAVOR };

/* A name and the id it stands for: the profile's fields and the runtime variables. */
typedef struct kw_id {
    const char *key;
    int id;
} kw_id;

/* The id of the @p n characters at @p name in @p keys, -1 if none. */
static int kw_find(const kw_id *keys, size_t nk, const char *name, size_t n)
{
    size_t i;
    for (i = 0; i < nk; i++)
        if (strlen(keys[i].key) == n && memcmp(keys[i].key, name, n) == 0)
            return keys[i].id;
    return -1;
}

static int field_id(const char *name, size_t n)
{
    static const kw_id keys[] = {{"temperature", F_TEMP}, {"nozzle_temperature", F_TEMP}, {"first_layer_temperature", F_TEMP1},
                {"nozzle_temperature_initial_layer", F_TEMP1}, {"bed_temperature", F_BED},
                {"hot_plate_temp", F_BED}, {"first_layer_bed_temperature", F_BED1},
                {"hot_plate_temp_initial_layer", F_BED1}, {"bed_temperature_initial_layer_single", F_BED1},
                {"nozzle_diameter", F_NOZZLE}, {"filament_diameter", F_FILAMENT}, {"layer_height", F_LAYER},
                {"first_layer_height", F_LAYER1}, {"initial_layer_print_height", F_LAYER1},
                {"max_print_height", F_HEIGHT}, {"printable_height", F_HEIGHT}, {"travel_speed", F_TRAVEL},
                {"retract_length", F_RETRACT}, {"retraction_length", F_RETRACT},
                {"retract_speed", F_RETRACT_SPEED}, {"retraction_speed", F_RETRACT_SPEED},
                {"retract_lift", F_LIFT}, {"z_hop", F_LIFT}, {"retract_before_travel", F_BEFORE},
                {"retraction_minimum_travel", F_BEFORE}, {"extrusion_multiplier", F_MULT},
                {"filament_flow_ratio", F_MULT}, {"disable_fan_first_layers", F_FAN_OFF},
                {"close_fan_the_first_x_layers", F_FAN_OFF}, {"printer_model", F_MODEL},
                {"gcode_flavor", F_FLAVOR}};
    return kw_find(keys, sizeof keys / sizeof keys[0], name, n);
}

/* A field, or the option that overrides it when the job has options. */
static double field_number(const amp_printer *p, const amp_gcode_opts *o, int f)
{
    switch (f) {
    case F_TEMP: return o ? o->hotend_temp : p->temp;
    case F_TEMP1: return o ? o->first_layer_hotend_temp : p->first_layer_temp;
    case F_BED: return o ? o->bed_temp : p->bed_temp;
    case F_BED1: return o ? o->first_layer_bed_temp : p->first_layer_bed_temp;
    case F_NOZZLE: return p->nozzle_diameter;
    case F_FILAMENT: return o ? o->filament_diameter : p->filament_diameter;
    case F_LAYER: return p->layer_height;
    case F_LAYER1: return o ? o->first_layer_height : p->first_layer_height;
    case F_HEIGHT: return o ? o->max_height : p->max_height;
    case F_TRAVEL: return o ? o->travel_feed : p->travel_speed;
    case F_RETRACT: return o ? o->retract_length : p->retract_length;
    case F_RETRACT_SPEED: return o ? o->retract_speed : p->retract_speed;
    case F_LIFT: return o ? o->z_hop : p->retract_lift;
    case F_BEFORE: return o ? o->retract_min_travel : p->retract_before_travel;
    case F_MULT: return o ? o->flow : p->extrusion_multiplier;
    default: return o ? (double)o->fan_off_layers : (double)p->fan_off_layers; /* F_FAN_OFF */
    }
}

static void field_value(const amp_pr_ctx *c, int f, amp_pr_val *v)
{
    double x;
    if (f == F_MODEL) {
        v->t = MV_STR;
        v->s = c->p->model;
        v->n = strlen(c->p->model);
        return;
    }
    if (f == F_FLAVOR) {
        /* the file's own name for it ("marlin2", "reprap", ...) unless the job writes another flavour
         * (gcode --flavor): a start sequence can then leave out what the other firmware lacks */
        const char *raw = vars_get(c->p, "gcode_flavor", 12);
        int fl = c->job && c->job->opts ? c->job->opts->flavor : c->p->flavor;
        v->t = MV_STR;
        v->s = raw && fl == c->p->flavor ? raw : fl == AMP_FLAVOR_KLIPPER ? "klipper" : "marlin2";
        v->n = strlen(v->s);
        return;
    }
    x = field_number(c->p, c->job ? c->job->opts : NULL, f);
    v->t = MV_NUM;
    v->d = x;
    /* temperatures and the fan layers are integers in PrusaSlicer (integer division, "215" not "215.0") */
    if ((f <= F_BED1 || f == F_FAN_OFF) && x == (double)(long long)x && x >= -AMP_PR_INT_MAX && x <= AMP_PR_INT_MAX) {
        v->t = MV_INT;
        v->i = (long long)x;
    }
}

/* ---------------------------------------------------------------- runtime variables */

enum { R_TOOL, R_LAYER_NUM, R_LAYER_Z, R_MAX_Z, R_LAYERS, R_FL_MIN, R_FL_MAX, R_FL_SIZE, R_BED_MIN, R_BED_MAX,
       R_BED_SIZE, R_USED, R_WIPE, R_TOOLCHANGES, R_EXTRUDERS, R_ZHOP };

static int runtime_id(const char *name, size_t n)
{
    static const kw_id keys[] = {{"initial_tool", R_TOOL}, {"initial_extruder", R_TOOL}, {"current_extruder", R_TOOL},
                {"layer_num", R_LAYER_NUM}, {"layer_z", R_LAYER_Z}, {"max_layer_z", R_MAX_Z},
                {"total_layer_count", R_LAYERS}, {"first_layer_print_min", R_FL_MIN},
                {"first_layer_print_max", R_FL_MAX}, {"first_layer_print_size", R_FL_SIZE},
                {"print_bed_min", R_BED_MIN}, {"print_bed_max", R_BED_MAX}, {"print_bed_size", R_BED_SIZE},
                {"is_extruder_used", R_USED}, {"has_wipe_tower", R_WIPE}, {"total_toolchanges", R_TOOLCHANGES},
                {"num_extruders", R_EXTRUDERS}, {"zhop", R_ZHOP}};
    return kw_find(keys, sizeof keys / sizeof keys[0], name, n);
}

/* Extruders the profile describes: the values of nozzle_diameter (ampath prints with the first). */
static size_t extruders(const amp_printer *p)
{
    const char *raw = vars_get(p, "nozzle_diameter", 15);
    return raw && raw[0] != '\001' ? raw_count(raw, raw_shape(raw)) : 1;
}

/* Value @p k of a two-value (x, y) runtime variable. */
static double xy_value(const amp_pr_ctx *c, int r, size_t k)
{
    const amp_printer_job *j = c->job;
    const amp_gcode_opts *o = j ? j->opts : NULL;
    double b0[2], b1[2];
    b0[0] = o ? o->bed_min_x : c->p->bed_min_x;
    b0[1] = o ? o->bed_min_y : c->p->bed_min_y;
    b1[0] = o ? o->bed_max_x : c->p->bed_max_x;
    b1[1] = o ? o->bed_max_y : c->p->bed_max_y;
    switch (r) {
    case R_FL_MIN: return j ? j->first_layer_min[k] : b0[k];
    case R_FL_MAX: return j ? j->first_layer_max[k] : b1[k];
    case R_FL_SIZE: return j ? j->first_layer_max[k] - j->first_layer_min[k] : b1[k] - b0[k];
    case R_BED_MIN: return b0[k];
    case R_BED_MAX: return b1[k];
    default: return b1[k] - b0[k]; /* R_BED_SIZE */
    }
}

/* Runtime variable @p r, value @p k: ampath prints with the first extruder only (the others unused), no wipe
 * tower, no tool changes. */
static void runtime_value(amp_pr_ctx *c, int r, size_t k, amp_pr_val *v)
{
    const amp_printer_job *j = c->job;
    v->t = MV_INT;
    switch (r) {
    case R_LAYER_NUM: v->i = j ? j->layer_num : 0; break;
    case R_LAYERS: v->i = j ? j->layers : 0; break;
    case R_LAYER_Z: v->t = MV_NUM; v->d = j ? j->layer_z : 0.0; break;
    case R_MAX_Z: v->t = MV_NUM; v->d = j ? j->max_layer_z : 0.0; break;
    case R_ZHOP: v->t = MV_NUM; v->d = 0.0; break; /* the lift in effect: none before and after the job */
    case R_USED: v->t = MV_BOOL; v->i = k == 0; break;
    case R_WIPE: v->t = MV_BOOL; v->i = 0; break;
    case R_EXTRUDERS: v->i = (long long)extruders(c->p); break; /* the printer's, as PrusaSlicer's */
    case R_TOOL: case R_TOOLCHANGES: v->i = 0; break;
    default: v->t = MV_NUM; v->d = xy_value(c, r, k); break;
    }
    if (r == R_LAYER_NUM || r == R_LAYERS || r == R_LAYER_Z || r == R_MAX_Z || r == R_FL_MIN || r == R_FL_MAX ||
        r == R_FL_SIZE)
        c->used_job = 1;
}

static size_t runtime_count(const amp_pr_ctx *c, int r)
{
    if (r == R_USED)
        return extruders(c->p);
    return r >= R_FL_MIN && r <= R_BED_SIZE ? 2 : 1;
}

/* Keys every PrusaSlicer export has: empty when the profile lacks them (built-in profiles). */
static int default_value(const char *name, size_t n, amp_pr_val *v)
{
    static const char *const empty[] = {"print_settings_id", "filament_settings_id", "printer_settings_id",
                                        "physical_printer_settings_id", "printer_notes", "filament_notes",
                                        "notes"};
    size_t i;
    if (n == 8 && memcmp(name, "z_offset", 8) == 0) {
        v->t = MV_NUM;
        v->d = 0.0;
        return 1;
    }
    if (n == 42 && memcmp(name, "has_single_extruder_multi_material_priming", 42) == 0) {
        v->t = MV_BOOL; /* one extruder, no priming tower: the MMU profiles' plain branch */
        v->i = 0;
        return 1;
    }
    if ((n == 14 && memcmp(name, "input_filename", 14) == 0) ||
        (n == 19 && memcmp(name, "input_filename_base", 19) == 0)) {
        v->t = MV_STR; /* a display message ("M117 Print [input_filename]"): the job has no model file name here */
        v->s = n == 14 ? "ampath.gcode" : "ampath";
        v->n = strlen(v->s);
        return 1;
    }
    for (i = 0; i < sizeof empty / sizeof empty[0]; i++)
        if (strlen(empty[i]) == n && memcmp(empty[i], name, n) == 0) {
            v->t = MV_STR;
            v->s = "";
            v->n = 0;
            return 1;
        }
    return 0;
}

/* PrusaSlicer's date and time variables: refused, the same job must give the same G-code. */
static int refused(const char *name, size_t n)
{
    static const char *const keys[] = {"timestamp", "year", "month", "day", "hour", "minute", "second"};
    size_t i;
    for (i = 0; i < sizeof keys / sizeof keys[0]; i++)
        if (strlen(keys[i]) == n && memcmp(keys[i], name, n) == 0)
            return 1;
    return 0;
}

static amp_status unknown(amp_pr_ctx *c, const char *name, size_t n, const char *at)
{
    int w = n > 40 ? 40 : (int)n;
    if (c->p->n_vars_dropped)
        return amp_pr_fail(c, AMP_ERR_PARSE, at, "unknown variable '%.*s' (%lu .ini values did not fit in %d bytes)",
                           w, name, (unsigned long)c->p->n_vars_dropped, AMP_PRINTER_VARS_MAX);
    return amp_pr_fail(c, AMP_ERR_PARSE, at, "unknown variable '%.*s'", w, name);
}

amp_status amp_pr_var(amp_pr_ctx *c, const char *name, size_t n, long index, const char *at, amp_pr_val *v,
                      size_t *count)
{
    const char *raw;
    size_t cnt = 1, k = index < 0 ? 0 : (size_t)index;
    int f, r, shape = RAW_SCALAR, w = n > 40 ? 40 : (int)n;
    memset(v, 0, sizeof *v);
    if (refused(name, n))
        return amp_pr_fail(c, AMP_ERR_PARSE, at, "variable '%.*s' is refused: the G-code must not depend on the "
                           "date or time", w, name);
    r = runtime_id(name, n);
    raw = r < 0 ? vars_get(c->p, name, n) : NULL;
    if (raw && raw[0] == '\001' && raw[1] == '\0')
        return amp_pr_fail(c, AMP_ERR_PARSE, at, "variable '%.*s': its value did not fit in the profile's %d bytes "
                           "of .ini values", w, name, AMP_PRINTER_VARS_MAX);
    f = r < 0 ? field_id(name, n) : -1;
    if (r >= 0)
        cnt = runtime_count(c, r);
    else if (raw)
        cnt = raw_count(raw, shape = raw_shape(raw));
    else if (f < 0 && !default_value(name, n, v))
        return unknown(c, name, n, at);
    if (count)
        *count = cnt;
    if (k >= cnt)
        return amp_pr_fail(c, AMP_ERR_PARSE, at, "index %ld out of range: '%.*s' has %lu value%s", index, w, name,
                           (unsigned long)cnt, cnt == 1 ? "" : "s");
    if (r >= 0)
        runtime_value(c, r, k, v);
    else if (f >= 0 && k == 0)
        field_value(c, f, v);
    else if (raw)
        return raw_value(c, name, n, raw, shape, k, v);
    return AMP_OK;
}

int amp_pr_var_known(const amp_printer *p, const char *name, size_t n)
{
    amp_pr_val v;
    return refused(name, n) || runtime_id(name, n) >= 0 || field_id(name, n) >= 0 || vars_get(p, name, n) ||
           default_value(name, n, &v);
}
