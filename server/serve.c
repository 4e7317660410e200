/* serve.c — `tessera serve`: options, start-up, the maintenance thread, shutdown.
 *
 * Start-up: parse options, restore jobs from --data, start the scheduler, the encoder
 * pool and the HTTP daemon, print the URL. Shutdown on SIGINT/SIGTERM (taken with
 * sigwait in the main thread, so no handler runs on a random thread): stop accepting,
 * stop the render workers after their current tiles, checkpoint every job, end the event
 * streams, drain the encoders, stop the daemon, free everything. */
#include "serve.h"

#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "persist.h"
#include "usage.h"
#include "tessera.h"

#define KEEPALIVE_S 15.0
#define TICK_S 1.0 /* progress events and history points of running jobs */
#define SRV_ENCODER_THREADS 2
#define SRV_LOADER_THREADS 2

static void usage(FILE *f)
{
    fprintf(f,
            "usage: tessera serve [OPTIONS]\n"
            "The render server: HTTP API v1 (proto/openapi.yaml) and the web UI at /. Runs until SIGINT/SIGTERM.\n"
            "  --bind ADDRESS              numeric IPv4/IPv6 address to listen on (default 127.0.0.1)\n"
            "  --port N                    TCP port, 0 for any free one (default 8080)\n"
            "  --threads N                 render threads, 1 to 1024 (default: one per core)\n"
            "  --max-running N             jobs rendering at once, 1 to 1024 (default 4)\n"
            "  --http-threads N            HTTP threads, 1 to 64 (default 4)\n"
            "  --data DIR                  checkpoint jobs to DIR and resume them after a restart (default: none)\n"
            "  --checkpoint-interval S     seconds between checkpoints with --data (default 30)\n"
            "  --token TOKEN               require 'Authorization: Bearer TOKEN' (default: no token)\n"
            "  --token-file FILE           the same, the token read from FILE's first line (kept out of ps)\n"
            "  --cors-origin ORIGIN        answer CORS requests from ORIGIN (default: none)\n"
            "  --allowed-hosts H1,H2       Host names to answer besides the bind address (and localhost on loopback)\n"
            "  --assets DIR                the only folder posted scenes may read files from (default: none)\n"
            "  --max-asset-bytes BYTES     largest file a scene may read under --assets (default 268435456)\n"
            "  --max-jobs N                jobs held at once, any state; a POST beyond gets 503 (default 1000)\n"
            "  --max-body BYTES            largest request body, 64 to 4294967296 (default 16777216)\n"
            "  --max-resolution N          largest film width or height in pixels, to 16384 (default 8192)\n"
            "  --max-pixels N              largest film area in pixels (default 16777216)\n"
            "  --max-spp N                 most samples per pixel a job may ask (default 65536)\n"
            "  --max-triangles N           most triangles in a posted scene (default 5242880)\n"
            "  --max-shapes N              most shapes in a posted scene (default 65536)\n"
            "  --client-timeout S          close a connection idle this many seconds (default 60)\n"
            "  --request-timeout S         close a connection whose request (headers and body) has not arrived\n"
            "                              this many seconds after it opened or after its previous answer (default 60)\n"
            "  --max-client-connections N  connections one address may hold, to 4000 (default 1024)\n"
            "  --max-subscribers N         event streams open at once, all jobs, to 4000 (default 2048)\n"
            "  --max-job-subscribers N     event streams of one job at once, to 4000 (default 1024)\n"
            "  --max-work RAYS             most rays one job may ask for: rays a sample x spp x pixels (default 1e13)\n"
            "  --max-load-seconds S        time a posted scene may take to load, from its arrival; beyond, 422\n"
            "                              (or 503 if it waited that long for a loader), 0.1 to 3600 (default 30)\n"
            "A job may be posted as a tar (optionally gzip) of scene.json or scene.pbrt and its files:\n"
            "  --max-bundle-bytes BYTES    largest bundle as posted (default 268435456)\n"
            "  --max-bundle-entries N      most entries in a bundle, folders included (default 10000)\n"
            "  --max-bundle-expanded BYTES most bytes of all a bundle's files together (default 1073741824)\n"
            "  --max-bundle-entry-bytes BYTES  largest file in a bundle (default 268435456)\n"
            "  --max-bundle-path BYTES     longest path of a bundle's entry (default 1024)\n"
            "  --log-format text|json      job events as text lines or JSON lines on stderr (default text)\n"
            "  --log-level LEVEL           error, warn, info (job events; default) or debug (and every request)\n"
            "  --queue-builtin             queue the built-in Cornell box as the first job (make run)\n"
            "  --display-server HOST:PORT  stream every job to a tev viewer there, as tiles finish (default: none)\n"
            "  --allow-job-display-server  let a job's job.display_server name any address (default: only the\n"
            "                              --display-server one; others get 403)\n"
            "Farm jobs (\"job\": {\"farm\": {\"shards\": N}}, or a bundle's ?shards=N) run as one Slurm job array:\n"
            "  --farm slurm                send farm jobs to Slurm (sbatch, squeue, scontrol, scancel on PATH)\n"
            "  --farm-dir DIR              where their scenes, task scripts and shards go: storage every node sees\n"
            "  --farm-sbatch-arg ARG       one more sbatch option for every array, repeatable (e.g. --partition=render)\n"
            "  --farm-retries N            requeues of a failed task before its job fails (default 2)\n"
            "  --farm-checkpoint-interval S  the tasks' --checkpoint-interval: how often the image grows (default 10)\n"
            "  --farm-tessera PATH         the tessera the tasks run (default: this program)\n"
            "  --max-shards N              most tasks a farm job may ask for (default 1000)\n"
            "docs/security.md has the threat model and every limit.\n");
}

#define usage_error(...) (srv_usage_error("tessera serve", usage, __VA_ARGS__), SRV_USAGE_EXIT)

/* The first line of FILE, without its line end or trailing blanks (malloc'd), or NULL with
 * a sentence in msg. The token itself is never echoed. */
static char *read_token_file(const char *path, char *msg, size_t msg_len)
{
    FILE *f = fopen(path, "r");
    if (!f) {
        snprintf(msg, msg_len, "cannot open (%s)", strerror(errno));
        return NULL;
    }
    char line[4096];
    char *got = fgets(line, sizeof line, f);
    fclose(f);
    size_t n = got ? strcspn(line, "\r\n") : 0;
    while (n > 0 && (line[n - 1] == ' ' || line[n - 1] == '\t'))
        n--;
    line[n] = '\0';
    char *token = n ? strdup(line) : NULL;
    if (!token) snprintf(msg, msg_len, n ? "out of memory" : "the first line holds no token");
    explicit_bzero(line, sizeof line);
    return token;
}

static bool parse_u64(const char *s, unsigned long long lo, unsigned long long hi, unsigned long long *out)
{
    char *end;
    if (!s[0] || s[0] == '-') return false;
    errno = 0;
    unsigned long long v = strtoull(s, &end, 10);
    if (*end || errno || v < lo || v > hi) return false;
    *out = v;
    return true;
}

static void srv_server_kick(srv_server *srv)
{
    pthread_mutex_lock(&srv->mu);
    srv->kick = true;
    pthread_cond_signal(&srv->cv);
    pthread_mutex_unlock(&srv->mu);
}

static void keepalive_all(srv_store *st)
{
    int n = 0;
    srv_job **jobs = srv_store_list(st, &n);
    for (int i = 0; jobs && i < n; i++) {
        srv_events_keepalive(jobs[i]->events);
        srv_job_release(jobs[i]);
    }
    free(jobs);
}

/* Running jobs: a progress event and a history point. */
static void tick_all(srv_store *st)
{
    int n = 0;
    srv_job **jobs = srv_store_list(st, &n);
    for (int i = 0; jobs && i < n; i++) {
        srv_job_tick(jobs[i]);
        srv_job_release(jobs[i]);
    }
    free(jobs);
}

static void shutdown_streams(srv_store *st)
{
    int n = 0;
    srv_job **jobs = srv_store_list(st, &n);
    for (int i = 0; jobs && i < n; i++) {
        srv_events_shutdown(jobs[i]->events);
        srv_job_release(jobs[i]);
    }
    free(jobs);
}

/* Checkpoints (--data) every interval and soon after a job finishes; keep-alives to SSE
 * clients (so vanished ones are noticed). Waits on srv->cv with a deadline. */
static void *maintenance(void *arg)
{
    srv_server *srv = arg;
    double next_ckpt = ts_now_seconds() + srv->cfg.checkpoint_interval_s, next_ka = ts_now_seconds() + KEEPALIVE_S;
    double next_tick = ts_now_seconds() + TICK_S;
    pthread_mutex_lock(&srv->mu);
    while (!srv->stopping) {
        double now = ts_now_seconds();
        double until = srv->cfg.data_dir && next_ckpt < next_ka ? next_ckpt : next_ka;
        if (next_tick < until) until = next_tick;
        if (!srv->kick && now < until) {
            struct timespec ts;
            clock_gettime(CLOCK_REALTIME, &ts);
            double wait = until - now, whole = floor(wait);
            ts.tv_sec += (time_t)whole;
            ts.tv_nsec += (long)((wait - whole) * 1e9);
            if (ts.tv_nsec >= 1000000000L) ts.tv_sec++, ts.tv_nsec -= 1000000000L;
            pthread_cond_timedwait(&srv->cv, &srv->mu, &ts);
            continue;
        }
        bool kicked = srv->kick;
        srv->kick = false;
        pthread_mutex_unlock(&srv->mu);
        now = ts_now_seconds();
        if (srv->cfg.data_dir && (kicked || now >= next_ckpt)) {
            /* A failing job is retried after 1 s (or the interval, when shorter), doubling
             * up to 10 s (or the interval, when longer). */
            double ci = srv->cfg.checkpoint_interval_s;
            srv_persist_retry retry = {ci < 1 ? ci : 1, ci > 10 ? ci : 10};
            srv_persist_save_changed(srv->cfg.data_dir, srv->store, &retry, &srv->persist);
            if (now >= next_ckpt) next_ckpt = now + srv->cfg.checkpoint_interval_s;
        }
        if (now >= next_ka) {
            keepalive_all(srv->store);
            next_ka = now + KEEPALIVE_S;
        }
        if (now >= next_tick) {
            tick_all(srv->store);
            next_tick = now + TICK_S;
        }
        pthread_mutex_lock(&srv->mu);
    }
    pthread_mutex_unlock(&srv->mu);
    return NULL;
}

static void on_job_finished(void *user) { srv_server_kick(user); }

bool srv_server_start(srv_server *srv, int *port_out, char *err, size_t err_len)
{
    const srv_config *cfg = &srv->cfg;
    ts_error e = {0};
    pthread_mutex_init(&srv->mu, NULL);
    pthread_cond_init(&srv->cv, NULL);
    srv_log_init(&srv->log, cfg->log_format, cfg->log_level, stderr);
    srv->metrics = srv_metrics_create();
    srv->offload = srv_offload_create(SRV_ENCODER_THREADS);
    srv->loaders = srv_offload_create(SRV_LOADER_THREADS);
    atomic_init(&srv->loads_stop, false);
    srv->sched = ts_scheduler_create(cfg->threads, cfg->max_running, &e);
    srv_store_config sc = {cfg->limits, cfg->assets_dir, cfg->max_jobs, cfg->max_work, srv->sched, on_job_finished, srv,
                           &srv->log, cfg->display_server, cfg->allow_job_display_server};
    sc.describe = srv_farm_describe; /* farm jobs' status (its user, the farm, is set below) */
    srv->store = srv->sched ? srv_store_create(&sc) : NULL;
    if (!srv->metrics || !srv->store || !srv->offload || !srv->loaders || !srv->sched) {
        snprintf(err, err_len, "%s", e.message[0] ? e.message : "out of memory");
        goto fail;
    }
    if (cfg->data_dir) {
        if (srv_persist_init(cfg->data_dir, &e)) {
            snprintf(err, err_len, "--data: %s", e.message);
            goto fail;
        }
        int n = srv_persist_restore_all(cfg->data_dir, srv->store, &cfg->limits, cfg->assets_dir, &srv->persist);
        if (n) fprintf(stderr, "tessera serve: %d job(s) restored from %s\n", n, cfg->data_dir);
    }
    if (cfg->farm.slurm && !(srv->farm = srv_farm_create(&cfg->farm, srv->store, cfg->data_dir, &srv->log, err, err_len)))
        goto fail;
    srv_store_set_describe_user(srv->store, srv->farm);
    if (cfg->data_dir) srv_farm_attach(srv->farm, srv->store, cfg->data_dir);
    /* Where bundles' files go: under --data (a crashed run's half-unpacked bundles are
     * swept), else a temporary folder made at the first bundle, removed at shutdown. */
    srv_bundle_root_init(&srv->files_root, cfg->data_dir);
    srv->files_root_made = true;
    if (!cfg->data_dir) { /* the temporary folders of runs that were killed */
        int swept = srv_bundle_root_sweep();
        if (swept) fprintf(stderr, "tessera serve: removed %d temporary folder(s) of servers that ended without removing them\n", swept);
    }
    if (cfg->data_dir) {
        char incoming[4096];
        snprintf(incoming, sizeof incoming, "%s/incoming", cfg->data_dir);
        if (srv_bundle_remove_tree(incoming) != 0)
            fprintf(stderr, "tessera serve: --data: cannot sweep %s: %s\n", incoming, strerror(errno));
    }
    if (cfg->assets_dir)
        fprintf(stderr, "tessera serve: posted scenes may read files under %s (each at most %llu bytes)\n",
                cfg->assets_dir, (unsigned long long)cfg->limits.max_file_bytes);
    if (cfg->queue_builtin) {
        size_t len;
        const char *text = ts_scene_builtin_text(&len);
        int status;
        srv_job *j = srv_store_submit_named(srv->store, text, len, "cornell-box", &status, &e); /* as render names it */
        if (!j) fprintf(stderr, "tessera serve: the built-in scene was not queued: %s\n", e.message);
        else snprintf(srv->builtin_job, sizeof srv->builtin_job, "%s", j->id);
        srv_job_release(j);
    }
    if (pthread_create(&srv->maint, NULL, maintenance, srv) != 0) {
        snprintf(err, err_len, "cannot start the maintenance thread");
        goto fail;
    }
    srv->maint_started = true;
    srv->sse_limits.max_per_job = cfg->max_job_subscribers;
    srv->sse_limits.max_total = cfg->max_subscribers;
    atomic_init(&srv->sse_limits.total, 0);
    atomic_init(&srv->sse_limits.dropped, 0);
    srv->api = (srv_api){cfg->token, cfg->data_dir, cfg->cors_origin, cfg->bind, cfg->allowed_hosts, srv->store, srv->sched, srv->metrics,
                         &srv->sse_limits, &srv->persist, &cfg->bundle, &srv->files_root, srv->loaders, srv->offload,
                         cfg->max_load_s, &srv->loads_stop, &srv->loads,
                         {cfg->limits.max_spp, cfg->limits.max_width, cfg->limits.max_pixels, cfg->max_body,
                          cfg->bundle.max_bytes, cfg->max_work}, srv->farm};
    srv_http_config hc = {cfg->bind,       cfg->port,        cfg->http_threads, cfg->client_timeout_s,
                          cfg->request_timeout_s, cfg->max_client_conns, cfg->max_body, cfg->cors_origin, srv->metrics,
                          srv->offload, &srv->log, (size_t)cfg->bundle.max_bytes};
    srv_http_handlers handlers = srv_api_handlers(&srv->api);
    srv->http = srv_http_start(&hc, &handlers, port_out, err, err_len);
    if (!srv->http) goto fail;
    return true;
fail:
    srv_server_stop(srv, false);
    return false;
}

void srv_server_stop(srv_server *srv, bool checkpoint)
{
    const srv_config *cfg = &srv->cfg;
    /* Loads stop first (at their next poll, within milliseconds) and answer 503, so none
     * queues a job after the scheduler stopped, and none holds the shutdown up. */
    atomic_store(&srv->loads_stop, true);
    if (srv->http) srv_http_quiesce(srv->http);
    if (srv->loaders) srv_offload_drain(srv->loaders);
    if (srv->maint_started) {
        pthread_mutex_lock(&srv->mu);
        srv->stopping = true;
        pthread_cond_signal(&srv->cv);
        pthread_mutex_unlock(&srv->mu);
        pthread_join(srv->maint, NULL);
        srv->maint_started = false;
    }
    if (srv->sched) ts_scheduler_stop(srv->sched);
    srv_farm_stop(srv->farm); /* its jobs' arrays go on with --data (a restart re-attaches) */
    if (cfg->data_dir && srv->store && checkpoint) {
        int n = srv_persist_save_changed(cfg->data_dir, srv->store, NULL, &srv->persist);
        fprintf(stderr, "tessera serve: checkpointed %d job(s) to %s\n", n, cfg->data_dir);
    }
    if (srv->store) shutdown_streams(srv->store);
    if (srv->offload) srv_offload_drain(srv->offload);
    srv_http_stop(srv->http);
    srv_farm_destroy(srv->farm); /* after the last status document */
    srv->farm = NULL;
    srv_offload_destroy(srv->offload);
    srv_offload_destroy(srv->loaders);
    srv_store_destroy(srv->store);
    ts_scheduler_destroy(srv->sched);
    srv_metrics_destroy(srv->metrics);
    srv->http = NULL, srv->offload = NULL, srv->loaders = NULL, srv->store = NULL, srv->sched = NULL, srv->metrics = NULL;
    if (srv->files_root_made) {
        char made[sizeof srv->files_root.tmp];
        snprintf(made, sizeof made, "%s", srv->files_root.tmp);
        if (srv_bundle_root_fini(&srv->files_root) != 0)
            fprintf(stderr, "tessera serve: removing %s: %s\n", made, strerror(errno));
        srv->files_root_made = false;
    }
    srv_log_fini(&srv->log);
    pthread_cond_destroy(&srv->cv);
    pthread_mutex_destroy(&srv->mu);
}

/* Fills cfg from the command line (defaults first); -1 to go ahead, else the exit status
 * (usage errors, --help). *owned gets what cfg points into (the token read from
 * --token-file, the resolved --assets folder): free both after the server stops. */
static int parse_serve_options(int argc, char **argv, srv_config *cfg, char *owned[2])
{
    enum {
        OPT_BIND = 256, OPT_PORT, OPT_THREADS, OPT_DATA, OPT_TOKEN, OPT_MAX_RUNNING, OPT_HTTP_THREADS, OPT_MAX_BODY,
        OPT_MAX_PIXELS, OPT_MAX_RES, OPT_MAX_SPP, OPT_MAX_TRIS, OPT_MAX_SHAPES, OPT_CKPT, OPT_CORS, OPT_BUILTIN, OPT_HELP,
        OPT_TOKEN_FILE, OPT_ASSETS, OPT_MAX_ASSET_BYTES, OPT_MAX_JOBS, OPT_CLIENT_TIMEOUT, OPT_REQUEST_TIMEOUT, OPT_MAX_CLIENT_CONNS,
        OPT_LOG_FORMAT, OPT_LOG_LEVEL, OPT_MAX_WORK, OPT_MAX_SUBS, OPT_MAX_JOB_SUBS, OPT_ALLOWED_HOSTS, OPT_DISPLAY, OPT_ALLOW_JOB_DISPLAY,
        OPT_BUNDLE_BYTES, OPT_BUNDLE_ENTRIES, OPT_BUNDLE_EXPANDED, OPT_BUNDLE_ENTRY_BYTES, OPT_BUNDLE_PATH, OPT_MAX_LOAD, OPT_FARM
    };
    static const struct option opts[] = {
        {"bind", required_argument, NULL, OPT_BIND},
        {"port", required_argument, NULL, OPT_PORT},
        {"threads", required_argument, NULL, OPT_THREADS},
        {"data", required_argument, NULL, OPT_DATA},
        {"token", required_argument, NULL, OPT_TOKEN},
        {"token-file", required_argument, NULL, OPT_TOKEN_FILE},
        {"assets", required_argument, NULL, OPT_ASSETS},
        {"max-asset-bytes", required_argument, NULL, OPT_MAX_ASSET_BYTES},
        {"max-jobs", required_argument, NULL, OPT_MAX_JOBS},
        {"max-work", required_argument, NULL, OPT_MAX_WORK},
        {"max-load-seconds", required_argument, NULL, OPT_MAX_LOAD},
        {"allowed-hosts", required_argument, NULL, OPT_ALLOWED_HOSTS},
        {"max-subscribers", required_argument, NULL, OPT_MAX_SUBS},
        {"max-job-subscribers", required_argument, NULL, OPT_MAX_JOB_SUBS},
        {"client-timeout", required_argument, NULL, OPT_CLIENT_TIMEOUT},
        {"request-timeout", required_argument, NULL, OPT_REQUEST_TIMEOUT},
        {"max-client-connections", required_argument, NULL, OPT_MAX_CLIENT_CONNS},
        {"max-running", required_argument, NULL, OPT_MAX_RUNNING},
        {"http-threads", required_argument, NULL, OPT_HTTP_THREADS},
        {"max-body", required_argument, NULL, OPT_MAX_BODY},
        {"max-pixels", required_argument, NULL, OPT_MAX_PIXELS},
        {"max-resolution", required_argument, NULL, OPT_MAX_RES},
        {"max-spp", required_argument, NULL, OPT_MAX_SPP},
        {"max-triangles", required_argument, NULL, OPT_MAX_TRIS},
        {"max-shapes", required_argument, NULL, OPT_MAX_SHAPES},
        {"checkpoint-interval", required_argument, NULL, OPT_CKPT},
        {"cors-origin", required_argument, NULL, OPT_CORS},
        {"queue-builtin", no_argument, NULL, OPT_BUILTIN},
        {"display-server", required_argument, NULL, OPT_DISPLAY},
        {"allow-job-display-server", no_argument, NULL, OPT_ALLOW_JOB_DISPLAY},
        {"log-format", required_argument, NULL, OPT_LOG_FORMAT},
        {"log-level", required_argument, NULL, OPT_LOG_LEVEL},
        {"max-bundle-bytes", required_argument, NULL, OPT_BUNDLE_BYTES},
        {"max-bundle-entries", required_argument, NULL, OPT_BUNDLE_ENTRIES},
        {"max-bundle-expanded", required_argument, NULL, OPT_BUNDLE_EXPANDED},
        {"max-bundle-entry-bytes", required_argument, NULL, OPT_BUNDLE_ENTRY_BYTES},
        {"max-bundle-path", required_argument, NULL, OPT_BUNDLE_PATH},
        {"farm", required_argument, NULL, OPT_FARM},
        {"farm-dir", required_argument, NULL, OPT_FARM},
        {"farm-sbatch-arg", required_argument, NULL, OPT_FARM},
        {"farm-retries", required_argument, NULL, OPT_FARM},
        {"farm-checkpoint-interval", required_argument, NULL, OPT_FARM},
        {"farm-tessera", required_argument, NULL, OPT_FARM},
        {"max-shards", required_argument, NULL, OPT_FARM},
        {"help", no_argument, NULL, OPT_HELP},
        {NULL, 0, NULL, 0}};
    memset(cfg, 0, sizeof *cfg);
    cfg->bind = "127.0.0.1";
    cfg->port = 8080;
    long ncpu = sysconf(_SC_NPROCESSORS_ONLN);
    cfg->threads = ncpu > 0 ? (int)ncpu : 1;
    cfg->max_running = 4;
    cfg->http_threads = 4;
    cfg->client_timeout_s = 60;
    cfg->request_timeout_s = 60;
    cfg->max_client_conns = 1024;
    cfg->max_body = 16u << 20;
    cfg->checkpoint_interval_s = 30;
    cfg->log_format = SRV_LOG_TEXT;
    cfg->log_level = SRV_LOG_INFO;
    ts_scene_limits_default(&cfg->limits);
    cfg->limits.max_width = cfg->limits.max_height = 8192;
    cfg->limits.max_pixels = 4096ull * 4096;
    cfg->limits.max_spp = 1u << 16;
    cfg->limits.max_triangles = 5ull << 20;
    cfg->limits.max_shapes = 1u << 16;
    cfg->limits.max_file_bytes = 256ull << 20; /* each asset file (only read with --assets) */
    cfg->max_jobs = 1000;
    cfg->max_work = 1e13;
    cfg->max_load_s = 30;
    cfg->max_subscribers = 2048;
    cfg->max_job_subscribers = 1024;
    const char *token_file = NULL, *assets = NULL;
    cfg->limits.max_memory = 2ull << 30;
    srv_bundle_limits_default(&cfg->bundle);
    srv_farm_options_default(&cfg->farm);
    unsigned long long v;
    int opt_index = 0;
    char farm_msg[512];
    optind = 1;
    opterr = 0;
    int c;
    while ((c = getopt_long(argc, argv, ":", opts, &opt_index)) != -1) {
        switch (c) {
        case OPT_BIND: cfg->bind = optarg; break;
        case OPT_PORT:
            if (!parse_u64(optarg, 0, 65535, &v)) return usage_error("--port: expected 0 to 65535, got '%s'", optarg);
            cfg->port = (int)v;
            break;
        case OPT_THREADS:
            if (!parse_u64(optarg, 1, 1024, &v)) return usage_error("--threads: expected 1 to 1024, got '%s'", optarg);
            cfg->threads = (int)v;
            break;
        case OPT_MAX_RUNNING:
            if (!parse_u64(optarg, 1, 1024, &v)) return usage_error("--max-running: expected 1 to 1024, got '%s'", optarg);
            cfg->max_running = (int)v;
            break;
        case OPT_HTTP_THREADS:
            if (!parse_u64(optarg, 1, 64, &v)) return usage_error("--http-threads: expected 1 to 64, got '%s'", optarg);
            cfg->http_threads = (int)v;
            break;
        case OPT_DATA: cfg->data_dir = optarg; break;
        case OPT_TOKEN:
            if (!optarg[0]) return usage_error("--token: expected a non-empty token");
            cfg->token = optarg;
            break;
        case OPT_TOKEN_FILE: token_file = optarg; break;
        case OPT_ASSETS: assets = optarg; break;
        case OPT_MAX_ASSET_BYTES:
            if (!parse_u64(optarg, 1, 1ull << 40, &v)) return usage_error("--max-asset-bytes: expected 1 to 1099511627776 bytes, got '%s'", optarg);
            cfg->limits.max_file_bytes = v;
            break;
        case OPT_MAX_JOBS:
            if (!parse_u64(optarg, 1, 1000000, &v)) return usage_error("--max-jobs: expected 1 to 1000000, got '%s'", optarg);
            cfg->max_jobs = (int)v;
            break;
        case OPT_CLIENT_TIMEOUT:
            if (!parse_u64(optarg, 1, 86400, &v)) return usage_error("--client-timeout: expected 1 to 86400 seconds, got '%s'", optarg);
            cfg->client_timeout_s = (unsigned)v;
            break;
        case OPT_REQUEST_TIMEOUT:
            if (!parse_u64(optarg, 1, 86400, &v)) return usage_error("--request-timeout: expected 1 to 86400 seconds, got '%s'", optarg);
            cfg->request_timeout_s = (unsigned)v;
            break;
        case OPT_MAX_CLIENT_CONNS:
            if (!parse_u64(optarg, 1, 4000, &v)) return usage_error("--max-client-connections: expected 1 to 4000, got '%s'", optarg);
            cfg->max_client_conns = (unsigned)v;
            break;
        case OPT_CORS: cfg->cors_origin = optarg; break;
        case OPT_ALLOWED_HOSTS: cfg->allowed_hosts = optarg; break;
        case OPT_MAX_BODY:
            if (!parse_u64(optarg, 64, 1ull << 32, &v)) return usage_error("--max-body: expected 64 to 4294967296 bytes, got '%s'", optarg);
            cfg->max_body = (size_t)v;
            break;
        case OPT_MAX_PIXELS:
            if (!parse_u64(optarg, 1, 1ull << 28, &v)) return usage_error("--max-pixels: expected 1 to 268435456, got '%s'", optarg);
            cfg->limits.max_pixels = v;
            break;
        case OPT_MAX_RES:
            if (!parse_u64(optarg, 1, 16384, &v)) return usage_error("--max-resolution: expected 1 to 16384, got '%s'", optarg);
            cfg->limits.max_width = cfg->limits.max_height = (uint32_t)v;
            break;
        case OPT_MAX_SPP:
            if (!parse_u64(optarg, 1, 1u << 24, &v)) return usage_error("--max-spp: expected 1 to 16777216, got '%s'", optarg);
            cfg->limits.max_spp = (uint32_t)v;
            break;
        case OPT_MAX_TRIS:
            if (!parse_u64(optarg, 1, 1ull << 32, &v)) return usage_error("--max-triangles: expected a positive count, got '%s'", optarg);
            cfg->limits.max_triangles = v;
            break;
        case OPT_MAX_SHAPES:
            if (!parse_u64(optarg, 1, 1u << 24, &v)) return usage_error("--max-shapes: expected a positive count, got '%s'", optarg);
            cfg->limits.max_shapes = (uint32_t)v;
            break;
        case OPT_MAX_SUBS:
            if (!parse_u64(optarg, 1, 4000, &v)) return usage_error("--max-subscribers: expected 1 to 4000, got '%s'", optarg);
            cfg->max_subscribers = (int)v;
            break;
        case OPT_MAX_JOB_SUBS:
            if (!parse_u64(optarg, 1, 4000, &v)) return usage_error("--max-job-subscribers: expected 1 to 4000, got '%s'", optarg);
            cfg->max_job_subscribers = (int)v;
            break;
        case OPT_MAX_WORK: {
            char *end;
            double w = strtod(optarg, &end);
            if (end == optarg || *end || !(w >= 1) || !isfinite(w))
                return usage_error("--max-work: expected a number of rays (at least 1, e.g. 1e12), got '%s'", optarg);
            cfg->max_work = w;
            break;
        }
        case OPT_MAX_LOAD: {
            char *end;
            double sec = strtod(optarg, &end);
            if (end == optarg || *end || !(sec >= 0.1 && sec <= 3600))
                return usage_error("--max-load-seconds: expected 0.1 to 3600 seconds, got '%s'", optarg);
            cfg->max_load_s = sec;
            break;
        }
        case OPT_CKPT: {
            char *end;
            double s = strtod(optarg, &end);
            if (*end || !(s > 0) || !isfinite(s)) return usage_error("--checkpoint-interval: expected positive seconds, got '%s'", optarg);
            cfg->checkpoint_interval_s = s;
            break;
        }
        case OPT_BUNDLE_BYTES:
            if (!parse_u64(optarg, 64, 1ull << 32, &v)) return usage_error("--max-bundle-bytes: expected 64 to 4294967296 bytes, got '%s'", optarg);
            cfg->bundle.max_bytes = v;
            break;
        case OPT_BUNDLE_ENTRIES:
            if (!parse_u64(optarg, 1, 1000000, &v)) return usage_error("--max-bundle-entries: expected 1 to 1000000, got '%s'", optarg);
            cfg->bundle.max_entries = (uint32_t)v;
            break;
        case OPT_BUNDLE_EXPANDED:
            if (!parse_u64(optarg, 1, 1ull << 40, &v)) return usage_error("--max-bundle-expanded: expected 1 to 1099511627776 bytes, got '%s'", optarg);
            cfg->bundle.max_expanded = v;
            break;
        case OPT_BUNDLE_ENTRY_BYTES:
            if (!parse_u64(optarg, 1, 1ull << 40, &v)) return usage_error("--max-bundle-entry-bytes: expected 1 to 1099511627776 bytes, got '%s'", optarg);
            cfg->bundle.max_entry_bytes = v;
            break;
        case OPT_BUNDLE_PATH:
            if (!parse_u64(optarg, 16, 4000, &v)) return usage_error("--max-bundle-path: expected 16 to 4000 bytes, got '%s'", optarg);
            cfg->bundle.max_path = (uint32_t)v;
            break;
        case OPT_BUILTIN: cfg->queue_builtin = true; break;
        case OPT_DISPLAY: {
            ts_error derr = {0};
            if (srv_display_parse_address(optarg, NULL, NULL, &derr)) return usage_error("--display-server: %s", derr.message);
            cfg->display_server = optarg;
            break;
        }
        case OPT_ALLOW_JOB_DISPLAY: cfg->allow_job_display_server = true; break;
        case OPT_LOG_FORMAT:
            if (!srv_log_parse_format(optarg, &cfg->log_format))
                return usage_error("--log-format: expected text or json, got '%s'", optarg);
            break;
        case OPT_LOG_LEVEL:
            if (!srv_log_parse_level(optarg, &cfg->log_level))
                return usage_error("--log-level: expected error, warn, info or debug, got '%s'", optarg);
            break;
        case OPT_FARM:
            if (srv_farm_option(&cfg->farm, opts[opt_index].name, optarg, farm_msg, sizeof farm_msg) < 0)
                return usage_error("%s", farm_msg);
            break;
        case OPT_HELP: usage(stdout); return 0;
        case ':': return usage_error("option '%s' needs a value", argv[optind - 1]);
        default: return usage_error("unknown option '%s'", argv[optind - 1]);
        }
    }
    if (optind < argc) return usage_error("unexpected argument '%s'", argv[optind]);
    if (token_file && cfg->token) return usage_error("--token and --token-file: give one of them");
    if (!srv_farm_options_check(&cfg->farm, farm_msg, sizeof farm_msg)) return usage_error("%s", farm_msg);
    owned[0] = owned[1] = NULL;
    if (token_file) {
        char msg[256];
        if (!(owned[0] = read_token_file(token_file, msg, sizeof msg))) {
            fprintf(stderr, "tessera serve: --token-file %s: %s\n", token_file, msg);
            return 2;
        }
        cfg->token = owned[0];
    }
    if (assets) {
        struct stat sb;
        if (!(owned[1] = realpath(assets, NULL)) || stat(owned[1], &sb) != 0 || !S_ISDIR(sb.st_mode)) {
            fprintf(stderr, "tessera serve: --assets %s: not a folder that can be opened\n", assets);
            free(owned[1]);
            free(owned[0]);
            return 2;
        }
        cfg->assets_dir = owned[1];
    }
    return -1;
}

int srv_serve_main(int argc, char **argv)
{
    srv_server srv_storage, *srv = &srv_storage;
    memset(srv, 0, sizeof *srv);
    srv_config *cfg = &srv->cfg;
    char *owned[2];
    int parsed = parse_serve_options(argc, argv, cfg, owned);
    if (parsed >= 0) return parsed;


    /* Signals are taken by sigwait below; every thread started from here inherits the mask. */
    sigset_t sigs;
    sigemptyset(&sigs);
    sigaddset(&sigs, SIGINT);
    sigaddset(&sigs, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &sigs, NULL);
    signal(SIGPIPE, SIG_IGN);

    int rc = 1;
    char msg[TS_ERROR_MAX];
    int port = 0;
    if (srv_server_start(srv, &port, msg, sizeof msg)) {
        char url[128];
        if (!strchr(cfg->bind, ':')) snprintf(url, sizeof url, "http://%s:%d", cfg->bind, port);
        else snprintf(url, sizeof url, "http://[%s]:%d", cfg->bind, port);
        printf("tessera: listening on %s/\n", url);
        fflush(stdout);
        if (srv->builtin_job[0])
            fprintf(stderr,
                    "tessera serve: the built-in Cornell box renders as job %s; watch it at %s/, and once it is done\n"
                    "tessera serve: its image is at %s/api/v1/jobs/%s/image.exr (and image.png)\n",
                    srv->builtin_job, url, url, srv->builtin_job);
        int sig = 0;
        sigwait(&sigs, &sig);
        fprintf(stderr, "tessera serve: %s, shutting down\n", sig == SIGINT ? "interrupted" : "terminated");
        srv_server_stop(srv, true);
        rc = 0;
    } else {
        fprintf(stderr, "tessera serve: %s\n", msg);
    }
    free(owned[1]);
    free(owned[0]);
    return rc;
}
