/* accel.c — the scene's Embree 3 scene; see accel.h.
 *
 * Design note. One RTCDevice and one RTCScene per ts_accel, built once with
 * RTC_SCENE_FLAG_ROBUST and high build quality; shape i is geometry ID i. Meshes are
 * native triangles: the index buffer is shared with the scene (validated by the loader),
 * the vertex buffer copied into an Embree-allocated one, which Embree pads for its 16-byte
 * loads. Spheres, disks and cylinders are user geometry with one primitive whose
 * callbacks call ts_shape_intersect, so analytic hits are exact and conservative.
 *
 * Rays leaving a mesh carry its (shape, prim) ids. They reach the triangle filter
 * functions through an RTCIntersectContext extended with the ray (Embree hands the
 * caller's context pointer to every callback): the filter rejects the ray's own triangle
 * and any triangle the ray does not cross at a t that double precision can tell from 0
 * (ts_shape_triangle_ahead) — Embree's float triangle test can report the coplanar
 * neighbour of the triangle a ray leaves. Rays without skip ids cost the filter one test.
 *
 * Each mesh triangle has a ts_tri_cache (shape.h: its normal, edge lengths, ∂p/∂u, ∂p/∂v),
 * made at build time, 72 bytes a triangle; the filter and the hit's interaction read it
 * instead of recomputing those per hit, with bit-identical results.
 *
 * Embree errors during the build are caught by the device error callback into the
 * accel's (build-time only) message and returned as a ts_error sentence. Queries are
 * thread-safe (the scene is immutable after rtcCommitScene, the context lives on the
 * caller's stack) and allocate nothing.
 *
 * Benchmarks may attach a ray log (accel.h): the one field set after the build, only
 * between renders. When it is NULL a query tests it and goes on (the logging itself is a
 * separate cold function). */
#include "geometry/accel.h"

#include <embree3/rtcore.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Under ThreadSanitizer Embree builds on the calling thread. Embree and TBB are not
 * instrumented, so TSan cannot see how TBB hands work to its worker threads and reports
 * everything the build touches there (Embree's buffers, our bounds callbacks' reads of
 * the shapes) as races. Queries run on our own threads either way. */
#if defined(__SANITIZE_THREAD__)
#define EMBREE_DEVICE_CONFIG "threads=1"
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define EMBREE_DEVICE_CONFIG "threads=1"
#endif
#endif
#ifndef EMBREE_DEVICE_CONFIG
#define EMBREE_DEVICE_CONFIG NULL
#endif

/* What a mesh's Embree geometry points to (its user data): the shape and its triangles'
 * caches (shape.h), one per triangle, owned by the accel. */
typedef struct mesh_geom {
    const ts_shape *shape;
    ts_tri_cache *tri;
} mesh_geom;

struct ts_accel {
    RTCDevice device;       /* immutable after create */
    RTCScene scene;         /* immutable after rtcCommitScene */
    const ts_shape *shapes; /* caller-owned, outlives the accel */
    uint32_t n_shapes;
    mesh_geom *meshes;      /* n_shapes entries (tri NULL for analytic shapes); immutable after create */
    ts_bounds3 bounds;
    ts_ray_log *log; /* NULL, or set by ts_accel_set_ray_log while no query runs */
    /* Written only by the Embree error callback while the creating thread builds; never
     * touched once ts_accel_create has returned. */
    char build_error[256];
    enum RTCError build_code; /* the first error's code, with build_error */
};

/* The per-query context: Embree's first, then what our callbacks need. */
typedef struct query_ctx {
    struct RTCIntersectContext rtc;
    const ts_ray *ray;
} query_ctx;

static const char *rtc_error_name(enum RTCError code)
{
    switch (code) {
    case RTC_ERROR_NONE: return "no error";
    case RTC_ERROR_UNKNOWN: return "unknown error";
    case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
    case RTC_ERROR_CANCELLED: return "cancelled";
    }
    return "unrecognised error";
}

static void on_embree_error(void *user, enum RTCError code, const char *str)
{
    ts_accel *a = user;
    if (!a || a->build_error[0]) return; /* keep the first */
    a->build_code = code;
    snprintf(a->build_error, sizeof a->build_error, "%s%s%s", rtc_error_name(code), str ? ": " : "", str ? str : "");
}

/* ---- user geometry callbacks (analytic shapes) ---- */

/* Ray i of an Embree ray packet of size N (struct-of-arrays floats: org xyz, tnear,
 * dir xyz, time, tfar, mask, id, flags; then the hit: Ng xyz, u, v, primID, geomID, instID). */
static ts_ray ray_from_packet(const float *rn, unsigned N, unsigned i)
{
    ts_ray r;
    r.o = (ts_vec3){rn[0 * N + i], rn[1 * N + i], rn[2 * N + i]};
    r.d = (ts_vec3){rn[4 * N + i], rn[5 * N + i], rn[6 * N + i]};
    r.tmax = rn[8 * N + i];
    r.skip_shape = r.skip_prim = TS_NONE;
    return r;
}

static void user_bounds(const struct RTCBoundsFunctionArguments *args)
{
    const ts_shape *s = args->geometryUserPtr;
    ts_bounds3 b = ts_shape_bounds(s);
    struct RTCBounds *o = args->bounds_o;
    o->lower_x = b.lo.x, o->lower_y = b.lo.y, o->lower_z = b.lo.z;
    o->upper_x = b.hi.x, o->upper_y = b.hi.y, o->upper_z = b.hi.z;
}

static void user_intersect(const struct RTCIntersectFunctionNArguments *args)
{
    const ts_shape *s = args->geometryUserPtr;
    float *rh = (float *)args->rayhit;
    unsigned N = args->N;
    for (unsigned i = 0; i < N; i++) {
        if (!args->valid[i]) continue;
        ts_ray r = ray_from_packet(rh, N, i);
        float t;
        if (!ts_shape_intersect(s, &r, r.tmax, &t)) continue;
        unsigned *uh = (unsigned *)rh;
        rh[8 * N + i] = t;              /* tfar */
        rh[12 * N + i] = 0;             /* Ng: unused, ts_shape_interaction recomputes */
        rh[13 * N + i] = 0;
        rh[14 * N + i] = 1;
        rh[15 * N + i] = 0;             /* u */
        rh[16 * N + i] = 0;             /* v */
        uh[17 * N + i] = args->primID;
        uh[18 * N + i] = args->geomID;
        uh[19 * N + i] = args->context->instID[0];
    }
}

static void user_occluded(const struct RTCOccludedFunctionNArguments *args)
{
    const ts_shape *s = args->geometryUserPtr;
    float *rn = (float *)args->ray;
    unsigned N = args->N;
    for (unsigned i = 0; i < N; i++) {
        if (!args->valid[i]) continue;
        ts_ray r = ray_from_packet(rn, N, i);
        float t;
        if (ts_shape_intersect(s, &r, r.tmax, &t)) rn[8 * N + i] = -INFINITY; /* Embree's "occluded" */
    }
}

/* ---- triangle filter (both intersect and occluded) ---- */

static void triangle_filter(const struct RTCFilterFunctionNArguments *args)
{
    const query_ctx *q = (const query_ctx *)args->context;
    const ts_ray *ray = q->ray;
    if (!ray || ray->skip_shape == TS_NONE) return;
    const mesh_geom *g = args->geometryUserPtr;
    const unsigned *hit = (const unsigned *)args->hit;
    unsigned N = args->N;
    for (unsigned i = 0; i < N; i++) {
        if (args->valid[i] != -1) continue;
        unsigned prim = hit[5 * N + i], geom = hit[6 * N + i];
        if ((geom == ray->skip_shape && prim == ray->skip_prim) ||
            !ts_shape_triangle_ahead_cached(g->shape, &g->tri[prim], prim, ray))
            args->valid[i] = 0;
    }
}

/* ---- build ---- */

static RTCGeometry make_mesh(ts_accel *a, uint32_t i)
{
    const ts_shape *s = &a->shapes[i];
    const ts_mesh *m = &s->mesh;
    mesh_geom *mg = &a->meshes[i];
    mg->shape = s;
    mg->tri = malloc(sizeof *mg->tri * (size_t)m->n_triangles);
    if (!mg->tri) {
        a->build_code = RTC_ERROR_OUT_OF_MEMORY;
        snprintf(a->build_error, sizeof a->build_error, "out of memory for %u triangles' data", m->n_triangles);
        return NULL;
    }
    for (uint32_t k = 0; k < m->n_triangles; k++) ts_shape_triangle_cache_init(s, k, &mg->tri[k]);
    RTCGeometry g = rtcNewGeometry(a->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    if (!g) return NULL;
    float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                       m->n_vertices);
    if (!v) {
        rtcReleaseGeometry(g);
        return NULL;
    }
    memcpy(v, m->p, (size_t)m->n_vertices * 3 * sizeof(float));
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, m->index, 0, 3 * sizeof(uint32_t),
                               m->n_triangles);
    rtcSetGeometryIntersectFilterFunction(g, triangle_filter);
    rtcSetGeometryOccludedFilterFunction(g, triangle_filter);
    rtcSetGeometryUserData(g, mg);
    return g;
}

static RTCGeometry make_user(ts_accel *a, const ts_shape *s)
{
    RTCGeometry g = rtcNewGeometry(a->device, RTC_GEOMETRY_TYPE_USER);
    if (!g) return NULL;
    rtcSetGeometryUserData(g, (void *)s);
    rtcSetGeometryUserPrimitiveCount(g, 1);
    rtcSetGeometryBoundsFunction(g, user_bounds, NULL);
    rtcSetGeometryIntersectFunction(g, user_intersect);
    rtcSetGeometryOccludedFunction(g, user_occluded);
    return g;
}

static void free_meshes(ts_accel *a)
{
    for (uint32_t i = 0; i < a->n_shapes; i++) free(a->meshes[i].tri);
    free(a->meshes);
}

ts_accel *ts_accel_create(const ts_shape *shapes, uint32_t n_shapes, ts_error *err)
{
    ts_accel *a = calloc(1, sizeof *a);
    if (!a) {
        ts_error_set(err, TS_ERR_NOMEM, "out of memory creating the ray-intersection structure");
        return NULL;
    }
    a->shapes = shapes;
    a->n_shapes = n_shapes;
    a->bounds = ts_bounds3_empty();
    a->meshes = calloc(n_shapes ? n_shapes : 1, sizeof *a->meshes);
    if (!a->meshes) {
        free(a);
        ts_error_set(err, TS_ERR_NOMEM, "out of memory creating the ray-intersection structure");
        return NULL;
    }

    a->device = rtcNewDevice(EMBREE_DEVICE_CONFIG);
    if (!a->device) {
        enum RTCError code = rtcGetDeviceError(NULL);
        ts_error_set(err, code == RTC_ERROR_OUT_OF_MEMORY ? TS_ERR_NOMEM : TS_ERR_INTERNAL,
                     "cannot create the Embree device (%s)", rtc_error_name(code));
        goto fail_device;
    }
    rtcSetDeviceErrorFunction(a->device, on_embree_error, a);

    a->scene = rtcNewScene(a->device);
    if (!a->scene) goto fail_embree;
    rtcSetSceneFlags(a->scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(a->scene, RTC_BUILD_QUALITY_HIGH);

    for (uint32_t i = 0; i < n_shapes; i++) {
        const ts_shape *s = &shapes[i];
        RTCGeometry g;
        if (s->type == TS_SHAPE_MESH) {
            if (s->mesh.n_triangles == 0 || s->mesh.n_vertices == 0) continue; /* nothing to hit */
            g = make_mesh(a, i);
        } else {
            g = make_user(a, s);
        }
        if (!g) goto fail_embree;
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(a->scene, g, i);
        rtcReleaseGeometry(g); /* the scene holds it */
        if (a->build_error[0]) goto fail_embree;
        a->bounds = ts_bounds3_union(a->bounds, ts_shape_bounds(s));
    }
    rtcCommitScene(a->scene);
    if (a->build_error[0] || rtcGetDeviceError(a->device) != RTC_ERROR_NONE) goto fail_embree;
    rtcSetDeviceErrorFunction(a->device, NULL, NULL); /* nothing writes to a after this */
    return a;

fail_embree:
    if (!a->build_error[0]) {
        a->build_code = rtcGetDeviceError(a->device);
        snprintf(a->build_error, sizeof a->build_error, "%s", rtc_error_name(a->build_code));
    }
    ts_error_set(err, a->build_code == RTC_ERROR_OUT_OF_MEMORY ? TS_ERR_NOMEM : TS_ERR_INTERNAL,
                 "Embree failed to build the scene's ray-intersection structure: %s", a->build_error);
    if (a->scene) rtcReleaseScene(a->scene);
    rtcReleaseDevice(a->device);
fail_device:
    free_meshes(a);
    free(a);
    return NULL;
}

void ts_accel_destroy(ts_accel *a)
{
    if (!a) return;
    rtcReleaseScene(a->scene);
    rtcReleaseDevice(a->device);
    free_meshes(a);
    free(a);
}

/* ---- queries ---- */

void ts_accel_set_ray_log(ts_accel *a, ts_ray_log *log) { a->log = log; }

__attribute__((noinline, cold)) static void log_ray(ts_ray_log *log, const ts_ray *ray, uint8_t kind)
{
    size_t i = atomic_fetch_add_explicit(&log->n, 1, memory_order_relaxed);
    if (i >= log->capacity) return;
    log->rays[i] = *ray;
    log->kinds[i] = kind;
}

static void ray_to_rtc(const ts_ray *ray, struct RTCRay *r)
{
    r->org_x = ray->o.x, r->org_y = ray->o.y, r->org_z = ray->o.z;
    r->dir_x = ray->d.x, r->dir_y = ray->d.y, r->dir_z = ray->d.z;
    r->tnear = 0;
    r->tfar = ray->tmax;
    r->time = 0;
    r->mask = 0xffffffffu;
    r->id = 0;
    r->flags = 0;
}

/* Embree requires |origin| and |direction| components ≤ 1.844e18 (its FLT_LARGE) and a
 * non-NaN tfar, and asserts otherwise. Scenes are kept far inside that at load time, but
 * a ray derived from extreme values must still never reach it: such a ray misses (and a
 * shadow ray counts as blocked, so no light arrives along it). */
#define TS_EMBREE_LARGE 1.0e18f
static inline bool ray_valid(const ts_ray *r)
{
    return fabsf(r->o.x) <= TS_EMBREE_LARGE && fabsf(r->o.y) <= TS_EMBREE_LARGE && fabsf(r->o.z) <= TS_EMBREE_LARGE &&
           fabsf(r->d.x) <= TS_EMBREE_LARGE && fabsf(r->d.y) <= TS_EMBREE_LARGE && fabsf(r->d.z) <= TS_EMBREE_LARGE &&
           (r->d.x != 0 || r->d.y != 0 || r->d.z != 0) && !isnan(r->tmax);
}

bool ts_accel_intersect(const ts_accel *a, const ts_ray *ray, ts_interaction *si)
{
    if (!(ray->tmax > 0) || !ray_valid(ray)) return false;
    if (__builtin_expect(a->log != NULL, 0)) log_ray(a->log, ray, TS_RAY_LOG_INTERSECT);
    query_ctx q;
    rtcInitIntersectContext(&q.rtc);
    q.ray = ray;
    struct RTCRayHit rh;
    ray_to_rtc(ray, &rh.ray);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(a->scene, &q.rtc, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID || rh.hit.geomID >= a->n_shapes) return false;
    const ts_shape *s = &a->shapes[rh.hit.geomID];
    if (s->type == TS_SHAPE_MESH) {
        const mesh_geom *g = &a->meshes[rh.hit.geomID];
        ts_shape_triangle_interaction_cached(s, &g->tri[rh.hit.primID], rh.hit.geomID, rh.hit.primID, ray,
                                             rh.ray.tfar, si);
    } else {
        ts_shape_interaction(s, rh.hit.geomID, 0, ray, rh.ray.tfar, si);
    }
    return true;
}

bool ts_accel_occluded(const ts_accel *a, const ts_ray *ray)
{
    if (!(ray->tmax > 0)) return false;
    if (!ray_valid(ray)) return true;
    if (__builtin_expect(a->log != NULL, 0)) log_ray(a->log, ray, TS_RAY_LOG_OCCLUDED);
    query_ctx q;
    rtcInitIntersectContext(&q.rtc);
    q.ray = ray;
    struct RTCRay r;
    ray_to_rtc(ray, &r);
    rtcOccluded1(a->scene, &q.rtc, &r);
    return r.tfar == -INFINITY;
}

ts_bounds3 ts_accel_bounds(const ts_accel *a) { return a->bounds; }
