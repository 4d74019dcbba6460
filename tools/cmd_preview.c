/* ampath preview PATHS.amp -o OUT.svg|OUT.png — a picture of the paths (docs/interfaces.md §4). */
#include <errno.h>
#include <stdio.h>
#include <string.h>

#include "cli.h"

const char cmd_preview_usage[] =
    "draw the paths: isometric and top views, tubes scaled by the deposition radius, coloured by print order\n"
    "usage: ampath preview PATHS.amp -o OUT.svg|OUT.png [--width N] [--json]\n"
    "  -o, --output FILE  the picture; the format follows the extension (.png or .svg)\n"
    "  --width N          picture width in pixels (1600; 200..8000); height = width/2 + 110 for the legend\n"
    "  --json             print the figures as one JSON object (width, height, paths, support, vertices,\n"
    "                     drawn_segments, bytes, seconds)\n"
    "Support paths are grey; object paths run from blue (first printed) to red (last).\n"
    "The PNG encoder is ampath's own (no image library).\n";

int cmd_preview(int argc, char **argv)
{
    const char *pos[1], *out = NULL;
    long width = 1600;
    int json = 0, npos = 0, rc, png;
    amp_status s;
    amp_pathset ps;
    amp_preview_stats st;
    amp_preview_opts po;
    cli_progress bar;
    double t0;
    amp_out f;
    amp_error err;
    cli_opt opts[] = {{"output", CLI_STR, &out, 0},
                      {"width", CLI_LONG, &width, 0},
                      {"json", CLI_FLAG, &json, 0},
                      {NULL, CLI_FLAG, NULL, 0}};
    rc = cli_parse("preview", argc, argv, opts, pos, 1, 1, &npos);
    if (rc != CLI_OK)
        return rc;
    if (!out)
        return cli_fail("preview", CLI_USAGE, "-o OUT.svg|OUT.png is required");
    if (cli_ends_with(out, ".png") || cli_ends_with(out, ".PNG"))
        png = 1;
    else if (cli_ends_with(out, ".svg") || cli_ends_with(out, ".SVG"))
        png = 0;
    else
        return cli_fail("preview", CLI_USAGE, "%s: the output must end in .png or .svg", out);
    if (width < 200 || width > 8000)
        return cli_fail("preview", CLI_USAGE, "--width must lie in 200..8000, got %ld", width);
    amp_pathset_init(&ps, NULL);
    rc = cli_load_paths("preview", pos[0], &ps);
    if (rc != CLI_OK)
        return rc;
    if (ps.npaths == 0) {
        amp_pathset_free(&ps);
        return cli_fail("preview", CLI_USAGE, "%s: no paths to draw", pos[0]);
    }
    t0 = cli_now();
    amp_error_clear(&err);
    if (amp_out_open(&f, out, &err) != AMP_OK) {
        amp_pathset_free(&ps);
        return cli_fail_err("preview", &err);
    }
    /* the renderer lives in the library (lib/preview.c) so that bindings write the same bytes */
    amp_preview_opts_default(&po);
    po.width = (int)width;
    po.progress = cli_progress_fn;
    po.progress_user = &bar;
    cli_progress_begin(&bar, "preview");
    s = png ? amp_preview_png_opts(&ps, &po, amp_out_sink, &f, &st, &err)
            : amp_preview_svg_opts(&ps, &po, amp_out_sink, &f, &st, &err);
    cli_progress_end(&bar);
    if (s != AMP_OK) {
        if (f.werr)
            amp_fail(&err, AMP_ERR_IO, 0, "%s: %s", f.target, strerror(f.werr));
        amp_out_abort(&f);
        amp_pathset_free(&ps);
        return cli_fail_err("preview", &err);
    }
    if (amp_out_commit(&f, &err) != AMP_OK) {
        amp_pathset_free(&ps);
        return cli_fail_err("preview", &err);
    }
    if (json) {
        cli_json j;
        cli_json_begin(&j, stdout);
        cli_json_str(&j, "output", out);
        cli_json_str(&j, "format", png ? "png" : "svg");
        cli_json_int(&j, "width", st.width);
        cli_json_int(&j, "height", st.height);
        cli_json_int(&j, "paths", (long long)st.paths);
        cli_json_int(&j, "support", (long long)st.support);
        cli_json_int(&j, "vertices", (long long)st.vertices);
        cli_json_int(&j, "drawn_segments", (long long)st.drawn);
        cli_json_int(&j, "bytes", (long long)st.bytes);
        cli_json_num(&j, "seconds", cli_now() - t0);
        cli_json_end(&j);
    } else {
        printf("wrote %s: %dx%d, %lu paths (%lu support), %lu segments drawn, %lu bytes\n", out, st.width, st.height,
               (unsigned long)st.paths, (unsigned long)st.support, (unsigned long)st.drawn,
               (unsigned long)st.bytes);
    }
    amp_pathset_free(&ps);
    return CLI_OK;
}
