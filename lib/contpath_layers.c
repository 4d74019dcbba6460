/* All layers: perimeters, regions, print order (continuous-toolpath-euler.txt §2.2). */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "contpath_internal.h"

amp_status amp_contpath_layers(const amp_slices *sl, const amp_contpath_opts *o, amp_pathset *out,
                               amp_contpath_stats *st, amp_error *err)
{
    const amp_allocator *al = out->alloc;
    amp_cx2 khat;
    amp_polyset isl, ins, reg;
    uint64_t *ke = NULL;
    size_t nke = 0, li, k, r, q, p0 = out->npaths;
    amp_contpath_stats s0;
    amp_status rc;
    memset(&s0, 0, sizeof s0);
    amp_cx2_init(&khat, al);
    amp_polyset_init(&isl, al);
    amp_polyset_init(&ins, al);
    amp_polyset_init(&reg, al);
    rc = amp_contpath_complex(sl, o, &khat, err);
    if (rc == AMP_OK && amp_cp_khat_edges(&khat, al, &ke, &nke) != AMP_OK)
        rc = amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the lattice edges");
    for (li = 0; li < sl->nlayers && rc == AMP_OK; li++) {
        const amp_layer *L = &sl->layers[li];
        s0.layers++;
        for (k = 0; k < L->polys.nislands && rc == AMP_OK; k++) {
            if ((rc = amp_polyset_island(&L->polys, k, &isl, err)) != AMP_OK)
                break;
            if (o->perimeters) {
                /* the perimeter bead's centre line: inset by r */
                if ((rc = amp_polyset_inset(&isl, o->radius, 0, &ins, err)) != AMP_OK)
                    break;
                for (r = 0; r < ins.nrings && rc == AMP_OK; r++) {
                    const amp_vec2 *p = amp_polyset_ring(&ins, r);
                    size_t n = ins.rings[r].n;
                    rc = amp_pathset_begin(out, AMP_ROLE_OBJECT, err);
                    for (q = 0; q <= n && rc == AMP_OK; q++)
                        rc = amp_pathset_push(out, amp_v3(p[q % n].x, p[q % n].y, L->z_print), o->radius, err);
                    s0.perimeter_loops++;
                }
            }
            /* R̃: inside the perimeter bead (2r) and one bead radius more */
            if (rc == AMP_OK)
                rc = amp_polyset_inset(&isl, 3 * o->radius, 0, &ins, err);
            for (q = 0; q < ins.nislands && rc == AMP_OK; q++) {
                if ((rc = amp_polyset_island(&ins, q, &reg, err)) != AMP_OK)
                    break;
                rc = amp_cp_region_run(&khat, ke, nke, &reg, L->z_print, o, out, &s0, err);
            }
        }
    }
    /* figures over the paths written by this call */
    for (q = p0; q < out->npaths && rc == AMP_OK; q++) {
        if (out->paths[q].role == AMP_ROLE_OBJECT)
            s0.printed_length += amp_cp_printed_len(out, q);
        if (q > p0 && out->paths[q - 1].n && out->paths[q].n) {
            amp_pvert a = amp_pathset_path_verts(out, q - 1)[out->paths[q - 1].n - 1];
            amp_pvert b = amp_pathset_path_verts(out, q)[0];
            s0.travel_moves++;
            s0.travel_length += amp_v3_dist(a.p, b.p);
        }
    }
    amp_free(al, ke);
    amp_cx2_free(&khat);
    amp_polyset_free(&isl);
    amp_polyset_free(&ins);
    amp_polyset_free(&reg);
    if (st)
        *st = s0;
    return rc;
}
