/*
 * Tests of lib/io.c and the tool's file handling: the one safe
 * writer (symlinks, devices, FIFOs, unique temporaries, permissions, a full or
 * size-limited disk), size checks before reading, the lexer's line limit, no
 * leak on a parse error, and the work estimates that refuse runaway requests.
 */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "runtool.h"
#include "testutil.h"

/* ---- helpers ---- */

/* A fresh empty scratch directory for one test. */
static const char *scratch_dir(const char *name)
{
    static char dir[200];
    char cmd[600];
    snprintf(dir, sizeof dir, "%s/ampath-test-%ld-%s", fx_tmpdir(), (long)getpid(), name);
    snprintf(cmd, sizeof cmd, "rm -rf '%s' && mkdir -p '%s'", dir, dir);
    ck_assert_int_eq(system(cmd), 0);
    return dir;
}

static void remove_dir(const char *dir)
{
    char cmd[600];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    ck_assert_int_eq(system(cmd), 0);
}

static void put_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    ck_assert_ptr_nonnull(f);
    fputs(text, f);
    ck_assert_int_eq(fclose(f), 0);
}

/* The content of a small file ("" when missing), in a static buffer. */
static const char *file_text(const char *path)
{
    static char buf[4096];
    size_t n = 0;
    FILE *f = fopen(path, "r");
    buf[0] = 0;
    if (f) {
        n = fread(buf, 1, sizeof buf - 1, f);
        fclose(f);
    }
    buf[n] = 0;
    return buf;
}

/* Number of directory entries other than . and .. (leftover temporaries show up here). */
static int count_entries(const char *dir)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    int n = 0;
    ck_assert_ptr_nonnull(d);
    while ((e = readdir(d)) != NULL)
        if (strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0)
            n++;
    closedir(d);
    return n;
}

/* amp_writer_fn: writes ctx->n bytes of ctx->ch, or fails with ctx->status after them. */
typedef struct fill_ctx {
    size_t n;
    char ch;
    amp_status status;
} fill_ctx;

static amp_status fill_writer(void *vctx, amp_sink_fn sink, void *user, amp_error *err)
{
    const fill_ctx *c = vctx;
    char block[1024];
    size_t done = 0;
    memset(block, c->ch, sizeof block);
    while (done < c->n) {
        size_t k = c->n - done < sizeof block ? c->n - done : sizeof block;
        amp_status st = sink(user, block, k);
        if (st != AMP_OK)
            return amp_fail(err, st, 0, "writing failed");
        done += k;
    }
    if (c->status != AMP_OK)
        return amp_fail(err, c->status, 0, "the writer gave up");
    return AMP_OK;
}

static amp_status write_fill(const char *path, size_t n, char ch, amp_error *err)
{
    fill_ctx c;
    c.n = n;
    c.ch = ch;
    c.status = AMP_OK;
    amp_error_clear(err);
    return amp_write_file_atomic(path, fill_writer, &c, err);
}

/* ---- the safe writer ---- */

START_TEST(writing_through_a_symlink_replaces_the_target_and_keeps_link_and_mode)
{
    const char *dir = scratch_dir("symlink");
    char target[300], link[300];
    struct stat st;
    amp_error err;
    snprintf(target, sizeof target, "%s/target.txt", dir);
    snprintf(link, sizeof link, "%s/link.txt", dir);
    put_file(target, "old");
    ck_assert_int_eq(chmod(target, 0640), 0);
    ck_assert_int_eq(symlink("target.txt", link), 0); /* relative, resolved against the link's directory */
    ck_assert_int_eq(write_fill(link, 5, 'n', &err), AMP_OK);
    ck_assert_int_eq(lstat(link, &st), 0);
    ck_assert_msg(S_ISLNK(st.st_mode), "the link was replaced by a regular file");
    ck_assert_str_eq(file_text(target), "nnnnn");
    ck_assert_int_eq(stat(target, &st), 0);
    ck_assert_int_eq(st.st_mode & 07777, 0640);
    ck_assert_int_eq(count_entries(dir), 2);
    remove_dir(dir);
}
END_TEST

START_TEST(a_dangling_symlink_creates_its_target)
{
    const char *dir = scratch_dir("dangling");
    char target[300], link[300];
    struct stat st;
    amp_error err;
    snprintf(target, sizeof target, "%s/new.txt", dir);
    snprintf(link, sizeof link, "%s/link.txt", dir);
    ck_assert_int_eq(symlink(target, link), 0); /* absolute */
    ck_assert_int_eq(write_fill(link, 3, 'a', &err), AMP_OK);
    ck_assert_int_eq(lstat(link, &st), 0);
    ck_assert(S_ISLNK(st.st_mode));
    ck_assert_str_eq(file_text(target), "aaa");
    remove_dir(dir);
}
END_TEST

START_TEST(dev_null_is_written_directly_and_stays_a_device)
{
    struct stat st;
    amp_error err;
    ck_assert_int_eq(write_fill("/dev/null", 100000, 'x', &err), AMP_OK);
    ck_assert_int_eq(lstat("/dev/null", &st), 0);
    ck_assert(S_ISCHR(st.st_mode));
}
END_TEST

START_TEST(dev_full_reports_no_space_and_stays_a_device)
{
    struct stat st;
    amp_error err;
    amp_status s = write_fill("/dev/full", 100000, 'x', &err);
    ck_assert_int_eq(s, AMP_ERR_IO);
    ck_assert_msg(strstr(err.msg, strerror(ENOSPC)) != NULL, "message: %s", err.msg);
    ck_assert_int_eq(lstat("/dev/full", &st), 0);
    ck_assert(S_ISCHR(st.st_mode));
    /* a short content stays in the stdio buffer until the commit: its failure must show too */
    s = write_fill("/dev/full", 10, 'x', &err);
    ck_assert_int_eq(s, AMP_ERR_IO);
    ck_assert_msg(strstr(err.msg, strerror(ENOSPC)) != NULL, "message: %s", err.msg);
}
END_TEST

START_TEST(a_fifo_is_written_directly_and_stays_a_fifo)
{
    const char *dir = scratch_dir("fifo");
    char fifo[300], got[300];
    struct stat st;
    amp_error err;
    pid_t pid;
    int status;
    snprintf(fifo, sizeof fifo, "%s/pipe", dir);
    snprintf(got, sizeof got, "%s/got.txt", dir);
    ck_assert_int_eq(mkfifo(fifo, 0600), 0);
    pid = fork();
    ck_assert_int_ge(pid, 0);
    if (pid == 0) { /* the reader: copies the FIFO into a file */
        char buf[4096];
        ssize_t n;
        int in = open(fifo, O_RDONLY), out = open(got, O_WRONLY | O_CREAT | O_TRUNC, 0600);
        if (in < 0 || out < 0)
            _exit(3);
        while ((n = read(in, buf, sizeof buf)) > 0)
            if (write(out, buf, (size_t)n) != n)
                _exit(4);
        _exit(close(out) == 0 ? 0 : 5);
    }
    ck_assert_int_eq(write_fill(fifo, 3000, 'f', &err), AMP_OK);
    ck_assert_int_eq(waitpid(pid, &status, 0), pid);
    ck_assert(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    ck_assert_int_eq(lstat(fifo, &st), 0);
    ck_assert(S_ISFIFO(st.st_mode));
    ck_assert_int_eq(stat(got, &st), 0);
    ck_assert_int_eq(st.st_size, 3000);
    remove_dir(dir);
}
END_TEST

START_TEST(a_planted_fixed_tmp_name_is_never_followed)
{
    /* the old writer opened "PATH.tmp" with fopen: a link planted there clobbered its target */
    const char *dir = scratch_dir("planted");
    char out[300], planted[300], victim[300];
    struct stat st;
    amp_error err;
    snprintf(out, sizeof out, "%s/out.amp", dir);
    snprintf(planted, sizeof planted, "%s/out.amp.tmp", dir);
    snprintf(victim, sizeof victim, "%s/victim", dir);
    put_file(victim, "precious");
    ck_assert_int_eq(symlink(victim, planted), 0);
    ck_assert_int_eq(write_fill(out, 4, 'o', &err), AMP_OK);
    ck_assert_str_eq(file_text(victim), "precious");
    ck_assert_str_eq(file_text(out), "oooo");
    ck_assert_int_eq(lstat(planted, &st), 0);
    ck_assert(S_ISLNK(st.st_mode));
    ck_assert_int_eq(count_entries(dir), 3); /* out.amp, the planted link, the victim: no temporary left */
    remove_dir(dir);
}
END_TEST

START_TEST(two_open_outputs_of_one_file_use_distinct_temporaries)
{
    const char *dir = scratch_dir("twice");
    char out[300];
    amp_out a, b;
    amp_error err;
    snprintf(out, sizeof out, "%s/same.svg", dir);
    amp_error_clear(&err);
    ck_assert_int_eq(amp_out_open(&a, out, &err), AMP_OK);
    ck_assert_int_eq(amp_out_open(&b, out, &err), AMP_OK);
    ck_assert_str_ne(a.tmp, b.tmp);
    ck_assert_int_eq(count_entries(dir), 2);
    fputs("first", a.f);
    fputs("second", b.f);
    ck_assert_int_eq(amp_out_commit(&a, &err), AMP_OK);
    ck_assert_int_eq(amp_out_commit(&b, &err), AMP_OK);
    ck_assert_str_eq(file_text(out), "second");
    ck_assert_int_eq(count_entries(dir), 1);
    remove_dir(dir);
}
END_TEST

START_TEST(a_failing_writer_leaves_the_old_file_and_no_temporary)
{
    const char *dir = scratch_dir("abort");
    char out[300];
    fill_ctx c;
    amp_error err;
    snprintf(out, sizeof out, "%s/keep.spl", dir);
    put_file(out, "old content");
    c.n = 20000;
    c.ch = 'z';
    c.status = AMP_ERR_GEOMETRY;
    amp_error_clear(&err);
    ck_assert_int_eq(amp_write_file_atomic(out, fill_writer, &c, &err), AMP_ERR_GEOMETRY);
    ck_assert_str_eq(file_text(out), "old content");
    ck_assert_int_eq(count_entries(dir), 1);
    remove_dir(dir);
}
END_TEST

START_TEST(a_directory_is_refused)
{
    const char *dir = scratch_dir("isdir");
    amp_error err;
    ck_assert_int_eq(write_fill(dir, 3, 'd', &err), AMP_ERR_IO);
    ck_assert_msg(strstr(err.msg, strerror(EISDIR)) != NULL, "message: %s", err.msg);
    ck_assert_int_eq(count_entries(dir), 0);
    remove_dir(dir);
}
END_TEST

/*
 * A full disk, unprivileged: RLIMIT_FSIZE makes every write past the limit fail (EFBIG),
 * exactly where ENOSPC would. Runs @p fn in a child with the limit set and SIGXFSZ
 * ignored; returns the child's exit status.
 */
static int with_file_size_limit(long bytes, int (*fn)(const void *), const void *arg)
{
    pid_t pid = fork();
    int status;
    ck_assert_int_ge(pid, 0);
    if (pid == 0) {
        struct rlimit rl;
        rl.rlim_cur = rl.rlim_max = (rlim_t)bytes;
        signal(SIGXFSZ, SIG_IGN);
        if (setrlimit(RLIMIT_FSIZE, &rl) != 0)
            _exit(100);
        _exit(fn(arg));
    }
    ck_assert_int_eq(waitpid(pid, &status, 0), pid);
    ck_assert_msg(WIFEXITED(status), "the child did not exit");
    return WEXITSTATUS(status);
}

static int big_write(const void *path)
{
    amp_error err;
    amp_status s = write_fill(path, 100000, 'b', &err);
    if (s != AMP_ERR_IO)
        return 1;
    return strstr(err.msg, strerror(EFBIG)) ? 0 : 2;
}

START_TEST(a_full_disk_reports_the_reason_and_keeps_the_old_file)
{
    const char *dir = scratch_dir("full");
    char out[300];
    snprintf(out, sizeof out, "%s/keep.amp", dir);
    put_file(out, "old content");
    ck_assert_int_eq(with_file_size_limit(4096, big_write, out), 0);
    ck_assert_str_eq(file_text(out), "old content");
    ck_assert_int_eq(count_entries(dir), 1);
    remove_dir(dir);
}
END_TEST

static int tool_under_limit(const void *args) { return fx_run_tool(args, NULL, 0); }

START_TEST(tool_writers_keep_the_old_file_on_a_full_disk)
{
    /* model -o F.spl, slice -o F.svg, euler -o F.svg and gcode -o F replaced F by a partial file */
    const char *dir = scratch_dir("toolfull");
    char stl[300], args[1200], out[300];
    const char *fmt[] = {"model helix -o %s/out.spl", "slice %s/m.stl --layer 0.5 -o %s/out.svg",
                         "euler %s/m.stl --layer 2 --cell 2 -o %s/out.svg", "model helix -o %s/out.stl"};
    const char *name[] = {"out.spl", "out.svg", "out.svg", "out.stl"};
    size_t i;
    snprintf(stl, sizeof stl, "model twisted-bridge -o %s/m.stl", dir);
    ck_assert_int_eq(fx_run_tool(stl, NULL, 0), 0);
    for (i = 0; i < sizeof fmt / sizeof fmt[0]; i++) {
        snprintf(args, sizeof args, fmt[i], dir, dir);
        snprintf(out, sizeof out, "%s/%s", dir, name[i]);
        put_file(out, "old content");
        ck_assert_int_eq(fx_run_tool(args, NULL, 0), 0); /* the command works without the limit */
        put_file(out, "old content");
        ck_assert_msg(with_file_size_limit(1024, tool_under_limit, args) == 2, "%s", args);
        ck_assert_msg(strcmp(file_text(out), "old content") == 0, "%s replaced %s", args, out);
        ck_assert_int_eq(count_entries(dir), 2);
        remove(out);
    }
    remove_dir(dir);
}
END_TEST

START_TEST(tool_writes_dev_full_with_enospc_and_dev_null_fine)
{
    char out[4096];
    ck_assert_int_eq(fx_run_tool_ex("model helix -o /dev/full", NULL, 1, out, sizeof out), 2);
    ck_assert_msg(strstr(out, strerror(ENOSPC)) != NULL, "output: %s", out);
    ck_assert_int_eq(fx_run_tool("model helix -o /dev/null", out, sizeof out), 0);
    /* one line without --json, as every command */
    ck_assert_msg(strcmp(out, "helix: trivariate, 297 control points -> /dev/null\n") == 0, "output: %s", out);
}
END_TEST

/* ---- reading: sizes checked before reading ---- */

START_TEST(an_oversized_sparse_file_is_refused_from_its_size)
{
    const char *path = fx_tmp("sparse.stl");
    char *data = NULL;
    size_t len = 0;
    amp_mesh m;
    amp_error err;
    int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0600);
    ck_assert_int_ge(fd, 0);
    ck_assert_int_eq(ftruncate(fd, (off_t)2147483648.0), 0); /* 2 GiB, no block allocated */
    close(fd);
    amp_error_clear(&err);
    ck_assert_int_eq(amp_read_file(path, NULL, 1 << 20, &data, &len, &err), AMP_ERR_LIMIT);
    ck_assert_ptr_null(data);
    ck_assert_msg(strstr(err.msg, "2147483648 bytes") != NULL, "message: %s", err.msg);
    amp_mesh_init(&m, NULL);
    amp_error_clear(&err);
    ck_assert_int_eq(amp_mesh_read_stl_file(&m, path, &err), AMP_ERR_LIMIT);
    ck_assert_msg(strstr(err.msg, "2147483648 bytes") != NULL, "message: %s", err.msg);
    amp_mesh_free(&m);
    remove(path);
}
END_TEST

START_TEST(a_file_at_the_size_limit_is_read)
{
    const char *path = fx_tmp("exact.txt");
    char *data = NULL;
    size_t len = 0;
    amp_error err;
    put_file(path, "0123456789");
    amp_error_clear(&err);
    ck_assert_int_eq(amp_read_file(path, NULL, 10, &data, &len, &err), AMP_OK);
    ck_assert_uint_eq(len, 10);
    amp_free(NULL, data);
    ck_assert_int_eq(amp_read_file(path, NULL, 9, &data, &len, &err), AMP_ERR_LIMIT);
    remove(path);
}
END_TEST

/* ---- the lexer's line limit ---- */

static amp_status parse_with_line(const char *line, size_t n)
{
    amp_buf b;
    amp_pathset ps;
    amp_error err;
    amp_status st;
    amp_buf_init(&b, NULL);
    ck_assert_int_eq(amp_buf_append(&b, "ampath-paths 1\n", 15), AMP_OK);
    while (n--)
        ck_assert_int_eq(amp_buf_append(&b, line, strlen(line)), AMP_OK);
    ck_assert_int_eq(amp_buf_append(&b, "\npath object 2\n0 0 0 0.2\n1 0 0 0.2\n", 35), AMP_OK);
    amp_pathset_init(&ps, NULL);
    amp_error_clear(&err);
    st = amp_pathset_parse(&ps, b.data, b.len, &err);
    if (st != AMP_OK)
        ck_assert_int_eq(err.line, 2);
    else
        ck_assert_uint_eq(ps.npaths, 1);
    amp_pathset_free(&ps);
    amp_buf_free(&b);
    return st;
}

START_TEST(a_comment_line_over_4096_bytes_is_rejected)
{
    ck_assert_int_eq(parse_with_line("#", 1) , AMP_OK);
    ck_assert_int_eq(parse_with_line("#234567890123456", 256), AMP_OK);     /* 4,096 bytes */
    ck_assert_int_eq(parse_with_line("#234567890123456", 257), AMP_ERR_PARSE); /* 4,112 */
    ck_assert_int_eq(parse_with_line("# a 10 MB comment line....", 400000), AMP_ERR_PARSE);
    ck_assert_int_eq(parse_with_line("                ", 300), AMP_ERR_PARSE); /* blank, 4,800 */
}
END_TEST

/* ---- no leak on a parse error: exit 2, also under ASan (a leak report would make it 1) ---- */

START_TEST(commands_exit_2_on_a_bad_path_file)
{
    const char *bad = fx_tmp("bad.amp");
    const char *cmds[] = {"info %s", "order %s -o /dev/null", "mdr %s -o /dev/null", "preview %s -o %s.svg",
                          "check %s", "support %s -o /dev/null"};
    char args[600];
    size_t i;
    /* two good paths grow the set, the third is broken */
    put_file(bad, "ampath-paths 1\npath object 2\n0 0 0 0.2\n1 0 0 0.2\npath object 2\n0 1 0 0.2\n1 1 0 0.2\n"
                  "path object 3\n0 2 0 0.2\nnot a vertex\n");
    for (i = 0; i < sizeof cmds / sizeof cmds[0]; i++) {
        snprintf(args, sizeof args, cmds[i], bad, bad);
        ck_assert_msg(fx_run_tool(args, NULL, 0) == 2, "ampath %s", args);
    }
    remove(bad);
}
END_TEST

/* ---- bounded work: ranges and estimates refuse before working (exit 2, the estimate said) ---- */

/* Run the tool, expect @p rc, and (when @p needle) a message containing it. */
static void expect_tool(const char *args, int rc, const char *needle)
{
    char out[8192];
    int got = fx_run_tool_ex(args, NULL, 1, out, sizeof out);
    ck_assert_msg(got == rc, "ampath %s: exit %d, expected %d; output: %.300s", args, got, rc, out);
    if (needle)
        ck_assert_msg(strstr(out, needle) != NULL, "ampath %s: no '%s' in: %.300s", args, needle, out);
}

START_TEST(nonsense_numbers_are_refused_by_the_option_parser)
{
    const char *dir = scratch_dir("ranges");
    char args[1000], amp[300], stl[300], gc[300];
    struct stat st;
    snprintf(amp, sizeof amp, "%s/p.amp", dir);
    snprintf(stl, sizeof stl, "%s/m.stl", dir);
    snprintf(gc, sizeof gc, "%s/out.gcode", dir);
    put_file(amp, "ampath-paths 1\npath object 2\n0 0 0.2 0.25\n10 0 0.2 0.25\n");
    snprintf(args, sizeof args, "model twisted-bridge -o %s", stl);
    expect_tool(args, 0, NULL);
    /* --feed 1e-300 wrote F0 and estimated 2 s */
    snprintf(args, sizeof args, "gcode %s --feed 1e-300 -o %s", amp, gc);
    expect_tool(args, 2, "--feed must lie in");
    ck_assert_int_ne(stat(gc, &st), 0); /* nothing written */
    snprintf(args, sizeof args, "gcode %s --feed 0.1 -o %s", amp, gc); /* the bound itself is fine */
    expect_tool(args, 0, NULL);
    /* --layer 1e308 gave 0 layers and exit 0; 5.7e-6 reached 6.7 GB */
    snprintf(args, sizeof args, "slice %s --layer 1e308", stl);
    expect_tool(args, 2, "--layer must lie in");
    snprintf(args, sizeof args, "slice %s --layer 5.7e-6", stl);
    expect_tool(args, 2, "--layer must lie in");
    snprintf(args, sizeof args, "field %s --field box --spacing 1e-300", stl);
    expect_tool(args, 2, "--spacing must lie in");
    expect_tool("cover vase --eps 1e-300 -o /dev/null", 2, "--eps must lie in");
    expect_tool("model helix --tol 1e-9 -o /dev/null.stl", 2, "--tol must lie in");
    expect_tool("preview x.amp --width 10 -o x.png", 2, "--width must lie in");
    remove_dir(dir);
}
END_TEST

START_TEST(cover_refuses_beyond_its_curve_estimate)
{
    const char *dir = scratch_dir("coverlimit");
    char args[600], spl[300];
    amp_spline v;
    amp_error err;
    amp_buf b;
    size_t i;
    FILE *f;
    /* minutes or all memory before: now refused at once with the Lemma A.2 estimate */
    expect_tool("cover helix --eps 0.02 --dir w -o /dev/null", 2, "refused: about");
    expect_tool("cover helix --eps 0.02 --dir w -o /dev/null", 2, "--max-curves");
    /* along the helix the curves are 30 times fewer but 4 times longer: their length is refused (it ran over
     * 100 s and 3.7 GB when only the count was estimated) */
    expect_tool("cover helix --eps 0.02 -o /dev/null", 2, "mm of paths estimated");
    expect_tool("cover helix --eps 0.02 --max-curves 1e15 -o /dev/null", 2, "--max-length");
    expect_tool("cover helix --eps 0.2 --max-length 1e5 -o /dev/null", 2, "--max-length");
    expect_tool("cover helix --eps 2 --max-length 1e5 -o /dev/null", 0, NULL);
    /* the estimate for vase at eps 2 is a few hundred curves (298 made): the limit decides */
    expect_tool("cover vase --eps 2 --max-curves 100 -o /dev/null", 2, "refused: about");
    expect_tool("cover vase --eps 2 --max-curves 5000 -o /dev/null", 0, NULL);
    /* a trivariate 1e5 times the helix (kilometres) at eps 1 mm */
    amp_error_clear(&err);
    ck_assert_int_eq(amp_trivariate_model("helix", NULL, &v, &err), AMP_OK);
    for (i = 0; i < v.ncp; i++) {
        double w;
        amp_vec3 p = amp_spline_cp_get(&v, i, &w);
        amp_spline_cp_set(&v, i, amp_v3_scale(p, 1e5), w);
    }
    amp_buf_init(&b, NULL);
    ck_assert_int_eq(amp_spline_write(&v, 1, amp_buf_sink, &b, &err), AMP_OK);
    snprintf(spl, sizeof spl, "%s/huge.spl", dir);
    f = fopen(spl, "w");
    ck_assert_ptr_nonnull(f);
    ck_assert_uint_eq(fwrite(b.data, 1, b.len, f), b.len);
    ck_assert_int_eq(fclose(f), 0);
    amp_buf_free(&b);
    amp_spline_free(&v);
    snprintf(args, sizeof args, "cover %s --eps 1 -o /dev/null", spl);
    expect_tool(args, 2, "refused: about");
    remove_dir(dir);
}
END_TEST

START_TEST(slicing_refuses_beyond_its_segment_estimate)
{
    const char *dir = scratch_dir("slicelimit");
    char args[600], tall[300], stl[300];
    snprintf(tall, sizeof tall, "%s/tall.stl", dir);
    snprintf(stl, sizeof stl, "%s/m.stl", dir);
    /* a tetrahedron 100 m high: 1e8 layers of 1 um */
    put_file(tall, "solid tall\n"
                   "facet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex 0 10 0\nvertex 10 0 0\nendloop\nendfacet\n"
                   "facet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex 10 0 0\nvertex 0 0 100000\nendloop\nendfacet\n"
                   "facet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex 0 0 100000\nvertex 0 10 0\nendloop\nendfacet\n"
                   "facet normal 0 0 0\nouter loop\nvertex 10 0 0\nvertex 0 10 0\nvertex 0 0 100000\nendloop\nendfacet\n"
                   "endsolid tall\n");
    snprintf(args, sizeof args, "slice %s --layer 0.001", tall);
    expect_tool(args, 2, "refused: about 4e+08 section segments");
    snprintf(args, sizeof args, "euler %s --layer 0.001 --cell 1 -o %s/e.svg", tall, dir);
    expect_tool(args, 2, "--max-segments");
    snprintf(args, sizeof args, "slice %s --layer 1", tall); /* 1e5 layers: within the default limit */
    expect_tool(args, 0, NULL);
    snprintf(args, sizeof args, "model twisted-bridge -o %s", stl);
    expect_tool(args, 0, NULL);
    snprintf(args, sizeof args, "slice %s --layer 0.5 --max-segments 1000", stl);
    expect_tool(args, 2, "refused: about");
    snprintf(args, sizeof args, "slice %s --layer 0.5 --max-segments 1e5", stl);
    expect_tool(args, 0, NULL);
    remove_dir(dir);
}
END_TEST

START_TEST(an_oversized_mesh_is_refused_by_the_tool_at_once)
{
    const char *path = fx_tmp("sparse2.stl");
    char args[600];
    int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0600);
    ck_assert_int_ge(fd, 0);
    ck_assert_int_eq(ftruncate(fd, (off_t)2147483648.0), 0);
    close(fd);
    snprintf(args, sizeof args, "slice %s --layer 1", path);
    expect_tool(args, 2, "2147483648 bytes, larger than the limit of 1073741824 bytes");
    remove(path);
}
END_TEST

/* Lines in @p s (a reason is exactly one). */
static int count_lines(const char *s)
{
    int n = 0;
    for (; *s; s++)
        n += *s == '\n';
    return n;
}

/* -o naming an input: refused (exit 2) and the input kept byte for byte; a path set rewritten in place by order
 * is fine (a black-box sweep found `gcode j.amp -o j.amp` turning the paths into G-code, and the same for slice,
 * cover, support --mesh and mdr --trivariate). */
START_TEST(an_output_naming_an_input_is_refused_and_the_input_kept)
{
    const char *dir = scratch_dir("clobber");
    static const char paths[] = "ampath-paths 1\npath object 2\n0 0 0.5 0.5\n10 0 0.5 0.5\n";
    char args[1200], amp[300], stl[300], out[8192];
    FILE *f;
    size_t n;
    snprintf(amp, sizeof amp, "%s/j.amp", dir);
    snprintf(stl, sizeof stl, "%s/m.stl", dir);
    put_file(amp, paths);
    snprintf(args, sizeof args, "model twisted-bridge -o %s", stl);
    expect_tool(args, 0, NULL);
    snprintf(args, sizeof args, "gcode %s -o %s", amp, amp);
    expect_tool(args, 2, "would be overwritten");
    snprintf(args, sizeof args, "support %s --mesh %s -o %s", amp, stl, stl);
    expect_tool(args, 2, "is the --mesh file");
    snprintf(args, sizeof args, "slice %s --layer 1 -o %s", stl, stl);
    expect_tool(args, 2, "would be overwritten");
    snprintf(args, sizeof args, "preview %s -o %s", amp, amp);
    expect_tool(args, 2, "would be overwritten");
    f = fopen(amp, "rb");
    ck_assert_ptr_nonnull(f);
    n = fread(out, 1, sizeof out - 1, f);
    fclose(f);
    out[n] = 0;
    ck_assert_str_eq(out, paths);
    snprintf(args, sizeof args, "info %s --json", stl);
    expect_tool(args, 0, "\"triangles\"");
    /* order rewrites its own path file in place */
    snprintf(args, sizeof args, "order %s -o %s", amp, amp);
    expect_tool(args, 0, NULL);
    remove_dir(dir);
}
END_TEST

/* Bad usage at the top level and in arguments: exit 2 and a reason of exactly one line (an unknown command
 * printed the whole overview, 22 lines; a newline in a file name split the reason in two); `--version` takes
 * no argument; hexadecimal floats are not decimal numbers (--eps 0x10 covered at eps 16). */
START_TEST(bad_usage_gets_exit_2_and_a_reason_of_one_line)
{
    static const char *const bad[] = {"frobnicate", "--frobnicate", "--version junk",
                                      "order 'no\nsuch.amp' -o /dev/null",
                                      "cover vase --eps 0x10 -o /dev/null",
                                      "gcode x.amp --fan-off-layers 2.5",
                                      "slice x.stl --layer 0.2 --first-layer 1e-300"};
    char out[8192];
    size_t i;
    for (i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        int rc = fx_run_tool_stderr(bad[i], NULL, out, sizeof out);
        ck_assert_msg(rc == 2, "ampath %s: exit %d", bad[i], rc);
        ck_assert_msg(count_lines(out) == 1, "ampath %s: %d lines: %s", bad[i], count_lines(out), out);
    }
}
END_TEST

/* A product or figures lost on stdout (a full disk) are a failure, exit 2 with the reason; the same runs to
 * /dev/null succeed (they exited 0 with nothing on stderr). */
START_TEST(a_failed_write_to_stdout_is_exit_2)
{
    static const char *const cmds[] = {"--version", "info %s/j.amp --json", "eval %s/v.spl"};
    const char *dir = scratch_dir("stdoutfull");
    char args[600], amp[300], out[4096];
    size_t i;
    snprintf(amp, sizeof amp, "%s/j.amp", dir);
    put_file(amp, "ampath-paths 1\npath object 2\n0 0 0.5 0.5\n10 0 0.5 0.5\n");
    snprintf(args, sizeof args, "model vase -o %s/v.spl", dir);
    expect_tool(args, 0, NULL);
    for (i = 0; i < sizeof cmds / sizeof cmds[0]; i++) {
        char cmd[400];
        snprintf(cmd, sizeof cmd, cmds[i], dir);
        snprintf(args, sizeof args, "%s >/dev/full", cmd);
        ck_assert_int_eq(fx_run_tool_stderr(args, "0.5 0.5 0.5\n", out, sizeof out), 2);
        ck_assert_msg(strstr(out, "No space left") != NULL, "ampath %s: %s", args, out);
        snprintf(args, sizeof args, "%s >/dev/null", cmd);
        ck_assert_int_eq(fx_run_tool_ex(args, "0.5 0.5 0.5\n", 1, out, sizeof out), 0);
    }
    remove_dir(dir);
}
END_TEST

/* check refuses a bad model before any check runs: exit 2, one line, nothing on stdout (it printed a partial
 * report and two lines on stderr). */
START_TEST(check_refuses_a_bad_model_before_checking)
{
    const char *dir = scratch_dir("checkmodel");
    char args[800], amp[300], out[8192];
    snprintf(amp, sizeof amp, "%s/j.amp", dir);
    put_file(amp, "ampath-paths 1\npath object 2\n0 0 0.5 0.5\n10 0 0.5 0.5\n");
    snprintf(args, sizeof args, "check %s --trivariate %s/missing.spl 2>/dev/null", amp, dir);
    ck_assert_int_eq(fx_run_tool_ex(args, NULL, 0, out, sizeof out), 2);
    ck_assert_str_eq(out, "");
    snprintf(args, sizeof args, "check %s --mesh %s", amp, dir);
    ck_assert_int_eq(fx_run_tool_stderr(args, NULL, out, sizeof out), 2);
    ck_assert_msg(count_lines(out) == 1, "%s", out);
    remove_dir(dir);
}
END_TEST

Suite *io_suite(void);
Suite *io_suite(void)
{
    Suite *s = suite_create("io");
    TCase *w = tcase_create("writer"), *r = tcase_create("reader"), *t = tcase_create("tool");
    tcase_add_test(w, writing_through_a_symlink_replaces_the_target_and_keeps_link_and_mode);
    tcase_add_test(w, a_dangling_symlink_creates_its_target);
    tcase_add_test(w, dev_null_is_written_directly_and_stays_a_device);
    tcase_add_test(w, dev_full_reports_no_space_and_stays_a_device);
    tcase_add_test(w, a_fifo_is_written_directly_and_stays_a_fifo);
    tcase_add_test(w, a_planted_fixed_tmp_name_is_never_followed);
    tcase_add_test(w, two_open_outputs_of_one_file_use_distinct_temporaries);
    tcase_add_test(w, a_failing_writer_leaves_the_old_file_and_no_temporary);
    tcase_add_test(w, a_directory_is_refused);
    tcase_add_test(w, a_full_disk_reports_the_reason_and_keeps_the_old_file);
    tcase_add_test(r, an_oversized_sparse_file_is_refused_from_its_size);
    tcase_add_test(r, a_file_at_the_size_limit_is_read);
    tcase_add_test(r, a_comment_line_over_4096_bytes_is_rejected);
    tcase_add_test(t, tool_writers_keep_the_old_file_on_a_full_disk);
    tcase_add_test(t, tool_writes_dev_full_with_enospc_and_dev_null_fine);
    tcase_add_test(t, commands_exit_2_on_a_bad_path_file);
    tcase_add_test(t, nonsense_numbers_are_refused_by_the_option_parser);
    tcase_add_test(t, cover_refuses_beyond_its_curve_estimate);
    tcase_add_test(t, slicing_refuses_beyond_its_segment_estimate);
    tcase_add_test(t, an_oversized_mesh_is_refused_by_the_tool_at_once);
    tcase_add_test(t, an_output_naming_an_input_is_refused_and_the_input_kept);
    tcase_add_test(t, bad_usage_gets_exit_2_and_a_reason_of_one_line);
    tcase_add_test(t, a_failed_write_to_stdout_is_exit_2);
    tcase_add_test(t, check_refuses_a_bad_model_before_checking);
    suite_add_tcase(s, w);
    suite_add_tcase(s, r);
    suite_add_tcase(s, t);
    return s;
}

FX_TEST_MAIN(io_suite)
