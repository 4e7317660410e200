/* test_display.c — tev display-server streaming (server/display.h).
 *
 * A viewer in the test listens on loopback and decodes every packet with a decoder of its
 * own, written from tev's description of the format (the length-prefixed packets of
 * include/tev/Ipc.h; CreateImage and UpdateImageV3), checking each field. A small render
 * through the library's scheduler with the display attached must arrive exactly: R, G, B
 * bit for bit equal to the STATS EXR of the job's final film (through ts_exr_write_memory
 * and back), and `error` equal to sqrt(Var[Y]/(Y²+1e-3)) of the EXR's variances. Then: the
 * viewer drops the connection mid-render and comes back (the stream resumes on a new
 * connection, whose image alone is complete); no viewer at all, and a viewer that never
 * reads (the render finishes with the same pixels, bit for bit, as without a display, and
 * destroying the display does not hang); the HOST:PORT syntax; and through the binary:
 * `tessera render --display-server` (the image equals its -o EXR; unreachable: the same
 * pixels, exit 0), `tessera serve --display-server` (every job, equal to image.exr) and the
 * job.display_server policy (403 unless the server's own address or
 * --allow-job-display-server; 400 for bad syntax). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <arpa/inet.h>
#include <errno.h>
#include <math.h>
#include <netinet/in.h>
#include <poll.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "cli_support.h"
#include "display.h"
#include "server_harness.h"

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* ---------------------------------------------------------------- the viewer */

typedef struct viewer {
    int lfd, port;
    pthread_t thread;
    /* behaviour, set before start */
    int drop_after;     /* close the first connection after this many packets (0: never) */
    bool never_read;    /* accept and read nothing */
    /* results, written by the viewer thread; read after it is joined (or under mu) */
    pthread_mutex_t mu;
    bool stop;
    int connections, creates, updates, updates_this_connection;
    int eofs;           /* connections the display closed (it finished or was destroyed) */
    char name[SRV_DISPLAY_NAME_MAX];
    int w, h;
    float *img;          /* w·h·4 of the current connection's image, planar per channel */
    unsigned char *seen; /* per pixel: updated on the current connection */
    char problem[256];   /* the first malformed packet, "" when none */
} viewer;

static int listen_on(int port)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    assert_true(fd >= 0);
    int one = 1;
    setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    struct sockaddr_in a = {0};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = htons((uint16_t)port);
    assert_int_equal(bind(fd, (struct sockaddr *)&a, sizeof a), 0);
    assert_int_equal(listen(fd, 4), 0);
    return fd;
}

static int port_of(int fd)
{
    struct sockaddr_in a;
    socklen_t n = sizeof a;
    getsockname(fd, (struct sockaddr *)&a, &n);
    return ntohs(a.sin_port);
}

static bool read_full(int fd, void *p, size_t n)
{
    while (n) {
        ssize_t r = recv(fd, p, n, 0);
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0) return false;
        p = (char *)p + r, n -= (size_t)r;
    }
    return true;
}

/* A cursor over one packet: every read checks the bounds. */
typedef struct cursor {
    const unsigned char *p;
    size_t n, i;
    bool bad;
} cursor;
static uint64_t get_le(cursor *c, int bytes)
{
    if (c->i + (size_t)bytes > c->n) {
        c->bad = true;
        return 0;
    }
    uint64_t v = 0;
    for (int k = 0; k < bytes; k++) v |= (uint64_t)c->p[c->i + k] << (8 * k);
    c->i += (size_t)bytes;
    return v;
}
static int32_t get_i32(cursor *c) { return (int32_t)(uint32_t)get_le(c, 4); }
static int64_t get_i64(cursor *c) { return (int64_t)get_le(c, 8); }
static const char *get_str(cursor *c)
{
    const char *s = (const char *)c->p + c->i;
    const void *z = c->i < c->n ? memchr(s, 0, c->n - c->i) : NULL;
    if (!z) {
        c->bad = true;
        return "";
    }
    c->i += (size_t)((const char *)z - s) + 1;
    return s;
}

static void complain(viewer *v, const char *what)
{
    if (!v->problem[0]) snprintf(v->problem, sizeof v->problem, "%s", what);
}

static void check_channels(viewer *v, cursor *c)
{
    int32_t nch = get_i32(c);
    if (nch != SRV_DISPLAY_CHANNELS) complain(v, "channel count");
    static const char *const want[4] = {"R", "G", "B", "error"};
    for (int k = 0; k < nch && k < 4 && !c->bad; k++)
        if (strcmp(get_str(c), want[k]) != 0) complain(v, "channel name");
}

/* mu held. */
static void decode(viewer *v, const unsigned char *p, size_t n)
{
    cursor c = {p, n, 4, false};
    int type = (int)get_le(&c, 1);
    bool grab = get_le(&c, 1) != 0;
    const char *name = get_str(&c);
    if (type == 4) { /* CreateImage */
        if (!grab) complain(v, "CreateImage should grab the focus");
        int32_t w = get_i32(&c), h = get_i32(&c);
        check_channels(v, &c);
        if (c.bad || c.i != n || w <= 0 || h <= 0 || w > 4096 || h > 4096) return complain(v, "CreateImage malformed");
        snprintf(v->name, sizeof v->name, "%s", name);
        free(v->img), free(v->seen);
        v->w = w, v->h = h;
        v->img = calloc((size_t)w * h * 4, sizeof(float));
        v->seen = calloc((size_t)w * h, 1);
        v->creates++;
        return;
    }
    if (type != 6) return complain(v, "unexpected packet type");
    check_channels(v, &c);
    int32_t x = get_i32(&c), y = get_i32(&c), w = get_i32(&c), h = get_i32(&c);
    int64_t off[4], stride[4];
    for (int k = 0; k < 4; k++) off[k] = get_i64(&c);
    for (int k = 0; k < 4; k++) stride[k] = get_i64(&c);
    if (c.bad || !v->img) return complain(v, "UpdateImage malformed or before CreateImage");
    if (strcmp(name, v->name) != 0) return complain(v, "UpdateImage of another image");
    if (x < 0 || y < 0 || w <= 0 || h <= 0 || x + w > v->w || y + h > v->h) return complain(v, "UpdateImage outside the image");
    int64_t npx = (int64_t)w * h, floats = 0;
    for (int k = 0; k < 4; k++) {
        if (off[k] < 0 || stride[k] < 1) return complain(v, "bad offset or stride");
        int64_t end = off[k] + (npx - 1) * stride[k] + 1;
        if (end > floats) floats = end;
    }
    if ((size_t)floats * 4 != n - c.i) return complain(v, "UpdateImage data size");
    const unsigned char *data = p + c.i;
    for (int64_t i = 0; i < npx; i++) {
        int px = x + (int)(i % w), py = y + (int)(i / w);
        for (int k = 0; k < 4; k++) {
            float f;
            memcpy(&f, data + 4 * (off[k] + i * stride[k]), 4); /* little-endian host (x86, arm) */
            v->img[((size_t)k * v->h + py) * v->w + px] = f;
        }
        v->seen[(size_t)py * v->w + px] = 1;
    }
    v->updates++;
    v->updates_this_connection++;
}

/* Serves one connection until EOF or (drop) the packet budget; false when it dropped it. */
static bool serve(viewer *v, int fd, int budget)
{
    unsigned char *p = NULL;
    for (;;) {
        unsigned char len4[4];
        if (!read_full(fd, len4, 4)) break;
        uint32_t n = (uint32_t)len4[0] | (uint32_t)len4[1] << 8 | (uint32_t)len4[2] << 16 | (uint32_t)len4[3] << 24;
        if (n < 6 || n > (64u << 20)) {
            pthread_mutex_lock(&v->mu);
            complain(v, "packet length");
            pthread_mutex_unlock(&v->mu);
            break;
        }
        unsigned char *q = realloc(p, n);
        assert_non_null(q);
        p = q;
        memcpy(p, len4, 4);
        if (!read_full(fd, p + 4, n - 4)) break;
        pthread_mutex_lock(&v->mu);
        decode(v, p, n);
        int seen = v->creates + v->updates;
        pthread_mutex_unlock(&v->mu);
        if (budget && seen >= budget) {
            free(p);
            return false;
        }
    }
    free(p);
    return true;
}

static bool stopping(viewer *v)
{
    pthread_mutex_lock(&v->mu);
    bool s = v->stop;
    pthread_mutex_unlock(&v->mu);
    return s;
}

static void *viewer_thread(void *arg)
{
    viewer *v = arg;
    while (!stopping(v)) {
        struct pollfd pfd = {v->lfd, POLLIN, 0};
        if (poll(&pfd, 1, 50) != 1) continue;
        int fd = accept(v->lfd, NULL, NULL);
        if (fd < 0) continue;
        pthread_mutex_lock(&v->mu);
        v->connections++;
        v->updates_this_connection = 0;
        int budget = v->connections == 1 ? v->drop_after : 0;
        pthread_mutex_unlock(&v->mu);
        if (v->never_read) {
            while (!stopping(v)) poll(NULL, 0, 20);
            close(fd);
            break;
        }
        bool whole = serve(v, fd, budget);
        if (whole) {
            pthread_mutex_lock(&v->mu);
            v->eofs++;
            pthread_mutex_unlock(&v->mu);
        }
        if (!whole) {
            /* A viewer that quits mid-stream and is started again a little later. */
            close(fd);
            close(v->lfd);
            poll(NULL, 0, 300);
            v->lfd = listen_on(v->port);
            continue;
        }
        close(fd);
    }
    return NULL;
}

static void viewer_start(viewer *v)
{
    pthread_mutex_init(&v->mu, NULL);
    v->lfd = listen_on(0);
    v->port = port_of(v->lfd);
    assert_int_equal(pthread_create(&v->thread, NULL, viewer_thread, v), 0);
}

static void viewer_stop(viewer *v)
{
    pthread_mutex_lock(&v->mu);
    v->stop = true;
    pthread_mutex_unlock(&v->mu);
    pthread_join(v->thread, NULL);
    close(v->lfd);
}

static void viewer_free(viewer *v)
{
    free(v->img);
    free(v->seen);
    pthread_mutex_destroy(&v->mu);
}

/* ---------------------------------------------------------------- rendering */

typedef struct done_wait {
    pthread_mutex_t mu;
    pthread_cond_t cv;
    bool done;
    srv_display *display;
} done_wait;

static void on_tile(void *user, ts_sched_job *j, const ts_tile_event *ev)
{
    done_wait *w = user;
    if (w->display) srv_display_tile(w->display, j, ev);
}
static void on_done(void *user, ts_sched_job *j, const ts_job_progress *p)
{
    (void)j, (void)p;
    done_wait *w = user;
    pthread_mutex_lock(&w->mu);
    w->done = true;
    pthread_cond_signal(&w->cv);
    pthread_mutex_unlock(&w->mu);
}

/* Renders the built-in Cornell box's window [100,230)×[200,290) (5×3 tiles, the last
 * column and row partial, not at the origin) with `integ` to `spp`, streaming to d (may be
 * NULL). Returns the job (caller releases) once done. */
static ts_sched_job *render_window(ts_scheduler *s, srv_display *d, ts_integrator_type integ, uint32_t spp, bool whole)
{
    ts_scene *scene = NULL;
    ts_error err = {0};
    assert_int_equal(ts_scene_load_builtin(NULL, &scene, &err), TS_OK);
    if (!whole) scene->crop_x0 = 100, scene->crop_x1 = 230, scene->crop_y0 = 200, scene->crop_y1 = 290;
    done_wait w = {PTHREAD_MUTEX_INITIALIZER, PTHREAD_COND_INITIALIZER, false, d};
    ts_sched_job_desc desc = {0};
    desc.scene = scene;
    desc.settings.integrator = integ;
    desc.settings.spp = spp;
    desc.callbacks = (ts_job_callbacks){on_tile, NULL, on_done, &w};
    ts_sched_job *j = ts_scheduler_submit(s, &desc, &err);
    assert_non_null(j);
    pthread_mutex_lock(&w.mu);
    while (!w.done) pthread_cond_wait(&w.cv, &w.mu);
    pthread_mutex_unlock(&w.mu);
    return j;
}

static ts_sched_job *render(ts_scheduler *s, srv_display *d, ts_integrator_type integ, uint32_t spp)
{
    return render_window(s, d, integ, spp, false);
}

/* The job's final film as its STATS EXR, decoded again (what the server serves). */
static void final_exr(ts_sched_job *j, ts_image *out)
{
    ts_error err = {0};
    ts_film *f = ts_sched_job_film(j, NULL, &err);
    assert_non_null(f);
    ts_image img;
    assert_int_equal(ts_film_to_image(f, TS_FILM_IMAGE_STATS, &img, &err), TS_OK);
    unsigned char *bytes = NULL;
    size_t len = 0;
    assert_int_equal(ts_exr_write_memory(&img, &bytes, &len, &err), TS_OK);
    assert_int_equal(ts_exr_read_memory(bytes, len, out, &err), TS_OK);
    free(bytes);
    ts_image_fini(&img);
    ts_film_destroy(f);
}

/* The viewer's image equals the EXR: colour bit for bit, error to float rounding. */
static void assert_matches(const viewer *v, const ts_image *exr)
{
    assert_string_equal(v->problem, "");
    assert_int_equal(v->w, exr->width);
    assert_int_equal(v->h, exr->height);
    int ch[7];
    static const char *const names[7] = {"R", "G", "B", "R.var", "G.var", "B.var", "count"};
    for (int k = 0; k < 7; k++) assert_true((ch[k] = ts_image_channel(exr, names[k])) >= 0);
    size_t npx = (size_t)v->w * v->h, mismatched = 0, err_off = 0;
    for (size_t i = 0; i < npx; i++) {
        assert_true(v->seen[i]);
        const float *px = exr->data + i * exr->n_channels;
        for (int k = 0; k < 3; k++) {
            float got = v->img[k * npx + i];
            if (memcmp(&got, &px[ch[k]], sizeof got) != 0) mismatched++;
        }
        /* The error channel, computed here from the EXR's own floats (double, then float:
         * the display may round differently by one float ulp, 6e-8 relative). */
        double y = 0.2126 * px[ch[0]] + 0.7152 * px[ch[1]] + 0.0722 * px[ch[2]];
        double var = 0.04519876 * px[ch[3]] + 0.51151104 * px[ch[4]] + 0.00521284 * px[ch[5]];
        double want = var > 0 ? sqrt(var / (y * y + 1e-3)) : 0, got = v->img[3 * npx + i];
        if (fabs(got - want) > 2e-7 * want + 1e-30) err_off++;
    }
    assert_int_equal(mismatched, 0);
    assert_int_equal(err_off, 0);
}

/* ---------------------------------------------------------------- tests */

static void test_stream_exact(void **state)
{
    (void)state;
    viewer v = {0};
    viewer_start(&v);
    char addr[64];
    snprintf(addr, sizeof addr, "127.0.0.1:%d", v.port);
    ts_error err = {0};
    srv_display *d = srv_display_create(addr, "cornell window", &err);
    assert_non_null(d);
    ts_scheduler *s = ts_scheduler_create(2, 1, &err);
    ts_sched_job *j = render(s, d, TS_INTEGRATOR_PATH, 16);
    assert_true(srv_display_flush(d, 20));
    srv_display_stats st;
    srv_display_get_stats(d, &st);
    srv_display_destroy(d);
    viewer_stop(&v);
    ts_image exr;
    final_exr(j, &exr);
    assert_int_equal(v.connections, 1);
    assert_int_equal(v.creates, 1);
    assert_string_equal(v.name, "cornell window");
    /* 15 tiles × 5 passes (1, 2, 4, 8, 16 spp) at most; at least every tile once. */
    assert_true(v.updates >= 15 && v.updates <= 75);
    assert_int_equal((int)st.tiles_sent, v.updates);
    assert_int_equal(st.connects, 1);
    assert_matches(&v, &exr);
    ts_image_fini(&exr);
    ts_sched_job_release(j);
    ts_scheduler_destroy(s);
    viewer_free(&v);
}

static void test_reconnect(void **state)
{
    (void)state;
    viewer v = {0};
    v.drop_after = 4; /* CreateImage and three tiles, then the viewer quits and restarts */
    viewer_start(&v);
    char addr[64];
    snprintf(addr, sizeof addr, "127.0.0.1:%d", v.port);
    ts_error err = {0};
    srv_display *d = srv_display_create(addr, "resumed", &err);
    assert_non_null(d);
    ts_scheduler *s = ts_scheduler_create(2, 1, &err);
    ts_sched_job *j = render(s, d, TS_INTEGRATOR_PATH, 64);
    /* The viewer may be between its two lives now: flush gives up at once then; retry. */
    double until = now_s() + 20;
    while (!srv_display_flush(d, 1) && now_s() < until) poll(NULL, 0, 50);
    assert_true(srv_display_flush(d, 1));
    srv_display_stats st;
    srv_display_get_stats(d, &st);
    srv_display_destroy(d);
    viewer_stop(&v);
    assert_int_equal(v.connections, 2);
    assert_int_equal(v.creates, 2); /* the new connection created the image again */
    assert_true(st.connects == 2 && st.disconnects >= 1);
    /* The second connection's image alone is whole and exact. */
    assert_true(v.updates_this_connection >= 15);
    ts_image exr;
    final_exr(j, &exr);
    assert_matches(&v, &exr);
    ts_image_fini(&exr);
    ts_sched_job_release(j);
    ts_scheduler_destroy(s);
    viewer_free(&v);
}

static bool same_film(ts_sched_job *a, ts_sched_job *b)
{
    ts_error err = {0};
    ts_film *fa = ts_sched_job_film(a, NULL, &err), *fb = ts_sched_job_film(b, NULL, &err);
    assert_true(fa && fb && fa->width == fb->width && fa->height == fb->height);
    bool same = memcmp(fa->pixels, fb->pixels, sizeof *fa->pixels * (size_t)fa->width * fa->height) == 0;
    ts_film_destroy(fa);
    ts_film_destroy(fb);
    return same;
}

/* No viewer: the address refuses connections. The render is unaffected (same pixels as
 * without a display), flush gives up, destroy is prompt. */
static void test_unreachable(void **state)
{
    (void)state;
    int fd = listen_on(0), port = port_of(fd);
    close(fd); /* nothing listens there now */
    char addr[64];
    snprintf(addr, sizeof addr, "127.0.0.1:%d", port);
    ts_error err = {0};
    srv_display *d = srv_display_create(addr, "nobody", &err);
    assert_non_null(d);
    ts_scheduler *s = ts_scheduler_create(2, 1, &err);
    ts_sched_job *with = render(s, d, TS_INTEGRATOR_PATH, 16);
    ts_sched_job *without = render(s, NULL, TS_INTEGRATOR_PATH, 16);
    assert_true(same_film(with, without));
    assert_false(srv_display_flush(d, 0.3));
    srv_display_stats st;
    srv_display_get_stats(d, &st);
    assert_int_equal(st.connects, 0);
    assert_true(st.failed_connects >= 1);
    double t = now_s();
    srv_display_destroy(d);
    assert_true(now_s() - t < 1.0);
    ts_sched_job_release(with);
    ts_sched_job_release(without);
    ts_scheduler_destroy(s);
}

/* A viewer that accepts and never reads: sends block on the display's thread only. */
static void test_stalled_viewer(void **state)
{
    (void)state;
    viewer v = {0};
    v.never_read = true;
    viewer_start(&v);
    char addr[64];
    snprintf(addr, sizeof addr, "127.0.0.1:%d", v.port);
    ts_error err = {0};
    srv_display *d = srv_display_create(addr, "stalled", &err);
    ts_scheduler *s = ts_scheduler_create(2, 1, &err);
    /* The whole 512×512 film to 8 spp: 4 passes of 256 tiles of 16 KiB, 16 MiB, far more
     * than the socket buffers hold (a few MiB at most on Linux's defaults). */
    ts_sched_job *with = render_window(s, d, TS_INTEGRATOR_AO, 8, true);
    ts_sched_job *without = render_window(s, NULL, TS_INTEGRATOR_AO, 8, true);
    assert_true(same_film(with, without));
    assert_false(srv_display_flush(d, 0.2));
    double t = now_s();
    srv_display_destroy(d); /* interrupts the blocked send */
    assert_true(now_s() - t < 1.0);
    viewer_stop(&v);
    ts_sched_job_release(with);
    ts_sched_job_release(without);
    ts_scheduler_destroy(s);
    viewer_free(&v);
}

/* ---------------------------------------------------------------- through the binary */

/* Waits until the display closed n connections (it has sent all it will). */
static void wait_eofs(viewer *v, int n)
{
    double until = now_s() + 20;
    for (;;) {
        pthread_mutex_lock(&v->mu);
        int e = v->eofs;
        pthread_mutex_unlock(&v->mu);
        if (e >= n) return;
        if (now_s() > until) fail_msg("the display closed %d connections in 20 s, expected %d", e, n);
        poll(NULL, 0, 20);
    }
}

static void read_exr_file(const char *path, ts_image *out)
{
    ts_error err = {0};
    if (ts_exr_read(path, out, &err)) fail_msg("%s: %s", path, err.message);
}

/* The test scene with "job": {"display_server": address} (malloc'd). */
static char *scene_with_display(const char *name, const char *address)
{
    char *base = ts_ao_scene(name, 80, 48, 8); /* 3×2 tiles, the last column partial */
    char *s = malloc(strlen(base) + 128);
    assert_non_null(s);
    sprintf(s, "{\"job\":{\"display_server\":\"%s\"},%s", address, base + 1);
    free(base);
    return s;
}

/* tessera render --display-server: the viewer gets the image the -o EXR holds. And with
 * nothing listening, the same pixels and exit 0 with a note. */
static void test_cli(void **state)
{
    (void)state;
    viewer v = {0};
    viewer_start(&v);
    char addr[64], dir[] = "/tmp/tessera-display-XXXXXX", scene[128], out[128], out2[128], log[128];
    snprintf(addr, sizeof addr, "127.0.0.1:%d", v.port);
    assert_non_null(mkdtemp(dir));
    snprintf(scene, sizeof scene, "%s/scene.json", dir);
    snprintf(out, sizeof out, "%s/out.exr", dir);
    snprintf(out2, sizeof out2, "%s/unreached.exr", dir);
    snprintf(log, sizeof log, "%s/log", dir);
    char *text = ts_ao_scene("cli-stream", 80, 48, 8);
    cli_write_file(scene, text);
    free(text);
    const char *args[] = {"render", scene, "--threads", "2", "-o", out, "--display-server", addr, NULL};
    assert_int_equal(cli_run(log, args, NULL), 0);
    wait_eofs(&v, 1);
    viewer_stop(&v);
    ts_image exr;
    read_exr_file(out, &exr);
    assert_int_equal(v.creates, 1);
    assert_string_equal(v.name, "cli-stream");
    assert_matches(&v, &exr);

    int fd = listen_on(0), port = port_of(fd);
    close(fd);
    snprintf(addr, sizeof addr, "127.0.0.1:%d", port);
    const char *args2[] = {"render", scene, "--threads", "2", "-o", out2, "--display-server", addr, NULL};
    assert_int_equal(cli_run(log, args2, NULL), 0);
    assert_non_null(strstr(cli_read_log(log), "not reachable"));
    ts_image again;
    read_exr_file(out2, &again);
    assert_memory_equal(exr.data, again.data, sizeof(float) * (size_t)exr.width * exr.height * exr.n_channels);
    const char *bad[] = {"render", scene, "--display-server", "no-port", NULL};
    assert_int_equal(cli_run(log, bad, NULL), 2);
    assert_non_null(strstr(cli_read_log(log), "--display-server"));
    ts_image_fini(&exr);
    ts_image_fini(&again);
    viewer_free(&v);
    unlink(scene), unlink(out), unlink(out2), unlink(log), rmdir(dir);
}

static long post(const test_server *srv, const char *scene, char *message, size_t n)
{
    http_resp r;
    ts_http(srv, "POST", "/api/v1/jobs", scene, strlen(scene), NULL, &r);
    long status = r.status;
    snprintf(message, n, "%s", r.body ? r.body : "");
    ts_http_free(&r);
    return status;
}

/* tessera serve --display-server: every job streams there; image.exr matches. A job's own
 * job.display_server is refused unless it is that address. */
static void test_serve(void **state)
{
    (void)state;
    viewer v = {0};
    viewer_start(&v);
    char addr[64], other[64], msg[1024];
    snprintf(addr, sizeof addr, "127.0.0.1:%d", v.port);
    int fd = listen_on(0);
    snprintf(other, sizeof other, "127.0.0.1:%d", port_of(fd));
    close(fd);
    test_server srv;
    const char *args[] = {"--threads", "2", "--display-server", addr, NULL};
    ts_server_start(&srv, args);
    char *text = ts_ao_scene("served", 80, 48, 8), id[64];
    ts_submit(&srv, text, id, sizeof id);
    free(text);
    cJSON *st = ts_wait_done(&srv, id, 30);
    cJSON_Delete(st);
    wait_eofs(&v, 1);
    char path[128];
    snprintf(path, sizeof path, "/api/v1/jobs/%s/image.exr", id);
    http_resp r;
    ts_http(&srv, "GET", path, NULL, 0, NULL, &r);
    assert_int_equal(r.status, 200);
    ts_image exr;
    ts_error err = {0};
    assert_int_equal(ts_exr_read_memory((const unsigned char *)r.body, r.len, &exr, &err), TS_OK);
    ts_http_free(&r);
    pthread_mutex_lock(&v.mu);
    char want[128];
    snprintf(want, sizeof want, "served (%s)", id);
    assert_string_equal(v.name, want);
    assert_matches(&v, &exr);
    pthread_mutex_unlock(&v.mu);
    ts_image_fini(&exr);

    /* The server's own address is fine in a job; another is not (403); bad syntax is 400. */
    text = scene_with_display("same", addr);
    assert_int_equal(post(&srv, text, msg, sizeof msg), 201);
    free(text);
    text = scene_with_display("elsewhere", other);
    assert_int_equal(post(&srv, text, msg, sizeof msg), 403);
    assert_non_null(strstr(msg, "job.display_server: this server does not let a job choose"));
    free(text);
    text = scene_with_display("bad", "no port");
    assert_int_equal(post(&srv, text, msg, sizeof msg), 400);
    assert_non_null(strstr(msg, "job.display_server:"));
    free(text);
    ts_server_stop(&srv, SIGTERM);
    viewer_stop(&v);
    viewer_free(&v);

    /* No display options: every job.display_server is refused. */
    const char *plain[] = {"--threads", "1", NULL};
    ts_server_start(&srv, plain);
    text = scene_with_display("refused", "127.0.0.1:14158");
    assert_int_equal(post(&srv, text, msg, sizeof msg), 403);
    free(text);
    ts_server_stop(&srv, SIGTERM);

    /* --allow-job-display-server: a job streams where it says. */
    viewer w = {0};
    viewer_start(&w);
    snprintf(addr, sizeof addr, "127.0.0.1:%d", w.port);
    const char *allow[] = {"--threads", "2", "--allow-job-display-server", NULL};
    ts_server_start(&srv, allow);
    text = scene_with_display("chosen", addr);
    ts_submit(&srv, text, id, sizeof id);
    free(text);
    st = ts_wait_done(&srv, id, 30);
    cJSON_Delete(st);
    wait_eofs(&w, 1);
    pthread_mutex_lock(&w.mu);
    assert_int_equal(w.creates, 1);
    assert_true(w.updates >= 6);
    assert_string_equal(w.problem, "");
    pthread_mutex_unlock(&w.mu);
    ts_server_stop(&srv, SIGTERM);
    viewer_stop(&w);
    viewer_free(&w);

    const char *badarg[] = {"serve", "--display-server", "[::1]", NULL};
    char log[] = "/tmp/tessera-display-serve.log";
    assert_int_equal(cli_run(log, badarg, NULL), 2);
    unlink(log);
}

static void test_address(void **state)
{
    (void)state;
    char host[SRV_DISPLAY_ADDRESS_MAX + 1], port[8];
    ts_error err = {0};
    assert_int_equal(srv_display_parse_address("localhost:14158", host, port, &err), TS_OK);
    assert_string_equal(host, "localhost");
    assert_string_equal(port, "14158");
    assert_int_equal(srv_display_parse_address("127.0.0.1:1", host, port, &err), TS_OK);
    assert_int_equal(srv_display_parse_address("[::1]:65535", host, port, &err), TS_OK);
    assert_string_equal(host, "::1");
    assert_string_equal(port, "65535");
    assert_int_equal(srv_display_parse_address("render-box_2.example.org:9", NULL, NULL, &err), TS_OK);
    static const char *const bad[] = {"", "localhost", "localhost:", ":14158", "host:0", "host:65536", "host:123456",
                                      "host:+1", "host:1x", "ho st:1", "host/x:1", "a:b", "[::1]14158", "[]:1",
                                      "[::g]:1", "host:1\n", "user@host:1"};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        err = (ts_error){0};
        if (srv_display_parse_address(bad[i], host, port, &err) != TS_ERR_INVALID) fail_msg("accepted '%s'", bad[i]);
        assert_true(strstr(err.message, "display server") != NULL);
    }
    char longest[SRV_DISPLAY_ADDRESS_MAX + 8];
    memset(longest, 'a', sizeof longest);
    memcpy(longest + SRV_DISPLAY_ADDRESS_MAX - 5, ":1234", 6); /* exactly the limit */
    assert_int_equal(srv_display_parse_address(longest, host, port, &err), TS_OK);
    memset(longest, 'a', sizeof longest);
    memcpy(longest + SRV_DISPLAY_ADDRESS_MAX - 4, ":1234", 6); /* one more */
    assert_int_equal(srv_display_parse_address(longest, host, port, &err), TS_ERR_INVALID);
    assert_null(srv_display_create("nowhere", "x", &err));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_address),       cmocka_unit_test(test_stream_exact), cmocka_unit_test(test_reconnect),
        cmocka_unit_test(test_unreachable),   cmocka_unit_test(test_stalled_viewer), cmocka_unit_test(test_cli),
        cmocka_unit_test(test_serve),
    };
    if (getenv("TS_TEST_FILTER")) cmocka_set_test_filter(getenv("TS_TEST_FILTER"));
    return cmocka_run_group_tests(tests, NULL, NULL);
}
