/* events.h — Server-Sent Events streams of one job (text/event-stream).
 *
 * Design note: a hub per job keeps its subscribers, each with a small byte buffer of
 * formatted events. A new subscriber first gets the job's current state — one event per
 * backlog item (the job's tiles) and a tail (progress, and `done` once finished) — but
 * that backlog is never built at once: it is pulled a few items at a time when the client
 * has read what was buffered, so subscribing costs O(1) and a subscriber holds O(one
 * chunk) however large the job. The hub keeps the latest event of each item (what was
 * published for it, else what the source printed for it once), so the backlog of many
 * subscribers is copied, not formatted again for each. Live events meanwhile: an item event for an
 * item the backlog has not reached yet, and any other event before the tail, is left out
 * (the backlog will read the newer state); everything else is appended. Items and events
 * are both written under the hub's mutex, so no update is lost between them.
 *
 * Publishing appends to every buffer and resumes connections that libmicrohttpd
 * suspended for lack of data; the response's content reader copies out what is buffered,
 * pulls more of the backlog, ends the stream once the hub is closed, the backlog is done
 * and the buffer drained, and otherwise suspends its connection (never busy-waits, never
 * blocks). A subscriber whose buffer would pass SRV_EVENTS_BUFFER_CAP (a client that
 * stopped reading) is dropped: its buffer is freed and its connection reset at once,
 * without waiting for the client to read (events.c, drop; an EventSource reconnects and
 * gets a fresh backlog). Subscribers are capped per job and in
 * all (srv_events_limits): past either, subscribing fails (503).
 *
 * Thread-safe: one mutex per hub; the source's functions are called with it held and may
 * take the scheduler's lock (never the other way round: publishing is never called with a
 * scheduler lock held). */
#ifndef SRV_EVENTS_H
#define SRV_EVENTS_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>

struct MHD_Connection;
struct MHD_Response;
typedef struct srv_events srv_events;

/* A subscriber more than this many bytes behind is dropped. */
#define SRV_EVENTS_BUFFER_CAP (256u << 10)

/* Subscriber caps shared by every hub of a server; `total` counts the subscribers of all
 * hubs (atomic). Owned by the server; must outlive every stream. */
typedef struct srv_events_limits {
    int max_per_job;   /* subscribers of one hub at once; 0 = no cap */
    int max_total;     /* subscribers of all hubs at once; 0 = no cap */
    atomic_int total;
    atomic_uint_fast64_t dropped; /* subscribers dropped for falling behind, ever */
} srv_events_limits;

srv_events *srv_events_create(void);
void srv_events_destroy(srv_events *h); /* after every stream ended (see the source's retain) */

/* The number of backlog items (a job's tiles) whose latest events the hub keeps; once,
 * before events are published. Without it (or out of memory) every backlog item is asked
 * of the source. */
void srv_events_set_items(srv_events *h, int n_items);

/* Appends "event: <name>\ndata: <json>\n\n" to every subscriber; `item` is the backlog
 * item the event updates (a tile's index; the hub keeps it as that item's latest), or -1
 * for events about the whole job. */
void srv_events_publish(srv_events *h, const char *name, const char *json, int item);
/* The same with the frame already formatted (srv_events_format's output). */
void srv_events_publish_frame(srv_events *h, const char *frame, int item);
/* A comment line (keep-alive) to every subscriber. */
void srv_events_keepalive(srv_events *h);
/* No more events: streams end once their backlog is sent and drained. */
void srv_events_close(srv_events *h);
/* Ends every stream now (server shutdown); later subscribers end at once. */
void srv_events_shutdown(srv_events *h);

/* What a new subscriber's backlog is read from. item(i) returns item i's event as it
 * stands (a malloc'd frame; NULL when it has none yet), asked only when the hub keeps none
 * for it; tail() the events that end the backlog (malloc'd frames, or NULL). They run with
 * the hub locked, on HTTP threads, and must be quick. retain/release bracket the stream's
 * lifetime (the source, and the hub with it, must outlive it). */
typedef struct srv_events_source {
    int n_items;
    char *(*item)(void *arg, int i);
    char *(*tail)(void *arg);
    void (*retain)(void *arg);
    void (*release)(void *arg);
    void *arg;
} srv_events_source;

/* A response streaming this hub to conn, starting with src's backlog. NULL with
 * *http_status 503 and a sentence in msg when a cap of `limits` is reached, or 500 when
 * out of memory. */
struct MHD_Response *srv_events_subscribe(srv_events *h, struct MHD_Connection *conn, const srv_events_source *src,
                                          srv_events_limits *limits, unsigned *http_status, char *msg,
                                          size_t msg_len);

/* Subscribers of this hub now (for tests and metrics). */
int srv_events_subscribers(srv_events *h);

/* Formats one event into a malloc'd string ("event: …\ndata: …\n\n"); each line of a
 * multi-line `json` gets its own data line. `name` is a token (no line break). */
char *srv_events_format(const char *name, const char *json);

#endif
