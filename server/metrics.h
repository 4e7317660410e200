/* metrics.h — HTTP request counters by route and status, rendered as Prometheus text
 * together with the job and scheduler gauges (GET /metrics).
 *
 * Design note: routes are a fixed list of templates ("/api/v1/jobs/{id}"), never raw
 * URLs, so the label set stays small. Counters are guarded by one mutex. */
#ifndef SRV_METRICS_H
#define SRV_METRICS_H

#include <stddef.h>
#include <stdint.h>

#define SRV_ROUTE_LIST(X)                          \
    X(SRV_ROUTE_UI, "/")                           \
    X(SRV_ROUTE_HEALTHZ, "/healthz")               \
    X(SRV_ROUTE_METRICS, "/metrics")               \
    X(SRV_ROUTE_JOBS, "/api/v1/jobs")              \
    X(SRV_ROUTE_JOB, "/api/v1/jobs/{id}")          \
    X(SRV_ROUTE_IMAGE, "/api/v1/jobs/{id}/image")  \
    X(SRV_ROUTE_TILE, "/api/v1/jobs/{id}/tiles/{tx}/{ty}") \
    X(SRV_ROUTE_EVENTS, "/api/v1/jobs/{id}/events") \
    X(SRV_ROUTE_HISTORY, "/api/v1/jobs/{id}/history") \
    X(SRV_ROUTE_CANCEL, "/api/v1/jobs/{id}/cancel") \
    X(SRV_ROUTE_LIMITS, "/api/v1/limits")          \
    X(SRV_ROUTE_OTHER, "other")

typedef enum srv_route {
#define SRV_ROUTE_ENUM(name, text) name,
    SRV_ROUTE_LIST(SRV_ROUTE_ENUM)
#undef SRV_ROUTE_ENUM
        SRV_ROUTE_COUNT
} srv_route;

const char *srv_route_name(srv_route r);

typedef struct srv_metrics srv_metrics;

srv_metrics *srv_metrics_create(void);
void srv_metrics_destroy(srv_metrics *m);
void srv_metrics_count(srv_metrics *m, srv_route route, unsigned status);
/* A connection closed because its request missed the header/body deadline. */
void srv_metrics_count_deadline_cut(srv_metrics *m);
/* Appends the request counters as Prometheus text to a malloc'd buffer (*buf, *len, *cap). */
void srv_metrics_format(srv_metrics *m, char **buf, size_t *len, size_t *cap);
/* printf-style append to such a buffer. */
void srv_buf_printf(char **buf, size_t *len, size_t *cap, const char *fmt, ...) __attribute__((format(printf, 4, 5)));

#endif
