/* log.h — the server's log: one line per event, plain text or JSON lines.
 *
 * Design note: a srv_log is a value the server owns (no global logger); the job store and
 * the HTTP layer get a pointer to it. Each call writes one whole line under the log's
 * mutex, so lines from different threads never interleave. Text lines read
 * `2026-12-01T20:30:00.123Z info job.pass id=… spp=64 …` (strings quoted when they hold a
 * space, a quote or a control character); JSON lines are one object each with "time",
 * "level", "event" and the fields, encoded by cJSON. Events below the log's level are not
 * written. Thread-safe. */
#ifndef SRV_LOG_H
#define SRV_LOG_H

#include <pthread.h>
#include <stdbool.h>
#include <stdio.h>

typedef enum srv_log_format { SRV_LOG_TEXT, SRV_LOG_JSON } srv_log_format;
typedef enum srv_log_level { SRV_LOG_ERROR, SRV_LOG_WARN, SRV_LOG_INFO, SRV_LOG_DEBUG } srv_log_level;

typedef struct srv_log {
    srv_log_format format; /* immutable after init */
    srv_log_level level;   /* immutable after init */
    FILE *out;             /* immutable after init; written under mu */
    pthread_mutex_t mu;
} srv_log;

/* One field: a string (str non-NULL) or a number; a number that is not finite, or a
 * negative one with `unknown_if_negative`, is written as null ("-" in text). */
typedef struct srv_log_field {
    const char *key;
    const char *str;
    double num;
    bool unknown_if_negative;
} srv_log_field;

#define SRV_LOG_STR(k, v) ((srv_log_field){(k), (v) ? (v) : "", 0, false})
#define SRV_LOG_NUM(k, v) ((srv_log_field){(k), NULL, (double)(v), false})
#define SRV_LOG_NUM_OR_NULL(k, v) ((srv_log_field){(k), NULL, (double)(v), true})

void srv_log_init(srv_log *l, srv_log_format format, srv_log_level level, FILE *out);
void srv_log_fini(srv_log *l);

/* Whether events of `level` are written (to skip building their fields). NULL: never. */
bool srv_log_enabled(const srv_log *l, srv_log_level level);

/* Writes one line: the event name and n fields. NULL l: nothing. */
void srv_log_event(srv_log *l, srv_log_level level, const char *event, const srv_log_field *fields, int n);

/* "text"/"json" and "error"/"warn"/"info"/"debug"; false for anything else. */
bool srv_log_parse_format(const char *s, srv_log_format *out);
bool srv_log_parse_level(const char *s, srv_log_level *out);

#endif
