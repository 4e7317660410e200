/* display.h — streaming a render's tiles to a tev display server, as pbrt-v4's --display-server.
 *
 * Design note: tev (an HDR image viewer) listens on TCP (127.0.0.1:14158 by default) for
 * packets of its IPC format; a renderer connects, creates an image and updates rectangles
 * of it as tiles finish. One srv_display is one connection and one image, fed by one
 * scheduler job: hand srv_display_on_tile to the job's on_tile callback (or call
 * srv_display_tile from one's own). The format, as tev documents it (src/Ipc.cpp,
 * include/tev/Ipc.h), written here from that description:
 *
 *   packet   u32 total length in bytes (these 4 included), u8 type, then the fields;
 *            integers and floats little-endian, a bool one byte (0/1), a string its bytes
 *            and a NUL
 *   CreateImage   (type 4)  bool grab_focus, string name, i32 width, i32 height,
 *                           i32 n_channels, n_channels × string channel name
 *   UpdateImageV3 (type 6)  bool grab_focus, string name, i32 n_channels, n × string name,
 *                           i32 x, y, width, height, n × i64 offset, n × i64 stride (in
 *                           floats), then the f32 pixel data: channel c of pixel i (row-major
 *                           in the rectangle) at offset[c] + i·stride[c]
 *
 * The image is the film's window (crop), width × height, with channels R, G, B (the
 * resolved colour, as the EXR's) and `error`, the pixel's relative standard error
 * sqrt(Var[Y] / (Y² + 1e-3)), Y the Rec. 709 luminance and Var[Y] the variance of its mean
 * (channel covariances ignored) — the per-pixel term of proto/error-estimate.md, so the
 * RMS of the channel over the image is the job's error estimate. Pixels sent are exactly
 * the floats of the STATS EXR of the same film (ts_film_to_image), planar per channel.
 *
 * Never slowing the render: on_tile (a worker thread) only records that a tile changed, in
 * a lock-free queue with one place per tile (a flag and a stamp: a tile already queued is
 * not queued again), so the queue is bounded, never full, and a worker never waits on it.
 * The display's own thread takes tiles from it, reads the tile's latest immutable snapshot
 * (ts_sched_job_tile), encodes and sends it. Workers never wake it (a wake-up is a system
 * call that can cost a worker its CPU on a loaded machine): it looks at the queue every
 * 20 ms while tiles come, every 0.2 s when none do, and runs as SCHED_BATCH, so its own
 * wake-ups do not preempt workers either. It paces itself to at most 2 % of one core while
 * the job renders (after a batch taking c seconds of its CPU it rests until 50·c after the
 * batch began; encoding and sending a 32×32 tile costs about 0.1 ms), so it can slow a
 * render whose workers fill the machine by at most 2 %; early passes (1, 2 spp) then show
 * up in steps rather than tile by tile on large images. Once the job is finished, or while
 * a flush waits, it sends without rests. A slow viewer therefore sees fewer
 * intermediate states, never stale final ones. Connecting, resolving the host, sending and
 * waiting all happen on that thread: a viewer that is down, slow or restarting costs the
 * workers nothing. On a failed connect or send the thread closes the socket and tries
 * again with exponential backoff (0.1 s doubling to 5 s); on every new connection it sends
 * CreateImage and then every tile rendered so far, so a restarted tev gets the whole
 * image. While idle it notices a viewer that closed the connection (within 0.2 s).
 *
 * Threads: srv_display_tile / _on_tile may be called from any thread; the others from the
 * thread that owns the display. */
#ifndef SRV_DISPLAY_H
#define SRV_DISPLAY_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "tessera.h"

/* The longest HOST:PORT accepted: 255, the longest string a posted document may hold. */
#define SRV_DISPLAY_ADDRESS_MAX 255
#define SRV_DISPLAY_NAME_MAX 256

/* tev's packet types (include/tev/Ipc.h). */
typedef enum srv_display_packet {
    SRV_DISPLAY_CLOSE_IMAGE = 2,
    SRV_DISPLAY_CREATE_IMAGE = 4,
    SRV_DISPLAY_UPDATE_IMAGE_V3 = 6,
} srv_display_packet;

/* Channels of the streamed image, in order. */
#define SRV_DISPLAY_CHANNELS 4
extern const char *const srv_display_channel_names[SRV_DISPLAY_CHANNELS]; /* R, G, B, error */

typedef struct srv_display srv_display;

/* Checks "HOST:PORT" and splits it: HOST a DNS name or IPv4 address (letters, digits, '.',
 * '-', '_') or a bracketed IPv6 address ("[::1]:14158"), PORT 1–65535 in decimal; at most
 * SRV_DISPLAY_ADDRESS_MAX characters. host/port may be NULL (check only); host needs
 * SRV_DISPLAY_ADDRESS_MAX + 1 bytes, port 6. TS_ERR_INVALID with a sentence otherwise. */
ts_status srv_display_parse_address(const char *address, char *host, char *port, ts_error *err);

/* A display streaming to `address` an image called `name` (truncated to
 * SRV_DISPLAY_NAME_MAX − 1 bytes). Starts the display's thread, which connects in the
 * background: an unreachable server is not an error here. NULL with err filled for a bad
 * address (TS_ERR_INVALID) or when memory or a thread cannot be had. */
srv_display *srv_display_create(const char *address, const char *name, ts_error *err);

/* Records that a tile of `job` changed (call from the job's on_tile). The first job seen is
 * the display's (it takes a reference to it); tiles of other jobs are ignored. Quick: a few
 * atomic operations, no lock, no system call, no allocation after the first call (which
 * takes a mutex once). */
void srv_display_tile(srv_display *d, ts_sched_job *job, const ts_tile_event *ev);
/* The same with the signature of ts_job_callbacks.on_tile (user = the display). */
void srv_display_on_tile(void *user, ts_sched_job *job, const ts_tile_event *ev);

/* Waits until every tile recorded so far has been sent on a live connection, at most
 * timeout_s seconds. True when everything was sent; false on timeout, or at once when not
 * connected and an attempt to connect has failed (before or during the wait): an
 * unreachable viewer is not waited for. */
bool srv_display_flush(srv_display *d, double timeout_s);

/* No more tiles will come (call from on_done): the thread sends what is queued if it is
 * connected (or connects first, when it has not tried yet), then ends without reconnecting;
 * srv_display_destroy then returns at once.
 * Quick, never blocks (may run on a render thread). */
void srv_display_finish(srv_display *d);

/* True while connected to the viewer. */
bool srv_display_connected(srv_display *d);

typedef struct srv_display_stats {
    uint64_t connects;        /* connections made */
    uint64_t failed_connects; /* attempts that failed (unresolved, refused, timed out) */
    uint64_t disconnects;     /* connections lost (send failed, peer closed) */
    uint64_t tiles_sent;      /* UpdateImage packets sent in full */
    uint64_t bytes_sent;
    double thread_cpu_s;      /* CPU time of the display's thread so far (encoding, sending) */
} srv_display_stats;
void srv_display_get_stats(srv_display *d, srv_display_stats *out);

/* Stops the thread (interrupting a send under way; a connect attempt under way ends within
 * its 2 s timeout), closes the connection and frees the display; NULL is fine. Call srv_display_flush first to send what is queued. */
void srv_display_destroy(srv_display *d);

/* The `error` channel of one pixel from its colour and variance of the mean (as above). */
float srv_display_relative_error(const float rgb[3], const float var[3]);

#endif
