/* api.h — the routes of HTTP API v1 (DESIGN.md §5, proto/openapi.yaml).
 *
 * Design note: one function picks the route (a template, for metrics) from the URL and
 * one answers a complete request. Handlers only read the store and the scheduler's
 * snapshots under short locks, parse posted scenes (bounded by the body cap), and defer
 * image encoding to the offload pool; SSE streams go to events.c. */
#ifndef SRV_API_H
#define SRV_API_H

#include "http.h"

srv_route srv_api_route(const char *url);
/* Answers r (its body, if any, is complete). Returns an MHD_Result. */
int srv_api_handle(srv_request *r);
/* Frees what the route attached to r (called once the request is over). */
void srv_api_request_done(srv_request *r);

#endif
