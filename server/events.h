/* events.h — Server-Sent Events streams of one job (text/event-stream).
 *
 * Design note: a hub per job keeps its subscribers, each with a byte buffer of
 * formatted events. Publishing appends to every buffer and resumes connections that
 * libmicrohttpd suspended for lack of data; the response's content reader copies out what
 * is buffered, ends the stream once the hub is closed and the buffer drained, and
 * otherwise suspends its connection (never busy-waits, never blocks). A subscriber whose
 * buffer exceeds a cap (a client that stopped reading) is ended. Thread-safe: one mutex
 * per hub, never held while calling into the scheduler except through `initial`. */
#ifndef SRV_EVENTS_H
#define SRV_EVENTS_H

#include <stdbool.h>
#include <stddef.h>

struct MHD_Connection;
struct MHD_Response;
typedef struct srv_events srv_events;

srv_events *srv_events_create(void);
void srv_events_destroy(srv_events *h); /* after the HTTP daemon stopped */

/* Appends "event: <name>\ndata: <json>\n\n" to every subscriber. */
void srv_events_publish(srv_events *h, const char *name, const char *json);
/* A comment line (keep-alive) to every subscriber. */
void srv_events_keepalive(srv_events *h);
/* No more events: streams end once drained; later subscribers get `initial` and end. */
void srv_events_close(srv_events *h);
/* Ends every stream now (server shutdown); later subscribers end at once. */
void srv_events_shutdown(srv_events *h);

/* A response streaming this hub to conn. `initial(arg, append, ctx)` is called with the
 * hub locked (so no event is missed between it and the subscription) to write the
 * current state through append(ctx, text). NULL when out of memory. */
typedef void (*srv_events_append_fn)(void *ctx, const char *text);
struct MHD_Response *srv_events_subscribe(srv_events *h, struct MHD_Connection *conn,
                                          void (*initial)(void *arg, srv_events_append_fn append, void *ctx),
                                          void *arg);

/* Formats one event into a malloc'd string ("event: …\ndata: …\n\n"); each line of a
 * multi-line `json` gets its own data line. `name` is a token (no line break). */
char *srv_events_format(const char *name, const char *json);

#endif
