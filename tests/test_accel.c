/* test_accel.c — the Embree scene: nearest hits against a brute-force loop over the
 * shapes' own double-precision tests, occlusion, tmax, skip ids, rays leaving a mesh,
 * empty scenes, concurrent queries.
 *
 * Embree's float triangle test and our double one can disagree on a ray that passes
 * within float round-off of a triangle edge, or when two surfaces are within round-off
 * of each other along the ray, or a hit sits at tmax; such disagreements are counted and
 * must be explained by one of those, and rare. Random streams are PCG32 with fixed seeds. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <string.h>

#include "core/hash.h"
#include "core/transform.h"
#include "geometry/accel.h"
#include "geometry/shape.h"

static double rnd(ts_pcg32 *g) { return ts_pcg32_double(g); }
static double rnd_range(ts_pcg32 *g, double a, double b) { return a + (b - a) * rnd(g); }
static ts_dvec3 rnd_unit(ts_pcg32 *g)
{
    double z = 1 - 2 * rnd(g), phi = 2 * TS_PI_D * rnd(g), r = sqrt(fmax(0, 1 - z * z));
    return (ts_dvec3){r * cos(phi), r * sin(phi), z};
}

/* ---- the test scene ----
 * 0: mesh — floor quad y = 0 over [-5, 5]² (prims 0, 1) and a tetrahedron (prims 2–5)
 * 1: sphere r = 1 at (−2, 1, 0)
 * 2: disk r = 1, r_i = 0.3 at (0, 1, −2.5) facing +z
 * 3: cylinder r = 0.5 from (2, 0, −2) up 2 along +y
 * 4: mesh — one slanted triangle
 * 5: mesh — empty (no triangles: not attached, never hit) */
#define N_SHAPES 6

static const float floor_tetra_p[] = {-5, 0, -5, 5, 0, -5, 5, 0, 5, -5, 0, 5,
                                      1.5f, 0.2f, 1.5f, 3, 0.2f, 1.5f, 2.2f, 0.2f, 3, 2.2f, 1.8f, 2};
static const uint32_t floor_tetra_i[] = {0, 3, 2, 0, 2, 1, 4, 5, 6, 4, 7, 5, 5, 7, 6, 6, 7, 4};
static const float slant_p[] = {-3, 2, 2, -1, 3, 3, -2, 2.5f, 4.5f};
static const uint32_t slant_i[] = {0, 1, 2};

static void build_scene(ts_shape s[N_SHAPES])
{
    memset(s, 0, N_SHAPES * sizeof *s);
    s[0].type = TS_SHAPE_MESH;
    s[0].to_world = ts_xform_identity();
    s[0].mesh = (ts_mesh){8, 6, floor_tetra_p, NULL, NULL, floor_tetra_i};
    s[1].type = TS_SHAPE_SPHERE;
    s[1].to_world = ts_xform_translate((ts_dvec3){-2, 1, 0});
    s[1].sphere.radius = 1;
    s[2].type = TS_SHAPE_DISK;
    s[2].to_world = ts_xform_frame((ts_dvec3){0, 1, -2.5}, (ts_dvec3){0, 0, 1});
    s[2].disk.radius = 1;
    s[2].disk.inner_radius = 0.3;
    s[3].type = TS_SHAPE_CYLINDER;
    s[3].to_world = ts_xform_frame((ts_dvec3){2, 0, -2}, (ts_dvec3){0, 1, 0});
    s[3].cylinder.radius = 0.5;
    s[3].cylinder.height = 2;
    s[4].type = TS_SHAPE_MESH;
    s[4].to_world = ts_xform_identity();
    s[4].mesh = (ts_mesh){3, 1, slant_p, NULL, NULL, slant_i};
    s[5].type = TS_SHAPE_MESH;
    s[5].to_world = ts_xform_identity();
}

typedef struct bf_hit {
    bool hit;
    uint32_t shape, prim;
    float t;
} bf_hit;

/* Brute force: every shape's own test, nearest first, honouring the ray's skip ids. */
static bf_hit brute_force(const ts_shape *s, uint32_t n, const ts_ray *r)
{
    bf_hit b = {false, TS_NONE, TS_NONE, r->tmax};
    for (uint32_t i = 0; i < n; i++) {
        float t;
        if (s[i].type == TS_SHAPE_MESH) {
            for (uint32_t k = 0; k < s[i].mesh.n_triangles; k++) {
                if (i == r->skip_shape && k == r->skip_prim) continue;
                if (r->skip_shape != TS_NONE && !ts_shape_triangle_ahead(&s[i], k, r)) continue;
                if (ts_shape_triangle_intersect(&s[i], k, r, b.t, &t)) b = (bf_hit){true, i, k, t};
            }
        } else if (ts_shape_intersect(&s[i], r, b.t, &t)) {
            b = (bf_hit){true, i, 0, t};
        }
    }
    return b;
}

/* Smallest barycentric coordinate of the ray's crossing of triangle prim (edge closeness). */
static double min_barycentric(const ts_shape *s, uint32_t prim, const ts_ray *r)
{
    const float *p = s->mesh.p;
    const uint32_t *ix = s->mesh.index + 3 * prim;
    ts_dvec3 v[3];
    for (int k = 0; k < 3; k++) v[k] = (ts_dvec3){p[3 * ix[k]], p[3 * ix[k] + 1], p[3 * ix[k] + 2]};
    ts_dvec3 o = ts_dvec3_from(r->o), d = ts_dvec3_from(r->d);
    ts_dvec3 e1 = ts_dvec3_sub(v[1], v[0]), e2 = ts_dvec3_sub(v[2], v[0]), pv = ts_dvec3_cross(d, e2);
    double det = ts_dvec3_dot(e1, pv);
    if (det == 0) return 0;
    ts_dvec3 tv = ts_dvec3_sub(o, v[0]), qv = ts_dvec3_cross(tv, e1);
    double u = ts_dvec3_dot(tv, pv) / det, w = ts_dvec3_dot(d, qv) / det;
    return fmin(fabs(u), fmin(fabs(w), fabs(1 - u - w)));
}

/* Float round-off of Embree's triangle test: edges within 1e-5 (barycentric), distances
 * within 1e-5 relative — some 100 float ulps, far beyond what it needs, far below what
 * a real disagreement would show. */
#define EDGE_TOL 1e-5

static bool explained(const ts_shape *s, const ts_ray *r, bf_hit b, bool a_hit, const ts_interaction *si)
{
    if (b.hit && s[b.shape].type == TS_SHAPE_MESH && min_barycentric(&s[b.shape], b.prim, r) < EDGE_TOL) return true;
    if (a_hit && s[si->shape].type == TS_SHAPE_MESH && min_barycentric(&s[si->shape], si->prim, r) < EDGE_TOL)
        return true;
    if (b.hit && a_hit && fabs(b.t - si->t) <= EDGE_TOL * b.t) return true; /* two surfaces at one distance */
    float t = b.hit ? b.t : (a_hit ? si->t : 0);
    if (isfinite(r->tmax) && fabs(t - r->tmax) <= EDGE_TOL * r->tmax) return true; /* at tmax */
    return false;
}

static ts_ray rnd_scene_ray(ts_pcg32 *g)
{
    ts_vec3 o = {(float)rnd_range(g, -6, 6), (float)rnd_range(g, -1, 5), (float)rnd_range(g, -6, 6)};
    ts_dvec3 d = rnd_unit(g);
    float tmax = rnd(g) < 0.5 ? INFINITY : (float)rnd_range(g, 0.01, 12);
    return ts_ray_make(o, ts_dvec3_to_vec3(d), tmax);
}

#define N_RANDOM 100000

static void test_random_rays(void **state)
{
    (void)state;
    ts_shape s[N_SHAPES];
    build_scene(s);
    ts_error err = {0};
    ts_accel *a = ts_accel_create(s, N_SHAPES, &err);
    if (!a) fail_msg("%s", err.message);
    ts_pcg32 g;
    ts_pcg32_seed(&g, 31, 1);
    long hits = 0, per_shape[N_SHAPES] = {0}, disagree = 0;
    for (int i = 0; i < N_RANDOM; i++) {
        ts_ray r = rnd_scene_ray(&g);
        ts_interaction si;
        bool hit = ts_accel_intersect(a, &r, &si);
        bool occ = ts_accel_occluded(a, &r);
        bf_hit b = brute_force(s, N_SHAPES, &r);
        if (occ != hit && !explained(s, &r, b, hit, &si))
            fail_msg("occluded %d but intersect %d (ray %d)", occ, hit, i);
        if (hit) {
            hits++;
            per_shape[si.shape]++;
            /* tmax respected (allow the float rounding of t). */
            assert_true(si.t > 0 && si.t <= r.tmax * (1 + 0x1p-20f));
            assert_true(ts_vec3_is_finite(si.p) && ts_vec3_is_finite(si.n));
            assert_true(fabsf(ts_vec3_length(si.n) - 1) < 1e-6f);
        }
        bool same = hit == b.hit && (!hit || (si.shape == b.shape && si.prim == b.prim));
        if (!same) {
            disagree++;
            if (!explained(s, &r, b, hit, &si))
                fail_msg("ray %d: accel %d (shape %u prim %u t %g), brute force %d (shape %u prim %u t %g)", i, hit,
                         hit ? si.shape : 0, hit ? si.prim : 0, hit ? si.t : 0, b.hit, b.shape, b.prim, b.t);
            continue;
        }
        /* Same surface: the same t. Brute force's is the double solve rounded to float; a
         * triangle hit's t is Embree's float t, whose round-off is a few ulps of the ray's
         * coordinates (its test works relative to the origin), not of t: 1e-6 of t plus of
         * max|o|/|d| is some 16 such ulps. */
        float o_max = fmaxf(fabsf(r.o.x), fmaxf(fabsf(r.o.y), fabsf(r.o.z)));
        if (hit && !(fabsf(si.t - b.t) <= 1e-6f * (b.t + o_max / ts_vec3_length(r.d))))
            fail_msg("ray %d: t %g vs %g", i, si.t, b.t);
    }
    print_message("  %d rays: %ld hits (mesh %ld, sphere %ld, disk %ld, cylinder %ld, triangle %ld), "
                  "%ld edge-case disagreements with brute force\n",
                  N_RANDOM, hits, per_shape[0], per_shape[1], per_shape[2], per_shape[3], per_shape[4], disagree);
    for (int k = 0; k < 5; k++) assert_true(per_shape[k] > 100);
    assert_int_equal(per_shape[5], 0);
    /* A float ray within 1e-5 of an edge: expect ~1e-5 of the rays, allow 1e-3. */
    assert_true(disagree <= N_RANDOM / 1000);
    ts_bounds3 bb = ts_accel_bounds(a);
    assert_true(bb.lo.x <= -5 && bb.lo.y <= 0 && bb.lo.z <= -5 && bb.hi.x >= 5 && bb.hi.y >= 3 && bb.hi.z >= 5);
    ts_accel_destroy(a);
}

static void test_nearest_and_tmax(void **state)
{
    (void)state;
    ts_shape s[N_SHAPES];
    build_scene(s);
    ts_accel *a = ts_accel_create(s, N_SHAPES, NULL);
    assert_non_null(a);
    ts_interaction si;
    /* Down onto the sphere's top (y = 2) above the floor (y = 0): the sphere is nearer. */
    ts_ray r = ts_ray_make((ts_vec3){-2, 5, 0}, (ts_vec3){0, -1, 0}, INFINITY);
    assert_true(ts_accel_intersect(a, &r, &si));
    assert_int_equal(si.shape, 1);
    assert_true(si.t == 3);
    assert_true(si.n.y > 0.99999f);
    /* tmax just short of the sphere: nothing; just past the floor: the sphere. */
    r.tmax = 3;
    assert_false(ts_accel_intersect(a, &r, &si));
    assert_false(ts_accel_occluded(a, &r));
    r.tmax = nextafterf(3, 4);
    assert_true(ts_accel_intersect(a, &r, &si));
    assert_true(ts_accel_occluded(a, &r));
    /* From inside the sphere: its far side (y = 0 is also where the floor is: the sphere
     * touches the floor at (−2, 0, 0) — a ray straight down must hit one of them at t = 1). */
    r = ts_ray_make((ts_vec3){-2, 1, 0}, (ts_vec3){0, -1, 0}, INFINITY);
    assert_true(ts_accel_intersect(a, &r, &si));
    assert_true(si.shape == 1 || si.shape == 0);
    assert_true(fabsf(si.t - 1) < 1e-6f);
    /* Through the disk's hole onto nothing behind it, and onto its ring. */
    r = ts_ray_make((ts_vec3){0, 1, 3}, (ts_vec3){0, 0, -1}, INFINITY);
    assert_false(ts_accel_intersect(a, &r, &si));
    r.o.x = 0.5f;
    assert_true(ts_accel_intersect(a, &r, &si));
    assert_int_equal(si.shape, 2);
    assert_true(si.t == 5.5f);
    assert_true(si.n.z > 0.99999f);
    /* Into the cylinder's side; down its axis onto the floor. */
    r = ts_ray_make((ts_vec3){2, 1.5f, 3}, (ts_vec3){0, 0, -1}, INFINITY);
    assert_true(ts_accel_intersect(a, &r, &si));
    assert_int_equal(si.shape, 3);
    assert_true(fabsf(si.t - 4.5f) < 1e-6f);
    r = ts_ray_make((ts_vec3){2, 5, -2}, (ts_vec3){0, -1, 0}, INFINITY);
    assert_true(ts_accel_intersect(a, &r, &si));
    assert_int_equal(si.shape, 0);
    assert_true(si.t == 5);
    /* The tetrahedron's apex region from above: shape 0, a tetrahedron prim (≥ 2). */
    r = ts_ray_make((ts_vec3){2.2f, 5, 2.1f}, (ts_vec3){0, -1, 0}, INFINITY);
    assert_true(ts_accel_intersect(a, &r, &si));
    assert_int_equal(si.shape, 0);
    assert_true(si.prim >= 2);
    /* The slanted triangle, shape 4. */
    r = ts_ray_make((ts_vec3){-2, 10, 3.2f}, (ts_vec3){0, -1, 0}, INFINITY);
    assert_true(ts_accel_intersect(a, &r, &si));
    assert_int_equal(si.shape, 4);
    assert_int_equal(si.prim, 0);
    ts_accel_destroy(a);
}

static void test_skip_ids(void **state)
{
    (void)state;
    ts_shape s[N_SHAPES];
    build_scene(s);
    ts_accel *a = ts_accel_create(s, N_SHAPES, NULL);
    assert_non_null(a);
    ts_interaction si;
    ts_ray r = ts_ray_make((ts_vec3){-4, 3, 0.5f}, (ts_vec3){0, -1, 0}, INFINITY);
    assert_true(ts_accel_intersect(a, &r, &si));
    assert_int_equal(si.shape, 0);
    uint32_t floor_prim = si.prim;
    assert_true(floor_prim < 2);
    /* Naming that triangle: the ray passes through it; there is nothing below. */
    r.skip_shape = 0, r.skip_prim = floor_prim;
    assert_false(ts_accel_intersect(a, &r, &si));
    assert_false(ts_accel_occluded(a, &r));
    /* Naming the other floor triangle, or the same prim of another shape: still hit. */
    r.skip_prim = 1 - floor_prim;
    assert_true(ts_accel_intersect(a, &r, &si));
    assert_int_equal(si.prim, floor_prim);
    assert_true(ts_accel_occluded(a, &r));
    r.skip_shape = 4, r.skip_prim = floor_prim;
    assert_true(ts_accel_intersect(a, &r, &si));
    assert_true(ts_accel_occluded(a, &r));
    /* Rays spawned from the floor, up or down, never hit it again (nothing else is there). */
    ts_ray down = ts_ray_make((ts_vec3){-4.5f, 2, -4.5f}, (ts_vec3){0, -1, 0}, INFINITY);
    assert_true(ts_accel_intersect(a, &down, &si));
    assert_int_equal(si.shape, 0);
    ts_ray up = ts_spawn_ray(&si, s, (ts_vec3){0.1f, 1, 0.1f});
    assert_int_equal(up.skip_shape, 0);
    assert_int_equal(up.skip_prim, si.prim);
    ts_interaction si2;
    assert_false(ts_accel_intersect(a, &up, &si2));
    assert_false(ts_accel_occluded(a, &up));
    ts_ray under = ts_spawn_ray(&si, s, (ts_vec3){0.1f, -1, 0.1f});
    assert_false(ts_accel_intersect(a, &under, &si2));
    assert_false(ts_accel_occluded(a, &under));
    ts_accel_destroy(a);
}

/* Two coplanar triangles sharing an edge, in a random plane: rays leaving one close to the
 * shared edge never hit either, through Embree (skip ids + the filter's double check). */
/* A mesh of world-space positions p and indices idx, without normals or uvs. */
static ts_shape world_mesh(uint32_t n_vertices, uint32_t n_triangles, const float *p, const uint32_t *idx)
{
    ts_shape m;
    memset(&m, 0, sizeof m);
    m.type = TS_SHAPE_MESH;
    m.to_world = ts_xform_identity();
    m.mesh = (ts_mesh){n_vertices, n_triangles, p, NULL, NULL, idx};
    return m;
}

static void test_quad_spawn(void **state)
{
    (void)state;
    ts_pcg32 g;
    ts_pcg32_seed(&g, 32, 1);
    long rays = 0, raw_rehits = 0, raw_rays = 0;
    for (int q = 0; q < 10; q++) {
        double L = exp(rnd_range(&g, log(1e-3), log(1e3)));
        ts_dvec3 c = ts_dvec3_scale(rnd_unit(&g), fmin(1e3, 100 * L) * rnd(&g));
        ts_dvec3 eu = rnd_unit(&g);
        ts_dvec3 ev = ts_dvec3_normalize(ts_dvec3_cross(eu, rnd_unit(&g)));
        eu = ts_dvec3_scale(eu, L), ev = ts_dvec3_scale(ev, L);
        ts_dvec3 corners[4] = {ts_dvec3_sub(ts_dvec3_sub(c, eu), ev), ts_dvec3_sub(ts_dvec3_add(c, eu), ev),
                               ts_dvec3_add(ts_dvec3_add(c, eu), ev), ts_dvec3_add(ts_dvec3_sub(c, eu), ev)};
        float p[12];
        for (int k = 0; k < 4; k++) {
            ts_vec3 f = ts_dvec3_to_vec3(corners[k]);
            p[3 * k] = f.x, p[3 * k + 1] = f.y, p[3 * k + 2] = f.z;
        }
        const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
        ts_shape quad = world_mesh(4, 2, p, idx);
        ts_accel *a = ts_accel_create(&quad, 1, NULL);
        assert_non_null(a);
        for (int h = 0; h < 10; h++) {
            /* A point at 10^[-7, -2]·L from the diagonal 0–2, on either side. */
            double along = rnd_range(&g, 0.05, 0.95), off = exp(rnd_range(&g, log(1e-7), log(1e-2)));
            ts_dvec3 dir = ts_dvec3_normalize(ts_dvec3_sub(eu, ev));
            if (h % 2) dir = ts_dvec3_scale(dir, -1);
            ts_dvec3 P = ts_dvec3_add(corners[0], ts_dvec3_scale(ts_dvec3_sub(corners[2], corners[0]), along));
            P = ts_dvec3_add(P, ts_dvec3_scale(dir, off * L));
            ts_vec3 of = ts_dvec3_to_vec3(ts_dvec3_add(P, ts_dvec3_scale(rnd_unit(&g), 3 * L)));
            ts_ray r = ts_ray_make(of, ts_dvec3_to_vec3(ts_dvec3_sub(P, ts_dvec3_from(of))), INFINITY);
            ts_interaction si, s2;
            if (!ts_accel_intersect(a, &r, &si)) continue;
            for (int i = 0; i < 20000; i++) {
                ts_vec3 n = si.n, b1, b2;
                ts_coordinate_system(n, &b1, &b2);
                float z = ts_pcg32_float(&g), phi = 2 * TS_PI * ts_pcg32_float(&g), rr = sqrtf(fmaxf(0, 1 - z * z));
                float side = i % 2 ? 1.0f : -1.0f;
                ts_vec3 d = ts_vec3_add(ts_vec3_add(ts_vec3_scale(b1, rr * cosf(phi)), ts_vec3_scale(b2, rr * sinf(phi))),
                                        ts_vec3_scale(n, side * z));
                ts_ray sr = ts_spawn_ray(&si, &quad, d);
                rays++;
                if (ts_accel_intersect(a, &sr, &s2))
                    fail_msg("ray leaving prim %u hit prim %u at t = %g (L = %g, offset %g·L)", si.prim, s2.prim, s2.t,
                             L, off);
                assert_false(ts_accel_occluded(a, &sr));
                /* The same ray without skip ids: Embree alone (informational). */
                if (i < 2000) {
                    sr.skip_shape = sr.skip_prim = TS_NONE;
                    raw_rays++;
                    raw_rehits += ts_accel_intersect(a, &sr, &s2);
                }
            }
        }
        ts_accel_destroy(a);
    }
    print_message("  %ld rays leaving a quad near its diagonal: no hit (without skip ids Embree alone re-hit "
                  "%ld of %ld)\n",
                  rays, raw_rehits, raw_rays);
    assert_true(rays > 0);
}

static void test_empty_scene(void **state)
{
    (void)state;
    ts_error err = {0};
    ts_accel *a = ts_accel_create(NULL, 0, &err);
    assert_non_null(a);
    ts_ray r = ts_ray_make((ts_vec3){0, 0, 0}, (ts_vec3){0, 0, 1}, INFINITY);
    ts_interaction si;
    assert_false(ts_accel_intersect(a, &r, &si));
    assert_false(ts_accel_occluded(a, &r));
    assert_true(ts_bounds3_is_empty(ts_accel_bounds(a)));
    ts_accel_destroy(a);
    ts_accel_destroy(NULL);
    /* Only an empty mesh: the same. */
    ts_shape e;
    memset(&e, 0, sizeof e);
    e.type = TS_SHAPE_MESH;
    e.to_world = ts_xform_identity();
    a = ts_accel_create(&e, 1, &err);
    assert_non_null(a);
    assert_false(ts_accel_intersect(a, &r, &si));
    assert_false(ts_accel_occluded(a, &r));
    ts_accel_destroy(a);
}

static void test_embree_error(void **state)
{
    (void)state;
    /* A shared index buffer at an address that is not 4-byte aligned is refused by
     * Embree: the failure comes back as a sentence, nothing is leaked. */
    static uint32_t storage[8];
    ts_shape m;
    memset(&m, 0, sizeof m);
    m.type = TS_SHAPE_MESH;
    m.to_world = ts_xform_identity();
    m.mesh = (ts_mesh){3, 1, slant_p, NULL, NULL, (const uint32_t *)((const char *)storage + 1)};
    ts_error err = {0};
    ts_accel *a = ts_accel_create(&m, 1, &err);
    assert_null(a);
    assert_int_equal(err.status, TS_ERR_INTERNAL);
    assert_non_null(strstr(err.message, "Embree"));
    print_message("  error: %s\n", err.message);
}

/* ---- concurrent queries ---- */

#define MT_THREADS 4
#define MT_RAYS 20000

typedef struct mt_job {
    const ts_accel *a;
    const ts_ray *rays;
    const ts_interaction *want;
    const bool *want_hit;
    int first, count, mismatches;
} mt_job;

static void *mt_worker(void *arg)
{
    mt_job *j = arg;
    for (int i = j->first; i < j->first + j->count; i++) {
        ts_interaction si;
        bool hit = ts_accel_intersect(j->a, &j->rays[i], &si);
        if (hit != j->want_hit[i] || (hit && (si.shape != j->want[i].shape || si.prim != j->want[i].prim ||
                                              si.t != j->want[i].t || si.p.x != j->want[i].p.x)))
            j->mismatches++;
        if (ts_accel_occluded(j->a, &j->rays[i]) != j->want_hit[i]) j->mismatches++;
    }
    return NULL;
}

static void test_concurrent(void **state)
{
    (void)state;
    ts_shape s[N_SHAPES];
    build_scene(s);
    ts_accel *a = ts_accel_create(s, N_SHAPES, NULL);
    assert_non_null(a);
    static ts_ray rays[MT_RAYS];
    static ts_interaction want[MT_RAYS];
    static bool want_hit[MT_RAYS];
    ts_pcg32 g;
    ts_pcg32_seed(&g, 33, 1);
    for (int i = 0; i < MT_RAYS; i++) {
        rays[i] = rnd_scene_ray(&g);
        want_hit[i] = ts_accel_intersect(a, &rays[i], &want[i]);
        /* occluded and intersect agree on these rays except at edges; keep only clean ones */
        if (ts_accel_occluded(a, &rays[i]) != want_hit[i]) rays[i].tmax = 0, want_hit[i] = false;
    }
    pthread_t th[MT_THREADS];
    mt_job jobs[MT_THREADS];
    for (int k = 0; k < MT_THREADS; k++) {
        jobs[k] = (mt_job){a, rays, want, want_hit, k * (MT_RAYS / MT_THREADS), MT_RAYS / MT_THREADS, 0};
        assert_int_equal(pthread_create(&th[k], NULL, mt_worker, &jobs[k]), 0);
    }
    int mism = 0;
    for (int k = 0; k < MT_THREADS; k++) {
        pthread_join(th[k], NULL);
        mism += jobs[k].mismatches;
    }
    /* Queries are pure: the same answers, bit for bit, from any thread. */
    assert_int_equal(mism, 0);
    ts_accel_destroy(a);
}

/* What the accel reports holding (ts_accel_memory_get, for bench/memory.c): the caches of
 * exactly the non-empty meshes' triangles, and Embree's bytes from its memory monitor —
 * at least the two copied vertex buffers, at most its peak, and more for more triangles. */
static void test_memory(void **state)
{
    (void)state;
    ts_shape s[N_SHAPES];
    build_scene(s);
    ts_error err = {0};
    ts_accel *a = ts_accel_create(s, N_SHAPES, &err);
    assert_non_null(a);
    ts_accel_memory m = {0};
    ts_accel_memory_get(a, &m);
    assert_int_equal(m.tri_cache_bytes, (6 + 1) * sizeof(ts_tri_cache)); /* meshes 0 and 4; 5 is empty */
    assert_true(m.embree_bytes >= (8 + 3) * 3 * sizeof(float));
    assert_true(m.embree_peak_bytes >= m.embree_bytes);
    ts_accel_destroy(a);
    /* A 20 000-triangle grid: Embree holds more, at least its copied vertices. */
    enum { SIDE = 100 };
    static float p[3 * (SIDE + 1) * (SIDE + 1)];
    static uint32_t idx[6 * SIDE * SIDE];
    for (int i = 0; i < (SIDE + 1) * (SIDE + 1); i++) {
        p[3 * i] = (float)(i % (SIDE + 1)), p[3 * i + 1] = 0, p[3 * i + 2] = (float)(i / (SIDE + 1));
    }
    for (int y = 0, k = 0; y < SIDE; y++)
        for (int x = 0; x < SIDE; x++) {
            uint32_t c = (uint32_t)(y * (SIDE + 1) + x);
            uint32_t t[6] = {c, c + 1, c + SIDE + 2, c, c + SIDE + 2, c + SIDE + 1};
            for (int j = 0; j < 6; j++) idx[k++] = t[j];
        }
    ts_shape g;
    memset(&g, 0, sizeof g);
    g.type = TS_SHAPE_MESH;
    g.to_world = ts_xform_identity();
    g.mesh = (ts_mesh){(SIDE + 1) * (SIDE + 1), 2 * SIDE * SIDE, p, NULL, NULL, idx};
    a = ts_accel_create(&g, 1, &err);
    assert_non_null(a);
    ts_accel_memory big = {0};
    ts_accel_memory_get(a, &big);
    assert_int_equal(big.tri_cache_bytes, 2 * SIDE * SIDE * sizeof(ts_tri_cache));
    assert_true(big.embree_bytes >= sizeof p);
    assert_true(big.embree_bytes > m.embree_bytes);
    assert_true(big.embree_peak_bytes >= big.embree_bytes);
    print_message("  Embree: %zu bytes held (%zu at its peak) for %d triangles\n", big.embree_bytes,
                  big.embree_peak_bytes, 2 * SIDE * SIDE);
    ts_accel_destroy(a);
}

/* The float hit refinement (shape.c, "the accelerator's hits"): a hit's p, evaluated from
 * Embree's barycentrics, is within its p_error of the float triangle's plane — the
 * distance |(p − p0)·n̂|, n̂ the unit normal of the float vertices in long double, is at
 * most |n|·p_error, the spawn offset (interaction.h) — and a ray spawned from it starts
 * strictly on the side it is sent to. Triangles 1e-4 … 1e4 across, up to 1e3 from the
 * origin (100 of their sizes), rays from 3 sizes away at points anywhere in them, a tenth
 * within 1e-6 of an edge. The bound is a worst case: the figure printed is the largest
 * distance seen over its bound (shrinking p_error by 8 makes the test fail). */
static void test_hit_bound(void **state)
{
    (void)state;
    ts_pcg32 g;
    ts_pcg32_seed(&g, 33, 1);
    long hits = 0, rays = 0;
    long double worst = 0;
    const double sizes[5] = {1e-4, 1e-2, 1, 1e2, 1e4};
    for (int si_ = 0; si_ < 5; si_++)
        for (int k = 0; k < 20; k++) {
            double L = sizes[si_];
            ts_dvec3 c = ts_dvec3_scale(rnd_unit(&g), fmin(1e3, 100 * L) * rnd(&g));
            float p[9];
            for (int v = 0; v < 3; v++) {
                ts_vec3 f = ts_dvec3_to_vec3(ts_dvec3_add(c, ts_dvec3_scale(rnd_unit(&g), L)));
                p[3 * v] = f.x, p[3 * v + 1] = f.y, p[3 * v + 2] = f.z;
            }
            const uint32_t idx[3] = {0, 1, 2};
            ts_shape tri = world_mesh(3, 1, p, idx);
            ts_accel *a = ts_accel_create(&tri, 1, NULL);
            assert_non_null(a);
            long double P0[3] = {p[0], p[1], p[2]}, E1[3], E2[3], N[3];
            for (int j = 0; j < 3; j++) E1[j] = p[3 + j] - P0[j], E2[j] = p[6 + j] - P0[j];
            N[0] = E1[1] * E2[2] - E1[2] * E2[1];
            N[1] = E1[2] * E2[0] - E1[0] * E2[2];
            N[2] = E1[0] * E2[1] - E1[1] * E2[0];
            long double nl = sqrtl(N[0] * N[0] + N[1] * N[1] + N[2] * N[2]);
            if (!(nl > 0)) continue;
            for (int j = 0; j < 3; j++) N[j] /= nl;
            for (int h = 0; h < 200; h++) {
                double b1 = rnd(&g), b2 = rnd(&g);
                if (b1 + b2 > 1) b1 = 1 - b1, b2 = 1 - b2;
                if (h % 10 == 0) b1 = 1e-6 * rnd(&g); /* near the edge p0–p2 */
                ts_dvec3 P = {P0[0] + b1 * E1[0] + b2 * E2[0], P0[1] + b1 * E1[1] + b2 * E2[1],
                              P0[2] + b1 * E1[2] + b2 * E2[2]};
                ts_vec3 o = ts_dvec3_to_vec3(ts_dvec3_add(P, ts_dvec3_scale(rnd_unit(&g), 3 * L)));
                ts_ray r = ts_ray_make(o, ts_dvec3_to_vec3(ts_dvec3_sub(P, ts_dvec3_from(o))), INFINITY);
                ts_interaction si;
                if (!ts_accel_intersect(a, &r, &si)) continue;
                hits++;
                long double q[3] = {si.p.x, si.p.y, si.p.z}, dist = 0;
                for (int j = 0; j < 3; j++) dist += (q[j] - P0[j]) * N[j];
                long double off = fabsl((long double)si.n.x) * si.p_error.x +
                                  fabsl((long double)si.n.y) * si.p_error.y +
                                  fabsl((long double)si.n.z) * si.p_error.z;
                if (fabsl(dist) > off)
                    fail_msg("p off its plane by %Lg, bound %Lg (size %g, at (%g %g %g))", fabsl(dist), off, L,
                             si.p.x, si.p.y, si.p.z);
                if (off > 0 && fabsl(dist) / off > worst) worst = fabsl(dist) / off;
                for (int side = -1; side <= 1; side += 2) {
                    ts_vec3 d = ts_vec3_scale(si.n, (float)side);
                    ts_dvec3 t = rnd_unit(&g);
                    d = ts_vec3_add(d, ts_vec3_scale(ts_dvec3_to_vec3(t), 0.9f));
                    if (ts_vec3_dot(d, si.n) * side <= 0) continue;
                    ts_ray sr = ts_spawn_ray(&si, &tri, d);
                    long double so = 0;
                    so += ((long double)sr.o.x - P0[0]) * N[0];
                    so += ((long double)sr.o.y - P0[1]) * N[1];
                    so += ((long double)sr.o.z - P0[2]) * N[2];
                    rays++;
                    if (!(so * side * (ts_vec3_dot(si.n, (ts_vec3){(float)N[0], (float)N[1], (float)N[2]}) > 0 ? 1 : -1) >
                          0))
                        fail_msg("spawned origin on the wrong side: %Lg (side %d, size %g)", so, side, L);
                }
            }
            ts_accel_destroy(a);
        }
    print_message("  %ld hits: p within p_error of the plane (largest distance / bound %.3Lg); %ld spawned "
                  "origins on their side\n",
                  hits, worst, rays);
    assert_true(hits > 15000);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_nearest_and_tmax), cmocka_unit_test(test_random_rays),
        cmocka_unit_test(test_skip_ids),         cmocka_unit_test(test_quad_spawn),
        cmocka_unit_test(test_empty_scene),      cmocka_unit_test(test_embree_error),
        cmocka_unit_test(test_concurrent),       cmocka_unit_test(test_memory),
        cmocka_unit_test(test_hit_bound),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
