/* test_bump.c — bump mapping with pbrt-v3's ∂n/∂u terms: the shapes' normal derivatives
 * (geometry/shape.h), Material::Bump's d·∂n/∂u and unit mesh tangents, and bump maps of
 * mixed materials (materials/material.h, ts_material_bump).
 *
 * Every check is deterministic, against a closed form or a central difference, with
 * tolerances from float rounding (stated where they are set). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "geometry/accel.h"
#include "materials/bsdf.h"
#include "materials/material.h"
#include "scene/scene.h"
#include "json/scene_json.h"
#include "load/scene_load.h"
#include "textures/texture.h"

#define HEAD "{\"tessera\":1,\"camera\":{\"from\":[0,0,9],\"to\":[0,0,0]},\"film\":{\"width\":4,\"height\":4},"
#define PI_D 3.14159265358979323846
/* A textured material "m": interactions of a scene without textures carry no dn/du
 * (geometry/shape.h), nothing there reads them. */
#define TEXTURED_M                                                                                           \
    "\"textures\":{\"t\":{\"type\":\"checkerboard\"}},\"materials\":{\"m\":{\"type\":\"diffuse\",\"reflectance\":\"t\"}},"

static ts_scene *load(const char *doc)
{
    ts_scene *s = NULL;
    ts_error err = {0};
    if (ts_scene_load_text(doc, strlen(doc), NULL, "bump", NULL, &s, &err)) fail_msg("%s", err.message);
    return s;
}

/* The hit of the ray from o towards target. */
static ts_interaction hit_towards(const ts_scene *s, ts_vec3 o, ts_vec3 target)
{
    ts_ray r = ts_ray_make(o, ts_vec3_sub(target, o), INFINITY);
    ts_interaction si;
    assert_true(ts_accel_intersect(s->accel, &r, &si));
    return si;
}

static void assert_near(ts_vec3 got, ts_vec3 want, float tol, const char *what)
{
    float d = ts_vec3_length(ts_vec3_sub(got, want));
    if (!(d <= tol))
        fail_msg("%s: (%.7g, %.7g, %.7g), want (%.7g, %.7g, %.7g) (off by %g > %g)", what, got.x, got.y, got.z,
                 want.x, want.y, want.z, d, tol);
}

/* Sphere and cylinder: the unit normal of a sphere of radius r is p/r, so ∂n/∂u = (∂p/∂u)/r
 * and ∂n/∂v = (∂p/∂v)/r; a cylinder's ∂n/∂u = (∂p/∂u)/r, ∂n/∂v = 0; a disk's are 0. Under
 * a uniform scale k the world radius is k·r; ReverseOrientation turns them with n. The
 * Weingarten equations in double agree with these to float rounding (1e-6 relative). */
static void closed_forms(void **state)
{
    (void)state;
    ts_scene *s = load(HEAD TEXTURED_M "\"shapes\":["
                            "{\"type\":\"sphere\",\"radius\":2,\"material\":\"m\",\"transform\":[{\"rotate\":{"
                            "\"angle\":30,\"axis\":[1,1,0]}},{\"scale\":1.5},{\"translate\":[-3,0,0]}]},"
                            "{\"type\":\"sphere\",\"radius\":1,\"center\":[3,0,0],\"reverse_orientation\":true,"
                            "\"material\":\"m\"},"
                            "{\"type\":\"cylinder\",\"p0\":[0,-1,0],\"p1\":[0,1,0.5],\"radius\":0.7,\"material\":\"m\"},"
                            "{\"type\":\"disk\",\"center\":[0,-3,0],\"normal\":[0,0.3,1],\"radius\":1,\"material\":\"m\"}"
                            "]}");
    struct {
        ts_vec3 target;
        float radius; /* world radius; 0: the disk */
        bool v_curved, reversed;
    } cases[] = {{{-3.4f, 0.5f, 1}, 3, true, false},
                 {{2.8f, 0.3f, 0}, 1, true, true},
                 {{0.2f, 0.1f, 0}, 0.7f, false, false},
                 {{0.3f, -3.2f, 0}, 0, false, false}};
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        ts_interaction si = hit_towards(s, (ts_vec3){0, 0, 9}, cases[i].target);
        ts_vec3 wu = {0, 0, 0}, wv = {0, 0, 0};
        if (cases[i].radius > 0) {
            float k = (cases[i].reversed ? -1.0f : 1.0f) / cases[i].radius;
            wu = ts_vec3_scale(si.dpdu, k);
            if (cases[i].v_curved) wv = ts_vec3_scale(si.dpdv, k);
        }
        char what[64];
        snprintf(what, sizeof what, "shape %zu dndu", i);
        assert_near(si.dndu, wu, 1e-6f * ts_vec3_length(si.dpdu) + 1e-7f, what);
        snprintf(what, sizeof what, "shape %zu dndv", i);
        assert_near(si.dndv, wv, 1e-6f * ts_vec3_length(si.dpdv) + 1e-7f, what);
        assert_false(si.mesh_normals);
    }
    ts_scene_destroy(s);
}

/* A non-uniformly scaled sphere (an ellipsoid): ∂n/∂u, ∂n/∂v of the world normal
 * n(u, v) = normalize(M^-T·p(u, v)) against central differences of it with h = 1e-4 in
 * double (truncation error h²·|∂³n| ≈ 1e-7, far below the float tolerance 2e-5·|∂n|). */
static void ellipsoid_against_differences(void **state)
{
    (void)state;
    ts_scene *s = load(HEAD TEXTURED_M "\"shapes\":[{\"type\":\"sphere\","
                            "\"radius\":1,\"material\":\"m\",\"transform\":[{\"scale\":[1,2,0.5]},{\"rotate\":{"
                            "\"angle\":20,\"axis\":[0,1,0]}}]}]}");
    const ts_xform *X = &s->shapes[0].to_world;
    for (int k = 0; k < 3; k++) {
        double u = 0.15 + 0.2 * k, v = 0.35 + 0.15 * k; /* φ = 2πu, θ = π − πv (the whole sphere) */
        ts_dvec3 n_at[2][2];
        ts_dvec3 p_w = {0, 0, 0}, n_w = {0, 0, 0};
        for (int axis = 0; axis < 3; axis++) {
            for (int side = 0; side < 2; side++) {
                double h = axis == 2 ? 0 : (side ? 1e-4 : -1e-4);
                double uu = u + (axis == 0 ? h : 0), vv = v + (axis == 1 ? h : 0);
                double phi = 2 * PI_D * uu, theta = PI_D - PI_D * vv;
                ts_dvec3 p = {sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta)};
                ts_dvec3 n = ts_dvec3_normalize(ts_xform_normal(X, p));
                if (axis < 2) n_at[axis][side] = n;
                else p_w = ts_xform_point(X, p), n_w = n;
            }
        }
        ts_vec3 target = ts_dvec3_to_vec3(p_w);
        ts_vec3 from = ts_dvec3_to_vec3(ts_dvec3_add(p_w, ts_dvec3_scale(n_w, 6)));
        ts_interaction si = hit_towards(s, from, target);
        assert_true(fabs(si.uv.x - u) < 1e-5 && fabs(si.uv.y - v) < 1e-5);
        ts_vec3 fu = ts_dvec3_to_vec3(ts_dvec3_scale(ts_dvec3_sub(n_at[0][1], n_at[0][0]), 1 / 2e-4));
        ts_vec3 fv = ts_dvec3_to_vec3(ts_dvec3_scale(ts_dvec3_sub(n_at[1][1], n_at[1][0]), 1 / 2e-4));
        assert_near(si.dndu, fu, 2e-5f * ts_vec3_length(fu), "ellipsoid dndu");
        assert_near(si.dndv, fv, 2e-5f * ts_vec3_length(fv), "ellipsoid dndv");
    }
    ts_scene_destroy(s);
}

/* A triangle with vertex normals n0, n1, n2 and uvs (0,0), (1,0), (0,1): its interpolated
 * normal is n0 + u(n1 − n0) + v(n2 − n0), so ∂n/∂u = n1 − n0, ∂n/∂v = n2 − n0 (pbrt-v3's
 * Triangle::Intersect); without normals both are 0. */
static void triangle_derivatives(void **state)
{
    (void)state;
    ts_scene *s = load(HEAD TEXTURED_M "\"shapes\":["
                            "{\"type\":\"mesh\",\"positions\":[-1,-1,0,1,-1,0,-1,1,0],\"indices\":[0,1,2],"
                            "\"uvs\":[0,0,1,0,0,1],\"normals\":[0,0,1,0.6,0,0.8,0,-0.6,0.8],\"material\":\"m\"},"
                            "{\"type\":\"mesh\",\"positions\":[2,-1,0,4,-1,0,2,1,0],\"indices\":[0,1,2],"
                            "\"material\":\"m\"}]}");
    ts_interaction si = hit_towards(s, (ts_vec3){-0.5f, -0.4f, 5}, (ts_vec3){-0.5f, -0.4f, 0});
    assert_true(si.mesh_normals);
    assert_near(si.dndu, (ts_vec3){0.6f, 0, -0.2f}, 1e-6f, "dndu");
    assert_near(si.dndv, (ts_vec3){0, -0.6f, -0.2f}, 1e-6f, "dndv");
    si = hit_towards(s, (ts_vec3){2.5f, -0.4f, 5}, (ts_vec3){2.5f, -0.4f, 0});
    assert_false(si.mesh_normals);
    assert_true(ts_vec3_length(si.dndu) == 0 && ts_vec3_length(si.dndv) == 0);
    ts_scene_destroy(s);
    /* Without textures nothing reads them, and they are left 0. */
    s = load(HEAD "\"materials\":{\"m\":{\"type\":\"diffuse\"}},\"shapes\":[{\"type\":\"sphere\",\"radius\":1,"
                  "\"material\":\"m\"}]}");
    si = hit_towards(s, (ts_vec3){0.2f, 0.1f, 5}, (ts_vec3){0.2f, 0.1f, 0});
    assert_true(ts_vec3_length(si.dndu) == 0 && ts_vec3_length(si.dndv) == 0);
    ts_scene_destroy(s);
}

/* The bumped normal's angle from n at a hit, after the material's bump map. */
static float bumped_angle(const ts_scene *s, ts_vec3 o, ts_vec3 target, ts_interaction *out)
{
    ts_interaction si = hit_towards(s, o, target);
    const ts_material *m = &s->materials[s->shapes[si.shape].material];
    ts_texture_context c;
    ts_material_texture_context(&si, &c);
    ts_material_bump(m, &si, &c);
    *out = si;
    return acosf(fminf(1, ts_vec3_dot(si.ns, si.n)));
}

/* A displacement d = a·u on a cylinder of radius r (φ_max = 2π): the displaced surface
 * p + a·u·n has ∂p'/∂u = (1 + a·u/r)·∂p/∂u + a·n, so the normal leans back from ∂p/∂u by
 * atan(a / (2π(r + a·u))); without the d·∂n/∂u term it would be atan(a / (2πr)), 0.05 rad
 * off here. On a sphere, d = a·v: atan(a / (π(r + a·v))). Tolerance 2e-4 rad: the
 * difference quotient of a float texture over du = 5e-4 (its rounding, ~1e-7/5e-4 of a,
 * gives ~1e-5) and float tangents. */
static void bumped_curved_surfaces(void **state)
{
    (void)state;
    const double a = 0.5, r = 0.5;
    ts_scene *s = load(HEAD "\"textures\":{\"du\":{\"type\":\"bilerp\",\"kind\":\"float\",\"v00\":0,\"v01\":0,"
                            "\"v10\":0.5,\"v11\":0.5},\"dv\":{\"type\":\"bilerp\",\"kind\":\"float\",\"v00\":0,"
                            "\"v01\":0.5,\"v10\":0,\"v11\":0.5}},"
                            "\"materials\":{\"u\":{\"type\":\"diffuse\",\"bumpmap\":\"du\"},"
                            "\"v\":{\"type\":\"diffuse\",\"bumpmap\":\"dv\"}},\"shapes\":["
                            "{\"type\":\"cylinder\",\"p0\":[-2,-1,0],\"p1\":[-2,1,0],\"radius\":0.5,\"material\":\"u\"},"
                            "{\"type\":\"sphere\",\"center\":[2,0,0],\"radius\":0.5,\"material\":\"v\"}]}");
    for (int k = 0; k < 3; k++) {
        ts_interaction si;
        float x = -0.3f + 0.25f * (float)k;
        float got = bumped_angle(s, (ts_vec3){-2 + x, 0.2f, 9}, (ts_vec3){-2 + x, 0.2f, 0}, &si);
        double u = si.uv.x, want = atan(a / (2 * PI_D * (r + a * u))), flat = atan(a / (2 * PI_D * r));
        if (fabs(got - want) > 2e-4)
            fail_msg("cylinder at u %.4f: tilt %.6f rad, want %.6f (without d·dn/du %.6f)", u, got, want, flat);
        assert_true(ts_vec3_dot(si.ns, si.dpdu) < 0); /* leaning away from the rising displacement */
        got = bumped_angle(s, (ts_vec3){2 + 0.1f, x, 9}, (ts_vec3){2 + 0.1f, x, 0}, &si);
        double v = si.uv.y;
        want = atan(a / (PI_D * (r + a * v)));
        flat = atan(a / (PI_D * r));
        if (fabs(got - want) > 2e-4)
            fail_msg("sphere at v %.4f: tilt %.6f rad, want %.6f (without d·dn/dv %.6f)", v, got, want, flat);
        assert_true(ts_vec3_dot(si.ns, si.dpdv) < 0);
    }
    ts_scene_destroy(s);
}

/* With vertex normals the bump runs on pbrt-v3's unit shading tangents: d = a·u on a flat
 * square whose ∂p/∂u has length 2 tilts n to (−a, 0, 1)/√(1 + a²) — without normals to
 * (−a, 0, 2)/√(4 + a²) (test_material_texture's test_bump_linear). */
static void bumped_mesh_with_normals(void **state)
{
    (void)state;
    ts_scene *s = load(HEAD "\"textures\":{\"du\":{\"type\":\"bilerp\",\"kind\":\"float\",\"v00\":0,\"v01\":0,"
                            "\"v10\":0.5,\"v11\":0.5}},\"materials\":{\"m\":{\"type\":\"diffuse\",\"bumpmap\":\"du\"}},"
                            "\"shapes\":[{\"type\":\"mesh\",\"positions\":[-1,-1,0,1,-1,0,1,1,0,-1,1,0],"
                            "\"indices\":[0,1,2,0,2,3],\"uvs\":[0,0,1,0,1,1,0,1],"
                            "\"normals\":[0,0,1,0,0,1,0,0,1,0,0,1],\"material\":\"m\"}]}");
    ts_interaction si;
    bumped_angle(s, (ts_vec3){0.2f, -0.3f, 5}, (ts_vec3){0.2f, -0.3f, 0}, &si);
    float k = 1 / sqrtf(1 + 0.25f);
    assert_near(si.ns, (ts_vec3){-0.5f * k, 0, k}, 1e-4f, "bumped normal");
    ts_scene_destroy(s);
}

/* Bump maps of mixed materials: the mix's shading normal is its first material's bumped
 * one (pbrt-v3's MixMaterial: the first computes on the interaction, the second on a
 * copy whose frame the mixed BSDF does not use), whichever order the two come in; a mix
 * of a mix follows the first material down. */
static void bumped_mix(void **state)
{
    (void)state;
    ts_scene *s = load(HEAD "\"textures\":{\"du\":{\"type\":\"bilerp\",\"kind\":\"float\",\"v00\":0,\"v01\":0,"
                            "\"v10\":0.5,\"v11\":0.5},\"dv\":{\"type\":\"bilerp\",\"kind\":\"float\",\"v00\":0,"
                            "\"v01\":0.5,\"v10\":0,\"v11\":0.5}},\"materials\":{"
                            "\"a\":{\"type\":\"diffuse\",\"bumpmap\":\"du\"},\"b\":{\"type\":\"mirror\",\"bumpmap\":\"dv\"},"
                            "\"c\":{\"type\":\"diffuse\"},"
                            "\"ab\":{\"type\":\"mix\",\"materials\":[\"a\",\"b\"],\"amount\":0.3},"
                            "\"ba\":{\"type\":\"mix\",\"materials\":[\"b\",\"a\"],\"amount\":0.3},"
                            "\"ca\":{\"type\":\"mix\",\"materials\":[\"c\",\"a\"]},"
                            "\"abc\":{\"type\":\"mix\",\"materials\":[\"ab\",\"c\"]}},"
                            "\"shapes\":[{\"type\":\"mesh\",\"positions\":[-1,-1,0,1,-1,0,1,1,0,-1,1,0],"
                            "\"indices\":[0,1,2,0,2,3],\"uvs\":[0,0,1,0,1,1,0,1],\"material\":\"c\"}]}");
    ts_interaction base = hit_towards(s, (ts_vec3){0.2f, -0.3f, 5}, (ts_vec3){0.2f, -0.3f, 0});
    ts_texture_context c;
    ts_material_texture_context(&base, &c);
    float k = 1 / sqrtf(4 + 0.25f);
    const ts_vec3 tilt_u = {-0.5f * k, 0, 2 * k}, tilt_v = {0, -0.5f * k, 2 * k}, none = {0, 0, 1};
    struct {
        const char *name;
        ts_vec3 want;
    } cases[] = {{"ab", tilt_u}, {"ba", tilt_v}, {"ca", none}, {"abc", tilt_u}};
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        const ts_material *m = NULL;
        for (uint32_t j = 0; j < s->n_materials; j++)
            if (strcmp(s->material_names[j], cases[i].name) == 0) m = &s->materials[j];
        assert_non_null(m);
        ts_interaction si = base;
        ts_material_bump(m, &si, &c);
        assert_near(si.ns, cases[i].want, 1e-4f, cases[i].name);
        /* the BSDF's frame is the bumped normal's */
        ts_bsdf b;
        ts_material_bsdf(m, &si, &c, &b);
        assert_near(b.ns, si.ns, 1e-6f, cases[i].name);
    }
    ts_scene_destroy(s);
}

static void count_warning(void *ctx, const char *msg)
{
    int *n = ctx;
    if (strstr(msg, "\"texture bumpmap\" is not used")) (*n)++;
}

/* A pbrt-v3 mix bumps with namedmaterial1's map; its own "bumpmap", which pbrt-v3's
 * MixMaterial does not read, is left unused with pbrt-v3's warning. */
static void pbrt_mix_bumps_first(void **state)
{
    (void)state;
    const char *text = "WorldBegin\n"
                       "Texture \"d\" \"float\" \"bilerp\" \"float v10\" 0.5 \"float v11\" 0.5 \"float v01\" 0\n"
                       "MakeNamedMaterial \"a\" \"string type\" \"matte\" \"texture bumpmap\" \"d\"\n"
                       "MakeNamedMaterial \"b\" \"string type\" \"mirror\"\n"
                       "MakeNamedMaterial \"m\" \"string type\" \"mix\" \"string namedmaterial1\" \"a\" "
                       "\"string namedmaterial2\" \"b\" \"texture bumpmap\" \"d\"\n"
                       "NamedMaterial \"m\"\n"
                       "Shape \"trianglemesh\" \"point P\" [-1 -1 0 1 -1 0 1 1 0 -1 1 0] \"integer indices\" [0 1 2 0 2 3]"
                       " \"float uv\" [0 0 1 0 1 1 0 1]\nWorldEnd\n";
    int unused = 0;
    ts_scene *s = NULL;
    ts_error err = {0};
    if (ts_scene_load_pbrt_text(text, strlen(text), NULL, "mix.pbrt", NULL, count_warning, &unused, &s, &err))
        fail_msg("%s", err.message);
    assert_int_equal(unused, 1);
    const ts_material *m = &s->materials[s->shapes[0].material];
    assert_int_equal(m->type, TS_MATERIAL_MIX);
    assert_null(m->bump);
    assert_true(m->textured);
    ts_interaction si = hit_towards(s, (ts_vec3){0.2f, -0.3f, 5}, (ts_vec3){0.2f, -0.3f, 0});
    ts_texture_context c;
    ts_material_texture_context(&si, &c);
    ts_material_bump(m, &si, &c);
    float k = 1 / sqrtf(4 + 0.25f);
    assert_near(si.ns, (ts_vec3){-0.5f * k, 0, 2 * k}, 1e-4f, "pbrt mix");
    ts_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(closed_forms),
        cmocka_unit_test(ellipsoid_against_differences),
        cmocka_unit_test(triangle_derivatives),
        cmocka_unit_test(bumped_curved_surfaces),
        cmocka_unit_test(bumped_mesh_with_normals),
        cmocka_unit_test(bumped_mix),
        cmocka_unit_test(pbrt_mix_bumps_first),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
