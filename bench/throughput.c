/* throughput.c — samples/s and rays/s of a render against the ceiling of raw Embree on the
 * same rays (docs/design.md §8; how to read the numbers: bench/README.md).
 *
 *   bench_throughput [--integrators LIST] [--threads N] [--reps R] [--seconds S]
 *                    [--max-rays N] [--header] [--packets] SCENE...
 *
 * For every scene and integrator (LIST: comma-separated `scene`, `ao`, `path`, `direct`,
 * `normals`; `scene` is the scene's own integrator, or `ao` while that is not available
 * in this build; duplicates after resolving are dropped) it prints CSV rows, one per
 * thread count (1 and N, N = all online CPUs by default):
 *
 *   1. Calibration: a 1-spp render at 1 thread (also warms caches) sets the sample count
 *      so a 1-thread render takes about S seconds (default 2), at most the scene's spp.
 *   2. Ray log: one more render at 1 thread with the accel's ray log on (accel.h) records
 *      every ray the integrator asks Embree about, in query order (nearest-hit and
 *      occlusion queries), up to --max-rays (default 2^21) rays.
 *   3. R repetitions (default 3), each measuring side by side, at 1 and at N threads
 *      (render, then the two replays, seconds apart, so load changes hit all three):
 *        render  — ts_render of the whole film, the CLI's code path;
 *        accel   — our ts_accel_intersect / ts_accel_occluded on the logged rays (Embree
 *                  plus our triangle filter, user geometry and the hit's
 *                  interaction);
 *        embree  — rtcIntersect1 / rtcOccluded1 on the logged rays, on a plain Embree
 *                  scene of the same geometry and build settings: triangles without
 *                  filter functions, analytic shapes as user geometry calling
 *                  ts_shape_intersect (Embree has no exact equivalent; their cost is
 *                  counted in the ceiling). The ceiling.
 *      Rays are split into contiguous chunks, one per thread, so each thread sees the
 *      render's ray order. Each repetition's ratios are taken within the repetition;
 *      the row reports medians.
 *   Peak memory is getrusage's ru_maxrss after one render at N threads and before the ray
 *   log is allocated, so it is the render's (this process holds one scene and one film).
 *
 * Columns: scene, integrator, threads, spp, width, height, samples, rays, rays_per_sample,
 * render_s, samples_per_s, rays_per_s, accel_rays_per_s, embree_rays_per_s, efficiency
 * (render rays/s ÷ embree rays/s), accel_efficiency (accel ÷ embree), peak_rss_mib,
 * logged_rays, reps, scaling (samples/s at this thread count ÷ at 1 thread, per repetition,
 * median). Rates are per second of wall time over all threads.
 *
 * --packets adds one row a scene and integrator, `packets,scene,integrator,camera_rays,
 * camera_share,x8,x16,saved8,saved16`: the logged camera rays (render order) replayed on
 * the plain scene at 1 thread singly and as Embree packets of 8 and 16 in each
 * repetition; camera_share is their single-ray time ÷ the whole log's, x8/x16 the packets'
 * speed-up on them, saved8/saved16 the fraction of the 1-thread render's time the packets
 * would save (time saved per camera ray × the render's camera rays ÷ its time); medians.
 * It measures what camera-ray packets could buy (docs/performance.md).
 *
 * Exit status 0, 1 when a scene fails to load or render, 2 on usage errors. */
#include <embree3/rtcore.h>
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include "geometry/accel.h"
#include "integrators/integrator.h"
#include "render/render.h"
#include "scene/scene.h"
#include "load/scene_load.h"
#include "bench_util.h"

#define MAX_REPS        15
#define MAX_INTEGRATORS 8

typedef struct options {
    const char *integrators;
    int threads, reps;
    double seconds;
    size_t max_rays;
    int header;
    int packets; /* --packets: the camera rays' packet replay (below) */
} options;

/* ---------------------------------------------------------------- the plain Embree scene */

typedef struct plain_scene {
    RTCDevice device;
    RTCScene scene;
} plain_scene;

static void plain_bounds(const struct RTCBoundsFunctionArguments *args)
{
    ts_bounds3 b = ts_shape_bounds(args->geometryUserPtr);
    struct RTCBounds *o = args->bounds_o;
    o->lower_x = b.lo.x, o->lower_y = b.lo.y, o->lower_z = b.lo.z;
    o->upper_x = b.hi.x, o->upper_y = b.hi.y, o->upper_z = b.hi.z;
}

/* Ray i of a struct-of-arrays packet of N (Embree's RTCRayN layout). */
static ts_ray packet_ray(const float *rn, unsigned N, unsigned i)
{
    return ts_ray_make((ts_vec3){rn[0 * N + i], rn[1 * N + i], rn[2 * N + i]},
                       (ts_vec3){rn[4 * N + i], rn[5 * N + i], rn[6 * N + i]}, rn[8 * N + i]);
}

static void plain_intersect(const struct RTCIntersectFunctionNArguments *args)
{
    float *rh = (float *)args->rayhit;
    unsigned *uh = (unsigned *)args->rayhit, N = args->N;
    for (unsigned i = 0; i < N; i++) {
        if (!args->valid[i]) continue;
        ts_ray r = packet_ray(rh, N, i);
        float t;
        if (!ts_shape_intersect(args->geometryUserPtr, &r, r.tmax, &t)) continue;
        rh[8 * N + i] = t;
        uh[17 * N + i] = args->primID;
        uh[18 * N + i] = args->geomID;
    }
}

static void plain_occluded(const struct RTCOccludedFunctionNArguments *args)
{
    float *rn = (float *)args->ray;
    unsigned N = args->N;
    for (unsigned i = 0; i < N; i++) {
        if (!args->valid[i]) continue;
        ts_ray r = packet_ray(rn, N, i);
        float t;
        if (ts_shape_intersect(args->geometryUserPtr, &r, r.tmax, &t)) rn[8 * N + i] = -INFINITY;
    }
}

/* The scene's geometry with accel.c's build settings (robust, high quality), no filters. */
static int plain_build(const ts_scene *s, plain_scene *p)
{
    p->device = rtcNewDevice(NULL);
    if (!p->device) return -1;
    p->scene = rtcNewScene(p->device);
    rtcSetSceneFlags(p->scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(p->scene, RTC_BUILD_QUALITY_HIGH);
    for (uint32_t i = 0; i < s->n_shapes; i++) {
        const ts_shape *sh = &s->shapes[i];
        RTCGeometry g;
        if (sh->type == TS_SHAPE_CURVE) continue; /* not replayed: Embree curves need accel.c's filters */
        if (sh->type == TS_SHAPE_MESH) {
            const ts_mesh *m = &sh->mesh;
            if (m->n_triangles == 0 || m->n_vertices == 0) continue;
            g = rtcNewGeometry(p->device, RTC_GEOMETRY_TYPE_TRIANGLE);
            float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                               3 * sizeof(float), m->n_vertices);
            if (!v) return -1;
            memcpy(v, m->p, (size_t)m->n_vertices * 3 * sizeof(float));
            rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, m->index, 0,
                                       3 * sizeof(uint32_t), m->n_triangles);
        } else {
            g = rtcNewGeometry(p->device, RTC_GEOMETRY_TYPE_USER);
            rtcSetGeometryUserPrimitiveCount(g, 1);
            rtcSetGeometryBoundsFunction(g, plain_bounds, NULL);
            rtcSetGeometryIntersectFunction(g, plain_intersect);
            rtcSetGeometryOccludedFunction(g, plain_occluded);
        }
        rtcSetGeometryUserData(g, (void *)sh);
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(p->scene, g, i);
        rtcReleaseGeometry(g);
    }
    rtcCommitScene(p->scene);
    return rtcGetDeviceError(p->device) == RTC_ERROR_NONE ? 0 : -1;
}

static void plain_destroy(plain_scene *p)
{
    if (p->scene) rtcReleaseScene(p->scene);
    if (p->device) rtcReleaseDevice(p->device);
}

/* ---------------------------------------------------------------- replays */

typedef enum replay_kind { REPLAY_ACCEL, REPLAY_EMBREE } replay_kind;

typedef struct replay_job {
    replay_kind kind;
    const ts_accel *accel;
    RTCScene plain;
    const ts_ray *rays;
    const uint8_t *kinds;
    size_t begin, end;
    uint64_t hits; /* result, so no query can be optimised away */
} replay_job;

static void *replay_worker(void *arg)
{
    replay_job *j = arg;
    uint64_t hits = 0;
    for (size_t i = j->begin; i < j->end; i++) {
        const ts_ray *ray = &j->rays[i];
        bool occl = j->kinds[i] == TS_RAY_LOG_OCCLUDED;
        if (j->kind == REPLAY_ACCEL) {
            ts_interaction si;
            hits += occl ? ts_accel_occluded(j->accel, ray) : ts_accel_intersect(j->accel, ray, &si);
            continue;
        }
        struct RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        struct RTCRayHit rh;
        rh.ray.org_x = ray->o.x, rh.ray.org_y = ray->o.y, rh.ray.org_z = ray->o.z;
        rh.ray.dir_x = ray->d.x, rh.ray.dir_y = ray->d.y, rh.ray.dir_z = ray->d.z;
        rh.ray.tnear = 0, rh.ray.tfar = ray->tmax, rh.ray.time = 0;
        rh.ray.mask = 0xffffffffu, rh.ray.id = 0, rh.ray.flags = 0;
        if (occl) {
            rtcOccluded1(j->plain, &ctx, &rh.ray);
            hits += rh.ray.tfar == -INFINITY;
        } else {
            rh.hit.geomID = rh.hit.primID = rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
            rtcIntersect1(j->plain, &ctx, &rh);
            hits += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
        }
    }
    j->hits = hits;
    return NULL;
}

/* Replays rays [0, n) on `threads` threads; returns seconds (negative on failure). */
static double replay(replay_kind kind, const ts_accel *accel, RTCScene plain, const ts_ray_log *log, size_t n,
                     int threads, uint64_t *hits)
{
    replay_job jobs[64];
    pthread_t th[64];
    if (threads > 64) threads = 64;
    for (int t = 0; t < threads; t++)
        jobs[t] = (replay_job){kind,
                               accel,
                               plain,
                               log->rays,
                               log->kinds,
                               n * (size_t)t / (size_t)threads,
                               n * (size_t)(t + 1) / (size_t)threads,
                               0};
    double t0 = ts_now_seconds();
    int started = 0;
    for (int t = 1; t < threads; t++, started++)
        if (pthread_create(&th[t], NULL, replay_worker, &jobs[t]) != 0) return -1;
    replay_worker(&jobs[0]);
    for (int t = 1; t <= started; t++)
        pthread_join(th[t], NULL);
    double dt = ts_now_seconds() - t0;
    *hits = 0;
    for (int t = 0; t < threads; t++)
        *hits += jobs[t].hits;
    return dt;
}


/* ---------------------------------------------------------------- camera-ray packets */

/* The logged camera rays (nearest-hit queries without skip ids from the first logged
 * ray's origin: a pinhole camera's; in render order, so 8 or 16 consecutive ones are one
 * pixel's samples or neighbours — as coherent as a tile's packets can be) replayed on the
 * plain scene one at a time (rtcIntersect1) and as packets of 8 and 16 (rtcIntersect8/16,
 * the last one padded with invalid lanes). Returns the three times in seconds and the
 * count, or -1 when there are no camera rays. */
typedef struct packet_times {
    size_t n;
    double t1, t8, t16;
    uint64_t h1, h8, h16; /* hits, so no query is optimised away (and the three agree) */
} packet_times;

static int replay_packets(RTCScene plain, const ts_ray_log *log, size_t n, packet_times *out)
{
    ts_ray *cam = malloc(sizeof *cam * (n ? n : 1));
    if (!cam || n == 0) {
        free(cam);
        return -1;
    }
    ts_vec3 o = log->rays[0].o;
    size_t m = 0;
    for (size_t i = 0; i < n; i++) {
        const ts_ray *r = &log->rays[i];
        if (log->kinds[i] == TS_RAY_LOG_INTERSECT && r->skip_shape == TS_NONE && r->o.x == o.x && r->o.y == o.y &&
            r->o.z == o.z)
            cam[m++] = *r;
    }
    if (m == 0) {
        free(cam);
        return -1;
    }
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    out->n = m;
    uint64_t h = 0;
    double t0 = ts_now_seconds();
    for (size_t i = 0; i < m; i++) {
        struct RTCRayHit rh;
        rh.ray.org_x = cam[i].o.x, rh.ray.org_y = cam[i].o.y, rh.ray.org_z = cam[i].o.z;
        rh.ray.dir_x = cam[i].d.x, rh.ray.dir_y = cam[i].d.y, rh.ray.dir_z = cam[i].d.z;
        rh.ray.tnear = 0, rh.ray.tfar = cam[i].tmax, rh.ray.time = 0;
        rh.ray.mask = 0xffffffffu, rh.ray.id = 0, rh.ray.flags = 0;
        rh.hit.geomID = rh.hit.primID = rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(plain, &ctx, &rh);
        h += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
    }
    out->t1 = ts_now_seconds() - t0;
    out->h1 = h;
    for (int w = 8; w <= 16; w += 8) {
        _Alignas(64) struct RTCRayHit16 rh; /* the 8-wide packet uses its first 8 lanes' layout */
        _Alignas(64) int valid[16];
        h = 0;
        t0 = ts_now_seconds();
        for (size_t i = 0; i < m; i += (size_t)w) {
            float *f = (float *)&rh;
            unsigned *u = (unsigned *)&rh;
            for (int k = 0; k < w; k++) {
                const ts_ray *r = &cam[i + (size_t)k < m ? i + (size_t)k : m - 1];
                valid[k] = i + (size_t)k < m ? -1 : 0;
                f[0 * w + k] = r->o.x, f[1 * w + k] = r->o.y, f[2 * w + k] = r->o.z, f[3 * w + k] = 0;
                f[4 * w + k] = r->d.x, f[5 * w + k] = r->d.y, f[6 * w + k] = r->d.z, f[7 * w + k] = 0;
                f[8 * w + k] = r->tmax;
                u[9 * w + k] = 0xffffffffu, u[10 * w + k] = 0, u[11 * w + k] = 0;
                u[17 * w + k] = u[18 * w + k] = u[19 * w + k] = RTC_INVALID_GEOMETRY_ID;
            }
            if (w == 8) rtcIntersect8(valid, plain, &ctx, (struct RTCRayHit8 *)&rh);
            else rtcIntersect16(valid, plain, &ctx, &rh);
            for (int k = 0; k < w; k++) h += valid[k] && u[18 * w + k] != RTC_INVALID_GEOMETRY_ID;
        }
        if (w == 8) out->t8 = ts_now_seconds() - t0, out->h8 = h;
        else out->t16 = ts_now_seconds() - t0, out->h16 = h;
    }
    free(cam);
    return 0;
}

/* ---------------------------------------------------------------- renders */

typedef struct render_result {
    double seconds;
    uint64_t samples, rays;
} render_result;

static int render(const ts_scene *s, ts_integrator_type integ, uint32_t spp, int threads, render_result *out,
                  ts_error *err)
{
    ts_film *film = ts_film_create(s->width, s->height, s->crop_x0, s->crop_y0, s->crop_x1 - s->crop_x0,
                                   s->crop_y1 - s->crop_y0, err);
    if (!film) return -1;
    ts_render_request req = {.scene = s,
                             .integrator = integ,
                             .film = film,
                             .sample_begin = 0,
                             .sample_end = spp,
                             .threads = threads};
    ts_render_stats stats = {0};
    ts_status st = ts_render(&req, &stats, err);
    ts_film_destroy(film);
    if (st != TS_OK) return -1;
    out->seconds = stats.seconds;
    out->samples = stats.counters.samples;
    out->rays = stats.counters.camera_rays + stats.counters.other_rays;
    return 0;
}

/* ---------------------------------------------------------------- one scene */

static const char *integrator_name(ts_integrator_type t) { return ts_integrator_name(t); }

static int bench_integrator(const char *path, ts_scene *s, ts_integrator_type integ, const options *o)
{
    ts_error err = {0};
    render_result cal;
    if (render(s, integ, 1, 1, &cal, &err) != 0) goto fail;
    double per_spp_1t = fmax(cal.seconds, 1e-6);
    double want = ceil(o->seconds / per_spp_1t);
    uint32_t spp = want < 1 ? 1 : (want > s->spp ? s->spp : (uint32_t)want);
    double rays_per_sample = cal.samples ? (double)cal.rays / (double)cal.samples : 1;

    int threads[2] = {1, o->threads}, n_cfg = o->threads > 1 ? 2 : 1;
    double r_samples[2][MAX_REPS], r_rays[2][MAX_REPS], r_accel[2][MAX_REPS], r_embree[2][MAX_REPS];
    double r_eff[2][MAX_REPS], r_aeff[2][MAX_REPS], r_secs[2][MAX_REPS];
    double p_share[MAX_REPS], p_gain8[MAX_REPS], p_gain16[MAX_REPS], p_x8[MAX_REPS], p_x16[MAX_REPS];
    double p_render[MAX_REPS];
    size_t p_n = 0;
    render_result rr = {0};

    /* One render at all threads before the ray log exists: the peak memory is the
     * render's (more repetitions do not raise it), not the log's. */
    if (render(s, integ, spp, o->threads, &rr, &err) != 0) goto fail;
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    double peak_mib = (double)ru.ru_maxrss / 1024.0;

    /* The ray log: one render at 1 thread, at most max_rays rays. */
    uint64_t pixels = (uint64_t)(s->crop_x1 - s->crop_x0) * (uint64_t)(s->crop_y1 - s->crop_y0);
    double spp_log = floor((double)o->max_rays / fmax(rays_per_sample * (double)pixels, 1));
    uint32_t spp_rec = spp_log < 1 ? 1 : (spp_log > spp ? spp : (uint32_t)spp_log);
    ts_ray_log log = {0};
    log.capacity = o->max_rays;
    log.rays = malloc(sizeof *log.rays * log.capacity);
    log.kinds = malloc(log.capacity);
    if (!log.rays || !log.kinds) {
        fprintf(stderr, "bench_throughput: out of memory for %zu logged rays\n", log.capacity);
        free(log.rays);
        free(log.kinds);
        return -1;
    }
    atomic_init(&log.n, 0);
    ts_accel_set_ray_log(s->accel, &log);
    int rc = render(s, integ, spp_rec, 1, &rr, &err);
    ts_accel_set_ray_log(s->accel, NULL);
    size_t n_logged = atomic_load(&log.n);
    size_t n = n_logged < log.capacity ? n_logged : log.capacity;
    plain_scene plain = {0};
    if (rc != 0 || plain_build(s, &plain) != 0 || n == 0) {
        if (rc == 0)
            snprintf(err.message, sizeof err.message, "cannot build the plain Embree scene or no rays");
        plain_destroy(&plain);
        free(log.rays);
        free(log.kinds);
        goto fail;
    }
    /* Every query the integrator counts reaches the accel once: a mismatch would mean the
     * counters or the log miss rays. */
    if (n_logged != rr.rays)
        fprintf(stderr, "bench_throughput: note: %s: %zu rays logged, %llu counted by the integrator\n", path,
                n_logged, (unsigned long long)rr.rays);

    /* Side by side: each repetition renders, then replays the log through our accel and
     * through plain Embree, at one thread count, within a few seconds of each other. */
    for (int k = 0; k < o->reps; k++)
        for (int c = 0; c < n_cfg; c++) {
            render_result rk;
            if (render(s, integ, spp, threads[c], &rk, &err) != 0) {
                plain_destroy(&plain);
                free(log.rays);
                free(log.kinds);
                goto fail;
            }
            r_secs[c][k] = rk.seconds;
            r_samples[c][k] = (double)rk.samples / rk.seconds;
            r_rays[c][k] = (double)rk.rays / rk.seconds;
            uint64_t h_accel, h_embree;
            double ta = replay(REPLAY_ACCEL, s->accel, NULL, &log, n, threads[c], &h_accel);
            double te = replay(REPLAY_EMBREE, NULL, plain.scene, &log, n, threads[c], &h_embree);
            r_accel[c][k] = (double)n / ta;
            r_embree[c][k] = (double)n / te;
            r_eff[c][k] = r_rays[c][k] / r_embree[c][k];
            r_aeff[c][k] = r_accel[c][k] / r_embree[c][k];
            /* Camera rays in packets, at 1 thread, beside this repetition's render and
             * replays: their share of the single-ray Embree time of the log, the packets'
             * speed-up on them, and what that would save of the render's time (the render
             * makes rk.samples camera rays, the log p.n of them). */
            packet_times p = {0};
            if (o->packets && c == 0 && replay_packets(plain.scene, &log, n, &p) == 0) {
                double per1 = p.t1 / (double)p.n, per8 = p.t8 / (double)p.n, per16 = p.t16 / (double)p.n;
                p_n = p.n;
                p_share[k] = p.t1 / te;
                p_x8[k] = p.t1 / p.t8;
                p_x16[k] = p.t1 / p.t16;
                p_gain8[k] = (per1 - per8) * (double)rk.samples / rk.seconds;
                p_gain16[k] = (per1 - per16) * (double)rk.samples / rk.seconds;
                p_render[k] = rk.seconds;
                if (p.h1 != p.h8 || p.h1 != p.h16)
                    fprintf(stderr, "bench_throughput: note: camera-ray hits %llu / %llu / %llu (1 / 8 / 16)\n",
                            (unsigned long long)p.h1, (unsigned long long)p.h8, (unsigned long long)p.h16);
            }
        }
    plain_destroy(&plain);
    free(log.rays);
    free(log.kinds);

    const char *name = strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
    for (int c = 0; c < n_cfg; c++) {
        double secs = median(r_secs[c], o->reps), sps = median(r_samples[c], o->reps);
        double rps = median(r_rays[c], o->reps);
        /* Thread scaling: samples/s at this count ÷ at 1 thread, within each repetition. */
        double scale[MAX_REPS];
        for (int k = 0; k < o->reps; k++) scale[k] = r_samples[c][k] / r_samples[0][k];
        printf("%s,%s,%d,%u,%d,%d,%llu,%llu,%.3f,%.3f,%.0f,%.0f,%.0f,%.0f,%.3f,%.3f,%.1f,%zu,%d,%.3f\n", name,
               integrator_name(integ), threads[c], spp, s->crop_x1 - s->crop_x0, s->crop_y1 - s->crop_y0,
               (unsigned long long)pixels * spp, (unsigned long long)llround(rps * secs), rps / sps, secs,
               sps, rps, median(r_accel[c], o->reps), median(r_embree[c], o->reps), median(r_eff[c], o->reps),
               median(r_aeff[c], o->reps), peak_mib, n, o->reps, median(scale, o->reps));
    }
    /* packets,scene,integrator,camera_rays,camera share of the log's Embree time, packet
     * speed-up ×8, ×16 on camera rays, fraction of the render's time they would save. */
    if (o->packets && p_n > 0)
        printf("packets,%s,%s,%zu,%.3f,%.2f,%.2f,%.4f,%.4f\n", name, integrator_name(integ), p_n,
               median(p_share, o->reps), median(p_x8, o->reps), median(p_x16, o->reps), median(p_gain8, o->reps),
               median(p_gain16, o->reps));
    (void)p_render;
    fflush(stdout);
    return 0;

fail:
    fprintf(stderr, "bench_throughput: %s (%s): %s\n", path, integrator_name(integ), err.message);
    return -1;
}

/* ---------------------------------------------------------------- main */

static int parse_integrator(const char *name, size_t len, const ts_scene *s, ts_integrator_type *out)
{
    static const struct {
        const char *name;
        ts_integrator_type type;
    } names[] = {{"path", TS_INTEGRATOR_PATH},
                 {"direct", TS_INTEGRATOR_DIRECT},
                 {"ao", TS_INTEGRATOR_AO},
                 {"normals", TS_INTEGRATOR_NORMALS}};
    if (len == 5 && strncmp(name, "scene", 5) == 0) {
        *out = s->integrator.type;
        return 0;
    }
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        if (strlen(names[i].name) == len && strncmp(name, names[i].name, len) == 0) {
            *out = names[i].type;
            return 0;
        }
    return -1;
}

enum { CHILD_SKIPPED = 3, CHILD_END = 4, CHILD_LOAD_FAILED = 5 };

/* Child process: entry j of the integrator list on scene `path`. Exit status 0 (done), 1
 * (failed), 2 (bad list), CHILD_SKIPPED (the same integrator as an earlier entry), CHILD_END (no entry j), CHILD_LOAD_FAILED. */
static int run_child(const char *path, int j, const options *o)
{
    ts_scene *s = NULL;
    ts_error err = {0};
    if (ts_scene_load_path(path, NULL, NULL, NULL, &s, &err) != TS_OK) {
        fprintf(stderr, "bench_throughput: %s: %s\n", path, err.message);
        return CHILD_LOAD_FAILED;
    }
    ts_integrator_type types[MAX_INTEGRATORS];
    int k = 0, rc = CHILD_END;
    for (const char *p = o->integrators; *p && k <= j && k < MAX_INTEGRATORS; k++) {
        const char *name = p;
        size_t len = strcspn(p, ",");
        int r = parse_integrator(name, len, s, &types[k]);
        p += len + (p[len] == ',');
        if (r < 0) {
            fprintf(stderr, "bench_throughput: --integrators: unknown name '%.*s'\n", (int)len, name);
            rc = 2;
            break;
        }
        if (k < j) continue;
        rc = 0;
        for (int m = 0; m < k && rc == 0; m++)
            if (types[m] == types[k]) rc = CHILD_SKIPPED;
        if (rc == 0) rc = bench_integrator(path, s, types[k], o) == 0 ? 0 : 1;
    }
    ts_scene_destroy(s);
    fflush(stdout);
    return rc;
}

static int usage(const char *msg)
{
    fprintf(stderr,
            "bench_throughput: %s\nusage: bench_throughput [--integrators scene,ao] [--threads N] [--reps R] "
            "[--seconds S] [--max-rays N] [--header] [--packets] SCENE.json...\n",
            msg);
    return 2;
}

int main(int argc, char **argv)
{
    long ncpu = sysconf(_SC_NPROCESSORS_ONLN);
    options o = {"scene,ao", ncpu > 0 ? (int)ncpu : 1, 3, 2.0, (size_t)1 << 21, 0, 0};
    int first = 1;
    for (; first < argc && strncmp(argv[first], "--", 2) == 0; first++) {
        const char *a = argv[first], *v = first + 1 < argc ? argv[first + 1] : NULL;
        if (strcmp(a, "--header") == 0) {
            o.header = 1;
            continue;
        }
        if (strcmp(a, "--packets") == 0) {
            o.packets = 1;
            continue;
        }
        if (!v) return usage("missing value");
        first++;
        char *end;
        errno = 0;
        if (strcmp(a, "--integrators") == 0)
            o.integrators = v;
        else if (strcmp(a, "--threads") == 0)
            o.threads = (int)strtol(v, &end, 10);
        else if (strcmp(a, "--reps") == 0)
            o.reps = (int)strtol(v, &end, 10);
        else if (strcmp(a, "--seconds") == 0)
            o.seconds = strtod(v, &end);
        else if (strcmp(a, "--max-rays") == 0)
            o.max_rays = (size_t)strtoull(v, &end, 10);
        else
            return usage("unknown option");
    }
    if (o.threads < 1 || o.threads > 64 || o.reps < 1 || o.reps > MAX_REPS || !(o.seconds > 0) ||
        o.max_rays < 1)
        return usage("--threads 1..64, --reps 1..15, --seconds > 0, --max-rays ≥ 1");
    if (o.header)
        printf(
            "scene,integrator,threads,spp,width,height,samples,rays,rays_per_sample,render_s,samples_per_s,"
            "rays_per_s,accel_rays_per_s,embree_rays_per_s,efficiency,accel_efficiency,peak_rss_mib,"
            "logged_rays,reps,scaling\n");
    /* One child process per (scene, integrator): each loads its scene afresh, so its peak
     * memory is its own, and no Embree thread pool is ever forked. */
    int status = 0;
    fflush(stdout);
    for (int i = first; i < argc; i++)
        for (int j = 0;; j++) {
            pid_t pid = fork();
            if (pid < 0) {
                perror("bench_throughput: fork");
                return 1;
            }
            if (pid == 0) _exit(run_child(argv[i], j, &o));
            int ws;
            while (waitpid(pid, &ws, 0) < 0 && errno == EINTR)
                continue;
            int code = WIFEXITED(ws) ? WEXITSTATUS(ws) : 1;
            if (code == CHILD_END) break;
            if (code == CHILD_LOAD_FAILED) {
                status = 1;
                break;
            }
            if (code == 2) return 2;
            if (code != 0 && code != CHILD_SKIPPED) status = 1;
        }
    return status;
}
