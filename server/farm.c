/* farm.c — farm jobs on Slurm; see farm.h and docs/design.md §7. */
#define _GNU_SOURCE /* pipe2, memmem */
#include "farm.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "bundle.h"
#include "tessera.h"

extern char **environ;

#define POLL_S 0.5          /* how often the farm thread looks at Slurm and the shard files */
#define COMMAND_TIMEOUT_S 60 /* a Slurm command that has not answered by then is killed */
#define OUTPUT_MAX 65536    /* what is kept of a command's stdout and of its stderr */
#define TAIL_LINES 5        /* a failed task's stderr lines named in the job's error */

/* ---------------------------------------------------------------- options */

void srv_farm_options_default(srv_farm_options *o)
{
    memset(o, 0, sizeof *o);
    o->retries = 2;
    o->max_shards = 1000;
    o->task_checkpoint_s = 10;
}

static bool parse_uint(const char *s, unsigned long lo, unsigned long hi, unsigned long *out)
{
    if (!s || !*s) return false;
    unsigned long v = 0;
    for (const char *c = s; *c; c++) {
        if (*c < '0' || *c > '9') return false;
        v = v * 10 + (unsigned long)(*c - '0');
        if (v > hi) return false;
    }
    if (v < lo) return false;
    *out = v;
    return true;
}

int srv_farm_option(srv_farm_options *o, const char *name, const char *value, char *msg, size_t msg_len)
{
    unsigned long v;
    if (!strcmp(name, "farm")) {
        if (strcmp(value, "slurm") != 0) {
            snprintf(msg, msg_len, "--farm: expected slurm (the one scheduler supported), got '%s'", value);
            return -1;
        }
        o->slurm = true;
    } else if (!strcmp(name, "farm-dir")) {
        if (!value[0] || strchr(value, '\'') || strchr(value, '\n')) {
            snprintf(msg, msg_len, "--farm-dir: expected a folder path without quotes or line breaks, got '%s'", value);
            return -1;
        }
        o->dir = value;
    } else if (!strcmp(name, "farm-sbatch-arg")) {
        if (o->n_sbatch_args == SRV_FARM_MAX_SBATCH_ARGS) {
            snprintf(msg, msg_len, "--farm-sbatch-arg: at most %d of them", SRV_FARM_MAX_SBATCH_ARGS);
            return -1;
        }
        o->sbatch_args[o->n_sbatch_args++] = value;
    } else if (!strcmp(name, "farm-retries")) {
        if (!parse_uint(value, 0, 100, &v)) {
            snprintf(msg, msg_len, "--farm-retries: expected 0 to 100, got '%s'", value);
            return -1;
        }
        o->retries = (int)v;
    } else if (!strcmp(name, "max-shards")) {
        if (!parse_uint(value, 1, 1000000, &v)) {
            snprintf(msg, msg_len, "--max-shards: expected 1 to 1000000, got '%s'", value);
            return -1;
        }
        o->max_shards = (uint32_t)v;
    } else if (!strcmp(name, "farm-checkpoint-interval")) {
        char *end;
        double s = strtod(value, &end);
        if (end == value || *end || !(s > 0) || !isfinite(s) || s > 86400) {
            snprintf(msg, msg_len, "--farm-checkpoint-interval: expected seconds above 0, at most 86400, got '%s'", value);
            return -1;
        }
        o->task_checkpoint_s = s;
    } else if (!strcmp(name, "farm-tessera")) {
        if (!value[0] || strchr(value, '\'') || strchr(value, '\n')) {
            snprintf(msg, msg_len, "--farm-tessera: expected a program path without quotes or line breaks, got '%s'",
                     value);
            return -1;
        }
        o->tessera = value;
    } else {
        return 0;
    }
    return 1;
}

bool srv_farm_options_check(const srv_farm_options *o, char *msg, size_t msg_len)
{
    if (o->slurm && !o->dir) {
        snprintf(msg, msg_len, "--farm slurm needs --farm-dir DIR (storage every node sees)");
        return false;
    }
    if (!o->slurm && (o->dir || o->n_sbatch_args || o->tessera)) {
        snprintf(msg, msg_len, "--farm-dir, --farm-sbatch-arg and --farm-tessera need --farm slurm");
        return false;
    }
    return true;
}

/* ---------------------------------------------------------------- state */

typedef enum task_state { TASK_PENDING, TASK_RUNNING, TASK_DONE, TASK_FAILED, TASK_CANCELLED } task_state;
static const char *task_state_name(task_state s)
{
    static const char *const names[] = {"pending", "running", "done", "failed", "cancelled"};
    return names[s];
}

typedef struct farm_task {
    task_state state;     /* guarded by f->mu */
    uint32_t spp;         /* samples per pixel merged from it; guarded */
    int retries;          /* requeues so far; guarded */
    /* farm thread only: the file last merged (its identity, to see rewrites) */
    struct timespec mtime;
    off_t size;
    ino_t ino;
    bool output;          /* it was the final output, not a checkpoint */
} farm_task;

typedef enum phase { PHASE_SUBMIT, PHASE_RUNNING, PHASE_ENDED } phase;

typedef struct farm_job {
    srv_job *j;           /* a reference */
    char id[24];
    uint32_t shards, spp;
    farm_task *tasks;
    /* guarded by f->mu */
    phase phase;
    char slurm_id[32];    /* the array's job id, "" before sbatch answered */
    bool scancel_sent;    /* the array was cancelled (by a cancel, or after a failure) */
    char error[1024];     /* why it failed, or "" */
    /* farm thread only */
    bool dirty;           /* a file changed: merge again */
    struct farm_job *next;
} farm_job;

struct srv_farm {
    srv_farm_options opt; /* immutable; strings copied below */
    char *dir, *tessera, *data_dir;
    char **sbatch_args;
    srv_store *store;
    srv_log *log;
    pthread_t thread;
    bool started;
    pthread_mutex_t mu;
    pthread_cond_t cv;
    bool stopping;        /* guarded by mu */
    farm_job *jobs;       /* guarded by mu */
};

/* ---------------------------------------------------------------- commands */

typedef struct command_result {
    int status;           /* exit status; -1 when it could not run or was killed */
    char out[OUTPUT_MAX], err[OUTPUT_MAX];
    char why[256];        /* when status is -1 */
} command_result;

static void append(char *buf, size_t *n, const char *data, size_t len)
{
    if (*n + 1 >= OUTPUT_MAX) return;
    size_t room = OUTPUT_MAX - 1 - *n;
    if (len > room) len = room;
    memcpy(buf + *n, data, len);
    *n += len;
    buf[*n] = '\0';
}

/* Runs argv (looked up on PATH) with stdin from /dev/null, collecting stdout and stderr,
 * at most COMMAND_TIMEOUT_S seconds. */
static void run(char *const argv[], command_result *r)
{
    r->status = -1;
    r->out[0] = r->err[0] = r->why[0] = '\0';
    int po[2] = {-1, -1}, pe[2] = {-1, -1};
    if (pipe2(po, O_CLOEXEC) != 0 || pipe2(pe, O_CLOEXEC) != 0) {
        snprintf(r->why, sizeof r->why, "cannot make a pipe: %s", strerror(errno));
        goto close;
    }
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_adddup2(&fa, po[1], 1);
    posix_spawn_file_actions_adddup2(&fa, pe[1], 2);
    posix_spawnattr_t at;
    posix_spawnattr_init(&at);
    sigset_t none;
    sigemptyset(&none);
    posix_spawnattr_setsigmask(&at, &none); /* the server blocks SIGINT/SIGTERM; the child must not */
    posix_spawnattr_setflags(&at, POSIX_SPAWN_SETSIGMASK);
    pid_t pid;
    int e = posix_spawnp(&pid, argv[0], &fa, &at, argv, environ);
    posix_spawn_file_actions_destroy(&fa);
    posix_spawnattr_destroy(&at);
    close(po[1]), close(pe[1]);
    po[1] = pe[1] = -1;
    if (e) {
        snprintf(r->why, sizeof r->why, "cannot run %s: %s", argv[0], strerror(e));
        goto close;
    }
    size_t no = 0, ne = 0;
    double deadline = ts_now_seconds() + COMMAND_TIMEOUT_S;
    bool open_o = true, open_e = true, killed = false;
    while (open_o || open_e) {
        struct pollfd p[2] = {{po[0], POLLIN, 0}, {pe[0], POLLIN, 0}};
        double left = deadline - ts_now_seconds();
        if (left <= 0) {
            kill(pid, SIGKILL);
            killed = true;
            break;
        }
        int k = poll(p, 2, (int)(left * 1000) + 1);
        if (k < 0 && errno != EINTR) break;
        char buf[4096];
        for (int i = 0; i < 2; i++) {
            if (!(i ? open_e : open_o) || !(p[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
            ssize_t n = read(p[i].fd, buf, sizeof buf);
            if (n <= 0) {
                if (i) open_e = false;
                else open_o = false;
            } else if (i) {
                append(r->err, &ne, buf, (size_t)n);
            } else {
                append(r->out, &no, buf, (size_t)n);
            }
        }
    }
    int ws = 0;
    while (waitpid(pid, &ws, 0) < 0 && errno == EINTR) {}
    if (killed) snprintf(r->why, sizeof r->why, "%s did not answer within %d s", argv[0], COMMAND_TIMEOUT_S);
    else if (WIFEXITED(ws)) r->status = WEXITSTATUS(ws);
    else snprintf(r->why, sizeof r->why, "%s was killed by signal %d", argv[0], WIFSIGNALED(ws) ? WTERMSIG(ws) : 0);
close:
    for (int i = 0; i < 2; i++) {
        if (po[i] >= 0) close(po[i]);
        if (pe[i] >= 0) close(pe[i]);
    }
}

/* The command's complaint in one line: its stderr (else stdout, else why), blanks folded. */
static void complaint(const command_result *r, char *out, size_t n)
{
    const char *s = r->status < 0 ? r->why : r->err[0] ? r->err : r->out[0] ? r->out : "no message";
    size_t k = 0;
    bool blank = false;
    for (; *s && k + 1 < n; s++) {
        bool b = *s == '\n' || *s == '\r' || *s == '\t' || *s == ' ';
        if (b) {
            blank = k > 0;
            continue;
        }
        if (blank && k + 2 < n) out[k++] = ' ';
        blank = false;
        out[k++] = *s;
    }
    out[k] = '\0';
}

/* ---------------------------------------------------------------- files */

static int mkdirs(const char *path)
{
    char tmp[4096];
    snprintf(tmp, sizeof tmp, "%s", path);
    for (char *p = tmp + 1; *p; p++)
        if (*p == '/') {
            *p = '\0';
            if (mkdir(tmp, 0755) != 0 && errno != EEXIST) return -1;
            *p = '/';
        }
    return mkdir(tmp, 0755) != 0 && errno != EEXIST ? -1 : 0;
}

/* Copies the folder src to dst (made), regular files and folders only (a bundle's files,
 * which bundle.c already confined). */
static int copy_tree(const char *src, const char *dst)
{
    if (mkdir(dst, 0755) != 0 && errno != EEXIST) return -1;
    DIR *d = opendir(src);
    if (!d) return -1;
    int rc = 0;
    struct dirent *e;
    while (rc == 0 && (e = readdir(d))) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
        char a[4096], b[4096];
        snprintf(a, sizeof a, "%s/%s", src, e->d_name);
        snprintf(b, sizeof b, "%s/%s", dst, e->d_name);
        struct stat sb;
        if (lstat(a, &sb) != 0) rc = -1;
        else if (S_ISDIR(sb.st_mode)) rc = copy_tree(a, b);
        else if (S_ISREG(sb.st_mode)) {
            int in = open(a, O_RDONLY | O_CLOEXEC | O_NOFOLLOW), out = -1;
            if (in < 0 || (out = open(b, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644)) < 0) rc = -1;
            char buf[65536];
            ssize_t n;
            while (rc == 0 && (n = read(in, buf, sizeof buf)) != 0) {
                if (n < 0 || write(out, buf, (size_t)n) != n) rc = -1;
            }
            if (in >= 0) close(in);
            if (out >= 0 && close(out) != 0) rc = -1;
        }
    }
    closedir(d);
    return rc;
}

static void job_folder(const srv_farm *f, const char *id, char *out, size_t n) { snprintf(out, n, "%s/%s", f->dir, id); }

static void task_file(const srv_farm *f, const char *id, const char *kind, uint32_t i, char *out, size_t n)
{
    snprintf(out, n, "%s/%s/shards/%s-%u.exr", f->dir, id, kind, i);
}

/* The last TAIL_LINES lines of a task's stderr, folded onto one line ("" when empty). */
static void stderr_tail(const srv_farm *f, const char *id, uint32_t i, char *out, size_t n)
{
    char path[4200];
    snprintf(path, sizeof path, "%s/%s/logs/task-%u.err", f->dir, id, i);
    out[0] = '\0';
    FILE *fp = fopen(path, "r");
    if (!fp) return;
    char buf[8192];
    fseek(fp, 0, SEEK_END);
    long size = ftell(fp);
    long from = size > (long)sizeof buf - 1 ? size - (long)sizeof buf + 1 : 0;
    fseek(fp, from, SEEK_SET);
    size_t k = fread(buf, 1, sizeof buf - 1, fp);
    fclose(fp);
    buf[k] = '\0';
    while (k && (buf[k - 1] == '\n' || buf[k - 1] == '\r')) buf[--k] = '\0';
    int lines = 0;
    size_t start = k;
    while (start > 0) {
        if (buf[start - 1] == '\n' && ++lines == TAIL_LINES) break;
        start--;
    }
    size_t o = 0;
    for (const char *s = buf + start; *s && o + 4 < n; s++) {
        if (*s == '\n') out[o++] = ' ', out[o++] = '|', out[o++] = ' ';
        else if (*s != '\r') out[o++] = *s;
    }
    out[o] = '\0';
}

/* ---------------------------------------------------------------- farm.json */

/* Writes what a restart needs under --data (jobs/<id>/farm.json). f->mu not held. */
static void save_state(srv_farm *f, farm_job *fj)
{
    if (!f->data_dir) return;
    cJSON *o = cJSON_CreateObject();
    pthread_mutex_lock(&f->mu);
    cJSON_AddStringToObject(o, "scheduler", "slurm");
    cJSON_AddStringToObject(o, "slurm_job", fj->slurm_id);
    cJSON_AddNumberToObject(o, "shards", fj->shards);
    cJSON_AddBoolToObject(o, "scancel_sent", fj->scancel_sent);
    cJSON_AddStringToObject(o, "error", fj->error);
    cJSON *r = cJSON_AddArrayToObject(o, "retries");
    for (uint32_t i = 0; i < fj->shards; i++) cJSON_AddItemToArray(r, cJSON_CreateNumber(fj->tasks[i].retries));
    pthread_mutex_unlock(&f->mu);
    char *text = cJSON_PrintUnformatted(o);
    cJSON_Delete(o);
    char path[4200];
    snprintf(path, sizeof path, "%s/jobs/%s", f->data_dir, fj->id);
    ts_error err = {0};
    if (!text || mkdirs(path) != 0) {
        fprintf(stderr, "tessera: farm job %s: cannot record its Slurm array under --data: %s\n", fj->id,
                text ? strerror(errno) : "out of memory");
    } else {
        snprintf(path, sizeof path, "%s/jobs/%s/farm.json", f->data_dir, fj->id);
        if (ts_image_write_file_atomic(path, text, strlen(text), &err))
            fprintf(stderr, "tessera: farm job %s: %s\n", fj->id, err.message);
    }
    free(text);
}

/* ---------------------------------------------------------------- the job's life */

static void log_farm(srv_farm *f, srv_log_level level, const char *event, const farm_job *fj, const char *k,
                     const char *v)
{
    if (!srv_log_enabled(f->log, level)) return;
    srv_log_field fl[] = {SRV_LOG_STR("id", fj->id), SRV_LOG_STR("slurm_job", fj->slurm_id), SRV_LOG_STR(k, v)};
    srv_log_event(f->log, level, event, fl, k ? 3 : 2);
}

/* Ends the job in state (its merged pixels stay). */
static void end_job(srv_farm *f, farm_job *fj, ts_job_state state, ts_halt_reason halt, const char *error)
{
    pthread_mutex_lock(&f->mu);
    if (error) snprintf(fj->error, sizeof fj->error, "%s", error);
    fj->phase = PHASE_ENDED;
    for (uint32_t i = 0; i < fj->shards; i++)
        if (fj->tasks[i].state == TASK_PENDING || fj->tasks[i].state == TASK_RUNNING) fj->tasks[i].state = TASK_CANCELLED;
    pthread_mutex_unlock(&f->mu);
    save_state(f, fj);
    ts_sched_job_finish(fj->j->sj, state, halt);
}

/* Writes the scene (a bundle's files with it) and the task script under DIR/<id>/. */
static bool prepare(srv_farm *f, farm_job *fj, char *why, size_t n)
{
    char dir[4096], path[4200];
    job_folder(f, fj->id, dir, sizeof dir);
    snprintf(path, sizeof path, "%s/shards", dir);
    if (mkdirs(path) != 0) goto io;
    snprintf(path, sizeof path, "%s/logs", dir);
    if (mkdirs(path) != 0) goto io;
    const srv_job *j = fj->j;
    char scene[4200];
    ts_error err = {0};
    if (j->files_dir) {
        snprintf(path, sizeof path, "%s/files", dir);
        if (copy_tree(j->files_dir, path) != 0) goto io;
        snprintf(scene, sizeof scene, "%s/files/scene.%s", dir, j->scene_pbrt ? "pbrt" : "json");
    } else {
        snprintf(scene, sizeof scene, "%s/scene.json", dir);
        if (ts_image_write_file_atomic(scene, j->scene_text, j->scene_len, &err)) {
            snprintf(why, n, "%s", err.message);
            return false;
        }
    }
    char script[16384];
    snprintf(script, sizeof script,
             "#!/bin/sh\n"
             "# One shard of tessera farm job %s (docs/design.md §7), written by tessera serve.\n"
             "i=${SLURM_ARRAY_TASK_ID:?not a job-array task}\n"
             "exec '%s' render '%s' --spp %u --shard auto --threads \"${SLURM_CPUS_PER_TASK:-1}\" --quiet \\\n"
             "    --checkpoint '%s/shards/checkpoint-'\"$i\"'.exr' --checkpoint-interval %g \\\n"
             "    -o '%s/shards/shard-'\"$i\"'.exr'\n",
             fj->id, f->tessera, scene, fj->spp, dir, f->opt.task_checkpoint_s, dir);
    snprintf(path, sizeof path, "%s/task.sh", dir);
    if (ts_image_write_file_atomic(path, script, strlen(script), &err)) {
        snprintf(why, n, "%s", err.message);
        return false;
    }
    if (chmod(path, 0755) != 0) goto io;
    return true;
io:
    snprintf(why, n, "cannot write %s under --farm-dir: %s", fj->id, strerror(errno));
    return false;
}

/* An array already submitted for this job (a crash between sbatch and farm.json): its id
 * into fj->slurm_id, true. */
static bool find_submitted(srv_farm *f, farm_job *fj)
{
    char name[64];
    snprintf(name, sizeof name, "--name=tessera-%s", fj->id);
    char *argv[] = {"squeue", "-h", "--states=all", name, "-o", "%F", NULL};
    command_result r;
    run(argv, &r);
    if (r.status != 0) return false;
    char *end;
    unsigned long id = strtoul(r.out, &end, 10);
    if (end == r.out || id == 0) return false;
    pthread_mutex_lock(&f->mu);
    snprintf(fj->slurm_id, sizeof fj->slurm_id, "%lu", id);
    pthread_mutex_unlock(&f->mu);
    return true;
}

static void submit_array(srv_farm *f, farm_job *fj)
{
    command_result r;
    char why[1024];
    ts_job_progress p;
    ts_sched_job_progress(fj->j->sj, &p);
    if (p.cancelling) {
        end_job(f, fj, TS_JOB_CANCELLED, TS_HALT_CANCELLED, NULL);
        return;
    }
    if (find_submitted(f, fj)) {
        log_farm(f, SRV_LOG_INFO, "farm.attached", fj, "how", "found by name in squeue");
        goto submitted;
    }
    if (!prepare(f, fj, why, sizeof why)) {
        end_job(f, fj, TS_JOB_FAILED, TS_HALT_NONE, why);
        return;
    }
    char dir[4096], name[64], array[64], out[4300], err[4300], chdir_arg[4200], script[4200];
    job_folder(f, fj->id, dir, sizeof dir);
    snprintf(name, sizeof name, "--job-name=tessera-%s", fj->id);
    snprintf(array, sizeof array, "--array=0-%u", fj->shards - 1);
    snprintf(out, sizeof out, "--output=%s/logs/task-%%a.out", dir);
    snprintf(err, sizeof err, "--error=%s/logs/task-%%a.err", dir);
    snprintf(chdir_arg, sizeof chdir_arg, "--chdir=%s", dir);
    snprintf(script, sizeof script, "%s/task.sh", dir);
    char *argv[16 + SRV_FARM_MAX_SBATCH_ARGS];
    int k = 0;
    argv[k++] = "sbatch", argv[k++] = "--parsable", argv[k++] = name, argv[k++] = array, argv[k++] = "--requeue";
    argv[k++] = out, argv[k++] = err, argv[k++] = chdir_arg;
    for (int i = 0; i < f->opt.n_sbatch_args; i++) argv[k++] = f->sbatch_args[i];
    argv[k++] = script;
    argv[k] = NULL;
    run(argv, &r);
    char *end;
    unsigned long id = r.status == 0 ? strtoul(r.out, &end, 10) : 0;
    if (r.status != 0 || id == 0) {
        char c[900];
        complaint(&r, c, sizeof c);
        snprintf(why, sizeof why, "sbatch did not submit the job's array: %s", c);
        log_farm(f, SRV_LOG_ERROR, "farm.sbatch_failed", fj, "message", c);
        end_job(f, fj, TS_JOB_FAILED, TS_HALT_NONE, why);
        return;
    }
    pthread_mutex_lock(&f->mu);
    snprintf(fj->slurm_id, sizeof fj->slurm_id, "%lu", id);
    pthread_mutex_unlock(&f->mu);
    log_farm(f, SRV_LOG_INFO, "farm.submitted", fj, "array", array + 8);
submitted:
    pthread_mutex_lock(&f->mu);
    fj->phase = PHASE_RUNNING;
    pthread_mutex_unlock(&f->mu);
    save_state(f, fj);
}

/* Live task states from squeue: st[i] pending/running, or -1 when squeue does not list it.
 * False when squeue itself failed (states unknown this round). */
static bool live_tasks(farm_job *fj, int *st)
{
    command_result r;
    for (uint32_t i = 0; i < fj->shards; i++) st[i] = -1;
    char *argv[] = {"squeue", "-h", "-r", "-j", fj->slurm_id, "-o", "%K %T", NULL};
    run(argv, &r);
    if (r.status != 0) return strstr(r.err, "Invalid job id") != NULL; /* purged: nothing live */
    for (char *line = strtok(r.out, "\n"); line; line = strtok(NULL, "\n")) {
        char state[64];
        unsigned long k;
        if (sscanf(line, "%lu %63s", &k, state) != 2 || k >= fj->shards) continue;
        st[k] = !strcmp(state, "RUNNING") || !strcmp(state, "COMPLETING") || !strcmp(state, "CONFIGURING") ||
                        !strcmp(state, "STOPPED") || !strcmp(state, "SUSPENDED")
                    ? TASK_RUNNING
                    : TASK_PENDING;
    }
    return true;
}

/* How task i of the array ended, from scontrol (then sacct): "FAILED, exit code 1:0". */
static void ended_how(farm_job *fj, uint32_t i, char *out, size_t n)
{
    command_result r;
    char task[64];
    snprintf(task, sizeof task, "%s_%u", fj->slurm_id, i);
    char *a1[] = {"scontrol", "-o", "show", "job", task, NULL};
    run(a1, &r);
    char *s = r.status == 0 ? strstr(r.out, "JobState=") : NULL;
    if (s) {
        char state[64] = "", code[32] = "";
        sscanf(s, "JobState=%63s", state);
        char *c = strstr(r.out, "ExitCode=");
        if (c) sscanf(c, "ExitCode=%31s", code);
        snprintf(out, n, "%s, exit code %s", state, code[0] ? code : "unknown");
        return;
    }
    char *a2[] = {"sacct", "-n", "-P", "-X", "-j", task, "-o", "State,ExitCode", NULL};
    run(a2, &r);
    if (r.status == 0 && r.out[0] && !strstr(r.out, "disabled")) {
        r.out[strcspn(r.out, "\n")] = '\0';
        char *bar = strchr(r.out, '|');
        if (bar) *bar = '\0';
        snprintf(out, n, "%s, exit code %s", r.out, bar ? bar + 1 : "unknown");
        return;
    }
    snprintf(out, n, "ended without its output (Slurm no longer says how)");
}

static bool scancel(farm_job *fj, const char *what, char *why, size_t n)
{
    command_result r;
    char *argv[] = {"scancel", (char *)what, NULL};
    run(argv, &r);
    if (r.status == 0) return true;
    complaint(&r, why, n);
    (void)fj;
    return false;
}

/* Requeues task i (it resumes from its checkpoint) and lets it start at once (a requeued
 * job otherwise waits out Slurm's begin-time delay). */
static bool requeue(farm_job *fj, uint32_t i, char *why, size_t n)
{
    command_result r;
    char task[64];
    snprintf(task, sizeof task, "%s_%u", fj->slurm_id, i);
    char *argv[] = {"scontrol", "requeue", task, NULL};
    run(argv, &r);
    if (r.status != 0) {
        complaint(&r, why, n);
        return false;
    }
    char id[80];
    snprintf(id, sizeof id, "JobId=%s", task);
    char *a2[] = {"scontrol", "update", id, "StartTime=now", NULL};
    run(a2, &r); /* best effort: without it the task starts a little later */
    return true;
}

/* Merges every task's latest file (output, else checkpoint) in task order and publishes
 * the result. *complete: every sample of every pixel is in. False (nothing published)
 * when a file could not be read this round (being replaced) or is not of this job. */
static bool merge_and_publish(srv_farm *f, farm_job *fj, bool *complete, char *why, size_t n)
{
    *complete = false;
    ts_error err = {0};
    ts_merge *m = ts_merge_create(&err);
    if (!m) return false;
    int added = 0;
    uint32_t *spp = calloc(fj->shards, sizeof *spp);
    bool ok = spp != NULL;
    for (uint32_t i = 0; ok && i < fj->shards; i++) {
        char path[4200];
        task_file(f, fj->id, "shard", i, path, sizeof path);
        struct stat sb;
        bool output = stat(path, &sb) == 0;
        if (!output) {
            task_file(f, fj->id, "checkpoint", i, path, sizeof path);
            if (stat(path, &sb) != 0) continue;
        }
        if (ts_merge_add_file(m, path, &err)) {
            if (err.status != TS_ERR_IO) snprintf(why, n, "%s", err.message); /* not of this job, or damaged */
            ok = false;
            break;
        }
        ts_shard_info fi;
        if (!ts_merge_file_info(m, added++, &fi)) continue;
        /* A task's file holds a beginning of its own share (all of it once it is the output). */
        ts_sample_range want = ts_shard_range(i, fj->shards, fj->spp);
        if (fi.n_ranges > 1 || (fi.n_ranges == 1 && (fi.ranges[0].begin != want.begin || fi.ranges[0].end > want.end)) ||
            (output && (fi.n_ranges != 1 || fi.ranges[0].end != want.end))) {
            char got[128];
            ts_shard_format_ranges(fi.ranges, fi.n_ranges, got, sizeof got);
            snprintf(why, n, "%s holds samples %s, not task %u's [%u,%u)", path, got, i, want.begin, want.end);
            ok = false;
            break;
        }
        spp[i] = ts_shard_range_samples(fi.ranges, fi.n_ranges);
    }
    ts_shard_info info;
    const ts_film *merged = ok && added ? ts_merge_result(m, &info, NULL) : NULL;
    const ts_scene *scene = ts_sched_job_scene(fj->j->sj);
    if (merged && scene && strcmp(info.digest, scene->digest) != 0) {
        snprintf(why, n, "the shards under --farm-dir are of another scene than the job's");
        merged = NULL;
        ok = false;
    }
    if (merged) {
        uint64_t samples = 0;
        for (size_t p = 0; p < (size_t)merged->width * (size_t)merged->height; p++) samples += merged->pixels[p].count;
        ts_film *copy = ts_film_create(merged->full_width, merged->full_height, merged->x0, merged->y0, merged->width,
                                       merged->height, &err);
        if (copy) {
            memcpy(copy->pixels, merged->pixels, sizeof(ts_film_pixel) * (size_t)merged->width * (size_t)merged->height);
            if (ts_sched_job_publish(fj->j->sj, copy, samples, &err) == TS_OK) {
                char missing[8];
                *complete = ts_merge_missing(m, missing, sizeof missing) == 0 && info.spp_total == fj->spp;
            } else {
                snprintf(why, n, "%s", err.message);
                ok = false;
            }
            ts_film_destroy(copy);
        }
        pthread_mutex_lock(&f->mu);
        for (uint32_t i = 0; i < fj->shards; i++) fj->tasks[i].spp = spp[i];
        pthread_mutex_unlock(&f->mu);
    }
    free(spp);
    ts_merge_destroy(m);
    return ok;
}

/* Did task i's file change since it was last merged? Records what it is now. */
static bool file_changed(srv_farm *f, farm_job *fj, uint32_t i, bool *has_output)
{
    char path[4200];
    farm_task *t = &fj->tasks[i];
    struct stat sb;
    task_file(f, fj->id, "shard", i, path, sizeof path);
    bool output = stat(path, &sb) == 0;
    if (!output) {
        task_file(f, fj->id, "checkpoint", i, path, sizeof path);
        if (stat(path, &sb) != 0) {
            *has_output = false;
            return false;
        }
    }
    *has_output = output;
    bool changed = output != t->output || sb.st_ino != t->ino || sb.st_size != t->size ||
                   sb.st_mtim.tv_sec != t->mtime.tv_sec || sb.st_mtim.tv_nsec != t->mtime.tv_nsec;
    t->output = output, t->ino = sb.st_ino, t->size = sb.st_size, t->mtime = sb.st_mtim;
    return changed;
}

/* One look at a running array: task states, requeues, merge, the end. */
static void follow(srv_farm *f, farm_job *fj)
{
    int *live = calloc(fj->shards, sizeof *live);
    if (!live) return;
    bool squeue_ok = live_tasks(fj, live);
    ts_job_progress p;
    ts_sched_job_progress(fj->j->sj, &p);
    char why[1024];
    pthread_mutex_lock(&f->mu);
    bool cancelled = fj->scancel_sent;
    pthread_mutex_unlock(&f->mu);
    if (p.cancelling && !cancelled) {
        if (scancel(fj, fj->slurm_id, why, sizeof why)) {
            pthread_mutex_lock(&f->mu);
            fj->scancel_sent = cancelled = true;
            pthread_mutex_unlock(&f->mu);
            save_state(f, fj);
            log_farm(f, SRV_LOG_INFO, "farm.cancelled", fj, NULL, NULL);
        } else {
            log_farm(f, SRV_LOG_WARN, "farm.scancel_failed", fj, "message", why);
        }
    }
    bool any_live = false, all_done = true, any_running = false;
    const char *failure = NULL;
    char failure_text[1024] = "";
    for (uint32_t i = 0; i < fj->shards; i++) {
        bool output = false;
        if (file_changed(f, fj, i, &output)) fj->dirty = true;
        task_state s;
        if (output) s = TASK_DONE;
        else if (!squeue_ok) s = fj->tasks[i].state; /* unknown this round: as it was */
        else if (live[i] >= 0) s = (task_state)live[i];
        else if (cancelled) s = TASK_CANCELLED;
        else {
            /* Ended without its output: requeue it, or fail the job. */
            char how[256], tail[768];
            ended_how(fj, i, how, sizeof how);
            stderr_tail(f, fj->id, i, tail, sizeof tail);
            pthread_mutex_lock(&f->mu);
            int tries = fj->tasks[i].retries;
            pthread_mutex_unlock(&f->mu);
            char msg[1200];
            snprintf(msg, sizeof msg, "%s; stderr: %s", how, tail[0] ? tail : "(empty)");
            why[0] = '\0';
            if (tries < f->opt.retries && requeue(fj, i, why, sizeof why)) {
                pthread_mutex_lock(&f->mu);
                fj->tasks[i].retries++;
                pthread_mutex_unlock(&f->mu);
                save_state(f, fj);
                log_farm(f, SRV_LOG_WARN, "farm.requeued", fj, "task", msg);
                s = TASK_PENDING;
            } else {
                s = TASK_FAILED;
                if (!failure) {
                    char refused[600] = "";
                    if (why[0]) snprintf(refused, sizeof refused, " (scontrol requeue refused: %s)", why);
                    snprintf(failure_text, sizeof failure_text,
                             "task %u of %u (Slurm job %s_%u) failed after %d requeue%s%s: %s", i, fj->shards,
                             fj->slurm_id, i, tries, tries == 1 ? "" : "s", refused, msg);
                    failure = failure_text;
                }
            }
        }
        if (s == TASK_PENDING || s == TASK_RUNNING) any_live = true;
        if (s == TASK_RUNNING) any_running = true;
        if (s != TASK_DONE) all_done = false;
        pthread_mutex_lock(&f->mu);
        fj->tasks[i].state = s;
        pthread_mutex_unlock(&f->mu);
    }
    free(live);
    if (any_running) ts_sched_job_start(fj->j->sj);
    bool complete = false;
    if (fj->dirty) {
        char merr[1024] = "";
        if (merge_and_publish(f, fj, &complete, merr, sizeof merr)) fj->dirty = false;
        else if (merr[0]) failure = strcpy(failure_text, merr);
    }
    if (failure) {
        /* The job has failed: stop the rest of the array; the pixels merged so far stay. */
        if (!cancelled && scancel(fj, fj->slurm_id, why, sizeof why)) {
            pthread_mutex_lock(&f->mu);
            fj->scancel_sent = true;
            pthread_mutex_unlock(&f->mu);
        }
        log_farm(f, SRV_LOG_ERROR, "farm.failed", fj, "message", failure);
        end_job(f, fj, TS_JOB_FAILED, TS_HALT_NONE, failure);
    } else if (all_done && complete) {
        end_job(f, fj, TS_JOB_DONE, TS_HALT_SPP, NULL);
    } else if (cancelled && squeue_ok && !any_live && !fj->dirty) {
        end_job(f, fj, TS_JOB_CANCELLED, TS_HALT_CANCELLED, NULL);
    }
}

static void *farm_main(void *arg)
{
    srv_farm *f = arg;
    pthread_mutex_lock(&f->mu);
    while (!f->stopping) {
        int n = 0;
        for (farm_job *fj = f->jobs; fj; fj = fj->next) n += fj->phase != PHASE_ENDED;
        farm_job **work = n ? calloc((size_t)n, sizeof *work) : NULL;
        int k = 0;
        for (farm_job *fj = f->jobs; fj && work; fj = fj->next)
            if (fj->phase != PHASE_ENDED) work[k++] = fj, srv_job_retain(fj->j);
        pthread_mutex_unlock(&f->mu);
        for (int i = 0; i < k; i++) {
            pthread_mutex_lock(&f->mu);
            bool stop = f->stopping;
            phase ph = work[i]->phase;
            pthread_mutex_unlock(&f->mu);
            if (!stop && ph == PHASE_SUBMIT) submit_array(f, work[i]);
            else if (!stop && ph == PHASE_RUNNING) follow(f, work[i]);
            srv_job_release(work[i]->j); /* the list keeps its own */
        }
        free(work);
        pthread_mutex_lock(&f->mu);
        if (f->stopping) break;
        struct timespec ts;
        clock_gettime(CLOCK_REALTIME, &ts);
        ts.tv_nsec += (long)(POLL_S * 1e9);
        if (ts.tv_nsec >= 1000000000L) ts.tv_sec++, ts.tv_nsec -= 1000000000L;
        pthread_cond_timedwait(&f->cv, &f->mu, &ts);
    }
    pthread_mutex_unlock(&f->mu);
    return NULL;
}

/* ---------------------------------------------------------------- public */

static farm_job *farm_job_new(srv_job *j, uint32_t shards)
{
    farm_job *fj = calloc(1, sizeof *fj);
    if (!fj || !(fj->tasks = calloc(shards, sizeof *fj->tasks))) {
        free(fj);
        return NULL;
    }
    srv_job_retain(j);
    fj->j = j;
    snprintf(fj->id, sizeof fj->id, "%s", j->id);
    fj->shards = shards;
    fj->spp = j->settings.spp;
    fj->dirty = true;
    return fj;
}

static void add_job(srv_farm *f, farm_job *fj)
{
    pthread_mutex_lock(&f->mu);
    fj->next = f->jobs;
    f->jobs = fj;
    pthread_cond_signal(&f->cv);
    pthread_mutex_unlock(&f->mu);
}

srv_farm *srv_farm_create(const srv_farm_options *opts, srv_store *store, const char *data_dir, srv_log *log,
                          char *err, size_t err_len)
{
    srv_farm *f = calloc(1, sizeof *f);
    if (!f) {
        snprintf(err, err_len, "out of memory");
        return NULL;
    }
    f->opt = *opts;
    f->store = store;
    f->log = log;
    pthread_mutex_init(&f->mu, NULL);
    pthread_cond_init(&f->cv, NULL);
    char probe[4200];
    if (mkdirs(opts->dir) != 0 || !(f->dir = realpath(opts->dir, NULL))) {
        snprintf(err, err_len, "--farm-dir %s: cannot make or open the folder: %s", opts->dir, strerror(errno));
        goto fail;
    }
    snprintf(probe, sizeof probe, "%s/.tessera-write-test.%d", f->dir, (int)getpid());
    int fd = open(probe, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
    if (fd < 0) {
        snprintf(err, err_len, "--farm-dir %s: cannot write there: %s", opts->dir, strerror(errno));
        goto fail;
    }
    close(fd);
    unlink(probe);
    f->tessera = opts->tessera ? strdup(opts->tessera) : realpath("/proc/self/exe", NULL);
    f->data_dir = data_dir ? strdup(data_dir) : NULL;
    f->sbatch_args = calloc((size_t)opts->n_sbatch_args + 1, sizeof *f->sbatch_args);
    if (!f->tessera || (data_dir && !f->data_dir) || !f->sbatch_args) {
        snprintf(err, err_len, "out of memory");
        goto fail;
    }
    for (int i = 0; i < opts->n_sbatch_args; i++)
        if (!(f->sbatch_args[i] = strdup(opts->sbatch_args[i]))) {
            snprintf(err, err_len, "out of memory");
            goto fail;
        }
    if (pthread_create(&f->thread, NULL, farm_main, f) != 0) {
        snprintf(err, err_len, "cannot start the farm thread");
        goto fail;
    }
    f->started = true;
    return f;
fail:
    srv_farm_destroy(f);
    return NULL;
}

void srv_farm_stop(srv_farm *f)
{
    if (!f || !f->started) return;
    pthread_mutex_lock(&f->mu);
    f->stopping = true;
    pthread_cond_signal(&f->cv);
    pthread_mutex_unlock(&f->mu);
    pthread_join(f->thread, NULL);
    f->started = false;
    for (farm_job *fj = f->jobs; fj && !f->data_dir; fj = fj->next)
        if (fj->phase == PHASE_RUNNING && fj->slurm_id[0]) {
            /* Nothing could re-attach to it: do not leave it using the cluster. */
            char why[256];
            if (!scancel(fj, fj->slurm_id, why, sizeof why))
                fprintf(stderr, "tessera serve: scancel %s (farm job %s): %s\n", fj->slurm_id, fj->id, why);
        }
}

void srv_farm_destroy(srv_farm *f)
{
    if (!f) return;
    srv_farm_stop(f);
    farm_job *fj = f->jobs;
    while (fj) {
        farm_job *next = fj->next;
        srv_job_release(fj->j);
        free(fj->tasks);
        free(fj);
        fj = next;
    }
    for (int i = 0; f->sbatch_args && i < f->opt.n_sbatch_args; i++) free(f->sbatch_args[i]);
    free(f->sbatch_args);
    free(f->dir);
    free(f->tessera);
    free(f->data_dir);
    pthread_mutex_destroy(&f->mu);
    pthread_cond_destroy(&f->cv);
    free(f);
}

uint32_t srv_farm_max_shards(const srv_farm *f)
{
    if (f) return f->opt.max_shards;
    srv_farm_options o;
    srv_farm_options_default(&o);
    return o.max_shards;
}

bool srv_farm_parse_shards(const char *value, uint32_t max_shards, uint32_t *shards, ts_error *err)
{
    *shards = 0;
    if (!value) return true;
    unsigned long v;
    if (!parse_uint(value, 1, max_shards, &v) || (value[0] == '0')) {
        ts_error_set(err, TS_ERR_INVALID, "shards: expected a whole number of tasks from 1 to %u (--max-shards), got '%s'",
                     max_shards, value);
        return false;
    }
    *shards = (uint32_t)v;
    return true;
}

bool srv_farm_parse_request(const char *text, size_t len, uint32_t max_shards, uint32_t *shards, char **stripped,
                            size_t *stripped_len, int *http_status, ts_error *err)
{
    *shards = 0;
    *stripped = NULL;
    if (!memmem(text, len, "farm", 4)) return true; /* cheap: most documents have no farm at all */
    cJSON *doc = cJSON_ParseWithLength(text, len);
    const cJSON *job = doc ? cJSON_GetObjectItemCaseSensitive(doc, "job") : NULL;
    cJSON *farm = cJSON_IsObject(job) ? cJSON_GetObjectItemCaseSensitive(job, "farm") : NULL;
    if (!farm) { /* none (or a document the loader will refuse with its own sentence) */
        cJSON_Delete(doc);
        return true;
    }
    *http_status = 400;
    const cJSON *n = cJSON_GetObjectItemCaseSensitive(farm, "shards");
    const cJSON *e;
    if (!cJSON_IsObject(farm)) {
        ts_error_set(err, TS_ERR_INVALID, "job.farm: expected an object {\"shards\": N}");
        goto fail;
    }
    cJSON_ArrayForEach(e, farm) if (strcmp(e->string, "shards") != 0)
    {
        ts_error_set(err, TS_ERR_INVALID, "job.farm.%s: unknown key (job.farm takes shards)", e->string);
        goto fail;
    }
    if (!cJSON_IsNumber(n) || n->valuedouble != floor(n->valuedouble) || n->valuedouble < 1 ||
        n->valuedouble > max_shards) {
        ts_error_set(err, TS_ERR_INVALID, "job.farm.shards: expected a whole number of tasks from 1 to %u (--max-shards)",
                     max_shards);
        goto fail;
    }
    *http_status = 422;
    if (cJSON_GetObjectItemCaseSensitive(job, "time_limit_s") || cJSON_GetObjectItemCaseSensitive(job, "target_error")) {
        ts_error_set(err, TS_ERR_UNSUPPORTED,
                     "job.farm: a farm job renders all its samples on its tasks; job.time_limit_s and "
                     "job.target_error are for jobs rendered here");
        goto fail;
    }
    *shards = (uint32_t)n->valuedouble;
    cJSON_DeleteItemFromObjectCaseSensitive((cJSON *)job, "farm");
    if (!(*stripped = cJSON_PrintUnformatted(doc))) {
        *http_status = 500;
        ts_error_set(err, TS_ERR_NOMEM, "out of memory");
        goto fail;
    }
    *stripped_len = strlen(*stripped);
    cJSON_Delete(doc);
    return true;
fail:
    *shards = 0;
    cJSON_Delete(doc);
    return false;
}

srv_job *srv_farm_submit(srv_farm *f, srv_store *st, const char *text, size_t len, const srv_submit_files *files,
                         ts_cancel *cancel, uint32_t shards, int *http_status, ts_error *err)
{
    if (!f) {
        *http_status = 422;
        ts_error_set(err, TS_ERR_UNSUPPORTED,
                     "job.farm: this server has no farm to send the job to (start it with --farm slurm --farm-dir DIR)");
        return NULL;
    }
    srv_job *j = srv_store_submit_external(st, text, len, files, cancel, http_status, err);
    if (!j) return NULL;
    if (shards > j->settings.spp || j->settings.adaptive) {
        /* Every task must render at least one sample, and the same samples in every pixel
         * (the merge adds them exactly): an adaptive job's pixels stop at counts chosen from
         * the whole image. The job was listed: it fails. */
        if (j->settings.adaptive)
            ts_error_set(err, TS_ERR_INVALID,
                         "job.adaptive: a farm job's tasks each render one sample range of every pixel, which the "
                         "merge adds exactly; an adaptive job's pixels stop at different counts chosen from the whole "
                         "image, so it is rendered here, without job.farm or ?shards");
        else
            ts_error_set(err, TS_ERR_INVALID,
                         "job.farm.shards: %u tasks of %u samples per pixel would leave tasks without samples", shards,
                         j->settings.spp);
        ts_sched_job_finish(j->sj, TS_JOB_FAILED, TS_HALT_NONE);
        srv_store_remove(st, j);
        if (j->files_dir) { /* a bundle's folder, ROOT/jobs/<id>/files: the job's folder goes */
            char folder[4096];
            snprintf(folder, sizeof folder, "%s", j->files_dir);
            char *slash = strrchr(folder, '/');
            if (slash) *slash = '\0';
            srv_bundle_remove_tree(folder);
        }
        srv_job_release(j);
        *http_status = 400;
        return NULL;
    }
    farm_job *fj = farm_job_new(j, shards);
    if (!fj) {
        ts_sched_job_finish(j->sj, TS_JOB_FAILED, TS_HALT_NONE);
        srv_store_remove(st, j);
        srv_job_release(j);
        *http_status = 500;
        ts_error_set(err, TS_ERR_NOMEM, "out of memory for a farm job");
        return NULL;
    }
    save_state(f, fj);
    add_job(f, fj);
    return j;
}

int srv_farm_attach(srv_farm *f, srv_store *st, const char *data_dir)
{
    int n = 0, count = 0;
    srv_job **all = srv_store_list(st, &n);
    for (int i = 0; i < n; i++) {
        srv_job *j = all[i];
        if (!j->external) goto next;
        bool finished = ts_job_state_finished(srv_job_state(j));
        if (!f) {
            if (!finished && j->sj)
                ts_sched_job_finish(j->sj, TS_JOB_FAILED, TS_HALT_NONE),
                    fprintf(stderr, "tessera serve: farm job %s is not followed: this server runs without --farm\n", j->id);
            goto next;
        }
        char path[4200];
        snprintf(path, sizeof path, "%s/jobs/%s/farm.json", data_dir, j->id);
        FILE *fp = fopen(path, "r");
        char buf[1 << 16];
        size_t len = fp ? fread(buf, 1, sizeof buf - 1, fp) : 0;
        if (fp) fclose(fp);
        buf[len] = '\0';
        cJSON *o = cJSON_Parse(buf);
        const cJSON *sh = cJSON_GetObjectItemCaseSensitive(o, "shards");
        const cJSON *id = cJSON_GetObjectItemCaseSensitive(o, "slurm_job");
        const cJSON *er = cJSON_GetObjectItemCaseSensitive(o, "error");
        const cJSON *sc = cJSON_GetObjectItemCaseSensitive(o, "scancel_sent");
        const cJSON *re = cJSON_GetObjectItemCaseSensitive(o, "retries");
        uint32_t shards = cJSON_IsNumber(sh) && sh->valuedouble >= 1 && sh->valuedouble <= 1000000 ? (uint32_t)sh->valuedouble : 0;
        farm_job *fj = shards ? farm_job_new(j, shards) : NULL;
        if (!fj) {
            if (!finished && j->sj) ts_sched_job_finish(j->sj, TS_JOB_FAILED, TS_HALT_NONE);
            fprintf(stderr, "tessera serve: farm job %s: jobs/%s/farm.json is unreadable; the job is not followed\n",
                    j->id, j->id);
            cJSON_Delete(o);
            goto next;
        }
        if (cJSON_IsString(id)) snprintf(fj->slurm_id, sizeof fj->slurm_id, "%s", id->valuestring);
        if (cJSON_IsString(er)) snprintf(fj->error, sizeof fj->error, "%s", er->valuestring);
        fj->scancel_sent = cJSON_IsTrue(sc);
        for (uint32_t t = 0; t < shards && cJSON_IsArray(re); t++) {
            const cJSON *v = cJSON_GetArrayItem(re, (int)t);
            fj->tasks[t].retries = cJSON_IsNumber(v) ? (int)v->valuedouble : 0;
        }
        cJSON_Delete(o);
        if (finished) {
            fj->phase = PHASE_ENDED;
            for (uint32_t t = 0; t < shards; t++) fj->tasks[t].state = TASK_CANCELLED;
        } else {
            fj->phase = fj->slurm_id[0] ? PHASE_RUNNING : PHASE_SUBMIT;
            if (fj->scancel_sent) ts_sched_job_cancel(j->sj); /* it was being cancelled */
            count++;
            fprintf(stderr, "tessera serve: farm job %s: re-attached to Slurm array %s\n", j->id,
                    fj->slurm_id[0] ? fj->slurm_id : "(not submitted yet)");
        }
        add_job(f, fj);
    next:
        srv_job_release(j);
    }
    free(all);
    return count;
}

void srv_farm_describe(void *farm, srv_job *j, cJSON *status)
{
    srv_farm *f = farm;
    if (!f) return;
    pthread_mutex_lock(&f->mu);
    farm_job *fj = f->jobs;
    while (fj && fj->j != j) fj = fj->next;
    if (fj) {
        cJSON *o = cJSON_AddObjectToObject(status, "farm");
        cJSON_AddStringToObject(o, "scheduler", "slurm");
        if (fj->slurm_id[0]) cJSON_AddStringToObject(o, "slurm_job", fj->slurm_id);
        else cJSON_AddNullToObject(o, "slurm_job");
        cJSON_AddNumberToObject(o, "shards", fj->shards);
        cJSON *tasks = cJSON_AddArrayToObject(o, "tasks");
        for (uint32_t i = 0; tasks && i < fj->shards; i++) {
            cJSON *t = cJSON_CreateObject();
            ts_sample_range r = ts_shard_range(i, fj->shards, fj->spp);
            cJSON_AddNumberToObject(t, "index", i);
            cJSON_AddStringToObject(t, "state", task_state_name(fj->tasks[i].state));
            cJSON_AddNumberToObject(t, "spp", fj->tasks[i].spp);
            cJSON_AddNumberToObject(t, "spp_target", r.end - r.begin);
            cJSON_AddNumberToObject(t, "retries", fj->tasks[i].retries);
            cJSON_AddItemToArray(tasks, t);
        }
        if (fj->error[0] && !cJSON_GetObjectItemCaseSensitive(status, "error"))
            cJSON_AddStringToObject(status, "error", fj->error);
    }
    pthread_mutex_unlock(&f->mu);
}

void srv_farm_forget(srv_farm *f, srv_job *j)
{
    if (!f) return;
    pthread_mutex_lock(&f->mu);
    farm_job **pp = &f->jobs, *fj = NULL;
    while (*pp && (*pp)->j != j) pp = &(*pp)->next;
    if (*pp && (*pp)->phase == PHASE_ENDED) {
        fj = *pp;
        *pp = fj->next;
    }
    pthread_mutex_unlock(&f->mu);
    if (!fj) return;
    char dir[4096];
    job_folder(f, fj->id, dir, sizeof dir);
    if (srv_bundle_remove_tree(dir) != 0 && errno != ENOENT)
        fprintf(stderr, "tessera: removing %s: %s\n", dir, strerror(errno));
    srv_job_release(fj->j);
    free(fj->tasks);
    free(fj);
}
