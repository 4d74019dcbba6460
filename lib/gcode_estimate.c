/*
 * Print-time estimate of the G-code writer (docs/interfaces.md §5): a look-ahead planner
 * of AMP_GCODE_LOOKAHEAD blocks like the firmware's block buffer, with
 * trapezoidal speed profiles and the junction-deviation rule of Grbl/Marlin.
 * Split out of gcode.c; it only reads the options and adds to it->stats.
 */
#include <math.h>

#include "gcode_internal.h"


double amp_gcode_trapezoid_time(double len, double v0, double v1, double vmax, double accel)
{
    double da, dd, vp;
    if (len <= 0.0)
        return 0.0;
    if (vmax <= 0.0 || accel <= 0.0)
        return vmax > 0.0 ? len / vmax : 0.0;
    if (v0 > vmax)
        v0 = vmax;
    if (v1 > vmax)
        v1 = vmax;
    da = (vmax * vmax - v0 * v0) / (2.0 * accel);
    dd = (vmax * vmax - v1 * v1) / (2.0 * accel);
    if (da + dd <= len)
        return (vmax - v0) / accel + (vmax - v1) / accel + (len - da - dd) / vmax;
    /* triangle: the peak where the acceleration and deceleration ramps meet */
    vp = sqrt(0.5 * (2.0 * accel * len + v0 * v0 + v1 * v1));
    if (vp < v0)
        vp = v0;
    if (vp < v1)
        vp = v1;
    return (vp - v0) / accel + (vp - v1) / accel;
}

double amp_gcode_junction_default(int flavor, double accel)
{
    const double scv = 5.0; /* Klipper's default square_corner_velocity, mm/s */
    if (flavor != AMP_FLAVOR_KLIPPER)
        return 0.05;
    return accel > 0.0 ? scv * scv * (sqrt(2.0) - 1.0) / accel : 0.0;
}

static amp_gcode_block *plan_at(amp_gcode_iter *it, size_t k)
{
    return &it->plan[(it->plan_head + k) % AMP_GCODE_LOOKAHEAD];
}

/*
 * The backward pass after a block joined the window's end (at rest): each
 * block's vback = min(sqrt(next's vback^2 + 2 a len), vjunc), from the end
 * down. Where a value comes out as it was, every block below keeps its value
 * too, so the pass stops there (as Marlin's planner does); the figures are
 * those of a full pass from the end at every commit, bit for bit.
 */
static void plan_back(amp_gcode_iter *it)
{
    double vexit = 0.0;
    size_t k;
    for (k = it->plan_n; k-- > 1;) {
        amp_gcode_block *b = plan_at(it, k);
        double ventry = sqrt(vexit * vexit + 2.0 * b->acc * b->len);
        vexit = ventry < b->vjunc ? ventry : b->vjunc;
        if (k + 1 < it->plan_n && vexit == b->vback)
            break;
        b->vback = vexit;
    }
}

/*
 * Execute the oldest planned block: a backward pass over the window (which
 * must end at rest, as a firmware planner with a finite buffer must) gives the
 * highest speed it may leave with; a forward step from its entry speed gives
 * the reachable one.
 */
static void plan_commit(amp_gcode_iter *it)
{
    double vexit = it->plan_n > 1 ? plan_at(it, 1)->vback : 0.0, t, a;
    amp_gcode_block *b0 = plan_at(it, 0);
    a = b0->acc;
    {
        double reach = sqrt(it->plan_v * it->plan_v + 2.0 * a * b0->len);
        if (vexit > reach)
            vexit = reach;
        if (vexit > b0->vnom)
            vexit = b0->vnom;
    }
    t = amp_gcode_trapezoid_time(b0->len, it->plan_v, vexit, b0->vnom, a);
    it->stats.time += t;
    if (b0->travel)
        it->stats.travel_time += t;
    else
        it->stats.print_time += t;
    it->plan_v = vexit;
    it->plan_head = (it->plan_head + 1) % AMP_GCODE_LOOKAHEAD;
    it->plan_n--;
}

void amp_gc_plan_flush(amp_gcode_iter *it)
{
    while (it->plan_n > 0)
        plan_commit(it);
    it->plan_v = 0.0;
}

/* Junction speed limit between unit directions u1 (incoming) and u2 (Grbl/Marlin junction deviation), at the
 * outgoing move's acceleration. */
static double junction_speed(const amp_gcode_opts *o, const amp_gcode_block *p, const amp_gcode_block *b)
{
    double c = -(p->ux * b->ux + p->uy * b->uy + p->uz * b->uz), s;
    if (c > 0.999999)
        return 0.0; /* reversal */
    if (c < -0.999999)
        return HUGE_VAL; /* straight on */
    s = sqrt(0.5 * (1.0 - c));
    return sqrt(b->acc * o->junction_deviation * s / (1.0 - s));
}

/* Marlin's per-axis acceleration limit: the move's acceleration a is lowered until no axis, moving |d_axis| of
 * the move's len, accelerates beyond its own limit (a |d_axis| / len <= max_axis). */
static double axis_limited(double a, double max, double d_axis, double len)
{
    double f = fabs(d_axis);
    return max > 0.0 && f > 0.0 && a * f > max * len ? max * len / f : a;
}

void amp_gc_plan_move(amp_gcode_iter *it, amp_vec3 d, double len, double feed, double de, int travel)
{
    amp_gcode_block b;
    double v = feed, hxy = sqrt(d.x * d.x + d.y * d.y);
    if (!(len > 0.0))
        return;
    b.len = len;
    b.vback = 0.0;
    b.travel = travel;
    b.ux = d.x / len;
    b.uy = d.y / len;
    b.uz = d.z / len;
    /* the firmware clamps each axis to its maximum feed */
    if (hxy > 0.0 && v * hxy / len > it->o.max_feed_xy)
        v = it->o.max_feed_xy * len / hxy;
    if (fabs(d.z) > 0.0 && v * fabs(d.z) / len > it->o.max_feed_z)
        v = it->o.max_feed_z * len / fabs(d.z);
    if (de > 0.0 && v * de / len > it->o.max_feed_e)
        v = it->o.max_feed_e * len / de;
    b.vnom = v;
    b.acc = it->o.accel;
    b.acc = axis_limited(b.acc, it->o.max_accel_xy, hxy, len);
    b.acc = axis_limited(b.acc, it->o.max_accel_z, d.z, len);
    b.acc = axis_limited(b.acc, it->o.max_accel_e, de, len);
    if (it->plan_n == 0) {
        b.vjunc = it->plan_v; /* from rest after a flush, or continuing speed */
    } else {
        const amp_gcode_block *p = plan_at(it, it->plan_n - 1);
        double vj = junction_speed(&it->o, p, &b);
        if (vj > p->vnom)
            vj = p->vnom;
        if (vj > b.vnom)
            vj = b.vnom;
        b.vjunc = vj;
    }
    if (it->plan_n == AMP_GCODE_LOOKAHEAD)
        plan_commit(it);
    *plan_at(it, it->plan_n) = b;
    it->plan_n++;
    plan_back(it);
}

/* A retraction or its undoing (the filament alone), outside the print planner: from rest to rest, at the
 * retraction acceleration within the filament's limit. */
void amp_gc_plan_single(amp_gcode_iter *it, double len, double v)
{
    double t, a = it->o.retract_accel > 0.0 ? it->o.retract_accel : it->o.accel;
    amp_gc_plan_flush(it);
    if (it->o.max_accel_e > 0.0 && a > it->o.max_accel_e)
        a = it->o.max_accel_e;
    t = amp_gcode_trapezoid_time(len, 0.0, 0.0, v, a);
    it->stats.time += t;
    it->stats.travel_time += t;
}

