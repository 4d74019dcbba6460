/* Pictures of path sets (PNG rasterised here and encoded by preview_png.c, or SVG): `ampath preview` and the bindings.
 * In the library so that hosts (the Python binding) get the same bytes as the tool;
 * output goes through an amp_sink_fn, memory through the path set's allocator. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "ampath/preview.h"
#include "preview_internal.h"

#define LEGEND_H 110
#define MARGIN 24.0

/* ---------------------------------------------------------------- layout and colours */

typedef struct view {
    int iso;                /* 1 isometric, 0 top */
    double x0, y0, w, h;    /* panel in pixels */
    double scale, ox, oy;   /* screen = (proj - o) * scale + panel origin */
} view;

static const double ISO_C = 0.86602540378443865, ISO_S = 0.5;

/* Projection: screen x, screen y (downwards) and a depth (larger = nearer the viewer). */
static void project(int iso, amp_vec3 p, double *sx, double *sy, double *depth)
{
    if (iso) {
        /* camera along +(1,1,1): z points up on the screen */
        *sx = (p.x - p.y) * ISO_C;
        *sy = (p.x + p.y) * ISO_S - p.z;
        *depth = p.x + p.y + p.z;
    } else {
        *sx = p.x;
        *sy = -p.y;
        *depth = p.z;
    }
}

static void fit_view(view *v, const amp_pathset *ps)
{
    double minx = HUGE_VAL, miny = HUGE_VAL, maxx = -HUGE_VAL, maxy = -HUGE_VAL, ex, ey;
    size_t i;
    for (i = 0; i < ps->nverts; i++) {
        double sx, sy, d, r = ps->verts[i].r;
        project(v->iso, ps->verts[i].p, &sx, &sy, &d);
        minx = fmin(minx, sx - r);
        maxx = fmax(maxx, sx + r);
        miny = fmin(miny, sy - r);
        maxy = fmax(maxy, sy + r);
    }
    if (!(minx <= maxx)) {
        minx = miny = 0;
        maxx = maxy = 1;
    }
    ex = fmax(maxx - minx, 1e-6);
    ey = fmax(maxy - miny, 1e-6);
    v->scale = fmin((v->w - 2 * MARGIN) / ex, (v->h - 2 * MARGIN - 20) / ey);
    /* centre the drawing in the panel (20 px at the top for the title) */
    v->ox = minx - ((v->w - 2 * MARGIN) / v->scale - ex) / 2;
    v->oy = miny - ((v->h - 2 * MARGIN - 20) / v->scale - ey) / 2;
}

static void to_screen(const view *v, amp_vec3 p, double *sx, double *sy, double *depth)
{
    project(v->iso, p, sx, sy, depth);
    *sx = v->x0 + MARGIN + (*sx - v->ox) * v->scale;
    *sy = v->y0 + MARGIN + 20 + (*sy - v->oy) * v->scale;
}

/* Print-order ramp: blue, cyan, green, yellow, red. */
static void ramp(double t, unsigned char rgb[3])
{
    static const double stops[5][3] = {{40, 60, 200}, {20, 170, 210}, {60, 185, 80}, {235, 200, 40}, {215, 50, 40}};
    double f;
    int i, k;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    f = t * 4;
    i = (int)f;
    if (i > 3)
        i = 3;
    f -= i;
    for (k = 0; k < 3; k++)
        rgb[k] = (unsigned char)(stops[i][k] + f * (stops[i + 1][k] - stops[i][k]) + 0.5);
}

static void path_colour(const amp_pathset *ps, size_t i, unsigned char rgb[3])
{
    if (ps->paths[i].role == AMP_ROLE_SUPPORT) {
        rgb[0] = rgb[1] = rgb[2] = 150;
        return;
    }
    ramp(ps->npaths > 1 ? (double)i / (double)(ps->npaths - 1) : 0.0, rgb);
}

static void layout(view v[2], int width, int height)
{
    v[0].iso = 1;
    v[1].iso = 0;
    v[0].x0 = 0;
    v[1].x0 = width / 2;
    v[0].y0 = v[1].y0 = 0;
    v[0].w = v[1].w = width / 2;
    v[0].h = v[1].h = height - LEGEND_H;
}

static void summary(const amp_pathset *ps, char *buf, size_t cap, size_t *support)
{
    size_t i;
    double rmin = HUGE_VAL, rmax = 0;
    *support = 0;
    for (i = 0; i < ps->npaths; i++)
        *support += ps->paths[i].role == AMP_ROLE_SUPPORT;
    for (i = 0; i < ps->nverts; i++) {
        rmin = fmin(rmin, ps->verts[i].r);
        rmax = fmax(rmax, ps->verts[i].r);
    }
    if (ps->nverts == 0)
        rmin = 0;
    snprintf(buf, cap, "%lu paths (%lu object, %lu support), %lu vertices, %.0f mm, radius %.2f-%.2f mm",
             (unsigned long)ps->npaths, (unsigned long)(ps->npaths - *support), (unsigned long)*support,
             (unsigned long)ps->nverts, amp_pathset_length(ps, -1), rmin, rmax);
}

/*
 * Walk path i in view v, keeping a vertex only when it lies at least one pixel
 * from the last kept one (the path's last vertex is always kept), so that the
 * work and the SVG size follow the picture, not the vertex count.
 */
typedef void (*seg_fn)(void *user, const double a[5], const double b[5]);

/* The progress report: vertices walked of the two views' total, reported at every 1/256 of it. */
typedef struct pv_prog {
    const amp_preview_opts *o;
    size_t total, done, next;
} pv_prog;

static void prog_init(pv_prog *g, const amp_preview_opts *o, const amp_pathset *ps)
{
    g->o = o;
    g->total = 2 * ps->nverts;
    g->done = 0;
    g->next = g->total / 256;
}

static void prog_add(pv_prog *g, size_t n)
{
    g->done += n;
    if (g->o->progress && (g->done >= g->next || g->done == g->total) && g->total > 0) {
        g->o->progress(g->o->progress_user, (double)g->done / (double)g->total);
        g->next = g->done + g->total / 256;
    }
}

static size_t walk_path(const amp_pathset *ps, size_t i, const view *v, seg_fn fn, void *user)
{
    const amp_pvert *p = amp_pathset_path_verts(ps, i);
    size_t n = ps->paths[i].n, k, drawn = 0;
    double last[5], cur[5];
    if (n == 0)
        return 0;
    to_screen(v, p[0].p, &last[0], &last[1], &last[2]);
    last[3] = p[0].r * v->scale;
    last[4] = p[0].r;
    if (n == 1) {
        fn(user, last, last);
        return 1;
    }
    for (k = 1; k < n; k++) {
        to_screen(v, p[k].p, &cur[0], &cur[1], &cur[2]);
        cur[3] = p[k].r * v->scale;
        cur[4] = p[k].r;
        if (k + 1 < n && hypot(cur[0] - last[0], cur[1] - last[1]) < 1.0)
            continue;
        fn(user, last, cur);
        drawn++;
        memcpy(last, cur, sizeof last);
    }
    return drawn;
}

/* ---------------------------------------------------------------- raster */


/* A shaded capsule a-b; a[] = {sx, sy, depth, radius px, radius world}. */
static void raster_seg(void *user, const double a[5], const double b[5])
{
    raster *r = user;
    double dx = b[0] - a[0], dy = b[1] - a[1], l2 = dx * dx + dy * dy;
    double wmax = fmax(fmax(a[3], b[3]), 0.8), bound = fmax(a[2], b[2]) + fmax(a[4], b[4]);
    int x0 = (int)floor(fmin(a[0], b[0]) - wmax), x1 = (int)ceil(fmax(a[0], b[0]) + wmax);
    int y0 = (int)floor(fmin(a[1], b[1]) - wmax), y1 = (int)ceil(fmax(a[1], b[1]) + wmax);
    int x, y;
    if (l2 > (4 * wmax + 8) * (4 * wmax + 8)) {
        /* long segment: halves keep the scanned boxes close to the tube */
        double m[5];
        int k;
        for (k = 0; k < 5; k++)
            m[k] = 0.5 * (a[k] + b[k]);
        raster_seg(user, a, m);
        raster_seg(user, m, b);
        return;
    }
    if (x0 < 0)
        x0 = 0;
    if (y0 < 0)
        y0 = 0;
    if (x1 >= r->w)
        x1 = r->w - 1;
    if (y1 >= r->h)
        y1 = r->h - 1;
    for (y = y0; y <= y1; y++)
        for (x = x0; x <= x1; x++) {
            double px = x + 0.5 - a[0], py = y + 0.5 - a[1], t = 0, u = 0, d, dp, w, q, depth, shade;
            size_t idx = (size_t)y * (size_t)r->w + (size_t)x;
            if (bound <= r->depth[idx])
                continue; /* nearer material already there: the common case when drawing top-down */
            if (l2 > 0) {
                u = (px * dx + py * dy) / l2;
                t = u < 0 ? 0 : u > 1 ? 1 : u;
            }
            d = hypot(px - t * dx, py - t * dy);
            w = fmax(a[3] + t * (b[3] - a[3]), 0.8);
            if (d > w)
                continue;
            /* shade by the distance across the tube (not to the end cap), so joints do not show as rings */
            dp = l2 > 0 ? fabs(px * dy - py * dx) / sqrt(l2) : d;
            q = sqrt(fmax(0.0, 1 - (dp / w) * (dp / w))); /* the tube's bulge towards the viewer */
            depth = a[2] + t * (b[2] - a[2]) + q * (a[4] + t * (b[4] - a[4]));
            if (depth <= r->depth[idx])
                continue;
            r->depth[idx] = (float)depth;
            /* a few shading levels: smooth enough to read the tubes, and far better compressed */
            shade = 0.45 + 0.55 * floor(q * 8 + 0.5) / 8;
            r->rgb[3 * idx] = (unsigned char)(r->col[0] * shade);
            r->rgb[3 * idx + 1] = (unsigned char)(r->col[1] * shade);
            r->rgb[3 * idx + 2] = (unsigned char)(r->col[2] * shade);
        }
}

static void fill_rect(raster *r, int x0, int y0, int w, int h, const unsigned char c[3])
{
    int x, y;
    for (y = y0; y < y0 + h; y++)
        for (x = x0; x < x0 + w; x++)
            if (x >= 0 && y >= 0 && x < r->w && y < r->h)
                memcpy(r->rgb + 3 * ((size_t)y * (size_t)r->w + (size_t)x), c, 3);
}

/* A 3x5 pixel font: five rows of three bits per glyph. */
static const char FONT_CHARS[] = "0123456789abcdefghijklmnopqrstuvwxyz.,-():/=%^";
static const unsigned char FONT[][5] = {
    {7, 5, 5, 5, 7}, {2, 6, 2, 2, 7}, {7, 1, 7, 4, 7}, {7, 1, 3, 1, 7}, {5, 5, 7, 1, 1}, {7, 4, 7, 1, 7},
    {7, 4, 7, 5, 7}, {7, 1, 1, 2, 2}, {7, 5, 7, 5, 7}, {7, 5, 7, 1, 7}, {2, 5, 7, 5, 5}, {6, 5, 6, 5, 6},
    {3, 4, 4, 4, 3}, {6, 5, 5, 5, 6}, {7, 4, 6, 4, 7}, {7, 4, 6, 4, 4}, {3, 4, 5, 5, 3}, {5, 5, 7, 5, 5},
    {7, 2, 2, 2, 7}, {1, 1, 1, 5, 2}, {5, 5, 6, 5, 5}, {4, 4, 4, 4, 7}, {5, 7, 7, 5, 5}, {6, 5, 5, 5, 5},
    {2, 5, 5, 5, 2}, {6, 5, 6, 4, 4}, {2, 5, 5, 6, 3}, {6, 5, 6, 5, 5}, {3, 4, 2, 1, 6}, {7, 2, 2, 2, 2},
    {5, 5, 5, 5, 7}, {5, 5, 5, 5, 2}, {5, 5, 7, 7, 5}, {5, 5, 2, 5, 5}, {5, 5, 2, 2, 2}, {7, 1, 2, 4, 7},
    {0, 0, 0, 0, 2}, {0, 0, 0, 2, 4}, {0, 0, 7, 0, 0}, {1, 2, 2, 2, 1}, {4, 2, 2, 2, 4}, {0, 2, 0, 2, 0},
    {1, 1, 2, 4, 4}, {0, 7, 0, 7, 0}, {5, 1, 2, 4, 5}, {2, 5, 0, 0, 0}};

static void text(raster *r, int x, int y, int px, const char *s)
{
    static const unsigned char ink[3] = {40, 40, 40};
    for (; *s; s++, x += 4 * px) {
        char c = (char)(*s >= 'A' && *s <= 'Z' ? *s - 'A' + 'a' : *s);
        const char *f = c ? strchr(FONT_CHARS, c) : NULL;
        int row, col;
        if (!f)
            continue;
        for (row = 0; row < 5; row++)
            for (col = 0; col < 3; col++)
                if (FONT[f - FONT_CHARS][row] & (4 >> col))
                    fill_rect(r, x + col * px, y + row * px, px, px, ink);
    }
}

/* ---------------------------------------------------------------- output */

static void pv_printf(pv_out *o, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* Every piece printed here is short (the legend line is at most 256 bytes): 512 always suffices. */
static void pv_printf(pv_out *o, const char *fmt, ...)
{
    char buf[512];
    va_list ap;
    int n;
    va_start(ap, fmt);
    n = vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    if (n < 0 || (size_t)n >= sizeof buf) {
        if (o->st == AMP_OK)
            o->st = AMP_ERR_LIMIT;
        return;
    }
    pv_put(o, buf, (size_t)n);
}

/* Size of a font pixel in the legend: the 3x5 font at 3 px per dot fits 1600 px pictures. */
static int legend_unit(int width) { return width >= 1200 ? 3 : width >= 700 ? 2 : 1; }

static void legend_common(int width, int height, int *lx, int *ly)
{
    *lx = 16;
    *ly = height - LEGEND_H + 10;
    (void)width;
}

static amp_status check_args(const amp_pathset *ps, int width, amp_sink_fn sink, amp_error *err)
{
    if (!ps || !sink)
        return amp_fail(err, AMP_ERR_ARG, 0, "preview: NULL path set or sink");
    if (ps->npaths == 0)
        return amp_fail(err, AMP_ERR_ARG, 0, "preview: no paths to draw");
    if (width < AMP_PREVIEW_MIN_WIDTH || width > AMP_PREVIEW_MAX_WIDTH)
        return amp_fail(err, AMP_ERR_RANGE, 0, "preview: width must lie in %d..%d, got %d", AMP_PREVIEW_MIN_WIDTH,
                        AMP_PREVIEW_MAX_WIDTH, width);
    return AMP_OK;
}

/* The figures common to both formats, and the status of the whole write. */
static amp_status finish(const amp_pathset *ps, const pv_out *o, int width, int height, size_t support,
                         amp_preview_stats *st, amp_error *err)
{
    st->width = width;
    st->height = height;
    st->paths = ps->npaths;
    st->support = support;
    st->vertices = ps->nverts;
    st->bytes = o->bytes;
    if (o->st != AMP_OK)
        return amp_fail(err, o->st, 0, "preview: writing the picture failed: %s", amp_strerror(o->st));
    return AMP_OK;
}

/* Both views and the legend into the raster; returns the number of support paths. */
static size_t draw_png(raster *r, const amp_pathset *ps, amp_preview_stats *st, pv_prog *g)
{
    static const unsigned char frame[3] = {210, 210, 205}, grey[3] = {150, 150, 150};
    view v[2];
    size_t i, support;
    int k, lx, ly, u = legend_unit(r->w);
    char line[256];
    layout(v, r->w, r->h);
    for (k = 0; k < 2; k++) {
        fit_view(&v[k], ps);
        /* z-buffered, so the order only matters for speed: the last printed paths tend to be the
           nearest, so drawing them first lets the depth test reject most of the rest early */
        for (i = ps->npaths; i-- > 0;) {
            path_colour(ps, i, r->col);
            st->drawn += walk_path(ps, i, &v[k], raster_seg, r);
            prog_add(g, ps->paths[i].n);
        }
        text(r, (int)v[k].x0 + 4 * u, 10, u, k == 0 ? "isometric view" : "top view");
    }
    fill_rect(r, r->w / 2, 0, 1, r->h - LEGEND_H, frame);
    fill_rect(r, 0, r->h - LEGEND_H, r->w, 1, frame);
    /* legend: the counts, the print-order ramp, the support swatch (sized by the picture width) */
    legend_common(r->w, r->h, &lx, &ly);
    summary(ps, line, sizeof line, &support);
    text(r, lx, ly, u, line);
    text(r, lx, ly + 10 * u, u, "print order: first");
    for (k = 0; k < 100 * u; k++) {
        unsigned char c[3];
        ramp(k / (100.0 * u - 1), c);
        fill_rect(r, lx + 77 * u + k, ly + 9 * u, 1, 7 * u, c);
    }
    text(r, lx + 180 * u, ly + 10 * u, u, "last");
    fill_rect(r, lx + 200 * u, ly + 9 * u, 10 * u, 7 * u, grey);
    snprintf(line, sizeof line, "support (%lu)", (unsigned long)support);
    text(r, lx + 213 * u, ly + 10 * u, u, line);
    text(r, lx, ly + 21 * u, u > 1 ? u - 1 : 1, "tube width follows the material deposition radius");
    return support;
}

void amp_preview_opts_default(amp_preview_opts *o)
{
    o->width = 1600;
    o->progress = NULL;
    o->progress_user = NULL;
}

/* The calls without options: the defaults at @p width. */
typedef amp_status (*opts_fn)(const amp_pathset *, const amp_preview_opts *, amp_sink_fn, void *, amp_preview_stats *,
                              amp_error *);

static amp_status at_width(opts_fn fn, const amp_pathset *ps, int width, amp_sink_fn sink, void *user,
                           amp_preview_stats *st, amp_error *err)
{
    amp_preview_opts o;
    amp_preview_opts_default(&o);
    o.width = width;
    return fn(ps, &o, sink, user, st, err);
}

amp_status amp_preview_png(const amp_pathset *ps, int width, amp_sink_fn sink, void *user, amp_preview_stats *st,
                           amp_error *err)
{
    return at_width(amp_preview_png_opts, ps, width, sink, user, st, err);
}

amp_status amp_preview_png_opts(const amp_pathset *ps, const amp_preview_opts *opt, amp_sink_fn sink, void *user,
                                amp_preview_stats *st, amp_error *err)
{
    static const unsigned char bg[3] = {250, 250, 247};
    amp_preview_stats tmp;
    pv_out o;
    pv_prog g;
    raster r;
    size_t i, npix, support;
    int width = opt ? opt->width : 0;
    amp_status s = opt ? check_args(ps, width, sink, err) : amp_fail(err, AMP_ERR_ARG, 0, "preview: NULL options");
    if (s != AMP_OK)
        return s;
    prog_init(&g, opt, ps);
    if (!st)
        st = &tmp;
    memset(st, 0, sizeof *st);
    r.w = width;
    r.h = width / 2 + LEGEND_H;
    npix = (size_t)r.w * (size_t)r.h;
    r.rgb = amp_alloc(ps->alloc, 3 * npix);
    r.depth = amp_calloc(ps->alloc, npix, sizeof(float));
    if (!r.rgb || !r.depth) {
        amp_free(ps->alloc, r.rgb);
        amp_free(ps->alloc, r.depth);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "preview: out of memory for a %d x %d picture", r.w, r.h);
    }
    for (i = 0; i < npix; i++) {
        memcpy(r.rgb + 3 * i, bg, 3);
        r.depth[i] = -HUGE_VALF;
    }
    support = draw_png(&r, ps, st, &g);
    o.sink = sink;
    o.user = user;
    o.bytes = 0;
    o.st = AMP_OK;
    i = (size_t)amp_pv_write_png(&o, &r, ps->alloc);
    amp_free(ps->alloc, r.rgb);
    amp_free(ps->alloc, r.depth);
    if (i != 0)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "preview: out of memory encoding a %d x %d picture", r.w, r.h);
    return finish(ps, &o, r.w, r.h, support, st, err);
}

/* ---------------------------------------------------------------- SVG */

typedef struct svgw {
    pv_out *o;
    int open;         /* a polyline is open */
    double width;     /* its stroke width (px) */
    double lx, ly;    /* its last point */
    const char *col;  /* "#rrggbb" */
} svgw;

static double qwidth(double r) { return floor(fmax(2 * r, 0.6) * 4 + 0.5) / 4; }

static void svg_close(svgw *s)
{
    if (s->open)
        pv_put(s->o, "\"/>\n", 4);
    s->open = 0;
}

/* Consecutive segments of equal (quantised) width join one polyline. */
static void svg_seg(void *user, const double a[5], const double b[5])
{
    svgw *s = user;
    double w = qwidth(0.5 * (a[3] + b[3]));
    if (!s->open || w != s->width || a[0] != s->lx || a[1] != s->ly) {
        svg_close(s);
        pv_printf(s->o, "<polyline stroke=\"%s\" stroke-width=\"%.2f\" points=\"%.1f,%.1f", s->col, w, a[0], a[1]);
        s->open = 1;
        s->width = w;
    }
    pv_printf(s->o, " %.1f,%.1f", b[0], b[1]);
    s->lx = b[0];
    s->ly = b[1];
}

static void svg_legend(pv_out *o, const amp_pathset *ps, int width, int h, size_t *support)
{
    char line[256];
    int k, lx, ly;
    legend_common(width, h, &lx, &ly);
    summary(ps, line, sizeof line, support);
    pv_printf(o, "<g font-family=\"sans-serif\" font-size=\"15\" fill=\"#282828\" transform=\"translate(%d %d) scale(%g)\">\n",
              lx, ly, legend_unit(width) / 3.0);
    pv_printf(o, "<text x=\"0\" y=\"14\">%s</text>\n", line);
    pv_printf(o, "<defs><linearGradient id=\"order\">");
    for (k = 0; k <= 4; k++) {
        unsigned char c[3];
        ramp(k / 4.0, c);
        pv_printf(o, "<stop offset=\"%d%%\" stop-color=\"#%02x%02x%02x\"/>", k * 25, c[0], c[1], c[2]);
    }
    pv_printf(o, "</linearGradient></defs>\n");
    pv_printf(o, "<text x=\"0\" y=\"44\">print order: first</text>\n");
    pv_printf(o, "<rect x=\"150\" y=\"26\" width=\"300\" height=\"24\" fill=\"url(#order)\"/>\n");
    pv_printf(o, "<text x=\"460\" y=\"44\">last</text>\n");
    pv_printf(o, "<rect x=\"520\" y=\"26\" width=\"30\" height=\"24\" fill=\"#969696\"/>\n");
    pv_printf(o, "<text x=\"560\" y=\"44\">support (%lu)</text>\n", (unsigned long)*support);
    pv_printf(o, "<text x=\"0\" y=\"78\">tube width follows the material deposition radius</text>\n");
    pv_printf(o, "</g>\n</svg>\n");
}

amp_status amp_preview_svg(const amp_pathset *ps, int width, amp_sink_fn sink, void *user, amp_preview_stats *st,
                           amp_error *err)
{
    return at_width(amp_preview_svg_opts, ps, width, sink, user, st, err);
}

amp_status amp_preview_svg_opts(const amp_pathset *ps, const amp_preview_opts *opt, amp_sink_fn sink, void *user,
                                amp_preview_stats *st, amp_error *err)
{
    amp_preview_stats tmp;
    view v[2];
    size_t i, support;
    int width = opt ? opt->width : 0, k, h = width / 2 + LEGEND_H;
    char col[8];
    svgw s;
    pv_out o;
    pv_prog g;
    amp_status rc = opt ? check_args(ps, width, sink, err) : amp_fail(err, AMP_ERR_ARG, 0, "preview: NULL options");
    if (rc != AMP_OK)
        return rc;
    prog_init(&g, opt, ps);
    if (!st)
        st = &tmp;
    memset(st, 0, sizeof *st);
    o.sink = sink;
    o.user = user;
    o.bytes = 0;
    o.st = AMP_OK;
    layout(v, width, h);
    pv_printf(&o,
              "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
              "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" viewBox=\"0 0 %d %d\">\n"
              "<rect width=\"%d\" height=\"%d\" fill=\"#fafaf7\"/>\n",
              width, h, width, h, width, h);
    for (k = 0; k < 2; k++) {
        fit_view(&v[k], ps);
        pv_printf(&o, "<text x=\"%.0f\" y=\"18\" font-family=\"sans-serif\" font-size=\"15\">%s</text>\n",
                  v[k].x0 + 12, k == 0 ? "isometric view" : "top view");
        pv_printf(&o, "<g fill=\"none\" stroke-linecap=\"round\" stroke-linejoin=\"round\">\n");
        for (i = 0; i < ps->npaths && o.st == AMP_OK; i++) {
            unsigned char c[3];
            path_colour(ps, i, c);
            snprintf(col, sizeof col, "#%02x%02x%02x", c[0], c[1], c[2]);
            s.o = &o;
            s.open = 0;
            s.col = col;
            st->drawn += walk_path(ps, i, &v[k], svg_seg, &s);
            svg_close(&s);
            prog_add(&g, ps->paths[i].n);
        }
        pv_printf(&o, "</g>\n");
    }
    pv_printf(&o, "<line x1=\"%d\" y1=\"0\" x2=\"%d\" y2=\"%d\" stroke=\"#d2d2cd\"/>\n", width / 2, width / 2,
              h - LEGEND_H);
    svg_legend(&o, ps, width, h, &support);
    return finish(ps, &o, width, h, support, st, err);
}
