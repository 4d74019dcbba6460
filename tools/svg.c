/* Minimal SVG writer for tools/cmd_slice.c and tools/cmd_euler.c. */
#include <string.h>

#include "svg.h"

int svg_open(svg_doc *s, const char *path, double xmin, double ymin, double xmax, double ymax)
{
    double w = xmax - xmin, h = ymax - ymin, m;
    if (!(w > 0))
        w = 1;
    if (!(h > 0))
        h = 1;
    m = 0.05 * (w > h ? w : h);
    amp_error_clear(&s->err);
    s->f = NULL;
    if (amp_out_open(&s->out, path, &s->err) != AMP_OK)
        return -1;
    s->f = s->out.f;
    s->x0 = xmin - m;
    s->y1 = ymax + m;
    s->px = (w > h ? w : h) / 500.0;
    fprintf(s->f,
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0fmm\" height=\"%.0fmm\" viewBox=\"0 0 %.6g %.6g\">\n"
            "<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n",
            w + 2 * m, h + 2 * m, w + 2 * m, h + 2 * m);
    return 0;
}

static void pt(svg_doc *s, char cmd, amp_vec2 p)
{
    fprintf(s->f, "%c%.5g %.5g", cmd, p.x - s->x0, s->y1 - p.y);
}

void svg_polyset(svg_doc *s, const amp_polyset *ps, const char *fill, const char *stroke, double width)
{
    size_t i, k;
    if (!ps->nrings)
        return;
    fprintf(s->f, "<path fill=\"%s\" fill-rule=\"evenodd\" stroke=\"%s\" stroke-width=\"%.4g\" d=\"", fill, stroke,
            width * s->px);
    for (i = 0; i < ps->nrings; i++) {
        const amp_vec2 *p = amp_polyset_ring(ps, i);
        for (k = 0; k < ps->rings[i].n; k++)
            pt(s, k ? 'L' : 'M', p[k]);
        fputc('Z', s->f);
    }
    fprintf(s->f, "\"/>\n");
}

void svg_cx2(svg_doc *s, const amp_cx2 *k, const char *stroke, double width)
{
    size_t f, h, i;
    fprintf(s->f, "<path fill=\"none\" stroke=\"%s\" stroke-width=\"%.4g\" d=\"", stroke, width * s->px);
    for (f = 0; f < k->nf; f++) {
        for (h = k->fstart[f]; h < k->fstart[f + 1]; h++)
            pt(s, h == k->fstart[f] ? 'M' : 'L', k->v[k->fidx[h]]);
        fputc('Z', s->f);
    }
    for (i = 0; i < k->nxe; i++) {
        pt(s, 'M', k->v[k->xedge[2 * i]]);
        pt(s, 'L', k->v[k->xedge[2 * i + 1]]);
    }
    fprintf(s->f, "\"/>\n");
}

void svg_text(svg_doc *s, int line, const char *text)
{
    fprintf(s->f, "<text x=\"%.4g\" y=\"%.4g\" font-size=\"%.4g\" font-family=\"sans-serif\">", 4 * s->px,
            (line + 1) * 14 * s->px, 12 * s->px);
    for (; *text; text++) {
        if (*text == '<')
            fputs("&lt;", s->f);
        else if (*text == '&')
            fputs("&amp;", s->f);
        else
            fputc(*text, s->f);
    }
    fputs("</text>\n", s->f);
}

int svg_close(svg_doc *s)
{
    fprintf(s->f, "</svg>\n");
    s->f = NULL;
    return amp_out_commit(&s->out, &s->err) == AMP_OK ? 0 : -1;
}
