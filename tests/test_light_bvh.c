/* test_light_bvh.c — light selection by the light hierarchy (lights/light_bvh.h).
 *
 * A scene of ~300 lights of every kind the hierarchy bounds — one- and two-sided emitting
 * triangles in random orientations (some forming rectangles), small emitting spheres, disks
 * and cylinders, point lights and spots — plus a distant and an infinite light, checked at
 * random shading points (with a random normal, and without one):
 *   - exactness: every light that can light the point (one of 64 stratified light samples
 *     brings radiance with a positive pdf, at a direction with |cos| > 0 to the normal) has
 *     pmf > 0;
 *   - the pmfs of all lights sum to at most 1 (1e-5: float products along paths of ≤ 64
 *     choices; less than 1 where a walk can end with no light, none of whose lights can
 *     light the point);
 *   - ts_light_bvh_sample on 2^14 stratified u values returns each light with the pmf that
 *     ts_light_bvh_pmf gives it, bit for bit, and the u values leading to a light form one
 *     interval of length pmf: counts within 2 of pmf · 2^14 (a deterministic bound, no
 *     false failures);
 *   - lights that emit nothing are never chosen; a scene of one light, of only unbounded
 *     lights, and of no light.
 * Images rendered with the hierarchy are checked against closed forms and the other
 * selections in test_integrator_strategies. */
#include <math.h>
#include <stdarg.h>
#include <setjmp.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "core/hash.h"
#include "json/scene_json.h"
#include "lights/light.h"
#include "lights/light_bvh.h"
#include "scene/scene.h"
#include "text_buffer.h"

typedef struct rng { uint64_t s; } rng;
static double rnd(rng *r)
{
    r->s = r->s * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(r->s >> 11) * 0x1p-53;
}

/* The many-lights scene (seeded): every kind of bounded light in a 10-unit cube. */
static char *many_lights_doc(uint64_t seed, int n_tris, int n_spheres, int n_points, bool unbounded,
                             const char *selection)
{
    rng r = {seed};
    text_buffer b = {0};
    text_put(&b, "{\"tessera\":1,\"camera\":{\"type\":\"perspective\",\"from\":[0,0,-20],\"to\":[0,0,0],\"fov\":40},"
            "\"film\":{\"width\":8,\"height\":8},\"integrator\":{\"type\":\"path\",\"light_sampling\":\"%s\"},"
            "\"materials\":{\"m\":{\"type\":\"diffuse\"}},\"shapes\":[",
        selection);
    const char *sep = "";
    /* triangles: each its own mesh, random orientation; every 4th two-sided, every 5th a rectangle */
    for (int i = 0; i < n_tris; i++) {
        double c[3] = {10 * rnd(&r) - 5, 10 * rnd(&r) - 5, 10 * rnd(&r) - 5};
        double a[3], bb[3];
        for (int k = 0; k < 3; k++)
            a[k] = 0.6 * rnd(&r) - 0.3, bb[k] = 0.6 * rnd(&r) - 0.3;
        double e = i % 7 == 3 ? 0 : 0.2 + 3 * rnd(&r); /* some emit nothing */
        if (i % 5 == 0) {
            text_put(&b, "%s{\"type\":\"mesh\",\"material\":\"m\",\"emission\":%g,\"two_sided\":%s,\"positions\":["
                    "%g,%g,%g, %g,%g,%g, %g,%g,%g, %g,%g,%g],\"indices\":[0,1,2, 0,2,3]}",
                sep, e, i % 4 == 0 ? "true" : "false", c[0], c[1], c[2], c[0] + a[0], c[1] + a[1], c[2] + a[2],
                c[0] + a[0] + bb[0], c[1] + a[1] + bb[1], c[2] + a[2] + bb[2], c[0] + bb[0], c[1] + bb[1],
                c[2] + bb[2]);
        } else {
            text_put(&b, "%s{\"type\":\"mesh\",\"material\":\"m\",\"emission\":%g,\"two_sided\":%s,\"positions\":["
                    "%g,%g,%g, %g,%g,%g, %g,%g,%g],\"indices\":[0,1,2]}",
                sep, e, i % 4 == 0 ? "true" : "false", c[0], c[1], c[2], c[0] + a[0], c[1] + a[1], c[2] + a[2],
                c[0] + bb[0], c[1] + bb[1], c[2] + bb[2]);
        }
        sep = ",";
    }
    for (int i = 0; i < n_spheres; i++) {
        double c[3] = {10 * rnd(&r) - 5, 10 * rnd(&r) - 5, 10 * rnd(&r) - 5};
        double nz[3] = {rnd(&r) - 0.5, rnd(&r) - 0.5, rnd(&r) - 0.5};
        if (i % 3 == 0)
            text_put(&b, "%s{\"type\":\"sphere\",\"center\":[%g,%g,%g],\"radius\":%g,\"material\":\"m\",\"emission\":%g}",
                sep, c[0], c[1], c[2], 0.05 + 0.2 * rnd(&r), 1 + 4 * rnd(&r));
        else if (i % 3 == 1)
            text_put(&b, "%s{\"type\":\"disk\",\"center\":[%g,%g,%g],\"normal\":[%g,%g,%g],\"radius\":%g,\"material\":\"m\","
                    "\"emission\":%g,\"two_sided\":%s}",
                sep, c[0], c[1], c[2], nz[0], nz[1], nz[2] + 0.01, 0.05 + 0.3 * rnd(&r), 1 + 4 * rnd(&r),
                i % 2 ? "true" : "false");
        else
            text_put(&b, "%s{\"type\":\"cylinder\",\"p0\":[%g,%g,%g],\"p1\":[%g,%g,%g],\"radius\":%g,\"material\":\"m\","
                    "\"emission\":%g}",
                sep, c[0], c[1], c[2], c[0] + nz[0], c[1] + nz[1], c[2] + nz[2] + 0.01, 0.05 + 0.1 * rnd(&r),
                1 + 4 * rnd(&r));
    }
    text_put(&b, "],\"lights\":[");
    sep = "";
    for (int i = 0; i < n_points; i++) {
        double c[3] = {10 * rnd(&r) - 5, 10 * rnd(&r) - 5, 10 * rnd(&r) - 5};
        if (i % 2)
            text_put(&b, "%s{\"type\":\"point\",\"position\":[%g,%g,%g],\"intensity\":%g}", sep, c[0], c[1], c[2],
                0.5 + rnd(&r));
        else
            text_put(&b, "%s{\"type\":\"spot\",\"from\":[%g,%g,%g],\"to\":[%g,%g,%g],\"intensity\":%g,\"cone_angle\":%g,"
                    "\"cone_delta\":%g}",
                sep, c[0], c[1], c[2], c[0] + rnd(&r) - 0.5, c[1] + rnd(&r) - 0.5, c[2] + rnd(&r) - 0.5,
                1 + rnd(&r), 5 + 40 * rnd(&r), i % 4 == 0 ? 0.0 : 5 * rnd(&r));
        sep = ",";
    }
    if (unbounded)
        text_put(&b, "%s{\"type\":\"distant\",\"irradiance\":1,\"from\":[0,1,0],\"to\":[0,0,0]},"
                "{\"type\":\"infinite\",\"radiance\":0.2}",
            sep);
    text_put(&b, "]}");
    return b.p;
}

static ts_scene *load(const char *doc)
{
    ts_scene *s = NULL;
    ts_error err = {0};
    if (ts_scene_load_text(doc, strlen(doc), NULL, "test", NULL, &s, &err)) fail_msg("scene: %s", err.message);
    return s;
}

static ts_vec3 rnd_dir(rng *r)
{
    double z = 2 * rnd(r) - 1, phi = 2 * TS_PI_D * rnd(r), s = sqrt(fmax(0, 1 - z * z));
    return (ts_vec3){(float)(s * cos(phi)), (float)(s * sin(phi)), (float)z};
}

/* Can light li bring radiance to (p, n)? Any of 8×8 stratified light samples. */
static bool can_contribute(const ts_scene *s, uint32_t li, ts_vec3 p, ts_vec3 n)
{
    ts_interaction ref = {0};
    ref.p = p;
    ref.n = ref.ns = n;
    ref.shape = ref.prim = TS_NONE;
    for (int a = 0; a < 8; a++)
        for (int b = 0; b < 8; b++) {
            ts_light_sample ls;
            if (!ts_light_sample_li(&s->lights[li], s->shapes, &ref, (ts_vec2){(a + 0.5f) / 8, (b + 0.5f) / 8}, &ls))
                continue;
            if (!(ls.pdf > 0) || ts_rgb_is_black(ls.L)) continue;
            bool has_n = n.x != 0 || n.y != 0 || n.z != 0;
            if (has_n && !(fabsf(ts_vec3_dot(ls.wi, n)) > 0)) continue;
            return true;
        }
    return false;
}

#define NU (1 << 14)

/* The checks of the header comment at n_points random (p, n) of scene s. */
static void check_scene(const ts_scene *s, uint64_t seed, int n_refs)
{
    const ts_light_distribution *d = &s->light_distribution;
    assert_true(d->bvh);
    rng r = {seed};
    uint32_t *count = calloc(s->n_lights, sizeof *count);
    float *first_pmf = calloc(s->n_lights, sizeof *first_pmf);
    assert_non_null(count);
    assert_non_null(first_pmf);
    int contributing = 0;
    for (int k = 0; k < n_refs; k++) {
        ts_vec3 p = {(float)(14 * rnd(&r) - 7), (float)(14 * rnd(&r) - 7), (float)(14 * rnd(&r) - 7)};
        ts_vec3 n = k % 3 == 2 ? (ts_vec3){0, 0, 0} : rnd_dir(&r);
        double sum = 0;
        for (uint32_t i = 0; i < s->n_lights; i++) {
            float pmf = ts_light_distribution_pmf_at(d, p, n, i);
            assert_true(pmf >= 0 && isfinite(pmf));
            sum += pmf;
            if (can_contribute(s, i, p, n)) {
                contributing++;
                if (!(pmf > 0))
                    fail_msg("light %u (type %d) lights (%g, %g, %g) n (%g, %g, %g) but has pmf 0", i,
                             (int)s->lights[i].type, p.x, p.y, p.z, n.x, n.y, n.z);
            }
        }
        /* ≤ 1: where a node's bounds reach p but neither child's does, the walk stops with no
         * light (none of them can light p) — pbrt-v4's behaviour; the counts below show the
         * sampled fraction is exactly this sum */
        bool sum_ok = sum <= 1 + 1e-5;
        memset(count, 0, s->n_lights * sizeof *count);
        for (int j = 0; j < NU; j++) {
            float pmf;
            uint32_t i = ts_light_distribution_sample_at(d, p, n, (ts_vec2){(j + 0.5f) / NU, 0.5f}, &pmf);
            if (i == TS_NONE) {
                assert_true(pmf == 0);
                continue;
            }
            assert_true(i < s->n_lights);
            float want = ts_light_distribution_pmf_at(d, p, n, i);
            if (pmf != want) fail_msg("light %u sampled with pmf %.9g, pmf() says %.9g", i, pmf, want);
            count[i]++;
        }
        for (uint32_t i = 0; i < s->n_lights; i++) {
            double want = (double)ts_light_distribution_pmf_at(d, p, n, i) * NU;
            if (!(fabs(count[i] - want) <= 2.5))
                fail_msg("light %u: chosen %u of %d times, pmf × %d = %.2f", i, count[i], NU, NU, want);
        }
        if (!sum_ok) fail_msg("pmfs at point %d sum to %.9g", k, sum);
    }
    print_message("%u lights, %d points: %d (point, light) pairs that can contribute, all with pmf > 0\n",
                  s->n_lights, n_refs, contributing);
    /* lights with no power: never */
    for (uint32_t i = 0; i < s->n_lights; i++)
        if (ts_rgb_is_black(ts_light_power(&s->lights[i], s->shapes)))
            assert_true(ts_light_distribution_pmf_at(d, (ts_vec3){0, 0, 0}, (ts_vec3){0, 0, 1}, i) == 0);
    free(count);
    free(first_pmf);
}

static void test_many_lights(void **state)
{
    (void)state;
    char *doc = many_lights_doc(7, 200, 60, 40, true, "bvh");
    ts_scene *s = load(doc);
    free(doc);
    assert_true(s->n_lights > 290);
    check_scene(s, 11, 24);
    ts_scene_destroy(s);
}

static void test_bounded_only(void **state)
{
    (void)state;
    char *doc = many_lights_doc(21, 60, 15, 10, false, "bvh");
    ts_scene *s = load(doc);
    free(doc);
    check_scene(s, 5, 16);
    ts_scene_destroy(s);
}

/* One light, only unbounded lights, no light: the edge cases of the walk. */
static void test_small(void **state)
{
    (void)state;
    const char *one =
        "{\"tessera\":1,\"camera\":{\"type\":\"perspective\",\"from\":[0,0,-5],\"to\":[0,0,0],\"fov\":40},"
        "\"film\":{\"width\":4,\"height\":4},\"integrator\":{\"type\":\"path\",\"light_sampling\":\"bvh\"},"
        "\"materials\":{\"m\":{\"type\":\"diffuse\"}},\"shapes\":[{\"type\":\"mesh\",\"material\":\"m\","
        "\"emission\":1,\"positions\":[0,0,0, 1,0,0, 0,1,0],\"indices\":[0,1,2]}]}";
    ts_scene *s = load(one);
    assert_int_equal(s->n_lights, 1);
    const ts_light_distribution *d = &s->light_distribution;
    ts_vec3 front = {0, 0, 0};
    /* the one triangle's own front side and back: pmf 1 where it lights, 0 where it cannot */
    const ts_light *l = &s->lights[0];
    ts_vec3 c = ts_vec3_scale(ts_vec3_add(ts_vec3_add(ts_dvec3_to_vec3(l->geom.tri_p[0]),
                                                      ts_dvec3_to_vec3(l->geom.tri_p[1])),
                                          ts_dvec3_to_vec3(l->geom.tri_p[2])),
                              1.0f / 3);
    ts_vec3 nf = ts_dvec3_to_vec3(l->geom.tri_n);
    front = ts_vec3_add(c, ts_vec3_scale(nf, 2));
    ts_vec3 back = ts_vec3_sub(c, ts_vec3_scale(nf, 2));
    assert_true(ts_light_distribution_pmf_at(d, front, (ts_vec3){0, 0, 0}, 0) == 1);
    float pmf;
    assert_int_equal(ts_light_distribution_sample_at(d, front, (ts_vec3){0, 0, 0}, (ts_vec2){0.3f, 0}, &pmf), 0);
    assert_true(pmf == 1);
    if (!l->two_sided) {
        assert_true(ts_light_distribution_pmf_at(d, back, (ts_vec3){0, 0, 0}, 0) == 0);
        assert_true(ts_light_distribution_sample_at(d, back, (ts_vec3){0, 0, 0}, (ts_vec2){0.3f, 0}, &pmf) == TS_NONE);
        assert_true(pmf == 0);
    }
    ts_scene_destroy(s);

    const char *only_unbounded =
        "{\"tessera\":1,\"camera\":{\"type\":\"perspective\",\"from\":[0,0,-5],\"to\":[0,0,0],\"fov\":40},"
        "\"film\":{\"width\":4,\"height\":4},\"integrator\":{\"type\":\"path\",\"light_sampling\":\"bvh\"},"
        "\"materials\":{\"m\":{\"type\":\"diffuse\"}},\"shapes\":[{\"type\":\"sphere\",\"radius\":1,\"material\":\"m\"}],"
        "\"lights\":[{\"type\":\"distant\",\"irradiance\":1,\"from\":[0,1,0],\"to\":[0,0,0]},"
        "{\"type\":\"infinite\",\"radiance\":0.2},{\"type\":\"distant\",\"irradiance\":0,\"from\":[1,0,0],\"to\":[0,0,0]}]}";
    s = load(only_unbounded);
    d = &s->light_distribution;
    assert_true(ts_light_distribution_pmf_at(d, (ts_vec3){0, 2, 0}, (ts_vec3){0, 1, 0}, 0) == 0.5f);
    assert_true(ts_light_distribution_pmf_at(d, (ts_vec3){0, 2, 0}, (ts_vec3){0, 1, 0}, 1) == 0.5f);
    assert_true(ts_light_distribution_pmf_at(d, (ts_vec3){0, 2, 0}, (ts_vec3){0, 1, 0}, 2) == 0); /* black */
    assert_int_equal(ts_light_distribution_sample_at(d, (ts_vec3){0, 2, 0}, (ts_vec3){0, 1, 0}, (ts_vec2){0.75f, 0}, &pmf), 1);
    assert_true(pmf == 0.5f);
    ts_scene_destroy(s);

    const char *none =
        "{\"tessera\":1,\"camera\":{\"type\":\"perspective\",\"from\":[0,0,-5],\"to\":[0,0,0],\"fov\":40},"
        "\"film\":{\"width\":4,\"height\":4},\"integrator\":{\"type\":\"path\",\"light_sampling\":\"bvh\"},"
        "\"materials\":{\"m\":{\"type\":\"diffuse\"}},\"shapes\":[{\"type\":\"sphere\",\"radius\":1,\"material\":\"m\"}]}";
    s = load(none);
    assert_true(ts_light_distribution_sample_at(&s->light_distribution, (ts_vec3){0, 2, 0}, (ts_vec3){0, 1, 0},
                                                (ts_vec2){0.5f, 0}, &pmf) == TS_NONE);
    assert_true(pmf == 0);
    ts_scene_destroy(s);
}

/* The hierarchy is a function of the light list: two builds of one document agree node for node. */
static void test_deterministic(void **state)
{
    (void)state;
    char *doc = many_lights_doc(9, 120, 30, 20, true, "bvh");
    ts_scene *a = load(doc), *b = load(doc);
    free(doc);
    const ts_light_bvh *ta = &a->light_distribution.tree, *tb = &b->light_distribution.tree;
    assert_int_equal(ta->n_nodes, tb->n_nodes);
    uint32_t bounded = 0;
    for (uint32_t i = 0; i < ta->n_lights; i++)
        bounded += ta->in_tree[i] == 1;
    assert_true(bounded > 100);
    assert_int_equal(ta->n_nodes, 2 * bounded - 1); /* one light a leaf */
    for (uint32_t i = 0; i < ta->n_nodes; i++)
        assert_true(ta->nodes[i].index == tb->nodes[i].index && ta->nodes[i].leaf == tb->nodes[i].leaf &&
                    ta->nodes[i].lb.phi == tb->nodes[i].lb.phi);
    ts_scene_destroy(a);
    ts_scene_destroy(b);
}

/* JSON path's default selection: bvh for two or more lights, power for one; a named one stays. */
static void test_default(void **state)
{
    (void)state;
    const char *fmt =
        "{\"tessera\":1,\"camera\":{\"type\":\"perspective\",\"from\":[0,0,-5],\"to\":[0,0,0],\"fov\":40},"
        "\"film\":{\"width\":4,\"height\":4}%s,\"materials\":{\"m\":{\"type\":\"diffuse\"}},"
        "\"shapes\":[{\"type\":\"sphere\",\"radius\":1,\"material\":\"m\"}],\"lights\":[%s]}";
    const char *one = "{\"type\":\"point\",\"position\":[0,3,0],\"intensity\":1}";
    const char *two = "{\"type\":\"point\",\"position\":[0,3,0],\"intensity\":1},"
                      "{\"type\":\"point\",\"position\":[3,0,0],\"intensity\":2}";
    struct {
        const char *integrator, *lights;
        ts_light_selection want;
    } cases[] = {
        {"", two, TS_LIGHT_SELECT_BVH},
        {"", one, TS_LIGHT_SELECT_POWER},
        {",\"integrator\":{\"type\":\"path\"}", two, TS_LIGHT_SELECT_BVH},
        {",\"integrator\":{\"type\":\"path\",\"max_depth\":3}", one, TS_LIGHT_SELECT_POWER},
        {",\"integrator\":{\"type\":\"path\",\"light_sampling\":\"power\"}", two, TS_LIGHT_SELECT_POWER},
        {",\"integrator\":{\"type\":\"path\",\"light_sampling\":\"spatial\"}", two, TS_LIGHT_SELECT_SPATIAL},
        {",\"integrator\":{\"type\":\"direct\",\"strategy\":\"one\"}", two, TS_LIGHT_SELECT_POWER},
    };
    for (size_t k = 0; k < sizeof cases / sizeof *cases; k++) {
        char doc[2048];
        snprintf(doc, sizeof doc, fmt, cases[k].integrator, cases[k].lights);
        ts_scene *s = load(doc);
        if (s->integrator.light_sampling != cases[k].want)
            fail_msg("case %zu: selection %d, want %d", k, (int)s->integrator.light_sampling, (int)cases[k].want);
        assert_int_equal(s->light_distribution.bvh, cases[k].want == TS_LIGHT_SELECT_BVH);
        ts_scene_destroy(s);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_many_lights),
        cmocka_unit_test(test_bounded_only),
        cmocka_unit_test(test_small),
        cmocka_unit_test(test_deterministic),
        cmocka_unit_test(test_default),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
