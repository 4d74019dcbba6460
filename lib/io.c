/* Byte sinks, the growable buffer and the whole-file reader. */
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

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

amp_status amp_read_file(const char *path, const amp_allocator *a, size_t max_len, char **data, size_t *len,
                         amp_error *err)
{
    FILE *f;
    char *buf = NULL;
    size_t cap = 0, n = 0;
    if (!path || !data || !len)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_read_file: NULL argument");
    if (max_len == 0)
        max_len = (size_t)1 << 30;
    f = fopen(path, "rb");
    if (!f)
        return amp_fail(err, AMP_ERR_IO, 0, "%s: %s", path, strerror(errno));
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
            return amp_fail(err, AMP_ERR_LIMIT, 0, "%s: larger than %lu bytes", path, (unsigned long)max_len);
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

amp_status amp_write_file_atomic(const char *path, amp_writer_fn write, void *ctx, amp_error *err)
{
    char tmp[1024];
    FILE *f;
    amp_status st;
    if (!path || !write)
        return amp_fail(err, AMP_ERR_ARG, 0, "amp_write_file_atomic: NULL argument");
    if (snprintf(tmp, sizeof tmp, "%s.tmp", path) >= (int)sizeof tmp)
        return amp_fail(err, AMP_ERR_ARG, 0, "%s: path too long", path);
    f = fopen(tmp, "wb");
    if (!f)
        return amp_fail(err, AMP_ERR_IO, 0, "%s: cannot create", tmp);
    st = write(ctx, amp_file_sink, f, err);
    if (fclose(f) != 0 && st == AMP_OK)
        st = amp_fail(err, AMP_ERR_IO, 0, "%s: write failed", tmp);
    if (st == AMP_OK && rename(tmp, path) != 0)
        st = amp_fail(err, AMP_ERR_IO, 0, "%s: cannot rename into place", path);
    if (st != AMP_OK)
        remove(tmp);
    return st;
}
