/* test_alloc_fault.c — allocation failure injected at every allocation of scene loading
 * and of job creation (docs/security.md, "Parsers under test").
 *
 * Design note: this executable defines malloc, calloc, realloc, free and the aligned
 * allocators itself; glibc lets a program replace them (every library, libc's own strdup,
 * cJSON and C++ operator new included, then calls these), and they forward to glibc's
 * __libc_* implementation. On the armed thread (the one running the operation; render
 * workers and Embree's TBB threads are never armed) they
 *   - count allocation calls and fail the n-th one (NULL and ENOMEM);
 *   - remember every block allocated until it is freed, by whichever thread, so what a
 *     run leaves behind is named by its call site.
 * For n = 1, 2, … the operation is run with the n-th allocation failing until a run makes
 * fewer than n allocations, i.e. succeeds without a fault. Each faulted run must fail with
 * an error sentence (no crash, no abort), leave the live-block count where it was, and
 * the same store must then take the document normally ("the server stays healthy").
 *
 * Covered: every malloc-family call made on the calling thread by tessera's code, cJSON and
 * libc (strdup, stdio). Allocations made from inside Embree or TBB (found by backtrace)
 * are tracked but never failed (Embree does not survive it: see fault()), and blocks
 * they keep are reported, not failed. Not covered: memory obtained with mmap directly. */
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
/* A sanitizer's runtime owns malloc & co., so this test's replacements cannot stand in
 * front of it: the plain build (make test) runs the test, which counts leaks itself. */
#include <stdio.h>

int main(void)
{
    printf("SKIPPED: the allocation-failure test replaces malloc, which the sanitizer owns here\n");
    return 77;
}
#else
#define _GNU_SOURCE /* dl_iterate_phdr */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <dlfcn.h>
#include <errno.h>
#include <execinfo.h>
#include <pthread.h>
#include <link.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "job_store.h"
#include "render/scheduler.h"
#include "scene/scene.h"

/* ---------------------------------------------------------------- the interposer */

extern void *__libc_malloc(size_t n);
extern void *__libc_calloc(size_t n, size_t size);
extern void *__libc_realloc(void *p, size_t n);
extern void __libc_free(void *p);
extern void *__libc_memalign(size_t align, size_t n);
extern void *__libc_valloc(size_t n);
extern void *__libc_pvalloc(size_t n);

#define MAX_SITES 4096

static _Thread_local bool armed;         /* this thread counts (and may fail) allocations */
static _Thread_local long fail_at;       /* 1-based index of the call to fail; 0 = none */
static _Thread_local long calls;         /* allocation calls since arming */
static _Thread_local bool injected;      /* the fault was delivered */
static _Thread_local long embree_calls; /* allocation calls from Embree/TBB (never failed) */
static _Thread_local bool cur_foreign;  /* the allocation under way is Embree's or TBB's */
/* Address ranges of the Embree and TBB libraries (set before any test). */
typedef struct range { uintptr_t lo, hi; } range;
static range foreign[8];
static int n_foreign;
/* Distinct call sites (return addresses) seen while armed: written by the armed thread. */
static void *sites[MAX_SITES];
static int n_sites;

static void *all_sites[MAX_SITES]; /* over every operation of the test */
static int n_all_sites;
static _Thread_local void *fault_site; /* where the delivered fault was */

static void add_site(void **set, int *n, void *ra)
{
    for (int i = 0; i < *n; i++)
        if (set[i] == ra) return;
    if (*n < MAX_SITES) set[(*n)++] = ra;
}

static void note_site(void *ra)
{
    add_site(sites, &n_sites, ra);
    add_site(all_sites, &n_all_sites, ra);
}

/* Is the current allocation made from inside Embree or TBB? (backtrace was initialised
 * in main, so it does not allocate here.) */
static bool from_embree(void)
{
    void *frames[48];
    int n = backtrace(frames, 48);
    for (int i = 0; i < n; i++)
        for (int k = 0; k < n_foreign; k++)
            if ((uintptr_t)frames[i] >= foreign[k].lo && (uintptr_t)frames[i] < foreign[k].hi) return true;
    return false;
}

/* True when this allocation is to fail. Allocations Embree and TBB make are counted as
 * live blocks but never failed: Embree does not survive it (a failure inside its device
 * creation was seen to leak and, some faults later, to corrupt the heap), so what is
 * tested is how tessera's own code handles failures, Embree's error reports included. */
static bool fault(void *ra)
{
    if (!armed) return false;
    armed = false; /* no recursion through backtrace */
    bool foreign_call = from_embree();
    armed = true;
    cur_foreign = foreign_call;
    if (foreign_call) {
        embree_calls++;
        return false;
    }
    calls++;
    note_site(ra);
    if (fail_at && calls == fail_at) {
        injected = true;
        fault_site = ra;
        errno = ENOMEM;
        return true;
    }
    return false;
}

/* Blocks allocated by the armed thread, until freed (by any thread): an open-addressing
 * set of (pointer, call site); 0 = empty slot, 1 = deleted. */
#define TRACK_SLOTS (1u << 17)
typedef struct tracked { uintptr_t p; void *ra; bool foreign; } tracked;
static tracked track[TRACK_SLOTS];
static pthread_mutex_t track_mu = PTHREAD_MUTEX_INITIALIZER;
static long track_live, track_used; /* guarded by track_mu */
static atomic_long track_any;       /* track_live, readable without the lock */

static uint32_t slot_of(uintptr_t p) { return (uint32_t)((p >> 4) * 2654435761u) & (TRACK_SLOTS - 1); }

static void track_add(void *p, void *ra, bool foreign)
{
    pthread_mutex_lock(&track_mu);
    if (track_used < TRACK_SLOTS - 1024) {
        uint32_t i = slot_of((uintptr_t)p);
        while (track[i].p > 1) i = (i + 1) & (TRACK_SLOTS - 1);
        if (track[i].p == 0) track_used++;
        track[i] = (tracked){(uintptr_t)p, ra, foreign};
        track_live++;
        atomic_store(&track_any, track_live);
    }
    pthread_mutex_unlock(&track_mu);
}

static bool track_remove(void *p)
{
    if (!atomic_load_explicit(&track_any, memory_order_relaxed)) return false;
    bool found = false;
    pthread_mutex_lock(&track_mu);
    uint32_t i = slot_of((uintptr_t)p);
    while (track[i].p != 0) {
        if (track[i].p == (uintptr_t)p) {
            track[i].p = 1;
            track_live--;
            atomic_store(&track_any, track_live);
            found = true;
            break;
        }
        i = (i + 1) & (TRACK_SLOTS - 1);
    }
    pthread_mutex_unlock(&track_mu);
    return found;
}

/* Forgets everything tracked (between runs). */
static void track_reset(void)
{
    pthread_mutex_lock(&track_mu);
    memset(track, 0, sizeof track);
    track_live = track_used = 0;
    atomic_store(&track_any, 0);
    pthread_mutex_unlock(&track_mu);
}

/* Blocks of tessera's (not Embree's or TBB's) still tracked, with the call sites of the
 * first few in `sites_out`; *foreign gets how many Embree/TBB blocks remain. Embree keeps
 * a few blocks of its own across scenes now and then (allocator caches), so those are
 * reported, not failed. */
static long track_leaks(char *sites_out, size_t n, long *foreign)
{
    pthread_mutex_lock(&track_mu);
    long live = 0;
    *foreign = 0;
    size_t used = 0;
    sites_out[0] = '\0';
    for (uint32_t i = 0; i < TRACK_SLOTS; i++) {
        if (track[i].p <= 1) continue;
        if (track[i].foreign) {
            ++*foreign;
            continue;
        }
        live++;
        if (used + 64 < n) {
            Dl_info info;
            const char *lib = dladdr(track[i].ra, &info) && info.dli_fname ? strrchr(info.dli_fname, '/') : NULL;
            used += (size_t)snprintf(sites_out + used, n - used, " %p (%s)", track[i].ra, lib ? lib + 1 : "?");
        }
    }
    pthread_mutex_unlock(&track_mu);
    return live;
}

static void *counted(void *p, void *ra)
{
    if (p && armed) track_add(p, ra, cur_foreign);
    return p;
}

void *malloc(size_t n)
{
    if (fault(__builtin_return_address(0))) return NULL;
    return counted(__libc_malloc(n), __builtin_return_address(0));
}

void *calloc(size_t n, size_t size)
{
    if (fault(__builtin_return_address(0))) return NULL;
    return counted(__libc_calloc(n, size), __builtin_return_address(0));
}

void *realloc(void *p, size_t n)
{
    if (!p) {
        if (fault(__builtin_return_address(0))) return NULL;
        return counted(__libc_realloc(NULL, n), __builtin_return_address(0));
    }
    if (n == 0) { /* glibc: frees p */
        track_remove(p);
        __libc_free(p);
        return NULL;
    }
    if (fault(__builtin_return_address(0))) return NULL; /* p stays valid */
    void *q = __libc_realloc(p, n);
    if (q && track_remove(p)) track_add(q, __builtin_return_address(0), cur_foreign);
    else if (q) counted(q, __builtin_return_address(0));
    return q;
}

void free(void *p)
{
    if (!p) return;
    track_remove(p);
    __libc_free(p);
}

void *memalign(size_t align, size_t n)
{
    if (fault(__builtin_return_address(0))) return NULL;
    return counted(__libc_memalign(align, n), __builtin_return_address(0));
}

void *aligned_alloc(size_t align, size_t n)
{
    if (fault(__builtin_return_address(0))) return NULL;
    return counted(__libc_memalign(align, n), __builtin_return_address(0));
}

int posix_memalign(void **out, size_t align, size_t n)
{
    if (align < sizeof(void *) || (align & (align - 1))) return EINVAL;
    if (fault(__builtin_return_address(0))) return ENOMEM;
    void *p = counted(__libc_memalign(align, n), __builtin_return_address(0));
    if (!p) return ENOMEM;
    *out = p;
    return 0;
}

void *valloc(size_t n)
{
    if (fault(__builtin_return_address(0))) return NULL;
    return counted(__libc_valloc(n), __builtin_return_address(0));
}

void *pvalloc(size_t n)
{
    if (fault(__builtin_return_address(0))) return NULL;
    return counted(__libc_pvalloc(n), __builtin_return_address(0));
}

/* The run's fault: inject_every sets it, the operation arms around the code under test. */
static _Thread_local long pending_fail_at;

static void arm(void)
{
    calls = 0;
    injected = false;
    embree_calls = 0;
    fail_at = pending_fail_at;
    armed = true;
}

/* Disarms; returns whether the fault was delivered. */
static bool disarm(void)
{
    armed = false;
    fail_at = 0;
    return injected;
}

/* ---------------------------------------------------------------- the loop */

typedef struct fault_stats {
    long runs;       /* faulted runs (= allocation calls of a clean run) */
    long tolerated;  /* faulted runs that still succeeded (a fallback took over) */
    long embree;     /* allocations Embree/TBB made in the clean run (not failed) */
    long embree_kept; /* runs after which Embree/TBB still held blocks they allocated */
    int sites;       /* distinct call sites of the clean run */
} fault_stats;

/* One attempt: returns TS_OK or the failure (err filled); releases what it made. */
typedef ts_status (*op_fn)(void *arg, ts_error *err);

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* Runs op with allocation n failing for n = 1, 2, … until it runs clean. */
static fault_stats inject_every(const char *what, op_fn op, void *arg)
{
    fault_stats fs = {0};
    ts_error err = {0};
    /* One clean run first: one-time library state (Embree, TBB, stdio) is set up then. */
    pending_fail_at = 0;
    if (op(arg, &err)) fail_msg("%s: fails without a fault: %s", what, err.message);
    disarm();
    double t0 = now_s();
    for (long n = 1;; n++) {
        ts_error_clear(&err);
        track_reset();
        n_sites = 0;
        pending_fail_at = n;
        if (getenv("TS_FAULT_VERBOSE")) fprintf(stderr, "%s: failing allocation %ld\n", what, n);
        ts_status st = op(arg, &err);
        bool hit = disarm();
        char leak_sites[512];
        long foreign = 0, leaked = track_leaks(leak_sites, sizeof leak_sites, &foreign);
        if (foreign) fs.embree_kept++;
        if (leaked)
            fail_msg("%s: with allocation %ld failing (%s): %ld block(s) leaked, allocated at%s", what, n,
                     st ? err.message : "succeeded", leaked, leak_sites);
        if (!hit) {
            if (st) fail_msg("%s: fails without a fault: %s", what, err.message);
            fs.sites = n_sites;
            fs.embree = embree_calls;
            break;
        }
        fs.runs++;
        if (st == TS_OK) {
            fs.tolerated++;
            printf("  allocation %ld (called from %p) failed and the operation still succeeded\n", n, fault_site);
            continue;
        }
        if (!err.message[0]) fail_msg("%s: allocation %ld failed and the error has no message", what, n);
        if (st != TS_ERR_NOMEM && !strstr(err.message, "memory"))
            fail_msg("%s: allocation %ld failed, but the error does not say so: %s (%s)", what, n, err.message,
                     ts_status_name(st));
    }
    printf("%-36s %5ld allocations failed one by one (%ld tolerated), %3d distinct call sites; "
           "%ld more by Embree/TBB not failed (Embree kept blocks after %ld runs); %.2f s\n",
           what, fs.runs, fs.tolerated, fs.sites, fs.embree, fs.embree_kept, now_s() - t0);
    return fs;
}

/* ---------------------------------------------------------------- scene loading */

typedef struct load_arg {
    const char *text;
    size_t len;
    const char *base_dir;
    const char *path; /* load from this file instead */
} load_arg;

static ts_status op_load(void *arg, ts_error *err)
{
    load_arg *a = arg;
    ts_scene *s = NULL;
    arm();
    ts_status st = a->path ? ts_scene_load_file(a->path, NULL, &s, err)
                           : ts_scene_load_text(a->text, a->len, a->base_dir, "t", NULL, &s, err);
    armed = false;
    if (st == TS_OK) {
        if (!s) return ts_error_set(err, TS_ERR_INTERNAL, "no scene returned");
        ts_scene_destroy(s);
    } else if (s) {
        return ts_error_set(err, TS_ERR_INTERNAL, "a scene returned with a failure");
    }
    return st;
}

static char *read_text(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *t = malloc((size_t)n + 1);
    if (t && fread(t, 1, (size_t)n, f) != (size_t)n) {
        free(t);
        t = NULL;
    }
    fclose(f);
    if (t) t[n] = '\0';
    *len = (size_t)n;
    return t;
}

static long total_runs;

static void load_source_file(const char *rel)
{
    const char *src = getenv("TS_SOURCE_DIR");
    if (!src) fail_msg("TS_SOURCE_DIR is not set (run through ctest)");
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", src, rel);
    load_arg a = {0};
    a.text = read_text(path, &a.len);
    if (!a.text) fail_msg("cannot read %s", path);
    fault_stats fs = inject_every(rel, op_load, &a);
    total_runs += fs.runs;
    free((void *)a.text);
}

static void test_scene_examples(void **state)
{
    (void)state;
    static const char *const files[] = {
        "proto/examples/all-materials.json", "proto/examples/all-shapes.json", "proto/examples/lights.json",
        "proto/examples/design-example.json", "scenes/cornell-box.json",       "scenes/veach-mis.json",
    };
    for (size_t i = 0; i < sizeof files / sizeof *files; i++) load_source_file(files[i]);
}

/* A scene file referencing an OBJ and an ASCII PLY mesh beside it. */
static void test_scene_with_mesh_files(void **state)
{
    (void)state;
    char dir[] = "/tmp/tessera-alloc-XXXXXX", path[128];
    assert_non_null(mkdtemp(dir));
    static const char obj[] = "# quad\nv -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                              "vn 0 1 0\nf 1/1/1 3/3/1 2/2/1\nf 1/1/1 4/4/1 3/3/1\n";
    static const char ply[] = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                              "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                              "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    static const char doc[] =
        "{\"tessera\":1,\"camera\":{\"from\":[0,2,6],\"to\":[0,0,0]},\"film\":{\"width\":16,\"height\":16},"
        "\"materials\":{\"m\":{\"type\":\"diffuse\"}},"
        "\"shapes\":[{\"type\":\"mesh\",\"file\":\"quad.obj\",\"material\":\"m\"},"
        "{\"type\":\"mesh\",\"file\":\"tri.ply\",\"material\":\"m\",\"emission\":[1,1,1]}],"
        "\"lights\":[{\"type\":\"point\",\"position\":[0,3,0],\"intensity\":[4,4,4]}]}";
    const char *names[] = {"quad.obj", "tri.ply", "scene.json"};
    const char *texts[] = {obj, ply, doc};
    for (int i = 0; i < 3; i++) {
        snprintf(path, sizeof path, "%s/%s", dir, names[i]);
        FILE *f = fopen(path, "wb");
        assert_non_null(f);
        fputs(texts[i], f);
        fclose(f);
    }
    load_arg a = {0};
    a.path = path; /* scene.json */
    fault_stats fs = inject_every("scene file with OBJ + PLY meshes", op_load, &a);
    total_runs += fs.runs;
    for (int i = 0; i < 3; i++) {
        snprintf(path, sizeof path, "%s/%s", dir, names[i]);
        unlink(path);
    }
    rmdir(dir);
}

/* ---------------------------------------------------------------- job creation */


typedef struct submit_arg {
    const char *text;
    long clean_jobs;   /* jobs rendered to the end */
} submit_arg;

static bool wait_done(srv_job *j, double timeout_s)
{
    double t0 = now_s();
    while (now_s() - t0 < timeout_s) {
        if (ts_job_state_finished(srv_job_state(j))) return true;
        struct timespec t = {0, 1000000L};
        nanosleep(&t, NULL);
    }
    return false;
}

/* A whole server's worth of job state — a store and a one-thread scheduler — is made and
 * torn down around each submission, so that every block the submission allocated must be
 * freed by the end. After a faulted submission the same
 * store takes the same document again and renders it: the fault left it usable. */
static ts_status op_submit(void *arg, ts_error *err)
{
    submit_arg *a = arg;
    struct { ts_scheduler *sched; srv_store *store; } srv = {0};
    srv_store_config sc = {0};
    ts_scene_limits_default(&sc.limits);
    ts_error e2 = {0};
    srv.sched = sc.sched = ts_scheduler_create(1, 2, &e2);
    srv.store = srv.sched ? srv_store_create(&sc) : NULL;
    if (!srv.store) fail_msg("cannot set up a store: %s", e2.message);

    int http = 0;
    arm();
    srv_job *j = srv_store_submit(srv.store, a->text, strlen(a->text), &http, err);
    armed = false; /* the rest of this run is the check, not under test */
    ts_status st = TS_OK;
    if (j) {
        if (http != 201) fail_msg("a job was returned with HTTP status %d", http);
        if (!wait_done(j, 10)) fail_msg("the job did not finish");
        a->clean_jobs++;
    } else {
        st = err->status ? err->status : TS_ERR_INTERNAL;
        if (http != 500) fail_msg("a failed allocation answered HTTP %d (%s), expected 500", http, err->message);
        /* Healthy: the same store takes the document now. */
        j = srv_store_submit(srv.store, a->text, strlen(a->text), &http, &e2);
        if (!j) fail_msg("after a failed allocation the store refuses a job: %s", e2.message);
        if (!wait_done(j, 10)) fail_msg("the job after a failed allocation did not finish");
        if (srv_job_state(j) != TS_JOB_DONE) fail_msg("the job after a failed allocation ended %d", srv_job_state(j));
    }
    srv_job_release(j);
    ts_scheduler_stop(srv.sched);
    srv_store_destroy(srv.store);
    ts_scheduler_destroy(srv.sched);
    return st;
}

static void test_job_creation(void **state)
{
    (void)state;
    /* A small document that still has what job creation handles: a name, a job block, a
     * mesh, an area light (effects), two tiles. */
    submit_arg a = {0};
    a.text = "{\"tessera\":1,\"name\":\"fault\",\"camera\":{\"from\":[0,1,5],\"to\":[0,0.5,0],\"fov\":40},"
             "\"film\":{\"width\":40,\"height\":8,\"filter\":{\"type\":\"box\"}},\"sampler\":{\"spp\":2},"
             "\"integrator\":{\"type\":\"path\",\"max_depth\":2},"
             "\"materials\":{\"w\":{\"type\":\"diffuse\"}},"
             "\"shapes\":[{\"type\":\"sphere\",\"center\":[0,0.5,0],\"radius\":0.5,\"material\":\"w\"},"
             "{\"type\":\"mesh\",\"positions\":[-3,0,-3, 3,0,-3, 3,0,3, -3,0,3],\"indices\":[0,2,1, 0,3,2],"
             "\"material\":\"w\",\"emission\":[0.5,0.5,0.5],\"two_sided\":true}],"
             "\"job\":{\"name\":\"fault job\",\"priority\":3,\"spp\":1}}";
    fault_stats fs = inject_every("job creation (srv_store_submit)", op_submit, &a);
    total_runs += fs.runs;
    assert_true(fs.runs > 50);
    printf("allocation failures injected in all: %ld, at %d distinct call sites (return addresses)\n", total_runs,
           n_all_sites);
}

static int find_foreign(struct dl_phdr_info *info, size_t size, void *data)
{
    (void)size, (void)data;
    if (!strstr(info->dlpi_name, "libembree") && !strstr(info->dlpi_name, "libtbb")) return 0;
    for (int i = 0; i < info->dlpi_phnum && n_foreign < 8; i++) {
        const ElfW(Phdr) *ph = &info->dlpi_phdr[i];
        if (ph->p_type != PT_LOAD || !(ph->p_flags & PF_X)) continue;
        foreign[n_foreign].lo = info->dlpi_addr + ph->p_vaddr;
        foreign[n_foreign].hi = foreign[n_foreign].lo + ph->p_memsz;
        n_foreign++;
    }
    return 0;
}

int main(void)
{
    void *frames[4];
    backtrace(frames, 4); /* loads the unwinder now, not inside malloc */
    dl_iterate_phdr(find_foreign, NULL);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_scene_examples),
        cmocka_unit_test(test_scene_with_mesh_files),
        cmocka_unit_test(test_job_creation),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
#endif /* sanitizers */
