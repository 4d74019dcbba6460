/*
 * Byte sinks, the growable buffer, the whole-file reader and the safe writer.
 *
 * Hosted POSIX systems get the full file semantics (fstat before reading;
 * writing through symlinks, straight into devices and FIFOs, through a unique
 * O_EXCL temporary renamed into place after fsync). Other targets (the
 * arm-none-eabi cross build, where newlib has no real file system) keep plain
 * stdio: AMP_IO_POSIX selects the variant at compile time.
 */
#if defined(__unix__) || defined(__unix) || (defined(__APPLE__) && defined(__MACH__))
#define AMP_IO_POSIX 1
#define _XOPEN_SOURCE 700
#else
#define AMP_IO_POSIX 0
#endif
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <time.h>
#if AMP_IO_POSIX
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#endif

#include "ampath/io.h"

void amp_buf_init(amp_buf *b, const amp_allocator *a)
{
    b->alloc = a;
    b->data = NULL;
    b->len = 0;
    b->cap = 0;
}

void amp_buf_free(amp_buf *b)
{
    amp_free(b->alloc, b->data);
    b->data = NULL;
    b->len = 0;
    b->cap = 0;
}

amp_status amp_buf_append(amp_buf *b, const char *data, size_t len)
{
    void *p = b->data;
    if (len + 1 < len || amp_grow(b->alloc, &p, &b->cap, b->len + len + 1, 1) != AMP_OK)
        return AMP_ERR_NOMEM;
    b->data = p;
    memcpy(b->data + b->len, data, len);
    b->len += len;
    b->data[b->len] = '\0';
    return AMP_OK;
}

amp_status amp_buf_sink(void *user, const char *data, size_t len) { return amp_buf_append(user, data, len); }

amp_status amp_sinkf(amp_sink_fn sink, void *user, const char *fmt, ...)
{
    char line[512];
    va_list ap;
    int n;
    va_start(ap, fmt);
    n = vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    if (n < 0 || (size_t)n >= sizeof line)
        return AMP_ERR_LIMIT;
    return sink(user, line, (size_t)n);
}

amp_status amp_file_sink(void *user, const char *data, size_t len)
{
    return fwrite(data, 1, len, (FILE *)user) == len ? AMP_OK : AMP_ERR_IO;
}

/* Refuse a regular file larger than @p max_len before reading a byte of it: a 2 GB sparse
 * file must not be read into memory only to be rejected afterwards. */
static amp_status check_size(FILE *f, const char *path, size_t max_len, amp_error *err)
{
#if AMP_IO_POSIX
    struct stat st;
    if (fstat(fileno(f), &st) != 0)
        return amp_fail(err, AMP_ERR_IO, 0, "%s: %s", path, strerror(errno));
    if (S_ISDIR(st.st_mode))
        return amp_fail(err, AMP_ERR_IO, 0, "%s: is a directory", path);
    if (S_ISREG(st.st_mode) && (unsigned long long)st.st_size > (unsigned long long)max_len)
        return amp_fail(err, AMP_ERR_LIMIT, 0, "%s: %llu bytes, larger than the limit of %llu bytes", path,
                        (unsigned long long)st.st_size, (unsigned long long)max_len);
#else
    (void)f;
    (void)path;
    (void)max_len;
    (void)err;
#endif
    return AMP_OK;
}

amp_status amp_read_file(const char *path, const amp_allocator *a, size_t max_len, char **data, size_t *len,
                         amp_error *err)
{
    FILE *f;
    char *buf = NULL;
    size_t cap = 0, n = 0;
    amp_status st;
    if (!path || !data || !len)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_read_file: NULL argument");
    if (max_len == 0)
        max_len = AMP_READ_MAX_DEFAULT;
    f = fopen(path, "rb");
    if (!f)
        return amp_fail(err, AMP_ERR_IO, 0, "%s: %s", path, strerror(errno));
    st = check_size(f, path, max_len, err);
    if (st != AMP_OK) {
        fclose(f);
        return st;
    }
    for (;;) {
        size_t got;
        void *p = buf;
        if (amp_grow(a, &p, &cap, n + 65536 + 1, 1) != AMP_OK) {
            amp_free(a, buf);
            fclose(f);
            return amp_fail(err, AMP_ERR_NOMEM, 0, "%s: out of memory", path);
        }
        buf = p;
        got = fread(buf + n, 1, cap - n - 1, f);
        n += got;
        if (n > max_len) {
            amp_free(a, buf);
            fclose(f);
            return amp_fail(err, AMP_ERR_LIMIT, 0, "%s: larger than the limit of %lu bytes", path,
                            (unsigned long)max_len);
        }
        if (got == 0)
            break;
    }
    if (ferror(f)) {
        amp_free(a, buf);
        fclose(f);
        return amp_fail(err, AMP_ERR_IO, 0, "%s: read error", path);
    }
    fclose(f);
    buf[n] = '\0';
    *data = buf;
    *len = n;
    return AMP_OK;
}

/* ---- the safe writer ---- */

static amp_status out_fail(amp_out *o, int e, amp_error *err)
{
    return amp_fail(err, AMP_ERR_IO, 0, "%s: %s", o->target, e ? strerror(e) : "write error");
}

static int copy_path(char *dst, const char *src, size_t n)
{
    if (n >= AMP_OUT_PATH_MAX)
        return -1;
    memcpy(dst, src, n);
    dst[n] = '\0';
    return 0;
}

amp_status amp_out_sink(void *user, const char *data, size_t len)
{
    amp_out *o = user;
    if (fwrite(data, 1, len, o->f) == len)
        return AMP_OK;
    if (!o->werr)
        o->werr = errno ? errno : EIO;
    return AMP_ERR_IO;
}

#if AMP_IO_POSIX
/* Follow symlinks from o->target until a non-link (or a missing name, which is then
 * created): writing "through" a link replaces its target's content, as a shell's ">"
 * does, and leaves the link itself in place. */
static amp_status resolve_target(amp_out *o, struct stat *st, int *exists, amp_error *err)
{
    int hops;
    for (hops = 0;; hops++) {
        char link[AMP_OUT_PATH_MAX];
        ssize_t n;
        const char *slash;
        size_t dlen;
        if (lstat(o->target, st) != 0) {
            if (errno != ENOENT)
                return out_fail(o, errno, err);
            *exists = 0;
            return AMP_OK;
        }
        if (!S_ISLNK(st->st_mode)) {
            *exists = 1;
            return AMP_OK;
        }
        if (hops == 40)
            return out_fail(o, ELOOP, err);
        n = readlink(o->target, link, sizeof link - 1);
        if (n < 0)
            return out_fail(o, errno, err);
        link[n] = '\0';
        slash = strrchr(o->target, '/');
        dlen = (link[0] == '/' || !slash) ? 0 : (size_t)(slash - o->target) + 1;
        if (dlen + (size_t)n >= AMP_OUT_PATH_MAX)
            return out_fail(o, ENAMETOOLONG, err);
        memmove(o->target + dlen, link, (size_t)n + 1);
    }
}

/* Create "DIR/.BASE.XXXXXXXX.tmp" with O_EXCL: a fresh name per run, so that two runs
 * writing the same output never share a temporary and a planted file or link at a
 * predictable name is never followed. The seed mixes pid, time and a stack address; a
 * collision only costs a retry. */
static int open_temp(amp_out *o, amp_error *err, amp_status *st)
{
    const char *slash = strrchr(o->target, '/');
    size_t dlen = slash ? (size_t)(slash - o->target) + 1 : 0;
    const char *base = o->target + dlen;
    unsigned long long seed = (unsigned long long)getpid() * 0x9E3779B97F4A7C15ULL ^
                              (unsigned long long)time(NULL) ^ (unsigned long long)clock() << 20 ^
                              (unsigned long long)(size_t)o;
    int attempt;
    for (attempt = 0; attempt < 100; attempt++) {
        int fd, len;
        seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
        len = snprintf(o->tmp, sizeof o->tmp, "%.*s.%.200s.%08lx.tmp", (int)dlen, o->target, base,
                       (unsigned long)(seed >> 32) & 0xffffffffUL);
        if (len < 0 || (size_t)len >= sizeof o->tmp) {
            *st = out_fail(o, ENAMETOOLONG, err);
            return -1;
        }
        fd = open(o->tmp, O_WRONLY | O_CREAT | O_EXCL | O_NOCTTY, 0666);
        if (fd >= 0)
            return fd;
        if (errno != EEXIST) {
            int e = errno;
            o->tmp[0] = '\0';
            *st = out_fail(o, e, err);
            return -1;
        }
    }
    o->tmp[0] = '\0';
    *st = out_fail(o, EEXIST, err);
    return -1;
}

static amp_status open_posix(amp_out *o, amp_error *err)
{
    struct stat st;
    int exists = 0, fd;
    amp_status s = resolve_target(o, &st, &exists, err);
    if (s != AMP_OK)
        return s;
    if (exists && S_ISDIR(st.st_mode))
        return out_fail(o, EISDIR, err);
    if (exists && !S_ISREG(st.st_mode)) {
        /* a device, FIFO or socket: write into it, never replace the node */
        fd = open(o->target, O_WRONLY | O_NOCTTY);
        if (fd < 0)
            return out_fail(o, errno, err);
        o->direct = 1;
    } else {
        if (exists && access(o->target, W_OK) != 0)
            return out_fail(o, errno, err);
        fd = open_temp(o, err, &s);
        if (fd < 0)
            return s;
        /* keep the replaced file's owner (when allowed) and permissions; a new file gets
         * 0666 less the umask as with any program */
        if (exists) {
            if (fchown(fd, st.st_uid, st.st_gid) != 0) {
                /* not permitted for others' files: the new file is then ours, as with cp */
            }
            if (fchmod(fd, st.st_mode & 07777) != 0) {
                int e = errno;
                close(fd);
                unlink(o->tmp);
                o->tmp[0] = '\0';
                return out_fail(o, e, err);
            }
        }
    }
    o->f = fdopen(fd, "wb");
    if (!o->f) {
        int e = errno;
        close(fd);
        if (o->tmp[0])
            unlink(o->tmp);
        o->tmp[0] = '\0';
        return out_fail(o, e, err);
    }
    return AMP_OK;
}

/* Make the rename durable: a crash right after must not leave an empty file. Best effort:
 * some file systems refuse fsync on directories. */
static void sync_dir(const amp_out *o)
{
    char dir[AMP_OUT_PATH_MAX];
    const char *slash = strrchr(o->target, '/');
    int fd;
    if (slash == o->target)
        copy_path(dir, "/", 1);
    else if (slash)
        copy_path(dir, o->target, (size_t)(slash - o->target));
    else
        copy_path(dir, ".", 1);
    fd = open(dir, O_RDONLY);
    if (fd >= 0) {
        if (fsync(fd) != 0) {
            /* ignored: see above */
        }
        close(fd);
    }
}
#endif

amp_status amp_out_open(amp_out *o, const char *path, amp_error *err)
{
    if (!o)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_out_open: NULL argument");
    memset(o, 0, sizeof *o);
    if (!path || !path[0])
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_out_open: no file name");
    if (copy_path(o->target, path, strlen(path)) != 0)
        return amp_fail(err, AMP_ERR_ARG, 0, "%.64s...: path too long", path);
#if AMP_IO_POSIX
    return open_posix(o, err);
#else
    if (snprintf(o->tmp, sizeof o->tmp, "%s.tmp", path) >= (int)sizeof o->tmp)
        return amp_fail(err, AMP_ERR_ARG, 0, "%.64s...: path too long", path);
    o->f = fopen(o->tmp, "wb");
    if (!o->f) {
        int e = errno;
        o->tmp[0] = '\0';
        return out_fail(o, e, err);
    }
    return AMP_OK;
#endif
}

amp_status amp_out_commit(amp_out *o, amp_error *err)
{
    int e = 0;
    if (!o || !o->f)
        return amp_fail(err, AMP_ERR_STATE, 0, "amp_out_commit: not open");
    if (fflush(o->f) != 0 || ferror(o->f))
        e = o->werr ? o->werr : (errno ? errno : EIO);
    else if (o->werr)
        e = o->werr;
#if AMP_IO_POSIX
    /* without fsync a full disk or a failing device may only show after the rename, when
     * the old content is gone already */
    if (!e && !o->direct && fsync(fileno(o->f)) != 0)
        e = errno;
#endif
    if (fclose(o->f) != 0 && !e)
        e = errno ? errno : EIO;
    o->f = NULL;
    if (!e && o->tmp[0] && rename(o->tmp, o->target) != 0)
        e = errno;
    if (e) {
        if (o->tmp[0])
            remove(o->tmp);
        o->tmp[0] = '\0';
        return out_fail(o, e, err);
    }
#if AMP_IO_POSIX
    if (o->tmp[0])
        sync_dir(o);
#endif
    o->tmp[0] = '\0';
    return AMP_OK;
}

void amp_out_abort(amp_out *o)
{
    if (!o)
        return;
    if (o->f)
        fclose(o->f);
    o->f = NULL;
    if (o->tmp[0])
        remove(o->tmp);
    o->tmp[0] = '\0';
}

amp_status amp_write_file_atomic(const char *path, amp_writer_fn write, void *ctx, amp_error *err)
{
    amp_out o;
    amp_status st;
    if (!path || !write)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_write_file_atomic: NULL argument");
    st = amp_out_open(&o, path, err);
    if (st != AMP_OK)
        return st;
    st = write(ctx, amp_out_sink, &o, err);
    if (st != AMP_OK) {
        /* a failed sink knows why (ENOSPC, EFBIG, EIO): say so rather than the writer's generic words */
        if (o.werr)
            out_fail(&o, o.werr, err);
        amp_out_abort(&o);
        return st == AMP_ERR_IO || o.werr ? AMP_ERR_IO : st;
    }
    return amp_out_commit(&o, err);
}
