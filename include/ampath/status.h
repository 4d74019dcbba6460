/*
 * ampath/status.h — status codes and error reports.
 *
 * Every fallible function of libampath returns an amp_status (0 = success,
 * negative = failure) and, when the caller passes a non-NULL amp_error, fills
 * it with the status, a position (line number or byte offset) and a one-line
 * human-readable reason. There is no global error state: two threads that use
 * distinct amp_error objects never interfere.
 */
#ifndef AMPATH_STATUS_H
#define AMPATH_STATUS_H

#ifdef __cplusplus
extern "C" {
#endif

/** Status codes. AMP_OK is zero; every error is negative. */
typedef enum amp_status {
    AMP_OK = 0,
    AMP_ERR_ARG = -1,         /**< invalid argument (NULL, out of range, inconsistent sizes) */
    AMP_ERR_NOMEM = -2,       /**< the allocator returned NULL or a size overflowed */
    AMP_ERR_PARSE = -3,       /**< malformed input text or binary data */
    AMP_ERR_GEOMETRY = -4,    /**< degenerate or unsupported geometry */
    AMP_ERR_IO = -5,          /**< reading or writing a file or device failed */
    AMP_ERR_RANGE = -6,       /**< a parameter lies outside a domain */
    AMP_ERR_LIMIT = -7,       /**< a documented limit was exceeded */
    AMP_ERR_STATE = -8,       /**< operation not valid in the current state */
    AMP_ERR_UNSUPPORTED = -9, /**< valid request that this build does not support */
    AMP_ERR_CHECK = -10       /**< a verification found a violation */
} amp_status;

/** Size of the message buffer inside amp_error, including the NUL. */
#define AMP_ERROR_MSG_SIZE 200

/**
 * A status together with where and why. Plain data owned by the caller;
 * zero-initialise it or call amp_error_clear() before use.
 */
typedef struct amp_error {
    amp_status status;            /**< last status recorded (AMP_OK if none) */
    long line;                    /**< 1-based line number, 0 when not applicable */
    long offset;                  /**< byte offset in the input, -1 when not applicable */
    char msg[AMP_ERROR_MSG_SIZE]; /**< NUL-terminated reason, "" when none */
} amp_error;

/**
 * Static English name of a status ("ok", "out of memory", ...).
 * Never returns NULL; unknown codes give "unknown error". Thread-safe.
 */
const char *amp_strerror(amp_status status);

/** Reset @p err to AMP_OK with no position or message. NULL is accepted. */
void amp_error_clear(amp_error *err);

/**
 * Record a failure in @p err (if not NULL) with a printf-style reason and
 * return @p status, so that callers can write `return amp_fail(err, ...)`.
 * @p line is the 1-based line (0 = none); the offset is set to -1.
 * The message is truncated to fit AMP_ERROR_MSG_SIZE.
 */
amp_status amp_fail(amp_error *err, amp_status status, long line, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

/** As amp_fail() but records a byte offset (for binary inputs) instead of a line. */
amp_status amp_fail_at(amp_error *err, amp_status status, long offset, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

#ifdef __cplusplus
}
#endif
#endif
