/* error.h — how the renderer reports failure.
 *
 * Design note (docs/style.md): a function that can fail returns a ts_status (TS_OK == 0) and
 * fills a caller-owned ts_error with one human sentence; for scene input the sentence
 * starts with the JSON path ("shapes[1].radius: expected a positive number, got -1").
 * Nothing below main() exits or aborts for anything a user can cause. The status codes
 * come from one X-macro list so names and numbers never drift apart. */
#ifndef TS_ERROR_H
#define TS_ERROR_H

#include <stddef.h>

#define TS_STATUS_LIST(X)                                                         \
    X(TS_OK, 0, "ok")                                                             \
    X(TS_ERR_INVALID, 1, "invalid input")                                         \
    X(TS_ERR_IO, 2, "input/output error")                                         \
    X(TS_ERR_NOMEM, 3, "out of memory")                                           \
    X(TS_ERR_LIMIT, 4, "limit exceeded")                                          \
    X(TS_ERR_UNSUPPORTED, 5, "unsupported")                                       \
    X(TS_ERR_INTERNAL, 6, "internal error")                                       \
    X(TS_ERR_CANCELLED, 7, "cancelled")

typedef enum ts_status {
#define TS_STATUS_ENUM(name, value, text) name = value,
    TS_STATUS_LIST(TS_STATUS_ENUM)
#undef TS_STATUS_ENUM
} ts_status;

#define TS_ERROR_MAX 512

/* A caller-owned error: status and sentence. Zero-initialise (or ts_error_clear) before use. */
typedef struct ts_error {
    ts_status status;
    char message[TS_ERROR_MAX];
} ts_error;

/* Short name of a status ("invalid input"). Thread-safe. */
const char *ts_status_name(ts_status status);

/* Fills err (if not NULL) with status and a printf-style sentence; returns status so a
 * caller can `return ts_error_set(err, TS_ERR_INVALID, "...")`. Thread-safe. */
ts_status ts_error_set(ts_error *err, ts_status status, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* Prefixes the existing message with "prefix: " (used to add a JSON path). */
void ts_error_prefix(ts_error *err, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

static inline void ts_error_clear(ts_error *err)
{
    if (err) {
        err->status = 0;
        err->message[0] = '\0';
    }
}

#endif
