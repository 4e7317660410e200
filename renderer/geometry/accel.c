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
 * Alpha cut-outs (shape.h): a mesh with an alpha texture gets other filter functions —
 * the intersect filter tests alpha, the occluded filter alpha and then shadow_alpha
 * (pbrt-v3's Triangle::Intersect and IntersectP), as does the intersect filter of a shadow
 * ray's nearest-hit query (ts_accel_intersect_shadow: the context says which), each after
 * the skip test above, at the hit's point and (u, v) as ts_shape_triangle_point_uv
 * computes them from Embree's barycentrics (through an instance those of the object's own
 * triangle, as pbrt-v3's TransformedPrimitive tests the object's own triangles), with no
 * footprint: a texture lookup of the finest MIP level. A
 * rejected hit is no hit and traversal goes on past it. A mesh without alpha textures
 * keeps the plain filter and pays nothing. The decision is a pure function of the ray and
 * the hit, so it is the same on every thread and in any traversal order.
 *
 * Curves (geometry/curve.h) are Embree's flat Bézier curves: their pieces' control points
 * copied (x, y, z, radius), one index per piece, the curve's tessellation rate; a ribbon
 * gets ribbon_filter (intersect and occluded), which keeps only hits within pbrt-v3's
 * width for the ray's direction. A hit's interaction comes from Embree's (t, u, v). Curves
 * carry no skip ids: a ray leaving one starts 2·width off it (pbrt-v3's error bound).
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
 * Embree's memory monitor counts the device's bytes (now and peak) for the memory
 * benchmark (ts_accel_memory_get); Embree allocates only while building and tearing down.
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

#include "geometry/curve.h"
#include "textures/texture.h"

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
    uint32_t shape_index; /* into the scene's shapes */
    ts_tri_cache *tri;
} mesh_geom;

struct ts_accel {
    RTCDevice device;       /* immutable after create */
    ts_cancel *cancel;      /* polled while building (NULL: never stops); not after */
    RTCScene scene;         /* immutable after rtcCommitScene */
    const ts_shape *shapes; /* caller-owned, outlives the accel */
    uint32_t n_shapes;
    mesh_geom *meshes;      /* n_shapes entries (tri NULL for analytic shapes); immutable after create */
    /* Object instancing (accel.h), immutable after create: instance k is top-level geometry
     * n_shapes + k over obj_scene[instances[k].object]. */
    const ts_object *objects;     /* caller-owned, outlive the accel */
    uint32_t n_objects;
    RTCScene *obj_scene;
    const ts_instance *instances; /* caller-owned, outlive the accel */
    uint32_t n_instances;
    /* Motion (accel.h), immutable after create: Embree's ray time is
     * clamp((time − time0)·time_scale, 0, 1) when `moving`. */
    bool moving;
    double time0, time1, time_scale;
    ts_bounds3 bounds;
    ts_ray_log *log; /* NULL, or set by ts_accel_set_ray_log while no query runs */
    /* Written only by the Embree error callback while the creating thread builds; never
     * touched once ts_accel_create has returned. */
    char build_error[256];
    enum RTCError build_code; /* the first error's code, with build_error */
    /* Embree's allocations for this device (its memory monitor; atomic: TBB's build threads
     * report concurrently; no allocation happens after the build). */
    _Atomic int64_t embree_bytes, embree_peak;
};

/* The per-query context: Embree's first, then what our callbacks need. The last moving
 * instance's transform at the ray's time is kept in it (the context is the caller's, on
 * its stack: one thread writes it). */
typedef struct query_ctx {
    struct RTCIntersectContext rtc;
    const ts_ray *ray;
    const ts_accel *a;
    bool shadow; /* a shadow ray's nearest hit (ts_accel_intersect_shadow): shadow_alpha cuts out too */
    uint32_t moved_k;  /* TS_NONE, or the instance moved_x holds */
    bool moved_ok;     /* its transform at the ray's time is invertible */
    ts_xform moved_x;
} query_ctx;

static void query_init(query_ctx *q, const ts_accel *a, const ts_ray *ray, bool shadow)
{
    rtcInitIntersectContext(&q->rtc);
    q->ray = ray;
    q->a = a;
    q->shadow = shadow;
    q->moved_k = TS_NONE;
}

/* Instance k's object → world at the query ray's time: its own transform when it does not
 * move; NULL where the moving transform is singular at that time (nothing is hit). */
static const ts_xform *instance_xform(const query_ctx *cq, uint32_t k)
{
    const ts_instance *in = &cq->a->instances[k];
    if (!in->motion) return &in->to_world;
    query_ctx *q = (query_ctx *)cq; /* the caller's own context */
    if (q->moved_k != k) {
        q->moved_ok = ts_anim_xform_at(in->motion, q->ray ? q->ray->time : 0, &q->moved_x);
        q->moved_k = k;
    }
    return q->moved_ok ? &q->moved_x : NULL;
}

/* The instance a callback runs under (Embree's context instID), or NONE at top level. */
static inline uint32_t current_instance(const ts_accel *a, const struct RTCIntersectContext *c)
{
    unsigned id = c->instID[0];
    return id == RTC_INVALID_GEOMETRY_ID || !a ? TS_NONE : (uint32_t)(id - a->n_shapes);
}

/* An analytic shape of an object as an instance places it (x: instance_xform): to_world
 * composed in double. */
static ts_shape placed(const ts_xform *x, const ts_shape *s)
{
    ts_shape t = *s;
    t.to_world = ts_xform_compose(x, &s->to_world);
    return t;
}

/* The world ray in an instance's object space (x: instance_xform), in double, rounded once. */
static ts_ray ray_to_object(const ts_xform *x, const ts_ray *ray)
{
    ts_ray r = *ray;
    r.o = ts_dvec3_to_vec3(ts_xform_point_inv(x, ts_dvec3_from(ray->o)));
    r.d = ts_dvec3_to_vec3(ts_xform_vector_inv(x, ts_dvec3_from(ray->d)));
    return r;
}

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

/* Embree's progress monitor (on its build threads): false stops the build
 * (RTC_ERROR_CANCELLED) once the accel's ts_cancel says so. */
static bool on_embree_progress(void *user, double done)
{
    (void)done;
    return !ts_cancel_requested(((ts_accel *)user)->cancel);
}

/* Embree's memory monitor: bytes > 0 allocated, < 0 freed; never refuses. */
static bool on_embree_memory(void *user, ssize_t bytes, bool post)
{
    (void)post;
    ts_accel *a = user;
    int64_t now = atomic_fetch_add_explicit(&a->embree_bytes, (int64_t)bytes, memory_order_relaxed) + bytes;
    int64_t peak = atomic_load_explicit(&a->embree_peak, memory_order_relaxed);
    while (now > peak &&
           !atomic_compare_exchange_weak_explicit(&a->embree_peak, &peak, now, memory_order_relaxed,
                                                  memory_order_relaxed)) {
    }
    return true;
}

void ts_accel_memory_get(const ts_accel *a, ts_accel_memory *m)
{
    size_t tri = 0;
    for (uint32_t i = 0; i < a->n_shapes; i++)
        if (a->meshes[i].tri) tri += sizeof(ts_tri_cache) * (size_t)a->shapes[i].mesh.n_triangles;
    m->tri_cache_bytes = tri;
    int64_t now = atomic_load_explicit(&a->embree_bytes, memory_order_relaxed);
    int64_t peak = atomic_load_explicit(&a->embree_peak, memory_order_relaxed);
    m->embree_bytes = now > 0 ? (size_t)now : 0;
    m->embree_peak_bytes = peak > 0 ? (size_t)peak : 0;
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
    const query_ctx *q = (const query_ctx *)args->context;
    uint32_t k = current_instance(q->a, args->context);
    ts_shape inst_s;
    if (k != TS_NONE) {
        const ts_xform *x = instance_xform(q, k);
        if (!x) return;
        inst_s = placed(x, s);
    }
    for (unsigned i = 0; i < N; i++) {
        if (!args->valid[i]) continue;
        ts_ray r = ray_from_packet(rh, N, i);
        float t;
        if (k != TS_NONE) {
            /* Through an instance: the world ray (same parameter t) against the placed shape. */
            ts_ray w = *q->ray;
            w.tmax = r.tmax;
            if (!ts_shape_intersect(&inst_s, &w, w.tmax, &t)) continue;
        } else if (!ts_shape_intersect(s, &r, r.tmax, &t)) continue;
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
    const query_ctx *q = (const query_ctx *)args->context;
    uint32_t k = current_instance(q->a, args->context);
    ts_shape inst_s;
    if (k != TS_NONE) {
        const ts_xform *x = instance_xform(q, k);
        if (!x) return;
        inst_s = placed(x, s);
    }
    for (unsigned i = 0; i < N; i++) {
        if (!args->valid[i]) continue;
        ts_ray r = ray_from_packet(rn, N, i);
        float t;
        if (k != TS_NONE) {
            ts_ray w = *q->ray;
            w.tmax = r.tmax;
            if (ts_shape_intersect(&inst_s, &w, w.tmax, &t)) rn[8 * N + i] = -INFINITY;
        } else if (ts_shape_intersect(s, &r, r.tmax, &t)) {
            rn[8 * N + i] = -INFINITY; /* Embree's "occluded" */
        }
    }
}

/* A filter's ray in the space of the instance k it runs under (instance_xform), into *out;
 * false, with every hit of the call rejected, where that instance's transform is
 * singular at the ray's time (nothing of it is hit). */
static bool filter_object_ray(const struct RTCFilterFunctionNArguments *args, const query_ctx *q, uint32_t k,
                              const ts_ray *ray, ts_ray *out)
{
    const ts_xform *x = instance_xform(q, k);
    if (!x) {
        for (unsigned i = 0; i < args->N; i++) args->valid[i] = 0;
        return false;
    }
    *out = ray_to_object(x, ray);
    return true;
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
    /* Through instance k the triangle is in the object's space: so is the ray tested. */
    uint32_t k = current_instance(q->a, args->context), inst = k == TS_NONE ? 0 : k + 1;
    ts_ray r_obj;
    if (k != TS_NONE && !filter_object_ray(args, q, k, ray, &r_obj)) return;
    for (unsigned i = 0; i < N; i++) {
        if (args->valid[i] != -1) continue;
        unsigned prim = hit[5 * N + i];
        if ((g->shape_index == ray->skip_shape && prim == ray->skip_prim && inst == ray->skip_inst) ||
            !ts_shape_triangle_ahead_cached(g->shape, &g->tri[prim], prim, k == TS_NONE ? ray : &r_obj))
            args->valid[i] = 0;
    }
}

/* ---- alpha cut-out filters (shape.h) ---- */

/* Whether triangle prim of g cuts out the hit of r (in the triangle's space) at parameter t:
 * alpha, or for a shadow ray shadow_alpha, evaluates to exactly 0 there (pbrt-v3's test).
 * The context is pbrt-v3's isectLocal: the hit's point and (u, v), the triangle's ∂p/∂u,
 * ∂p/∂v, no footprint. */
static bool cut_out(const mesh_geom *g, uint32_t prim, float b1, float b2, bool shadow)
{
    const ts_shape *s = g->shape;
    ts_texture_context c;
    ts_shape_triangle_point_uv(s, prim, b1, b2, &c.p, &c.uv);
    c.dpdu = g->tri[prim].dpdu;
    c.dpdv = g->tri[prim].dpdv;
    ts_texture_context_clear_differentials(&c);
    if (s->alpha && ts_texture_eval_float(s->alpha, &c) == 0) return true;
    return shadow && s->shadow_alpha && ts_texture_eval_float(s->shadow_alpha, &c) == 0;
}

/* triangle_filter's skip test, then the cut-out test, for every valid hit. */
static inline void cutout_filter(const struct RTCFilterFunctionNArguments *args, bool shadow)
{
    const query_ctx *q = (const query_ctx *)args->context;
    const ts_ray *ray = q->ray;
    const mesh_geom *g = args->geometryUserPtr;
    const unsigned *hit = (const unsigned *)args->hit;
    const float *hf = (const float *)args->hit;
    unsigned N = args->N;
    uint32_t k = current_instance(q->a, args->context), inst = k == TS_NONE ? 0 : k + 1;
    ts_ray r_obj;
    if (ray && k != TS_NONE && !filter_object_ray(args, q, k, ray, &r_obj)) return;
    const ts_ray *r = ray && k != TS_NONE ? &r_obj : ray;
    bool skips = ray && ray->skip_shape != TS_NONE;
    for (unsigned i = 0; i < N; i++) {
        if (args->valid[i] != -1) continue;
        unsigned prim = hit[5 * N + i];
        if (skips && ((g->shape_index == ray->skip_shape && prim == ray->skip_prim && inst == ray->skip_inst) ||
                      !ts_shape_triangle_ahead_cached(g->shape, &g->tri[prim], prim, r))) {
            args->valid[i] = 0;
            continue;
        }
        /* RTCHitN's u and v: the hit's barycentrics of p1 and p2. */
        if (cut_out(g, prim, hf[3 * N + i], hf[4 * N + i], shadow)) args->valid[i] = 0;
    }
}

static void alpha_filter(const struct RTCFilterFunctionNArguments *args)
{
    cutout_filter(args, ((const query_ctx *)args->context)->shadow);
}
static void shadow_alpha_filter(const struct RTCFilterFunctionNArguments *args) { cutout_filter(args, true); }
/* The intersect filter of a mesh with shadow_alpha only: cut-outs for shadow rays alone. */
static void shadow_only_filter(const struct RTCFilterFunctionNArguments *args)
{
    if (((const query_ctx *)args->context)->shadow) cutout_filter(args, true);
    else triangle_filter(args);
}

/* ---- ribbon curves (geometry/curve.h) ---- */

/* Embree's flat curve carries a ribbon at its full width; this keeps the hits within
 * pbrt-v3's ribbon width for the ray's direction (taken to the object's space through an
 * instance, where pbrt-v3 tests it). Both intersect and occluded. */
static void ribbon_filter(const struct RTCFilterFunctionNArguments *args)
{
    const query_ctx *q = (const query_ctx *)args->context;
    const ts_shape *s = args->geometryUserPtr;
    const float *rn = (const float *)args->ray;
    const float *hf = (const float *)args->hit;
    const unsigned *hu = (const unsigned *)args->hit;
    unsigned N = args->N;
    uint32_t k = q && q->ray ? current_instance(q->a, args->context) : TS_NONE;
    ts_ray r_obj;
    if (k != TS_NONE && !filter_object_ray(args, q, k, q->ray, &r_obj)) return;
    for (unsigned i = 0; i < N; i++) {
        if (args->valid[i] != -1) continue;
        ts_vec3 d = q && q->ray ? (k != TS_NONE ? r_obj.d : q->ray->d)
                                : (ts_vec3){rn[4 * N + i], rn[5 * N + i], rn[6 * N + i]};
        if (!ts_curve_ribbon_covers(&s->curve, hu[5 * N + i], hf[3 * N + i], hf[4 * N + i], d)) args->valid[i] = 0;
    }
}

/* ---- build ---- */

static RTCGeometry make_mesh(ts_accel *a, uint32_t i)
{
    const ts_shape *s = &a->shapes[i];
    const ts_mesh *m = &s->mesh;
    mesh_geom *mg = &a->meshes[i];
    mg->shape = s;
    mg->shape_index = i;
    mg->tri = malloc(sizeof *mg->tri * (size_t)m->n_triangles);
    if (!mg->tri) {
        a->build_code = RTC_ERROR_OUT_OF_MEMORY;
        snprintf(a->build_error, sizeof a->build_error, "out of memory for %u triangles' data", m->n_triangles);
        return NULL;
    }
    for (uint32_t k = 0; k < m->n_triangles; k++) {
        if (k % 65536 == 0 && ts_cancel_requested(a->cancel)) {
            a->build_code = RTC_ERROR_CANCELLED;
            snprintf(a->build_error, sizeof a->build_error, "cancelled");
            return NULL;
        }
        ts_shape_triangle_cache_init(s, k, &mg->tri[k]);
    }
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
    rtcSetGeometryIntersectFilterFunction(g, s->alpha ? alpha_filter : s->shadow_alpha ? shadow_only_filter : triangle_filter);
    rtcSetGeometryOccludedFilterFunction(g, s->alpha || s->shadow_alpha ? shadow_alpha_filter : triangle_filter);
    rtcSetGeometryUserData(g, mg);
    return g;
}

/* A curve as Embree's ray-facing Bézier curve (geometry/curve.h): its control points
 * copied (x, y, z, radius), one index per segment, its tessellation rate; ribbons keep
 * pbrt-v3's width through ribbon_filter. */
static RTCGeometry make_curve(ts_accel *a, const ts_shape *s)
{
    const ts_curve *c = &s->curve;
    RTCGeometry g = rtcNewGeometry(a->device, RTC_GEOMETRY_TYPE_FLAT_BEZIER_CURVE);
    if (!g) return NULL;
    float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float),
                                       4 * (size_t)c->n_pieces);
    unsigned *ix = v ? rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT, sizeof(unsigned),
                                               c->n_pieces)
                     : NULL;
    if (!v || !ix) {
        rtcReleaseGeometry(g);
        return NULL;
    }
    memcpy(v, c->cp, 16 * (size_t)c->n_pieces * sizeof(float));
    for (uint32_t k = 0; k < c->n_pieces; k++) ix[k] = 4 * k;
    rtcSetGeometryTessellationRate(g, (float)c->tessellation);
    rtcSetGeometryUserData(g, (void *)s);
    if (c->type == TS_CURVE_RIBBON) {
        rtcSetGeometryIntersectFilterFunction(g, ribbon_filter);
        rtcSetGeometryOccludedFilterFunction(g, ribbon_filter);
    }
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
    for (uint32_t o = 0; a->obj_scene && o < a->n_objects; o++)
        if (a->obj_scene[o]) rtcReleaseScene(a->obj_scene[o]);
    free(a->obj_scene);
}

/* The geometry of shape i (NULL with build_error set on failure; *none when there is nothing
 * to attach: an empty mesh). */
static RTCGeometry make_geometry(ts_accel *a, uint32_t i, bool *none)
{
    const ts_shape *s = &a->shapes[i];
    *none = false;
    if (s->type == TS_SHAPE_MESH) {
        if (s->mesh.n_triangles == 0 || s->mesh.n_vertices == 0) {
            *none = true; /* nothing to hit */
            return NULL;
        }
        return make_mesh(a, i);
    }
    if (s->type == TS_SHAPE_CURVE) {
        if (s->curve.n_pieces == 0) {
            *none = true;
            return NULL;
        }
        return make_curve(a, s);
    }
    return make_user(a, s);
}

/* World bounds of b under x (its 8 corners, rounded outwards by a float ulp). */
static ts_bounds3 xform_bounds(const ts_xform *x, ts_bounds3 b)
{
    ts_bounds3 w = ts_bounds3_empty();
    if (ts_bounds3_is_empty(b)) return w;
    for (int c = 0; c < 8; c++) {
        ts_dvec3 q = {(c & 1) ? b.hi.x : b.lo.x, (c & 2) ? b.hi.y : b.lo.y, (c & 4) ? b.hi.z : b.lo.z};
        ts_vec3 p = ts_dvec3_to_vec3(ts_xform_point(x, q));
        w = ts_bounds3_extend(w, p);
    }
    w.lo = (ts_vec3){ts_next_float_down(w.lo.x), ts_next_float_down(w.lo.y), ts_next_float_down(w.lo.z)};
    w.hi = (ts_vec3){ts_next_float_up(w.hi.x), ts_next_float_up(w.hi.y), ts_next_float_up(w.hi.z)};
    return w;
}

/* ---- motion (accel.h) ---- */

/* Whether 4×4 s's 3×3 part is diagonal. */
static bool diagonal(const ts_mat4 *s)
{
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            if (i != j && s->m[i][j] != 0) return false;
    return true;
}

/* Linear part L = Q·U, Q a rotation, U upper triangular (Gram–Schmidt on L's columns in
 * double, U's last diagonal entry negative for a mirroring L). */
static void qr3(const ts_mat4 *m, ts_mat4 *q, double u[3][3])
{
    ts_dvec3 c[3], e[3];
    for (int j = 0; j < 3; j++) c[j] = (ts_dvec3){m->m[0][j], m->m[1][j], m->m[2][j]};
    memset(u, 0, sizeof(double[3][3]));
    for (int j = 0; j < 3; j++) {
        ts_dvec3 v = c[j];
        for (int i = 0; i < j; i++) {
            u[i][j] = ts_dvec3_dot(e[i], c[j]);
            v = ts_dvec3_sub(v, ts_dvec3_scale(e[i], u[i][j]));
        }
        u[j][j] = ts_dvec3_length(v);
        e[j] = u[j][j] > 0 ? ts_dvec3_scale(v, 1 / u[j][j]) : (ts_dvec3){0, 0, 0};
    }
    if (ts_dvec3_dot(ts_dvec3_cross(e[0], e[1]), e[2]) < 0) { /* a mirror: into U */
        e[2] = ts_dvec3_scale(e[2], -1);
        u[2][2] = -u[2][2];
    }
    *q = ts_mat4_identity();
    for (int j = 0; j < 3; j++) q->m[0][j] = e[j].x, q->m[1][j] = e[j].y, q->m[2][j] = e[j].z;
}

static void set_step(RTCGeometry g, unsigned step, ts_dvec3 t, ts_quat r, const double u[3][3])
{
    struct RTCQuaternionDecomposition qd;
    rtcInitQuaternionDecomposition(&qd);
    rtcQuaternionDecompositionSetScale(&qd, (float)u[0][0], (float)u[1][1], (float)u[2][2]);
    rtcQuaternionDecompositionSetSkew(&qd, (float)u[0][1], (float)u[0][2], (float)u[1][2]);
    rtcQuaternionDecompositionSetQuaternion(&qd, (float)r.w, (float)r.x, (float)r.y, (float)r.z);
    rtcQuaternionDecompositionSetTranslation(&qd, (float)t.x, (float)t.y, (float)t.z);
    rtcSetGeometryTransformQuaternion(g, step, &qd);
}

/* Embree's time steps for a moving instance (accel.h): pbrt's own T, R, S at the two ends
 * where Embree's interpolation is pbrt's, else TS_ACCEL_MOTION_STEPS steps of pbrt's
 * matrix at their times, each re-decomposed as T·Q·U. */
/* Whether Embree's interpolation between m's two keyframes is pbrt's (accel.h). */
static bool two_steps(const ts_accel *a, const ts_anim_xform *m)
{
    bool signs = true;
    for (int i = 0; i < 3; i++) signs = signs && ((m->s[0].m[i][i] > 0) == (m->s[1].m[i][i] > 0));
    return m->start_time == a->time0 && m->end_time == a->time1 && diagonal(&m->s[0]) && diagonal(&m->s[1]) && signs;
}

static void set_motion_steps(ts_accel *a, RTCGeometry g, const ts_anim_xform *m)
{
    double t0 = a->time0, t1 = a->time1;
    if (two_steps(a, m)) {
        rtcSetGeometryTimeStepCount(g, 2);
        for (unsigned k = 0; k < 2; k++) {
            double u[3][3] = {{m->s[k].m[0][0], 0, 0}, {0, m->s[k].m[1][1], 0}, {0, 0, m->s[k].m[2][2]}};
            set_step(g, k, m->t[k], m->r[k], u);
        }
        return;
    }
    rtcSetGeometryTimeStepCount(g, TS_ACCEL_MOTION_STEPS);
    ts_quat prev = {0, 0, 0, 1};
    for (unsigned k = 0; k < TS_ACCEL_MOTION_STEPS; k++) {
        double t = t0 + (t1 - t0) * k / (TS_ACCEL_MOTION_STEPS - 1);
        ts_mat4 mt = ts_anim_xform_matrix(m, t), q;
        double u[3][3];
        qr3(&mt, &q, u);
        ts_quat r = ts_quat_from_mat4(&q);
        if (k > 0 && ts_quat_dot(r, prev) < 0) r = (ts_quat){-r.x, -r.y, -r.z, -r.w};
        prev = r;
        set_step(g, k, (ts_dvec3){mt.m[0][3], mt.m[1][3], mt.m[2][3]}, r, u);
    }
}

/* The scene's motion interval: the union of the moving instances' [start, end]. */
static void motion_interval(ts_accel *a)
{
    double lo = INFINITY, hi = -INFINITY;
    for (uint32_t k = 0; k < a->n_instances; k++) {
        const ts_anim_xform *m = a->instances[k].motion;
        if (!m || !m->animated) continue;
        lo = fmin(lo, m->start_time);
        hi = fmax(hi, m->end_time);
    }
    a->moving = lo < hi;
    a->time0 = a->moving ? lo : 0;
    a->time1 = a->moving ? hi : 1;
    a->time_scale = a->moving ? 1 / (hi - lo) : 1;
}

/* Embree's time steps of every moving instance together, within TS_ACCEL_MOTION_STEP_LIMIT
 * (Embree holds a transform a step and its motion BVH grows with them). */
static bool motion_steps_fit(const ts_accel *a, ts_error *err)
{
    uint64_t steps = 0;
    for (uint32_t k = 0; k < a->n_instances; k++) {
        const ts_anim_xform *m = a->instances[k].motion;
        if (m && m->animated) steps += two_steps(a, m) ? 2 : TS_ACCEL_MOTION_STEPS;
    }
    if (steps <= TS_ACCEL_MOTION_STEP_LIMIT) return true;
    ts_error_set(err, TS_ERR_LIMIT,
                 "instances: the moving shapes and instances need %llu time steps of the ray-intersection structure, "
                 "more than its limit of %u (a motion with shear, or over part of the scene's motion interval, "
                 "takes %u, others 2)",
                 (unsigned long long)steps, TS_ACCEL_MOTION_STEP_LIMIT, TS_ACCEL_MOTION_STEPS);
    return false;
}

/* One Embree scene per object, then an instance geometry per instance (top-level ID
 * n_shapes + k); object shapes are left out of the top level. */
static bool build_objects(ts_accel *a)
{
    a->obj_scene = calloc(a->n_objects ? a->n_objects : 1, sizeof *a->obj_scene);
    ts_bounds3 *ob = calloc(a->n_objects ? a->n_objects : 1, sizeof *ob);
    if (!a->obj_scene || !ob) {
        free(ob);
        a->build_code = RTC_ERROR_OUT_OF_MEMORY;
        snprintf(a->build_error, sizeof a->build_error, "out of memory for %u objects", a->n_objects);
        return false;
    }
    for (uint32_t o = 0; o < a->n_objects; o++) {
        RTCScene sc = rtcNewScene(a->device);
        if (!sc) goto fail;
        a->obj_scene[o] = sc;
        rtcSetSceneFlags(sc, RTC_SCENE_FLAG_ROBUST);
        rtcSetSceneBuildQuality(sc, RTC_BUILD_QUALITY_HIGH);
        if (a->cancel) rtcSetSceneProgressMonitorFunction(sc, on_embree_progress, a);
        ob[o] = ts_bounds3_empty();
        const ts_object *obj = &a->objects[o];
        for (uint32_t j = 0; j < obj->n_shapes; j++) {
            uint32_t i = obj->first_shape + j;
            bool none;
            RTCGeometry g = make_geometry(a, i, &none);
            if (none) continue;
            if (!g) goto fail;
            rtcCommitGeometry(g);
            rtcAttachGeometryByID(sc, g, j);
            rtcReleaseGeometry(g);
            if (a->build_error[0]) goto fail;
            ob[o] = ts_bounds3_union(ob[o], ts_shape_bounds(&a->shapes[i]));
        }
        rtcCommitScene(sc);
    }
    for (uint32_t k = 0; k < a->n_instances; k++) {
        const ts_instance *in = &a->instances[k];
        if (ts_bounds3_is_empty(ob[in->object])) continue; /* nothing to see */
        RTCGeometry g = rtcNewGeometry(a->device, RTC_GEOMETRY_TYPE_INSTANCE);
        if (!g) goto fail;
        rtcSetGeometryInstancedScene(g, a->obj_scene[in->object]);
        if (in->motion && in->motion->animated) {
            set_motion_steps(a, g, in->motion);
            a->bounds = ts_bounds3_union(a->bounds, ts_anim_xform_motion_bounds(in->motion, ob[in->object]));
        } else {
            float xfm[12]; /* 3×4 column-major, for traversal only (hits are redone in double) */
            for (int c = 0; c < 4; c++)
                for (int r = 0; r < 3; r++) xfm[3 * c + r] = (float)in->to_world.m.m[r][c];
            rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, xfm);
            a->bounds = ts_bounds3_union(a->bounds, xform_bounds(&in->to_world, ob[in->object]));
        }
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(a->scene, g, a->n_shapes + k);
        rtcReleaseGeometry(g);
        if (a->build_error[0]) goto fail;
    }
    free(ob);
    return true;
fail:
    free(ob);
    return false;
}

ts_accel *ts_accel_create(const ts_shape *shapes, uint32_t n_shapes, ts_error *err)
{
    return ts_accel_create_instanced(shapes, n_shapes, NULL, 0, NULL, 0, NULL, err);
}

ts_accel *ts_accel_create_instanced(const ts_shape *shapes, uint32_t n_shapes, const ts_object *objects,
                                    uint32_t n_objects, const ts_instance *instances, uint32_t n_instances,
                                    ts_cancel *cancel, ts_error *err)
{
    ts_accel *a = calloc(1, sizeof *a);
    if (!a) {
        ts_error_set(err, TS_ERR_NOMEM, "out of memory creating the ray-intersection structure");
        return NULL;
    }
    a->shapes = shapes;
    a->n_shapes = n_shapes;
    a->cancel = cancel;
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
    rtcSetDeviceMemoryMonitorFunction(a->device, on_embree_memory, a);

    a->scene = rtcNewScene(a->device);
    if (!a->scene) goto fail_embree;
    rtcSetSceneFlags(a->scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(a->scene, RTC_BUILD_QUALITY_HIGH);
    if (cancel) rtcSetSceneProgressMonitorFunction(a->scene, on_embree_progress, a);

    a->objects = objects;
    a->instances = instances;
    a->n_objects = n_objects;
    a->n_instances = n_instances;
    motion_interval(a);
    if (!motion_steps_fit(a, err)) goto fail_limit;
    for (uint32_t i = 0; i < n_shapes; i++) {
        const ts_shape *s = &shapes[i];
        if (s->in_object) continue; /* seen through its instances */
        bool none;
        RTCGeometry g = make_geometry(a, i, &none);
        if (none) continue;
        if (!g) goto fail_embree;
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(a->scene, g, i);
        rtcReleaseGeometry(g); /* the scene holds it */
        if (a->build_error[0]) goto fail_embree;
        a->bounds = ts_bounds3_union(a->bounds, ts_shape_bounds(s));
    }
    if (n_objects && !build_objects(a)) goto fail_embree;
    rtcCommitScene(a->scene);
    if (ts_cancel_requested(cancel)) {
        ts_cancel_check(cancel, err);
        goto fail_cancelled;
    }
    if (a->build_error[0] || rtcGetDeviceError(a->device) != RTC_ERROR_NONE) goto fail_embree;
    a->cancel = NULL;
    /* Nothing writes to a after this but the memory monitor, which counts the teardown's frees. */
    rtcSetDeviceErrorFunction(a->device, NULL, NULL);
    return a;

fail_embree:
    if (!a->build_error[0]) {
        a->build_code = rtcGetDeviceError(a->device);
        snprintf(a->build_error, sizeof a->build_error, "%s", rtc_error_name(a->build_code));
    }
    if (a->build_code == RTC_ERROR_CANCELLED && ts_cancel_requested(cancel))
        ts_cancel_check(cancel, err);
    else
        ts_error_set(err, a->build_code == RTC_ERROR_OUT_OF_MEMORY ? TS_ERR_NOMEM : TS_ERR_INTERNAL,
                     "Embree failed to build the scene's ray-intersection structure: %s", a->build_error);
fail_cancelled:
fail_limit:
    if (a->scene) rtcReleaseScene(a->scene);
    for (uint32_t o = 0; a->obj_scene && o < a->n_objects; o++)
        if (a->obj_scene[o]) rtcReleaseScene(a->obj_scene[o]);
    free(a->obj_scene);
    a->obj_scene = NULL;
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
    for (uint32_t o = 0; o < a->n_objects; o++) rtcReleaseScene(a->obj_scene[o]);
    free(a->obj_scene);
    a->obj_scene = NULL;
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

static void ray_to_rtc(const ts_accel *a, const ts_ray *ray, struct RTCRay *r)
{
    r->org_x = ray->o.x, r->org_y = ray->o.y, r->org_z = ray->o.z;
    r->dir_x = ray->d.x, r->dir_y = ray->d.y, r->dir_z = ray->d.z;
    r->tnear = 0;
    r->tfar = ray->tmax;
    r->time = 0;
    if (a->moving) {
        double t = (ray->time - a->time0) * a->time_scale;
        r->time = (float)(t > 0 ? (t < 1 ? t : 1) : 0); /* NaN: 0 */
    }
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

/* A hit on shape `local` of instance k's object (accel.h): analytic shapes solved in world
 * space under the composed transform; triangles in object space from the ray taken there,
 * then mapped to world space. */
static void instanced_interaction(const query_ctx *q, uint32_t k, uint32_t local, uint32_t prim, const ts_ray *ray,
                                  float t, float hit_u, float hit_v, ts_interaction *si)
{
    const ts_accel *a = q->a;
    const ts_instance *in = &a->instances[k];
    uint32_t index = a->objects[in->object].first_shape + local;
    const ts_shape *s = &a->shapes[index];
    const ts_xform *x = instance_xform(q, k); /* not NULL: its callbacks reported the hit */
    if (s->type != TS_SHAPE_MESH && s->type != TS_SHAPE_CURVE) {
        ts_shape p = placed(x, s);
        ts_shape_interaction(&p, index, 0, ray, t, si);
        si->inst = k + 1;
        return;
    }
    ts_ray r = ray_to_object(x, ray);
    ts_interaction o;
    if (s->type == TS_SHAPE_CURVE)
        ts_curve_interaction(&s->curve, s->reverse_orientation, index, prim, &r, t, hit_u, hit_v, &o);
    else
        ts_shape_triangle_interaction_cached(s, &a->meshes[index].tri[prim], index, prim, &r, t, hit_u, hit_v, &o);
    const double(*m)[4] = x->m.m;
    /* p and its bound (pbrt-v3's transformed pError): |M|·e plus the double sum's and the
     * final float rounding's share, four half-ulps of the result as in shape.c. */
    double pv[3] = {o.p.x, o.p.y, o.p.z}, ev[3] = {o.p_error.x, o.p_error.y, o.p_error.z}, pw[3], ew[3];
    for (int i = 0; i < 3; i++) {
        double acc = m[i][3], mag = fabs(m[i][3]), e = 0;
        for (int j = 0; j < 3; j++) {
            acc += m[i][j] * pv[j];
            mag += fabs(m[i][j] * pv[j]);
            e += fabs(m[i][j]) * ev[j];
        }
        pw[i] = acc;
        ew[i] = e * (1 + 0x1p-50) + 0x1p-40 * mag + 0x1p-22 * fabs(acc);
    }
    *si = o;
    si->p = (ts_vec3){(float)pw[0], (float)pw[1], (float)pw[2]};
    ts_vec3 e = {(float)ew[0], (float)ew[1], (float)ew[2]};
    si->p_error = (ts_vec3){ts_next_float_up(e.x), ts_next_float_up(e.y), ts_next_float_up(e.z)};
    /* Normals by the inverse transpose: the same side of the surface as in object space. */
    ts_dvec3 n = ts_dvec3_normalize(ts_xform_normal(x, ts_dvec3_from(o.n)));
    ts_dvec3 ns = ts_dvec3_normalize(ts_xform_normal(x, ts_dvec3_from(o.ns)));
    double sign = 1;
    if (ts_dvec3_dot(ns, n) < 0) ns = ts_dvec3_scale(ns, -1), sign = -1;
    si->n = ts_dvec3_to_vec3(n);
    si->ns = ts_dvec3_to_vec3(ns);
    /* ∂n/∂u, ∂n/∂v as normals (pbrt-v3's instance transform of shading.dndu), turned with ns. */
    si->dndu = ts_dvec3_to_vec3(ts_dvec3_scale(ts_xform_normal(x, ts_dvec3_from(o.dndu)), sign));
    si->dndv = ts_dvec3_to_vec3(ts_dvec3_scale(ts_xform_normal(x, ts_dvec3_from(o.dndv)), sign));
    si->dpdu = ts_dvec3_to_vec3(ts_xform_vector(x, ts_dvec3_from(o.dpdu)));
    si->dpdv = ts_dvec3_to_vec3(ts_xform_vector(x, ts_dvec3_from(o.dpdv)));
    ts_dvec3 wo = ts_dvec3_scale(ts_dvec3_from(ray->d), -1);
    double len = ts_dvec3_length(wo);
    si->wo = ts_dvec3_to_vec3(len > 0 ? ts_dvec3_scale(wo, 1 / len) : wo);
    si->inst = k + 1;
}

static inline bool intersect(const ts_accel *a, const ts_ray *ray, bool shadow, ts_interaction *si)
{
    if (!(ray->tmax > 0) || !ray_valid(ray)) return false;
    if (__builtin_expect(a->log != NULL, 0)) log_ray(a->log, ray, TS_RAY_LOG_INTERSECT);
    query_ctx q;
    query_init(&q, a, ray, shadow);
    struct RTCRayHit rh;
    ray_to_rtc(a, ray, &rh.ray);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(a->scene, &q.rtc, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    if (rh.hit.instID[0] != RTC_INVALID_GEOMETRY_ID) {
        instanced_interaction(&q, rh.hit.instID[0] - a->n_shapes, rh.hit.geomID, rh.hit.primID, ray, rh.ray.tfar,
                              rh.hit.u, rh.hit.v, si);
        return true;
    }
    if (rh.hit.geomID >= a->n_shapes) return false;
    const ts_shape *s = &a->shapes[rh.hit.geomID];
    if (s->type == TS_SHAPE_MESH) {
        const mesh_geom *g = &a->meshes[rh.hit.geomID];
        ts_shape_triangle_interaction_cached(s, &g->tri[rh.hit.primID], rh.hit.geomID, rh.hit.primID, ray,
                                             rh.ray.tfar, rh.hit.u, rh.hit.v, si);
    } else if (s->type == TS_SHAPE_CURVE) {
        ts_curve_interaction(&s->curve, s->reverse_orientation, rh.hit.geomID, rh.hit.primID, ray, rh.ray.tfar,
                             rh.hit.u, rh.hit.v, si);
    } else {
        ts_shape_interaction(s, rh.hit.geomID, 0, ray, rh.ray.tfar, si);
    }
    return true;
}

bool ts_accel_intersect(const ts_accel *a, const ts_ray *ray, ts_interaction *si)
{
    return intersect(a, ray, false, si);
}

bool ts_accel_intersect_shadow(const ts_accel *a, const ts_ray *ray, ts_interaction *si)
{
    return intersect(a, ray, true, si);
}

bool ts_accel_occluded(const ts_accel *a, const ts_ray *ray)
{
    if (!(ray->tmax > 0)) return false;
    if (!ray_valid(ray)) return true;
    if (__builtin_expect(a->log != NULL, 0)) log_ray(a->log, ray, TS_RAY_LOG_OCCLUDED);
    query_ctx q;
    query_init(&q, a, ray, true);
    struct RTCRay r;
    ray_to_rtc(a, ray, &r);
    rtcOccluded1(a->scene, &q.rtc, &r);
    return r.tfar == -INFINITY;
}

ts_bounds3 ts_accel_bounds(const ts_accel *a) { return a->bounds; }
