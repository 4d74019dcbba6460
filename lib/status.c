/* Status names and error reports: no globals, the caller owns amp_error. */
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "ampath/status.h"

const char *amp_strerror(amp_status status)
{
    switch (status) {
    case AMP_OK: return "ok";
    case AMP_ERR_ARG: return "invalid argument";
    case AMP_ERR_NOMEM: return "out of memory";
    case AMP_ERR_PARSE: return "parse error";
    case AMP_ERR_GEOMETRY: return "geometry error";
    case AMP_ERR_IO: return "input/output error";
    case AMP_ERR_RANGE: return "out of range";
    case AMP_ERR_LIMIT: return "limit exceeded";
    case AMP_ERR_STATE: return "invalid state";
    case AMP_ERR_UNSUPPORTED: return "unsupported";
    case AMP_ERR_CHECK: return "check failed";
    }
    return "unknown error";
}

void amp_error_clear(amp_error *err)
{
    if (!err)
        return;
    err->status = AMP_OK;
    err->line = 0;
    err->offset = -1;
    err->msg[0] = '\0';
}

static void set_msg(amp_error *err, const char *fmt, va_list ap)
{
    int n = vsnprintf(err->msg, sizeof err->msg, fmt, ap);
    if (n < 0)
        err->msg[0] = '\0';
}

amp_status amp_fail(amp_error *err, amp_status status, long line, const char *fmt, ...)
{
    va_list ap;
    if (!err)
        return status;
    err->status = status;
    err->line = line;
    err->offset = -1;
    va_start(ap, fmt);
    set_msg(err, fmt, ap);
    va_end(ap);
    return status;
}

amp_status amp_fail_at(amp_error *err, amp_status status, long offset, const char *fmt, ...)
{
    va_list ap;
    if (!err)
        return status;
    err->status = status;
    err->line = 0;
    err->offset = offset;
    va_start(ap, fmt);
    set_msg(err, fmt, ap);
    va_end(ap);
    return status;
}
