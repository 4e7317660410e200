/* metrics.c — request counters; see metrics.h. */
#include "metrics.h"

#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>

#define MAX_STATUSES 16 /* distinct status codes tracked per route */

typedef struct counter { unsigned status; uint64_t n; } counter;

struct srv_metrics {
    pthread_mutex_t mu;
    counter c[SRV_ROUTE_COUNT][MAX_STATUSES]; /* guarded by mu */
    uint64_t deadline_cuts;                   /* guarded by mu */
};

const char *srv_route_name(srv_route r)
{
    static const char *const names[] = {
#define SRV_ROUTE_NAME(name, text) text,
        SRV_ROUTE_LIST(SRV_ROUTE_NAME)
#undef SRV_ROUTE_NAME
    };
    return r < SRV_ROUTE_COUNT ? names[r] : "other";
}

srv_metrics *srv_metrics_create(void)
{
    srv_metrics *m = calloc(1, sizeof *m);
    if (m) pthread_mutex_init(&m->mu, NULL);
    return m;
}

void srv_metrics_destroy(srv_metrics *m)
{
    if (!m) return;
    pthread_mutex_destroy(&m->mu);
    free(m);
}

void srv_metrics_count(srv_metrics *m, srv_route route, unsigned status)
{
    if (route >= SRV_ROUTE_COUNT) route = SRV_ROUTE_OTHER;
    pthread_mutex_lock(&m->mu);
    counter *c = m->c[route];
    for (int i = 0; i < MAX_STATUSES; i++)
        if (c[i].status == status || c[i].status == 0) {
            c[i].status = status;
            c[i].n++;
            break;
        }
    pthread_mutex_unlock(&m->mu);
}

void srv_metrics_count_deadline_cut(srv_metrics *m)
{
    if (!m) return;
    pthread_mutex_lock(&m->mu);
    m->deadline_cuts++;
    pthread_mutex_unlock(&m->mu);
}

void srv_buf_printf(char **buf, size_t *len, size_t *cap, const char *fmt, ...)
{
    va_list ap;
    for (;;) {
        va_start(ap, fmt);
        size_t room = *cap - *len;
        int n = vsnprintf(*buf ? *buf + *len : NULL, *buf ? room : 0, fmt, ap);
        va_end(ap);
        if (n < 0) return;
        if ((size_t)n < room && *buf) {
            *len += (size_t)n;
            return;
        }
        size_t ncap = *cap ? *cap * 2 : 4096;
        while (ncap < *len + (size_t)n + 1) ncap *= 2;
        char *b = realloc(*buf, ncap);
        if (!b) return;
        *buf = b;
        *cap = ncap;
    }
}

void srv_metrics_format(srv_metrics *m, char **buf, size_t *len, size_t *cap)
{
    srv_buf_printf(buf, len, cap, "# HELP tessera_http_requests_total HTTP requests answered, by route and status.\n"
                                  "# TYPE tessera_http_requests_total counter\n");
    pthread_mutex_lock(&m->mu);
    uint64_t cuts = m->deadline_cuts;
    for (int r = 0; r < SRV_ROUTE_COUNT; r++)
        for (int i = 0; i < MAX_STATUSES && m->c[r][i].status; i++)
            srv_buf_printf(buf, len, cap, "tessera_http_requests_total{route=\"%s\",status=\"%u\"} %llu\n",
                           srv_route_name((srv_route)r), m->c[r][i].status, (unsigned long long)m->c[r][i].n);
    pthread_mutex_unlock(&m->mu);
    srv_buf_printf(buf, len, cap,
                   "# HELP tessera_http_deadline_closed_total Connections closed because a request's headers and body "
                   "did not arrive within --request-timeout.\n"
                   "# TYPE tessera_http_deadline_closed_total counter\ntessera_http_deadline_closed_total %llu\n",
                   (unsigned long long)cuts);
}
