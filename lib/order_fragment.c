/* Fragments ([P1 §5.1], Def. 5.3): every path cut into equal pieces shorter than z_offs. */
#include <math.h>
#include <string.h>

#include "ampath/order.h"

void amp_fragments_free(amp_fragments *fs)
{
    if (!fs)
        return;
    amp_free(fs->alloc, fs->frag);
    amp_free(fs->alloc, fs->first);
    fs->frag = NULL;
    fs->first = NULL;
    fs->n = fs->npaths = 0;
}

/* Number of pieces for a path of length len: equal pieces strictly shorter than max_len. */
static size_t piece_count(double len, double max_len)
{
    double n = floor(len / max_len) + 1.0;
    while (len / n >= max_len) /* guard the rounding of the division */
        n += 1.0;
    return (size_t)n;
}

amp_status amp_fragments_build(amp_fragments *fs, const amp_pathset *ps, double max_len, const amp_allocator *a,
                               amp_error *err)
{
    size_t i, total = 0, out = 0;
    if (!fs || !ps)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_fragments_build: NULL argument");
    memset(fs, 0, sizeof *fs);
    fs->alloc = a;
    fs->ps = ps;
    fs->max_len = max_len;
    if (!isfinite(max_len) || max_len <= 0.0)
        return amp_fail(err, AMP_ERR_ARG, 0, "fragment length must be positive (got %g)", max_len);
    if (ps->npaths >= 0xffffffffUL)
        return amp_fail(err, AMP_ERR_LIMIT, 0, "too many paths (%lu)", (unsigned long)ps->npaths);
    for (i = 0; i < ps->npaths; i++) {
        double len = amp_path_length(ps, i), np;
        if (ps->paths[i].n == 0)
            continue;
        np = floor(len / max_len) + 2.0;
        if (np > 4e9 || (double)total + np > 4e9)
            return amp_fail(err, AMP_ERR_LIMIT, 0, "more than 2^32 fragments: path %lu is %g mm long for pieces of %g mm",
                            (unsigned long)i, len, max_len);
        total += piece_count(len, max_len);
    }
    fs->first = amp_calloc(a, ps->npaths + 1, sizeof *fs->first);
    fs->frag = total ? amp_calloc(a, total, sizeof *fs->frag) : NULL;
    if (!fs->first || (total && !fs->frag)) {
        amp_fragments_free(fs);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for %lu fragments", (unsigned long)total);
    }
    fs->npaths = ps->npaths;
    for (i = 0; i < ps->npaths; i++) {
        const amp_pvert *v = amp_pathset_path_verts(ps, i);
        size_t n = ps->paths[i].n, nf, f, k = 0;
        double len, acc = 0.0;
        amp_vec3 start;
        double rstart;
        fs->first[i] = out;
        if (n == 0)
            continue;
        len = amp_path_length(ps, i);
        nf = piece_count(len, max_len);
        start = v[0].p;
        rstart = v[0].r;
        for (f = 0; f < nf; f++) {
            amp_fragment *fr = &fs->frag[out++];
            size_t q;
            fr->path = (uint32_t)i;
            fr->p0 = start;
            fr->r0 = rstart;
            fr->vfirst = ps->paths[i].first + k + 1;
            fr->nin = 0;
            if (f + 1 == nf || n == 1) {
                /* the last piece takes every remaining vertex and ends at the path's end */
                fr->nin = n >= 2 ? (uint32_t)(n - 2 - k) : 0;
                fr->p1 = v[n - 1].p;
                fr->r1 = v[n - 1].r;
            } else {
                double cut = len * (double)(f + 1) / (double)nf, seg, t;
                while (k + 2 < n && acc + amp_v3_dist(v[k].p, v[k + 1].p) < cut) {
                    acc += amp_v3_dist(v[k].p, v[k + 1].p);
                    k++;
                    fr->nin++;
                }
                seg = amp_v3_dist(v[k].p, v[k + 1].p);
                t = seg > 0.0 ? (cut - acc) / seg : 0.0;
                t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
                fr->p1 = amp_v3_lerp(v[k].p, v[k + 1].p, t);
                fr->r1 = v[k].r + t * (v[k + 1].r - v[k].r);
            }
            fr->box = amp_box3_add(amp_box3_add(amp_box3_empty(), fr->p0), fr->p1);
            for (q = 0; q < fr->nin; q++)
                fr->box = amp_box3_add(fr->box, ps->verts[fr->vfirst + q].p);
            start = fr->p1;
            rstart = fr->r1;
        }
    }
    fs->first[ps->npaths] = out;
    fs->n = out;
    return AMP_OK;
}
