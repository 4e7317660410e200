/* serve.c — `tessera serve`: options, start-up, the maintenance thread, shutdown.
 *
 * Start-up: parse options, restore jobs from --data, start the scheduler, the encoder
 * pool and the HTTP daemon, print the URL. Shutdown on SIGINT/SIGTERM (taken with
 * sigwait in the main thread, so no handler runs on a random thread): stop accepting,
 * stop the render workers after their current tiles, checkpoint every job, end the event
 * streams, drain the encoders, stop the daemon, free everything. */
#include "serve.h"

#include <errno.h>
#include <stddef.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "options.h"
#include "persist.h"
#include "usage.h"
#include "tessera.h"

#define KEEPALIVE_S 15.0
#define TICK_S 1.0 /* progress events and history points of running jobs */
#define SRV_ENCODER_THREADS 2
#define SRV_LOADER_THREADS 2

/* ---------------------------------------------------------------- options */

/* What the command line fills: the configuration, and two values read after parsing. */
typedef struct serve_args {
    srv_config cfg;
    const char *token_file, *assets;
} serve_args;

#define F(f) offsetof(serve_args, f), sizeof(((serve_args *)0)->f)

static bool parse_display(void *opts, const char *name, const char *arg, char *why, size_t n)
{
    (void)name;
    ts_error derr = {0};
    if (srv_display_parse_address(arg, NULL, NULL, &derr)) {
        snprintf(why, n, "%s", derr.message);
        return false;
    }
    ((serve_args *)opts)->cfg.display_server = arg;
    return true;
}

static bool parse_log_format(void *opts, const char *name, const char *arg, char *why, size_t n)
{
    (void)name;
    if (srv_log_parse_format(arg, &((serve_args *)opts)->cfg.log_format)) return true;
    snprintf(why, n, "expected text or json, got '%s'", arg);
    return false;
}

static bool parse_log_level(void *opts, const char *name, const char *arg, char *why, size_t n)
{
    (void)name;
    if (srv_log_parse_level(arg, &((serve_args *)opts)->cfg.log_level)) return true;
    snprintf(why, n, "expected error, warn, info or debug, got '%s'", arg);
    return false;
}

/* The farm's options are the farm's (farm.h): its sentence names the option already. */
static bool parse_farm(void *opts, const char *name, const char *arg, char *why, size_t n)
{
    char msg[400];
    if (srv_farm_option(&((serve_args *)opts)->cfg.farm, name, arg, msg, sizeof msg) >= 0) return true;
    const char *own = msg;
    size_t k = strlen(name);
    if (!strncmp(own, "--", 2) && !strncmp(own + 2, name, k) && own[2 + k] == ':') own += 3 + k + (own[3 + k] == ' ');
    snprintf(why, n, "%s", own);
    return false;
}

#define U(name, meta, lo, hi, unit, fld, help) {name, 0, meta, SRV_OPT_UINT, lo, hi, false, false, unit, F(fld), help, NULL, NULL, NULL}
#define D(name, meta, lo, excl, hi, unit, fld, help, dflt) \
    {name, 0, meta, SRV_OPT_NUMBER, lo, hi, excl, false, unit, F(fld), help, dflt, NULL, NULL}
#define S(name, meta, fld, help) {name, 0, meta, SRV_OPT_STRING, 0, 0, false, false, NULL, F(fld), help, NULL, NULL, NULL}
#define B(name, fld, help) {name, 0, NULL, SRV_OPT_FLAG, 0, 0, false, false, NULL, F(fld), help, "", NULL, NULL}
#define C(name, meta, fn, help, dflt, heading) {name, 0, meta, SRV_OPT_CUSTOM, 0, 0, false, false, NULL, 0, 0, help, dflt, fn, heading}

/* Every option of `tessera serve`: --help, the parser and the errors are made from this. */
static const srv_option serve_options[] = {
    S("bind", "ADDRESS", cfg.bind, "numeric IPv4/IPv6 address to listen on"),
    U("port", "N", 0, 65535, NULL, cfg.port, "TCP port, 0 for any free one"),
    {"threads", 0, "N", SRV_OPT_UINT, 1, 1024, false, false, NULL, F(cfg.threads), "render threads", "one per core", NULL, NULL},
    U("max-running", "N", 1, 1024, NULL, cfg.max_running, "jobs rendering at once"),
    U("http-threads", "N", 1, 64, NULL, cfg.http_threads, "HTTP threads"),
    S("data", "DIR", cfg.data_dir, "checkpoint jobs to DIR and resume them after a restart"),
    D("checkpoint-interval", "S", 0, true, INFINITY, "seconds", cfg.checkpoint_interval_s,
      "seconds between checkpoints with --data", NULL),
    {"token", 0, "TOKEN", SRV_OPT_STRING, 0, 0, false, true, "token", F(cfg.token),
     "require 'Authorization: Bearer TOKEN'", "no token", NULL, NULL},
    {"token-file", 0, "FILE", SRV_OPT_STRING, 0, 0, false, false, NULL, F(token_file),
     "the same, the token read from FILE's first line (kept out of ps)", "", NULL, NULL},
    S("cors-origin", "ORIGIN", cfg.cors_origin, "answer CORS requests from ORIGIN"),
    {"allowed-hosts", 0, "H1,H2", SRV_OPT_STRING, 0, 0, false, false, NULL, F(cfg.allowed_hosts),
     "Host names to answer besides the bind address (and localhost on loopback)", "", NULL, NULL},
    S("assets", "DIR", assets, "the only folder posted scenes may read files from"),
    U("max-asset-bytes", "BYTES", 1, 1099511627776.0, "bytes", cfg.limits.max_file_bytes,
      "largest file a scene may read under --assets"),
    U("max-jobs", "N", 1, 1000000, NULL, cfg.max_jobs, "jobs held at once, any state; a POST beyond gets 503"),
    U("max-body", "BYTES", 64, 4294967296.0, "bytes", cfg.max_body, "largest request body"),
    U("max-resolution", "N", 1, 16384, NULL, cfg.limits.max_width, "largest film width or height in pixels"),
    U("max-pixels", "N", 1, 268435456, NULL, cfg.limits.max_pixels, "largest film area in pixels"),
    U("max-spp", "N", 1, 16777216, NULL, cfg.limits.max_spp, "most samples per pixel a job may ask"),
    U("max-triangles", "N", 1, 4294967296.0, NULL, cfg.limits.max_triangles, "most triangles in a posted scene"),
    U("max-shapes", "N", 1, 16777216, NULL, cfg.limits.max_shapes, "most shapes in a posted scene"),
    U("client-timeout", "S", 1, 86400, "seconds", cfg.client_timeout_s, "close a connection idle this many seconds"),
    U("request-timeout", "S", 1, 86400, "seconds", cfg.request_timeout_s,
      "close a connection whose request (headers and body) has not arrived\nthis many seconds after it opened or "
      "after its previous answer"),
    U("max-client-connections", "N", 1, 4000, NULL, cfg.max_client_conns, "connections one address may hold"),
    U("max-subscribers", "N", 1, 4000, NULL, cfg.max_subscribers, "event streams open at once, all jobs"),
    U("max-job-subscribers", "N", 1, 4000, NULL, cfg.max_job_subscribers, "event streams of one job at once"),
    D("max-work", "RAYS", 1, false, INFINITY, NULL, cfg.max_work,
      "most rays one job may ask for: rays a sample x spp x pixels", "1e13"),
    D("max-load-seconds", "S", 0.1, false, 3600, "seconds", cfg.max_load_s,
      "time a posted scene may take to load, from its arrival; beyond, 422\n(or 503 if it waited that long for a "
      "loader)", NULL),
    {"max-bundle-bytes", 0, "BYTES", SRV_OPT_UINT, 64, 4294967296.0, false, false, "bytes", F(cfg.bundle.max_bytes),
     "largest bundle as posted", NULL, NULL,
     "A job may be posted as a tar (optionally gzip) of scene.json or scene.pbrt and its files:"},
    U("max-bundle-entries", "N", 1, 1000000, NULL, cfg.bundle.max_entries, "most entries in a bundle, folders included"),
    U("max-bundle-expanded", "BYTES", 1, 1099511627776.0, "bytes", cfg.bundle.max_expanded,
      "most bytes of all a bundle's files together"),
    U("max-bundle-entry-bytes", "BYTES", 1, 1099511627776.0, "bytes", cfg.bundle.max_entry_bytes,
      "largest file in a bundle"),
    U("max-bundle-path", "BYTES", 16, 4000, "bytes", cfg.bundle.max_path, "longest path of a bundle's entry"),
    C("log-format", "text|json", parse_log_format, "job events as text lines or JSON lines on stderr", "text", NULL),
    C("log-level", "LEVEL", parse_log_level, "error, warn, info (job events) or debug (and every request)", "info",
      NULL),
    B("queue-builtin", cfg.queue_builtin, "queue the built-in Cornell box as the first job (make run)"),
    C("display-server", "HOST:PORT", parse_display, "stream every job to a tev viewer there, as tiles finish", "none",
      NULL),
    B("allow-job-display-server", cfg.allow_job_display_server,
      "let a job's job.display_server name any address (default: only the\n--display-server one; others get 403)"),
    C("farm", "slurm", parse_farm, "send farm jobs to Slurm (sbatch, squeue, scontrol, scancel on PATH)", "",
      "Farm jobs (\"job\": {\"farm\": {\"shards\": N}}, or a bundle's ?shards=N) run as one Slurm job array:"),
    C("farm-dir", "DIR", parse_farm, "where their scenes, task scripts and shards go: storage every node sees", "", NULL),
    C("farm-sbatch-arg", "ARG", parse_farm,
      "one more sbatch option for every array, repeatable (e.g. --partition=render)", "", NULL),
    C("farm-retries", "N", parse_farm, "requeues of a failed task before its job fails", "2", NULL),
    C("farm-checkpoint-interval", "S", parse_farm, "the tasks' --checkpoint-interval: how often the image grows", "10",
      NULL),
    C("farm-tessera", "PATH", parse_farm, "the tessera the tasks run", "this program", NULL),
    C("max-shards", "N", parse_farm, "most tasks a farm job may ask for", "1000", NULL),
    {"help", 0, NULL, SRV_OPT_HELP, 0, 0, false, false, NULL, 0, 0, "this text", "", NULL, NULL},
};
#define N_SERVE_OPTIONS (sizeof serve_options / sizeof *serve_options)

/* The defaults of every option (before the command line). */
static void serve_defaults(serve_args *a)
{
    memset(a, 0, sizeof *a);
    srv_config *cfg = &a->cfg;
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
    cfg->limits.max_memory = 2ull << 30;
    srv_bundle_limits_default(&cfg->bundle);
    srv_farm_options_default(&cfg->farm);
}

static void usage(FILE *f)
{
    serve_args defaults;
    serve_defaults(&defaults);
    fprintf(f, "usage: tessera serve [OPTIONS]\n"
               "The render server: HTTP API v1 (proto/openapi.yaml) and the web UI at /. Runs until SIGINT/SIGTERM.\n");
    srv_options_help(f, serve_options, N_SERVE_OPTIONS, &defaults);
    fprintf(f, "docs/security.md has the threat model and every limit.\n");
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
    serve_args a;
    serve_defaults(&a);
    char why[600];
    int first = 1;
    int rc = srv_options_parse(serve_options, N_SERVE_OPTIONS, argc, argv, &a, &first, why, sizeof why);
    *cfg = a.cfg;
    const char *token_file = a.token_file, *assets = a.assets;
    char farm_msg[512];
    if (rc == SRV_OPTIONS_HELP) {
        usage(stdout);
        return 0;
    }
    if (rc == SRV_OPTIONS_BAD) return usage_error("%s", why);
    cfg->limits.max_height = cfg->limits.max_width; /* --max-resolution bounds both */
    if (first < argc) return usage_error("unexpected argument '%s'", argv[first]);
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
