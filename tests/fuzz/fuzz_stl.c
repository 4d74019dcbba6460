/* libFuzzer target: the STL reader, then the BVH and a writer round trip on whatever it accepted. */
#include <stddef.h>
#include <stdint.h>

#include "ampath/ampath.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    amp_mesh m, back;
    amp_error err;
    amp_bvh *b = NULL;
    amp_buf buf;
    amp_mesh_init(&m, NULL);
    if (amp_mesh_read_stl(&m, data, size, &err) == AMP_OK) {
        amp_mesh_edge_report er;
        (void)amp_mesh_edges(&m, &er, &err);
        (void)amp_mesh_volume(&m);
        if (m.ntris < 2000 && amp_bvh_build(&b, &m, &err) == AMP_OK) {
            amp_box3 bb = amp_bvh_bbox(b);
            amp_vec3 c = amp_box3_center(bb);
            amp_pvert line[2];
            amp_pathset ps;
            line[0].p = amp_v3_sub(bb.min, amp_v3(1, 1, 1));
            line[1].p = amp_v3_add(bb.max, amp_v3(1, 1, 1));
            line[0].r = line[1].r = 0.5;
            (void)amp_bvh_winding(b, c);
            (void)amp_bvh_closest(b, c, NULL, NULL);
            (void)amp_bvh_ray_first(b, line[0].p, amp_v3_sub(line[1].p, line[0].p), 1.0, NULL);
            amp_pathset_init(&ps, NULL);
            (void)amp_bvh_clip_polyline(b, line, 2, 0.0, AMP_ROLE_OBJECT, &ps, &err);
            amp_pathset_free(&ps);
            amp_bvh_free(b);
        }
        amp_buf_init(&buf, NULL);
        amp_mesh_init(&back, NULL);
        if (amp_mesh_write_stl(&m, 0, amp_buf_sink, &buf, &err) == AMP_OK)
            (void)amp_mesh_read_stl(&back, buf.data, buf.len, &err);
        amp_mesh_free(&back);
        amp_buf_free(&buf);
        (void)amp_mesh_weld(&m, 1e-3, &err);
    }
    amp_mesh_free(&m);
    return 0;
}
