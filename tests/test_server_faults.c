/* test_server_faults.c — `tessera serve` under faults (disk, crash, clients), one group per
 * ctest entry (the first argument):
 *
 *   checkpoint  checkpoints into a full file system (a 1 MiB tmpfs) and into a read-only
 *               folder (a read-only bind mount; chmod 555 when not root): the job status
 *               and the log report it, rendering goes on to the end, the previous
 *               checkpoint stays byte for byte, and checkpoints resume once the fault is
 *               gone. Mounts happen in a private mount namespace of this process (the
 *               server inherits it); where that is not allowed the group reports SKIPPED.
 *   kill        SIGKILL at 100 moments (fixed seed) during renders with 50 ms checkpoints,
 *               each followed by a restart that must load a consistent state; every job
 *               finishes with exactly its sample count and pixels equal to `tessera render`.
 *   clients     clients that disconnect mid-download and mid-event-stream, slow clients
 *               (one byte per second, more of them than HTTP threads), an idle client past
 *               --client-timeout, and --max-client-connections: the server stays healthy
 *               and holds no socket afterwards (its open descriptors return to baseline);
 *               1000 event-stream subscribers that never read leave /healthz prompt and the
 *               server's memory bounded, subscriber caps answer 503, and a subscriber that
 *               falls too far behind is dropped. */
#define _GNU_SOURCE /* unshare, mount namespaces */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <arpa/inet.h>
#include <curl/curl.h>
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mount.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "cli_support.h"
#include "core/hash.h"
#include "image/exr.h"
#include "image/image.h"
#include "server_harness.h"

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}


static char *read_file(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    char *buf = NULL;
    size_t n = 0, cap = 0;
    for (;;) {
        if (n + 65536 > cap) {
            cap = cap ? cap * 2 : 65536 * 2;
            buf = realloc(buf, cap);
            assert_non_null(buf);
        }
        size_t r = fread(buf + n, 1, cap - n, f);
        n += r;
        if (!r) break;
    }
    fclose(f);
    *len = n;
    return buf;
}

static bool exists(const char *path)
{
    struct stat sb;
    return stat(path, &sb) == 0;
}

static cJSON *job_status(const test_server *s, const char *id)
{
    char path[128];
    snprintf(path, sizeof path, "/api/v1/jobs/%s", id);
    return ts_http_json(s, path, 200);
}

static ts_image get_exr(const test_server *s, const char *id)
{
    char path[160];
    snprintf(path, sizeof path, "/api/v1/jobs/%s/image.exr", id);
    http_resp r;
    ts_http(s, "GET", path, NULL, 0, NULL, &r);
    if (r.status != 200) fail_msg("GET %s: %ld", path, r.status);
    ts_image img;
    ts_error err = {0};
    if (ts_exr_read_memory((const unsigned char *)r.body, r.len, &img, &err)) fail_msg("%s", err.message);
    ts_http_free(&r);
    return img;
}

static double metric(const test_server *s, const char *name);
static int subscribe(const test_server *s, const char *id);
static int status_of(int fd);

/* ================================================================ checkpoint faults */

static char mount_dir[64], plain_dir[64];
static bool have_mounts; /* a private mount namespace with a tmpfs at mount_dir */

/* Waits until the job's status carries (want) or lacks (!want) a checkpoint_error; returns
 * its text (static) or fails. */
static const char *wait_checkpoint_error(const test_server *s, const char *id, bool want, double timeout_s)
{
    static char text[600];
    double t0 = now_s();
    while (now_s() - t0 < timeout_s) {
        cJSON *o = job_status(s, id);
        const cJSON *e = cJSON_GetObjectItemCaseSensitive(o, "checkpoint_error");
        bool has = cJSON_IsString(e);
        snprintf(text, sizeof text, "%s", has ? e->valuestring : "");
        cJSON_Delete(o);
        if (has == want) return text;
        ts_sleep_ms(20);
    }
    fail_msg("job %s: checkpoint_error %s after %g s", id, want ? "never appeared" : "stayed", timeout_s);
    return NULL;
}

static bool log_has(const test_server *s, const char *needle)
{
    size_t n = 0;
    char *t = read_file(s->log, &n);
    if (!t) return false;
    t = realloc(t, n + 1);
    t[n] = '\0';
    bool found = strstr(t, needle) != NULL;
    free(t);
    return found;
}

/* The temporary files in the job's folder, as "name\n…" (static). */
static const char *temporaries(const char *folder)
{
    static char names[4096];
    names[0] = '\0';
    DIR *d = opendir(folder);
    assert_non_null(d);
    struct dirent *de;
    while ((de = readdir(d)))
        if (strstr(de->d_name, ".tmp.") && strlen(names) + strlen(de->d_name) + 2 < sizeof names)
            strcat(strcat(names, de->d_name), "\n");
    closedir(d);
    return names;
}

/* The temporary files in the job's folder that were not made by process `live`
 * (image.c names them PATH.tmp.PID.SERIAL), as "name\n…" (static). */
static const char *stale_temporaries(const char *folder, pid_t live)
{
    static char names[4096];
    names[0] = '\0';
    char own[32];
    snprintf(own, sizeof own, ".tmp.%ld.", (long)live);
    DIR *d = opendir(folder);
    assert_non_null(d);
    struct dirent *de;
    while ((de = readdir(d)))
        if (strstr(de->d_name, ".tmp.") && !strstr(de->d_name, own) &&
            strlen(names) + strlen(de->d_name) + 2 < sizeof names)
            strcat(strcat(names, de->d_name), "\n");
    closedir(d);
    return names;
}

/* No temporary file is left in the job's folder, but those in `allowed` ("name\n…"): a
 * write in flight at the very moment a folder became read-only cannot remove its
 * temporary file, and nothing can. */
static void assert_no_temporaries(const char *folder, const char *allowed)
{
    DIR *d = opendir(folder);
    assert_non_null(d);
    struct dirent *de;
    char line[300];
    while ((de = readdir(d))) {
        snprintf(line, sizeof line, "%s\n", de->d_name);
        if (strstr(de->d_name, ".tmp.") && !strstr(allowed, line))
            fail_msg("%s/%s: a temporary file was left behind", folder, de->d_name);
    }
    closedir(d);
}

typedef enum fault_kind { FAULT_FULL, FAULT_READONLY } fault_kind;

/* Fills the file system holding dir (a tmpfs) to the last byte; returns the filler path. */
static void fill_up(const char *dir, char *filler, size_t n)
{
    snprintf(filler, n, "%s/filler", dir);
    int fd = open(filler, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    assert_true(fd >= 0);
    static char block[65536];
    memset(block, 0x5a, sizeof block);
    for (size_t chunk = sizeof block; chunk >= 1;) {
        ssize_t w = write(fd, block, chunk);
        if (w < 0 && errno == ENOSPC) chunk /= 2;
        else if (w < 0) fail_msg("filling %s: %s", filler, strerror(errno));
    }
    close(fd);
}

static void checkpoint_fault(fault_kind kind)
{
    const char *dir = kind == FAULT_FULL ? mount_dir : plain_dir;
    test_server s;
    const char *args[] = {"--threads", "2", "--data", dir, "--checkpoint-interval", "0.1", NULL};
    ts_server_start(&s, args);
    /* 64×64 at 1024 spp of ambient occlusion: a few seconds on two threads, long enough to
     * fault it mid-render; its film checkpoint (64·64·72 bytes + a header) fits the tmpfs
     * twice (the file and its temporary copy). */
    char *doc = ts_ao_scene("faults", 64, 64, 1024), id[32], folder[160], film[200], filler[128] = "";
    ts_submit(&s, doc, id, sizeof id);
    snprintf(folder, sizeof folder, "%s/jobs/%s", dir, id);
    snprintf(film, sizeof film, "%s/film.bin", folder);
    ts_wait_field(&s, id, "spp_done", 8, 20);
    for (int i = 0; i < 250 && !exists(film); i++) ts_sleep_ms(20);
    assert_true(exists(film));

    /* The fault. */
    if (kind == FAULT_FULL) {
        fill_up(dir, filler, sizeof filler);
    } else if (geteuid() == 0) {
        if (mount(folder, folder, NULL, MS_BIND, NULL) || mount(NULL, folder, NULL, MS_REMOUNT | MS_BIND | MS_RDONLY, NULL))
            fail_msg("read-only bind mount of %s: %s", folder, strerror(errno));
    } else {
        assert_int_equal(chmod(folder, 0555), 0);
    }
    /* A checkpoint being written as the folder turned read-only keeps its temporary file. */
    char in_flight[4096];
    snprintf(in_flight, sizeof in_flight, "%s", kind == FAULT_READONLY ? temporaries(folder) : "");
    const char *why = wait_checkpoint_error(&s, id, true, 10);
    const char *expect = kind == FAULT_FULL ? "No space left on device" : geteuid() == 0 ? "Read-only file system" : "Permission denied";
    if (!strstr(why, expect)) fail_msg("checkpoint_error '%s' does not say '%s'", why, expect);
    char line[128];
    snprintf(line, sizeof line, "checkpoint of job %s failed", id);
    assert_true(log_has(&s, line));
    assert_true(log_has(&s, expect));
    /* From now on no checkpoint can land: this is the previous one. */
    size_t before_len = 0, after_len = 0;
    char *before = read_file(film, &before_len);
    assert_non_null(before);

    /* No path of the server's in what clients see. */
    if (strstr(why, dir)) fail_msg("checkpoint_error '%s' names the server's folder", why);
    double fault_t0 = now_s(), failures0 = metric(&s, "tessera_checkpoint_failures_total");

    /* Rendering goes on to the end. */
    cJSON *o = ts_wait_done(&s, id, 60);
    assert_string_equal(ts_json_str(o, "state"), "done");
    assert_int_equal((int)ts_json_num(o, "spp_done"), 1024);
    assert_non_null(cJSON_GetObjectItemCaseSensitive(o, "checkpoint_error"));
    cJSON_Delete(o);
    /* Jobs that finish while the fault lasts (on a full disk not even their submission
     * lands): a restart must not make them failed. */
    char small_ids[3][32];
    char *small = ts_ao_scene("faults-small", 16, 16, 4);
    for (int i = 0; i < 3; i++) {
        ts_submit(&s, small, small_ids[i], sizeof small_ids[i]);
        cJSON_Delete(ts_wait_done(&s, small_ids[i], 20));
    }
    free(small);
    ts_sleep_ms(300); /* a few more failed attempts */
    /* One log line per job when its checkpoints start failing (they once logged one line
     * per attempt, each naming a new temporary file: 550 lines in 10 s), and retries that
     * back off: from 0.1 s doubling to 10 s, at most ⌈log2(T/0.1)⌉ + T/10 + 1 attempts a
     * job in T seconds, where a retry every interval (0.1 s) would make T/0.1. */
    double fault_s = now_s() - fault_t0, failures = metric(&s, "tessera_checkpoint_failures_total") - failures0;
    size_t log_len = 0;
    char *log_text = read_file(s.log, &log_len);
    int lines = 0;
    for (size_t k = 0; k + 20 < log_len; k++) lines += !strncmp(log_text + k, "checkpoint of job", 17);
    free(log_text);
    double bound = 4 * (ceil(log2(fault_s / 0.1)) + fault_s / 10 + 2);
    printf("%s: %.1f s of faults: %d log lines about checkpoints, %.0f failed attempts for 4 jobs (bound %.0f; "
           "every interval would be %.0f)\n",
           kind == FAULT_FULL ? "full disk" : "read-only", fault_s, lines, failures, bound, 4 * fault_s / 0.1);
    assert_true(lines <= 4);
    assert_true(failures <= bound);
    char *after = read_file(film, &after_len);
    assert_non_null(after);
    assert_int_equal(after_len, before_len);
    assert_memory_equal(after, before, before_len);
    assert_true(before_len > 8 && !memcmp(before, "TSFILM02", 8));
    assert_no_temporaries(folder, in_flight);

    /* The fault goes away: the next checkpoint lands and the error clears. */
    if (kind == FAULT_FULL) assert_int_equal(unlink(filler), 0);
    else if (geteuid() == 0) assert_int_equal(umount2(folder, 0), 0);
    else assert_int_equal(chmod(folder, 0755), 0);
    wait_checkpoint_error(&s, id, false, 15); /* the next retry: at most 10 s later */
    snprintf(line, sizeof line, "checkpoint of job %s written again", id);
    assert_true(log_has(&s, line));
    free(after);
    after = read_file(film, &after_len);
    assert_int_equal(after_len, before_len);
    assert_true(memcmp(after, before, before_len) != 0); /* the finished film now */
    free(before);
    free(after);
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);

    /* And it restores as the finished job; so do the small ones (their checkpoints landed
     * once the fault went away), and no temporary file is left. */
    ts_server_start(&s, args);
    o = job_status(&s, id);
    assert_string_equal(ts_json_str(o, "state"), "done");
    assert_int_equal((int)ts_json_num(o, "spp_done"), 1024);
    cJSON_Delete(o);
    for (int i = 0; i < 3; i++) {
        o = job_status(&s, small_ids[i]);
        assert_string_equal(ts_json_str(o, "state"), "done");
        cJSON_Delete(o);
    }
    assert_no_temporaries(folder, "");
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
    free(doc);
}

static void test_checkpoint_full_disk(void **state)
{
    (void)state;
    if (!have_mounts) skip();
    checkpoint_fault(FAULT_FULL);
}

static void test_checkpoint_read_only(void **state)
{
    (void)state;
    if (geteuid() == 0 && !have_mounts) skip();
    checkpoint_fault(FAULT_READONLY);
}

/* A private mount namespace and a 1 MiB tmpfs at mount_dir; false (with the reason on
 * stdout) where this process may not do that. */
static bool setup_mounts(void)
{
    if (geteuid() != 0) {
        printf("note: not root, so no tmpfs can be mounted: the full-disk case is skipped\n");
        return false;
    }
    if (unshare(CLONE_NEWNS) != 0) {
        printf("note: cannot make a private mount namespace (%s): the full-disk and read-only cases are skipped\n",
               strerror(errno));
        return false;
    }
    if (mount(NULL, "/", NULL, MS_REC | MS_PRIVATE, NULL) != 0 ||
        mount("tessera-test", mount_dir, "tmpfs", MS_NOSUID | MS_NODEV, "size=1m,mode=0755") != 0) {
        printf("note: cannot mount a tmpfs (%s): the full-disk and read-only cases are skipped\n", strerror(errno));
        return false;
    }
    return true;
}

static int run_checkpoint(void)
{
    snprintf(mount_dir, sizeof mount_dir, "/tmp/tessera-fullfs-XXXXXX");
    snprintf(plain_dir, sizeof plain_dir, "/tmp/tessera-rofs-XXXXXX");
    if (!mkdtemp(mount_dir) || !mkdtemp(plain_dir)) return 1;
    have_mounts = setup_mounts(); /* unshare(CLONE_NEWNS) needs a single-threaded process: before curl */
    curl_global_init(CURL_GLOBAL_DEFAULT);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_checkpoint_full_disk),
        cmocka_unit_test(test_checkpoint_read_only),
    };
    int rc = cmocka_run_group_tests_name("checkpoint", tests, NULL, NULL);
    if (have_mounts) umount2(mount_dir, MNT_DETACH);
    char cmd[200];
    snprintf(cmd, sizeof cmd, "rm -rf '%s' '%s'", mount_dir, plain_dir);
    if (system(cmd) != 0 && !rc) rc = 1;
    if (!rc && !have_mounts && geteuid() == 0) {
        printf("SKIPPED: mounting is not allowed here (no private mount namespace)\n");
        return 77;
    }
    return rc;
}

/* ================================================================ kill -9 */

static char kill_dir[64];

/* The reference: `tessera render` of the same document (same pixels, docs/design.md §1). */
static ts_image reference(const char *doc)
{
    char scene_path[128], out[128], log[128];
    snprintf(scene_path, sizeof scene_path, "%s/ref.json", kill_dir);
    snprintf(out, sizeof out, "%s/ref.exr", kill_dir);
    snprintf(log, sizeof log, "%s/ref.log", kill_dir);
    cli_write_file(scene_path, doc);
    const char *args[] = {"render", scene_path, "-o", out, "--threads", "2", "--quiet", NULL};
    if (cli_run(log, args, NULL) != 0) fail_msg("tessera render: %s", cli_read_log(log));
    size_t len = 0;
    char *bytes = read_file(out, &len);
    assert_non_null(bytes);
    ts_image img;
    ts_error err = {0};
    if (ts_exr_read_memory((const unsigned char *)bytes, len, &img, &err)) fail_msg("%s", err.message);
    free(bytes);
    return img;
}

static void assert_same_pixels(const ts_image *a, const ts_image *ref, const char *id)
{
    assert_int_equal(a->width, ref->width);
    assert_int_equal(a->height, ref->height);
    static const char *const names[] = {"R", "G", "B", "count"};
    for (int k = 0; k < 4; k++) {
        int ca = ts_image_channel(a, names[k]), cr = ts_image_channel(ref, names[k]);
        assert_true(ca >= 0 && cr >= 0);
        for (int i = 0; i < a->width * a->height; i++)
            if (a->data[i * a->n_channels + ca] != ref->data[i * ref->n_channels + cr])
                fail_msg("job %s, pixel %d, %s: %.9g, uninterrupted render %.9g", id, i, names[k],
                         a->data[i * a->n_channels + ca], ref->data[i * ref->n_channels + cr]);
    }
}

/* A restarted server's state of the job: listed, not failed, and its image consistent with
 * its status (every pixel of a tile has the tile's count; none beyond the target, none
 * below spp_done). Returns spp_done. */
static int check_consistent(const test_server *s, const char *id, int spp_target, int w, int h)
{
    cJSON *o = job_status(s, id);
    const char *state = ts_json_str(o, "state");
    if (!strcmp(state, "failed") || !strcmp(state, "cancelled"))
        fail_msg("job %s restored as %s: %s", id, state, ts_json_str(o, "error"));
    int spp = (int)ts_json_num(o, "spp_done");
    assert_true(spp >= 0 && spp <= spp_target);
    if (!strcmp(state, "done")) assert_int_equal(spp, spp_target);
    cJSON_Delete(o);
    ts_image img = get_exr(s, id);
    int cc = ts_image_channel(&img, "count");
    assert_true(cc >= 0);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            float c = img.data[(y * w + x) * img.n_channels + cc];
            float c0 = img.data[((y / 32 * 32) * w + x / 32 * 32) * img.n_channels + cc]; /* the tile's first pixel */
            if (c != c0 || c < (float)spp || c > (float)spp_target)
                fail_msg("job %s: pixel (%d, %d) has %g samples (its tile %g, spp_done %d, target %d)", id, x, y, c,
                         c0, spp, spp_target);
        }
    ts_image_fini(&img);
    return spp;
}

static void test_kill_at_random_moments(void **state)
{
    (void)state;
    enum { KILLS = 100, W = 64, H = 32, SPP = 256 };
    /* Two tiles, 256 spp of ambient occlusion: about 0.3 s uninterrupted, so kills land in
     * every pass, in checkpoint writes, and after the end. */
    char *doc = ts_ao_scene("faults", W, H, SPP);
    ts_image ref = reference(doc);
    const char *args[] = {"--threads", "2", "--data", kill_dir, "--checkpoint-interval", "0.05", NULL};
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 11, 4);
    char id[32] = "", job_file[160];
    int jobs_done = 0, last_spp = 0, kills_mid_render = 0, swept = 0;
    double t0 = now_s();
    test_server s;
    for (int k = 0; k <= KILLS; k++) {
        ts_server_start(&s, args);
        if (id[0]) {
            /* What survives a kill is what was checkpointed: job.json's spp_done, which is
             * written after (and taken before) the film it describes, so the film on disk
             * holds at least that. It never goes back, and the restored job starts from at
             * least it. (The live spp_done seen after the previous restart may be ahead of
             * every checkpoint, so it is no bound.) */
            size_t jl = 0;
            char *jt = read_file(job_file, &jl);
            cJSON *jj = jt ? cJSON_ParseWithLength(jt, jl) : NULL;
            if (!jj) fail_msg("job %s: %s unreadable after kill %d", id, job_file, k);
            int durable = (int)ts_json_num(jj, "spp_done");
            cJSON_Delete(jj);
            free(jt);
            if (durable < last_spp)
                fail_msg("job %s: the checkpoint went back from %d to %d spp after kill %d", id, last_spp, durable, k);
            last_spp = durable;
            /* A kill in the middle of a write leaves its temporary file; start-up removed
             * it (once 6 files, 511 MB, after 8 kills). */
            char folder[160];
            snprintf(folder, sizeof folder, "%s/jobs/%s", kill_dir, id);
            /* The restarted server resumes the job at once and may be writing a checkpoint
             * right now: a temporary named with its own pid is a write in flight (a CI run
             * found film.bin.tmp.<new pid>.0 here). Only one of a killed process is debris. */
            const char *left = stale_temporaries(folder, s.pid);
            if (left[0]) fail_msg("after kill %d, temporary files are left: %s", k, left);
            swept += (int)metric(&s, "tessera_checkpoint_temporaries_removed_total");
            int spp = check_consistent(&s, id, SPP, W, H);
            if (spp < durable)
                fail_msg("job %s restarted at %d spp below its checkpoint's %d after kill %d", id, spp, durable, k);
            if (spp == SPP) { /* finished: compare, then a new job */
                ts_image img = get_exr(&s, id);
                assert_same_pixels(&img, &ref, id);
                ts_image_fini(&img);
                jobs_done++;
                id[0] = '\0';
            }
        }
        if (k == KILLS) break;
        if (!id[0]) {
            ts_submit(&s, doc, id, sizeof id);
            last_spp = 0;
            /* An accepted job is on disk before its 201 (it survives a kill at once). */
            snprintf(job_file, sizeof job_file, "%s/jobs/%s/job.json", kill_dir, id);
            assert_true(exists(job_file));
        }
        ts_sleep_ms((int)(ts_pcg32_next(&rng) % 200)); /* the moment: 0–199 ms after start */
        cJSON *o = job_status(&s, id);
        if (!strcmp(ts_json_str(o, "state"), "running")) kills_mid_render++;
        cJSON_Delete(o);
        assert_int_equal(ts_server_stop(&s, SIGKILL), 128 + SIGKILL);
    }
    /* The last one finishes uninterrupted. */
    if (id[0]) {
        cJSON *o = ts_wait_done(&s, id, 30);
        assert_int_equal((int)ts_json_num(o, "spp_done"), SPP);
        assert_int_equal((long)ts_json_num(o, "samples"), (long)W * H * SPP);
        cJSON_Delete(o);
        ts_image img = get_exr(&s, id);
        assert_same_pixels(&img, &ref, id);
        ts_image_fini(&img);
        jobs_done++;
    }
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
    printf("%d kills (%d of them while the job was running), %d jobs finished equal to the uninterrupted render, "
           "%d temporary files removed at start-up, %.1f s\n", KILLS, kills_mid_render, jobs_done, swept, now_s() - t0);
    assert_true(kills_mid_render >= KILLS / 4);
    ts_image_fini(&ref);
    free(doc);
}

static int run_kill(void)
{
    snprintf(kill_dir, sizeof kill_dir, "/tmp/tessera-kill-XXXXXX");
    if (!mkdtemp(kill_dir)) return 1;
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_kill_at_random_moments)};
    int rc = cmocka_run_group_tests_name("kill", tests, NULL, NULL);
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", kill_dir);
    if (system(cmd) != 0 && !rc) rc = 1;
    return rc;
}

/* ================================================================ clients */

static int open_fds(pid_t pid)
{
    char path[64];
    snprintf(path, sizeof path, "/proc/%d/fd", (int)pid);
    DIR *d = opendir(path);
    if (!d) return -1;
    int n = 0;
    while (readdir(d)) n++;
    closedir(d);
    return n - 2;
}

/* Waits until the server holds at most `baseline` descriptors again. */
static void wait_fds(const test_server *s, int baseline, double timeout_s, const char *what)
{
    double t0 = now_s();
    int n = open_fds(s->pid);
    while (n > baseline && now_s() - t0 < timeout_s) {
        ts_sleep_ms(20);
        n = open_fds(s->pid);
    }
    if (n > baseline) fail_msg("%s: the server still holds %d descriptors (baseline %d) after %g s", what, n, baseline, timeout_s);
}

static int connect_to(const test_server *s)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    assert_true(fd >= 0);
    int rcvbuf = 4096; /* a small window: big replies stay in the server's hands */
    setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);
    struct sockaddr_in a = {0};
    a.sin_family = AF_INET;
    a.sin_port = htons((uint16_t)s->port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (connect(fd, (struct sockaddr *)&a, sizeof a) != 0) fail_msg("connect: %s", strerror(errno));
    return fd;
}

static void send_all(int fd, const char *text)
{
    size_t n = strlen(text);
    while (n) {
        ssize_t w = send(fd, text, n, MSG_NOSIGNAL);
        if (w <= 0) fail_msg("send: %s", strerror(errno));
        text += w, n -= (size_t)w;
    }
}

/* Reads until `want` bytes came or timeout; returns how many. */
static size_t recv_some(int fd, size_t want, double timeout_s)
{
    char buf[16384];
    size_t got = 0;
    double t0 = now_s();
    while (got < want && now_s() - t0 < timeout_s) {
        struct pollfd p = {fd, POLLIN, 0};
        if (poll(&p, 1, 100) <= 0) continue;
        ssize_t r = recv(fd, buf, sizeof buf < want - got ? sizeof buf : want - got, 0);
        if (r <= 0) break;
        got += (size_t)r;
    }
    return got;
}

/* True when the server closed fd (EOF or reset) within timeout_s. */
static bool closed_by_server(int fd, double timeout_s)
{
    double t0 = now_s();
    char buf[4096];
    while (now_s() - t0 < timeout_s) {
        struct pollfd p = {fd, POLLIN, 0};
        if (poll(&p, 1, 50) <= 0) continue;
        ssize_t r = recv(fd, buf, sizeof buf, 0);
        if (r == 0 || (r < 0 && errno != EAGAIN && errno != EINTR)) return true;
    }
    return false;
}

/* Whether the server reset fd within timeout_s, seen without reading from it (a client
 * that stopped reading learns of it too): poll reports the error or hang-up. */
static bool reset_by_server(int fd, double timeout_s)
{
    double t0 = now_s();
    while (now_s() - t0 < timeout_s) {
        struct pollfd p = {fd, POLLRDHUP, 0};
        if (poll(&p, 1, 20) > 0 && (p.revents & (POLLERR | POLLHUP))) return true;
    }
    return false;
}

static double healthz_ms(const test_server *s)
{
    double t0 = now_s();
    http_resp r;
    ts_http(s, "GET", "/healthz", NULL, 0, NULL, &r);
    assert_int_equal(r.status, 200);
    ts_http_free(&r);
    return 1e3 * (now_s() - t0);
}

static size_t abort_after(char *data, size_t size, size_t nmemb, void *user)
{
    (void)data;
    size_t *got = user;
    *got += size * nmemb;
    return *got > 8192 ? 0 : size * nmemb; /* 0: curl aborts the transfer */
}

static void test_disconnects(void **state)
{
    (void)state;
    test_server s;
    const char *args[] = {"--threads", "2", "--http-threads", "2", NULL};
    ts_server_start(&s, args);
    /* A big image: 1024×1024, one sample (its EXR is some 300 KB; the raw clients below
     * shrink their receive window to 4 KiB, so the server is mid-send when they leave). */
    char *big = ts_ao_scene("faults", 1024, 1024, 1), *slow = ts_ao_scene("faults", 256, 256, 1 << 14);
    char id[32], sid[32], path[160];
    ts_submit(&s, big, id, sizeof id);
    cJSON_Delete(ts_wait_done(&s, id, 60));
    healthz_ms(&s);
    int baseline = open_fds(s.pid);
    assert_true(baseline > 0);

    /* Mid-download: raw sockets that read 8 KiB and close, and curl aborting. */
    snprintf(path, sizeof path, "GET /api/v1/jobs/%s/image.exr HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n", id);
    for (int i = 0; i < 4; i++) {
        int fd = connect_to(&s);
        send_all(fd, path);
        assert_true(recv_some(fd, 8192, 10) == 8192);
        close(fd);
    }
    for (int i = 0; i < 2; i++) {
        CURL *c = curl_easy_init();
        char url[200];
        size_t got = 0;
        snprintf(url, sizeof url, "%s/api/v1/jobs/%s/image.exr", s.base, id);
        curl_easy_setopt(c, CURLOPT_URL, url);
        curl_easy_setopt(c, CURLOPT_WRITEFUNCTION, abort_after);
        curl_easy_setopt(c, CURLOPT_WRITEDATA, &got);
        assert_int_equal(curl_easy_perform(c), CURLE_WRITE_ERROR);
        curl_easy_cleanup(c);
    }
    wait_fds(&s, baseline, 10, "after aborted downloads");
    assert_true(healthz_ms(&s) < 1000);
    ts_image img = get_exr(&s, id); /* a whole download still works */
    assert_int_equal(img.width, 1024);
    ts_image_fini(&img);

    /* Mid-stream: event streams of a running job read a little and close. */
    ts_submit(&s, slow, sid, sizeof sid);
    ts_wait_field(&s, sid, "spp_done", 1, 20);
    snprintf(path, sizeof path, "GET /api/v1/jobs/%s/events HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n", sid);
    for (int i = 0; i < 6; i++) {
        int fd = connect_to(&s);
        send_all(fd, path);
        assert_true(recv_some(fd, 200, 10) == 200);
        close(fd);
    }
    wait_fds(&s, baseline, 10, "after abandoned event streams");
    assert_true(healthz_ms(&s) < 1000);
    snprintf(path, sizeof path, "/api/v1/jobs/%s/cancel", sid);
    http_resp r;
    ts_http(&s, "POST", path, NULL, 0, NULL, &r);
    assert_int_equal(r.status, 200);
    ts_http_free(&r);
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
    free(big);
    free(slow);
}

static void test_slow_clients(void **state)
{
    (void)state;
    enum { SLOW = 6, LIMIT = 10 };
    test_server s;
    const char *args[] = {"--threads", "1", "--http-threads", "2", "--client-timeout", "2", "--max-client-connections",
                          "10", NULL};
    ts_server_start(&s, args);
    healthz_ms(&s);
    int baseline = open_fds(s.pid);

    /* SLOW clients (three times --http-threads) send a request one byte per second, and an
     * idle one sends half a request line and stops. */
    static const char req[] = "GET /healthz HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n";
    int fds[SLOW], idle = connect_to(&s);
    send_all(idle, "GET /hea");
    for (int i = 0; i < SLOW; i++) fds[i] = connect_to(&s);
    double worst_ms = 0, t0 = now_s();
    bool idle_closed = false;
    double idle_closed_at = 0;
    for (size_t b = 0; b < 5; b++) { /* five seconds, one byte per client per second */
        for (int i = 0; i < SLOW; i++) {
            char one[2] = {req[b], 0};
            send_all(fds[i], one);
        }
        /* Meanwhile a normal client is answered promptly, every 100 ms. */
        for (int k = 0; k < 10; k++) {
            double ms = healthz_ms(&s);
            if (ms > worst_ms) worst_ms = ms;
            if (!idle_closed && closed_by_server(idle, 0.09)) idle_closed = true, idle_closed_at = now_s() - t0;
        }
    }
    /* Slow but not idle: the slow clients are still connected (1 s between bytes < 2 s). */
    for (int i = 0; i < SLOW; i++) assert_false(closed_by_server(fds[i], 0.01));
    printf("%d slow clients at one byte per second, 2 HTTP threads: worst /healthz %.1f ms over 50 requests; "
           "an idle client was dropped after %.2f s (--client-timeout 2)\n",
           SLOW, worst_ms, idle_closed_at);
    /* A thread held by a slow client would delay /healthz by seconds (a byte per second,
     * 34 bytes); 1.5 s leaves room for a loaded CI machine. */
    assert_true(worst_ms < 1500);
    assert_true(idle_closed);
    assert_true(idle_closed_at >= 1.5 && idle_closed_at < 4.5);
    close(idle);

    /* --max-client-connections 10: SLOW are open; fill up to the limit, the next is refused. */
    int extra[LIMIT], n_extra = 0;
    for (int i = SLOW; i < LIMIT; i++) extra[n_extra++] = connect_to(&s);
    ts_sleep_ms(100);
    for (int i = 0; i < n_extra; i++) assert_false(closed_by_server(extra[i], 0.01));
    int refused = connect_to(&s);
    assert_true(closed_by_server(refused, 2));
    close(refused);
    for (int i = 0; i < n_extra; i++) close(extra[i]);
    for (int i = 0; i < SLOW; i++) close(fds[i]);
    wait_fds(&s, baseline, 5, "after the slow clients left");
    assert_true(healthz_ms(&s) < 1000);
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
}

/* Slow-loris: a header trickled a byte every 0.5 s, and a body the same way, each faster
 * than the idle timeout (3 s) resets, are cut at the request deadline (--request-timeout 2;
 * before it existed they stayed open as long as the bytes came). What is not late is not
 * cut: an event stream open past the deadline, and a kept-alive connection's next request
 * (its deadline starts at the previous answer). */
static void test_slow_loris(void **state)
{
    (void)state;
    test_server s;
    const char *args[] = {"--threads", "1", "--client-timeout", "3", "--request-timeout", "2", NULL};
    ts_server_start(&s, args);
    char *doc = ts_ao_scene("loris", 256, 256, 1 << 14), id[32], head[512], body_head[512];
    ts_submit(&s, doc, id, sizeof id);
    ts_wait_field(&s, id, "spp_done", 1, 20);
    snprintf(head, sizeof head, "GET /api/v1/jobs/%s HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Pad: %0200d\r\n\r\n", id, 0);
    snprintf(body_head, sizeof body_head,
             "POST /api/v1/jobs HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\nContent-Length: 100\r\n\r\n");
    int header_fd = connect_to(&s), body_fd = connect_to(&s), stream_fd = subscribe(&s, id);
    send_all(body_fd, body_head);
    double t0 = now_s(), header_cut = 0, body_cut = 0;
    size_t at = 0;
    while (now_s() - t0 < 6 && !(header_cut && body_cut)) {
        char one[2] = {head[at++], 0};
        if (!header_cut) send(header_fd, one, 1, MSG_NOSIGNAL);
        if (!body_cut) send(body_fd, "{", 1, MSG_NOSIGNAL);
        double until = now_s() + 0.5;
        while (now_s() < until) {
            if (!header_cut && closed_by_server(header_fd, 0.02)) header_cut = now_s() - t0;
            if (!body_cut && closed_by_server(body_fd, 0.02)) body_cut = now_s() - t0;
        }
        assert_true(at < strlen(head)); /* the header never completes in this time */
    }
    /* The stream is still open and events still come; the kept-alive connection answers
     * a request now and another a second later (more than the deadline after it opened). */
    char buf[4096];
    assert_true(recv_some(stream_fd, 1, 2) == 1);
    assert_false(closed_by_server(stream_fd, 0.01));
    static const char hz[] = "GET /healthz HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n";
    int keep_fd = connect_to(&s);
    for (int k = 0; k < 3; k++) {
        if (k) ts_sleep_ms(1200);
        send_all(keep_fd, hz);
        assert_int_equal(status_of(keep_fd), 200);
        ts_sleep_ms(50);
        while (recv(keep_fd, buf, sizeof buf, MSG_DONTWAIT) > 0) {} /* the rest of the answer */
    }
    printf("slow-loris at a byte per 0.5 s (--client-timeout 3, --request-timeout 2): header cut after %.2f s, body "
           "after %.2f s; an event stream and a kept-alive connection stayed\n", header_cut, body_cut);
    /* The deadline thread wakes at the earliest deadline; 1.5 s of slack for a loaded
     * machine, and never before the deadline (less the 0.02 s polls). */
    assert_true(header_cut >= 1.9 && header_cut < 3.5);
    assert_true(body_cut >= 1.9 && body_cut < 3.5);
    assert_int_equal((int)metric(&s, "tessera_http_deadline_closed_total"), 2);
    close(header_fd), close(body_fd), close(stream_fd), close(keep_fd);
    char path[160];
    snprintf(path, sizeof path, "/api/v1/jobs/%s/cancel", id);
    http_resp r;
    ts_http(&s, "POST", path, NULL, 0, NULL, &r);
    ts_http_free(&r);
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
    free(doc);
}

static long rss_kib(pid_t pid)
{
    char path[64], line[256];
    snprintf(path, sizeof path, "/proc/%d/status", (int)pid);
    FILE *f = fopen(path, "r");
    long kib = -1;
    while (f && fgets(line, sizeof line, f))
        if (!strncmp(line, "VmRSS:", 6)) kib = atol(line + 6);
    if (f) fclose(f);
    return kib;
}

static double metric(const test_server *s, const char *name)
{
    http_resp r;
    ts_http(s, "GET", "/metrics", NULL, 0, NULL, &r);
    char key[128];
    snprintf(key, sizeof key, "\n%s ", name);
    const char *at = strstr(r.body, key);
    double v = at ? atof(at + strlen(key)) : -1;
    ts_http_free(&r);
    return v;
}

static int subscribe(const test_server *s, const char *id)
{
    char req[256];
    snprintf(req, sizeof req, "GET /api/v1/jobs/%s/events HTTP/1.1\r\nHost: 127.0.0.1:%d\r\n\r\n", id, s->port);
    int fd = connect_to(s);
    send_all(fd, req);
    return fd;
}

/* The status line of what fd received first (waits up to 5 s). */
static int status_of(int fd)
{
    char buf[64] = "";
    double t0 = now_s();
    size_t got = 0;
    while (got < 12 && now_s() - t0 < 5) {
        struct pollfd p = {fd, POLLIN, 0};
        if (poll(&p, 1, 50) <= 0) continue;
        ssize_t r = recv(fd, buf + got, 12 - got, 0);
        if (r <= 0) break;
        got += (size_t)r;
    }
    return got >= 12 ? atoi(buf + 9) : -1;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* 1000 subscribers that never read, to a finished job of 1024 tiles: subscribing costs
 * O(1) and the backlog is pulled only as each socket takes it, so /healthz stays prompt
 * (p99 < 50 ms over 200 requests once the sockets are full) and the server's memory grows
 * by a bounded amount (each stream holds at most SRV_EVENTS_BUFFER_CAP, 256 KiB). Then the
 * caps (503 past --max-job-subscribers and --max-subscribers) and a subscriber that stops
 * reading while events keep coming: dropped, its connection closed. */
static void test_idle_subscribers(void **state)
{
    (void)state;
    enum { SUBS = 1000 };
    struct rlimit rl;
    getrlimit(RLIMIT_NOFILE, &rl);
    if (rl.rlim_cur < SUBS + 200) {
        rl.rlim_cur = rl.rlim_max < SUBS + 200 ? rl.rlim_max : SUBS + 200;
        setrlimit(RLIMIT_NOFILE, &rl); /* the server inherits it */
    }
    if (rl.rlim_cur < SUBS + 200) {
        printf("note: only %lu descriptors may be open: the idle-subscriber case is skipped\n", (unsigned long)rl.rlim_cur);
        skip();
    }
    test_server s;
    const char *args[] = {"--threads", "2", NULL};
    ts_server_start(&s, args);
    char *doc = ts_ao_scene("subscribers", 1024, 1024, 1), id[32];
    ts_submit(&s, doc, id, sizeof id);
    free(doc);
    cJSON_Delete(ts_wait_done(&s, id, 60));
    long rss0 = rss_kib(s.pid);
    int *fds = malloc(sizeof *fds * SUBS);
    for (int i = 0; i < SUBS; i++) fds[i] = subscribe(&s, id);
    ts_sleep_ms(2000); /* the sockets fill up */
    assert_int_equal((int)metric(&s, "tessera_event_streams"), SUBS);
    double ms[200];
    for (int i = 0; i < 200; i++) ms[i] = healthz_ms(&s);
    qsort(ms, 200, sizeof *ms, cmp_double);
    long rss1 = rss_kib(s.pid);
    printf("%d idle subscribers to a finished 1024-tile job: /healthz p50 %.1f ms, p99 %.1f ms; server RSS %ld → %ld MiB\n",
           SUBS, ms[100], ms[197], rss0 >> 10, rss1 >> 10);
    assert_true(ms[197] < 50);
    assert_true(rss1 - rss0 < (long)SUBS * 256 + (64 << 10)); /* KiB: the buffer cap each, and slack */
    for (int i = 0; i < SUBS; i++) close(fds[i]);
    free(fds);
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);

    /* The caps: 2 streams a job, 3 in all. */
    const char *capped[] = {"--threads", "2", "--max-job-subscribers", "2", "--max-subscribers", "3", NULL};
    ts_server_start(&s, capped);
    char a[32], b[32];
    doc = ts_ao_scene("caps", 2048, 512, 1 << 16); /* 1024 tiles: 230 KiB of tile events a pass */
    ts_submit(&s, doc, a, sizeof a);
    ts_submit(&s, doc, b, sizeof b);
    free(doc);
    /* One at a time: requests sent together reach the server's HTTP threads in any order,
     * so which of them finds the cap full would be a race. */
    int fa1 = subscribe(&s, a);
    assert_int_equal(status_of(fa1), 200);
    int fa2 = subscribe(&s, a);
    assert_int_equal(status_of(fa2), 200);
    int fa3 = subscribe(&s, a);
    assert_int_equal(status_of(fa3), 503);
    int fb1 = subscribe(&s, b);
    assert_int_equal(status_of(fb1), 200);
    int fb2 = subscribe(&s, b);
    assert_int_equal(status_of(fb2), 503); /* 3 in all */
    close(fa3), close(fb2);
    /* fa1, fa2 and fb1 never read while both jobs publish a tile event a tile pass: the
     * server drops them once they are SRV_EVENTS_BUFFER_CAP behind (a few passes) and
     * resets their connections at once, without their reading (server/events.c, drop):
     * the streams' places come back while the clients still hold their sockets, and each
     * client's poll reports the reset. Before, the connection ended only when the client
     * read again, and then only after the ~100 KiB still queued in the server's socket had
     * crept through the client's 4 KiB window (ss showed the zero-window probe timer backed
     * off 5 times; 3.5 s seen here, over 10 s once on a loaded machine); a client that
     * never read held its place until the 60 s idle timeout. Taking out the shutdown in drop fails both waits below. The drop and the
     * reset are one step on the server, so what the waits allow is only the scheduling of
     * an HTTP thread and of this process: 10 s is generous on a loaded machine. */
    double t0 = now_s();
    while (metric(&s, "tessera_event_streams_dropped_total") < 3 && now_s() - t0 < 30) ts_sleep_ms(100);
    assert_int_equal((int)metric(&s, "tessera_event_streams_dropped_total"), 3);
    double t_dropped = now_s();
    while (metric(&s, "tessera_event_streams") > 0 && now_s() - t_dropped < 10) ts_sleep_ms(20);
    double t_freed = now_s();
    assert_int_equal((int)metric(&s, "tessera_event_streams"), 0);
    assert_true(reset_by_server(fa1, 10));
    assert_true(reset_by_server(fa2, 10));
    assert_true(reset_by_server(fb1, 10));
    printf("3 subscribers dropped: their streams freed %.3f s and their connections reset %.3f s after the drops "
           "were counted, none of them reading\n",
           t_freed - t_dropped, now_s() - t_dropped);
    close(fa1), close(fa2), close(fb1);
    assert_int_equal(status_of(subscribe(&s, a)), 200); /* places are given back */
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
}

static int run_clients(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_disconnects),
        cmocka_unit_test(test_slow_clients),
        cmocka_unit_test(test_slow_loris),
        cmocka_unit_test(test_idle_subscribers),
    };
    return cmocka_run_group_tests_name("clients", tests, NULL, NULL);
}

/* ================================================================ restore of a damaged --data */

static char restore_dir[64];

/* Everything the status documents of all jobs say, as one string (caller frees). */
static char *all_statuses(const test_server *s)
{
    http_resp r;
    ts_http(s, "GET", "/api/v1/jobs?limit=1000", NULL, 0, NULL, &r);
    assert_int_equal(r.status, 200);
    char *t = strndup(r.body, r.len);
    ts_http_free(&r);
    return t;
}

static void write_bytes(const char *path, const void *bytes, size_t len)
{
    unlink(path);
    int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    assert_true(fd >= 0);
    assert_int_equal(write(fd, bytes, len), (ssize_t)len);
    close(fd);
}

/* Every pixel of the job's image is finite and holds spp samples. */
static void assert_clean_image(const test_server *s, const char *id, int spp)
{
    ts_image img = get_exr(s, id);
    int cc = ts_image_channel(&img, "count");
    for (int i = 0; i < img.width * img.height * img.n_channels; i++)
        if (!isfinite(img.data[i])) fail_msg("job %s: value %d of its image is %g", id, i, img.data[i]);
    for (int i = 0; i < img.width * img.height; i++)
        if (img.data[i * img.n_channels + cc] != (float)spp)
            fail_msg("job %s: pixel %d holds %g samples, not %d", id, i, img.data[i * img.n_channels + cc], spp);
    ts_image_fini(&img);
}

/* Damage of every kind a crash, a full disk or a stranger can leave under --data, in
 * finished jobs' folders: a FIFO as film.bin (once blocked start-up forever), a symbolic
 * link as film.bin, random bytes of the right size with and without the film header (once
 * restored as "done" with non-finite pixels), a missing film.bin and a missing job.json
 * (once "failed"), temporary files of interrupted writes (once never removed), and stray
 * entries under jobs/ (once each held a --max-jobs place). The server starts at once, no
 * finished job becomes failed, each damaged one renders again to a clean image, the
 * temporaries are gone, strays hold no place, the metrics count them, and no status names
 * a path of the server's. */
static void test_restore_damaged(void **state)
{
    (void)state;
    enum { JOBS = 7, W = 40, H = 24, SPP = 8 };
    const char *args[] = {"--threads", "2", "--data", restore_dir, "--checkpoint-interval", "0.1", "--max-jobs", "8", NULL};
    test_server s;
    ts_server_start(&s, args);
    char ids[JOBS][32], dir[JOBS][160], p[300];
    char *doc = ts_ao_scene("restore", W, H, SPP);
    for (int i = 0; i < JOBS; i++) {
        ts_submit(&s, doc, ids[i], sizeof ids[i]);
        cJSON_Delete(ts_wait_done(&s, ids[i], 30));
        snprintf(dir[i], sizeof dir[i], "%s/jobs/%s", restore_dir, ids[i]);
    }
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
    snprintf(p, sizeof p, "%s/film.bin", dir[0]);
    size_t film_len = 0;
    char *film = read_file(p, &film_len);
    assert_true(film && film_len > 200);

    /* 0 stays as it is. 1: a FIFO. 2: a symbolic link to 0's film. 3: random bytes. */
    snprintf(p, sizeof p, "%s/film.bin", dir[1]);
    assert_int_equal(unlink(p), 0);
    assert_int_equal(mkfifo(p, 0644), 0);
    snprintf(p, sizeof p, "%s/film.bin", dir[2]);
    assert_int_equal(unlink(p), 0);
    char target[300];
    snprintf(target, sizeof target, "%s/film.bin", dir[0]);
    assert_int_equal(symlink(target, p), 0);
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 19, 5);
    char *noise = malloc(film_len);
    for (size_t k = 0; k < film_len; k++) noise[k] = (char)(ts_pcg32_next(&rng) & 0xff);
    snprintf(p, sizeof p, "%s/film.bin", dir[3]);
    write_bytes(p, noise, film_len);
    /* 4: random pixels under the film's own header (the first 72 bytes: magic, window,
     * digest), so only the checksum can tell. */
    memcpy(noise, film, 72);
    snprintf(p, sizeof p, "%s/film.bin", dir[4]);
    write_bytes(p, noise, film_len);
    /* 5: film.bin missing. 6: job.json missing. */
    snprintf(p, sizeof p, "%s/film.bin", dir[5]);
    assert_int_equal(unlink(p), 0);
    snprintf(p, sizeof p, "%s/job.json", dir[6]);
    assert_int_equal(unlink(p), 0);
    /* Debris of 8 interrupted writes in 0's folder, and strays: a file, a link, a folder
     * that is no job (a bad name), a job folder where nothing ever landed. */
    for (int k = 0; k < 8; k++) {
        snprintf(p, sizeof p, "%s/film.bin.tmp.%d.%d", dir[0], 4000 + k, k);
        write_bytes(p, film, film_len);
    }
    snprintf(p, sizeof p, "%s/jobs/notes.txt", restore_dir);
    write_bytes(p, "x", 1);
    snprintf(p, sizeof p, "%s/jobs/link", restore_dir);
    assert_int_equal(symlink("/", p), 0);
    snprintf(p, sizeof p, "%s/jobs/not a job", restore_dir);
    assert_int_equal(mkdir(p, 0755), 0);
    snprintf(p, sizeof p, "%s/jobs/0123456789abcdef", restore_dir);
    assert_int_equal(mkdir(p, 0755), 0);
    snprintf(p, sizeof p, "%s/jobs/0123456789abcdef/job.json.tmp.1.0", restore_dir);
    write_bytes(p, "{", 1);

    double t0 = now_s();
    ts_server_start(&s, args); /* fails the test if it does not listen within 10 s */
    printf("restarted on the damaged folder in %.0f ms\n", 1e3 * (now_s() - t0));
    assert_true(temporaries(dir[0])[0] == '\0');
    assert_false(exists(p));
    assert_int_equal((int)metric(&s, "tessera_checkpoint_temporaries_removed_total"), 9);
    assert_int_equal((int)metric(&s, "tessera_checkpoint_stray_entries"), 3);
    assert_int_equal((int)metric(&s, "tessera_checkpoint_damaged_total"), 6);
    assert_true(log_has(&s, "removed 9 temporary file(s)"));
    /* Seven jobs and a free place: the strays hold none (--max-jobs 8). */
    char extra[32];
    ts_submit(&s, doc, extra, sizeof extra);
    cJSON_Delete(ts_wait_done(&s, extra, 30));
    http_resp r;
    ts_http(&s, "POST", "/api/v1/jobs", doc, strlen(doc), NULL, &r);
    assert_int_equal(r.status, 503);
    ts_http_free(&r);

    static const char *const why[JOBS] = {NULL, "is not a regular file", "is a symbolic link", "is not a film checkpoint",
                                          "fails its checksum", "is missing", "job.json is missing"};
    for (int i = 0; i < JOBS; i++) {
        cJSON *o = job_status(&s, ids[i]);
        const char *state = ts_json_str(o, "state");
        if (!strcmp(state, "failed")) fail_msg("job %d (%s) restored as failed: %s", i, ids[i], ts_json_str(o, "error"));
        if (i == 0) {
            assert_string_equal(state, "done");
        } else {
            const cJSON *ce = cJSON_GetObjectItemCaseSensitive(o, "checkpoint_error");
            if (ce && cJSON_IsString(ce) && !strstr(ce->valuestring, why[i]))
                fail_msg("job %d: checkpoint_error '%s' does not say '%s'", i, ce->valuestring, why[i]);
            snprintf(p, sizeof p, "restored job %s (queued): the checkpoint was damaged", ids[i]);
            assert_true(log_has(&s, p));
            assert_true(log_has(&s, why[i]));
        }
        cJSON_Delete(o);
        o = ts_wait_done(&s, ids[i], 30);
        assert_string_equal(ts_json_str(o, "state"), "done");
        assert_int_equal((int)ts_json_num(o, "spp_done"), SPP);
        assert_int_equal((int)ts_json_num(o, "nonfinite_samples"), 0);
        cJSON_Delete(o);
        assert_clean_image(&s, ids[i], SPP);
    }
    char *all = all_statuses(&s);
    if (strstr(all, restore_dir)) fail_msg("a status names the server's folder %s: %s", restore_dir, all);
    free(all);
    /* They were checkpointed again, whole: a third start restores all as done. */
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
    ts_server_start(&s, args);
    assert_int_equal((int)metric(&s, "tessera_checkpoint_damaged_total"), 0);
    for (int i = 0; i < JOBS; i++) {
        cJSON *o = job_status(&s, ids[i]);
        assert_string_equal(ts_json_str(o, "state"), "done");
        cJSON_Delete(o);
    }
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
    free(noise);
    free(film);
    free(doc);
}

static int run_restore(void)
{
    snprintf(restore_dir, sizeof restore_dir, "/tmp/tessera-restore-XXXXXX");
    if (!mkdtemp(restore_dir)) return 1;
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_restore_damaged)};
    int rc = cmocka_run_group_tests_name("restore", tests, NULL, NULL);
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", restore_dir);
    if (system(cmd) != 0 && !rc) rc = 1;
    return rc;
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: test_server_faults checkpoint|kill|clients|restore\n");
        return 2;
    }
    signal(SIGPIPE, SIG_IGN);
    /* One case of the group, e.g. TS_TEST_FILTER=test_idle_subscribers (a flake hunt). */
    if (getenv("TS_TEST_FILTER")) cmocka_set_test_filter(getenv("TS_TEST_FILTER"));
    int rc = 2;
    if (!strcmp(argv[1], "checkpoint")) rc = run_checkpoint(); /* calls curl_global_init after unshare */
    else curl_global_init(CURL_GLOBAL_DEFAULT);
    if (!strcmp(argv[1], "kill")) rc = run_kill();
    else if (!strcmp(argv[1], "clients")) rc = run_clients();
    else if (!strcmp(argv[1], "restore")) rc = run_restore();
    curl_global_cleanup();
    return rc;
}
