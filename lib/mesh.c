/* Triangle mesh container. STL, BVH and inside tests live in their own files. */
#include <string.h>

#include "ampath/mesh.h"

void amp_mesh_init(amp_mesh *m, const amp_allocator *a)
{
    memset(m, 0, sizeof *m);
    m->alloc = a;
}

void amp_mesh_free(amp_mesh *m)
{
    if (!m)
        return;
    amp_free(m->alloc, m->verts);
    amp_free(m->alloc, m->tris);
    amp_mesh_init(m, m->alloc);
}

amp_status amp_mesh_add_vertex(amp_mesh *m, amp_vec3 p, uint32_t *index, amp_error *err)
{
    void *v = m->verts;
    if (!amp_v3_finite(p))
        return amp_fail(err, AMP_ERR_ARG, 0, "vertex coordinate is not finite");
    if (m->nverts >= 0xffffffffUL)
        return amp_fail(err, AMP_ERR_LIMIT, 0, "more than 2^32-1 vertices");
    if (amp_grow(m->alloc, &v, &m->cap_verts, m->nverts + 1, sizeof *m->verts) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for mesh vertices");
    m->verts = v;
    m->verts[m->nverts] = p;
    if (index)
        *index = (uint32_t)m->nverts;
    m->nverts++;
    return AMP_OK;
}

amp_status amp_mesh_add_tri(amp_mesh *m, uint32_t a, uint32_t b, uint32_t c, amp_error *err)
{
    void *t = m->tris;
    if (a >= m->nverts || b >= m->nverts || c >= m->nverts)
        return amp_fail(err, AMP_ERR_ARG, 0, "triangle index out of range");
    if (amp_grow(m->alloc, &t, &m->cap_tris, m->ntris + 1, sizeof *m->tris) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for mesh triangles");
    m->tris = t;
    m->tris[m->ntris].v[0] = a;
    m->tris[m->ntris].v[1] = b;
    m->tris[m->ntris].v[2] = c;
    m->ntris++;
    return AMP_OK;
}

amp_box3 amp_mesh_bbox(const amp_mesh *m)
{
    amp_box3 b = amp_box3_empty();
    size_t i;
    for (i = 0; i < m->nverts; i++)
        b = amp_box3_add(b, m->verts[i]);
    return b;
}

void amp_mesh_translate(amp_mesh *m, amp_vec3 d)
{
    size_t i;
    for (i = 0; i < m->nverts; i++)
        m->verts[i] = amp_v3_add(m->verts[i], d);
}
