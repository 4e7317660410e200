/* test_effects.c — the effects analysis and the specialisation it drives: each scene
 * renders bit-identically with the analysis forced off (every effect simulated) and on,
 * and a job that switches `indirect` off renders exactly what max_depth 1 renders. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <stdio.h>
#include <string.h>

#include "integrators/effects.h"
#include "render/render.h"
#include "json/scene_json.h"

static ts_scene *load(const char *doc)
{
    ts_scene *s = NULL;
    ts_error err = {0};
    if (ts_scene_load_text(doc, strlen(doc), NULL, "t", NULL, &s, &err)) fail_msg("%s", err.message);
    return s;
}

static ts_film *render(const ts_scene *s, bool generic, int spp)
{
    ts_error err = {0};
    ts_film *f = ts_film_create(s->width, s->height, 0, 0, s->width, s->height, &err);
    ts_render_stats stats = {0};
    ts_render_request req = {s, s->integrator.type, f, 0, (uint32_t)spp, 2, NULL, NULL, NULL, generic};
    assert_int_equal(ts_render(&req, &stats, &err), TS_OK);
    assert_int_equal(stats.counters.nonfinite, 0);
    return f;
}

#define CAMERA "\"camera\":{\"from\":[0,2,6],\"to\":[0,0.5,0],\"fov\":40,\"lens_radius\":%s,\"focus_distance\":6}"
#define FILM "\"film\":{\"width\":24,\"height\":16},\"sampler\":{\"spp\":4}"
#define FLOOR "{\"type\":\"disk\",\"normal\":[0,1,0],\"radius\":5,\"material\":\"floor\"}"

static const struct {
    const char *name, *doc;
    uint32_t expected;
} cases[] = {
    {"diffuse, area light, path",
     "{\"tessera\":1," CAMERA "," FILM ",\"integrator\":{\"type\":\"path\",\"max_depth\":5},"
     "\"materials\":{\"floor\":{\"type\":\"diffuse\"},\"black\":{\"type\":\"diffuse\",\"reflectance\":0}},"
     "\"shapes\":[" FLOOR ",{\"type\":\"sphere\",\"center\":[0,2,0],\"radius\":0.3,\"material\":\"black\","
     "\"emission\":20}]}",
     TS_EFFECT_AREA_LIGHTS | TS_EFFECT_DIFFUSE | TS_EFFECT_INDIRECT},
    {"diffuse, point light, path",
     "{\"tessera\":1," CAMERA "," FILM ",\"integrator\":{\"type\":\"path\"},"
     "\"materials\":{\"floor\":{\"type\":\"diffuse\"}},\"shapes\":[" FLOOR
     ",{\"type\":\"sphere\",\"center\":[0,0.5,0],\"radius\":0.5,\"material\":\"floor\"}],"
     "\"lights\":[{\"type\":\"point\",\"position\":[1,3,1],\"intensity\":10}]}",
     TS_EFFECT_DELTA_LIGHTS | TS_EFFECT_DIFFUSE | TS_EFFECT_INDIRECT},
    {"glass and mirror under an environment, depth of field, direct",
     "{\"tessera\":1,\"camera\":{\"from\":[0,2,6],\"to\":[0,0.5,0],\"fov\":40,\"lens_radius\":0.05,\"focus_distance\":6},"
     FILM ",\"integrator\":{\"type\":\"direct\",\"max_depth\":4},"
     "\"materials\":{\"floor\":{\"type\":\"mirror\"},\"glass\":{\"type\":\"dielectric\"}},\"shapes\":[" FLOOR
     ",{\"type\":\"sphere\",\"center\":[0,0.5,0],\"radius\":0.5,\"material\":\"glass\"}],"
     "\"lights\":[{\"type\":\"infinite\",\"radiance\":[0.5,0.6,0.8]}]}",
     TS_EFFECT_ENVIRONMENT | TS_EFFECT_SPECULAR_REFLECTION | TS_EFFECT_SPECULAR_TRANSMISSION |
         TS_EFFECT_DEPTH_OF_FIELD | TS_EFFECT_INDIRECT},
    {"glossy plastic, spot light, path",
     "{\"tessera\":1," CAMERA "," FILM ",\"integrator\":{\"type\":\"path\",\"max_depth\":3},"
     "\"materials\":{\"floor\":{\"type\":\"plastic\",\"roughness\":0.2}},\"shapes\":[" FLOOR "],"
     "\"lights\":[{\"type\":\"spot\",\"from\":[0,3,0],\"to\":[0,0,0],\"intensity\":30}]}",
     TS_EFFECT_DELTA_LIGHTS | TS_EFFECT_DIFFUSE | TS_EFFECT_GLOSSY | TS_EFFECT_INDIRECT | TS_EFFECT_LOBE_CHOICE},
    {"diffuse, point light, direct all",
     "{\"tessera\":1," CAMERA "," FILM ",\"integrator\":{\"type\":\"direct\",\"strategy\":\"all\","
     "\"samples_per_light\":2},\"materials\":{\"floor\":{\"type\":\"diffuse\",\"sigma\":10}},\"shapes\":[" FLOOR
     ",{\"type\":\"sphere\",\"center\":[0,0.5,0],\"radius\":0.5,\"material\":\"floor\"}],"
     "\"lights\":[{\"type\":\"point\",\"position\":[1,3,1],\"intensity\":10},"
     "{\"type\":\"distant\",\"from\":[0,1,1],\"to\":[0,0,0],\"irradiance\":1}]}",
     TS_EFFECT_DELTA_LIGHTS | TS_EFFECT_DIFFUSE},
    {"plastic under a sphere light and a point light, direct all",
     "{\"tessera\":1," CAMERA "," FILM ",\"integrator\":{\"type\":\"direct\",\"strategy\":\"all\"},"
     "\"materials\":{\"floor\":{\"type\":\"plastic\",\"roughness\":0.3},\"black\":{\"type\":\"diffuse\","
     "\"reflectance\":0}},\"shapes\":[" FLOOR ",{\"type\":\"sphere\",\"center\":[0,2,0],\"radius\":0.3,"
     "\"material\":\"black\",\"emission\":20}],"
     "\"lights\":[{\"type\":\"point\",\"position\":[1,3,1],\"intensity\":10}]}",
     TS_EFFECT_DELTA_LIGHTS | TS_EFFECT_AREA_LIGHTS | TS_EFFECT_DIFFUSE | TS_EFFECT_GLOSSY | TS_EFFECT_LOBE_CHOICE},
    {"translucent leaf under a point light, path: diffuse and glossy transmission",
     "{\"tessera\":1," CAMERA "," FILM ",\"integrator\":{\"type\":\"path\",\"max_depth\":3},"
     "\"materials\":{\"floor\":{\"type\":\"translucent\",\"reflectance\":0}},\"shapes\":[" FLOOR "],"
     "\"lights\":[{\"type\":\"point\",\"position\":[0,-3,0],\"intensity\":30}]}",
     TS_EFFECT_DELTA_LIGHTS | TS_EFFECT_DIFFUSE | TS_EFFECT_GLOSSY | TS_EFFECT_INDIRECT | TS_EFFECT_LOBE_CHOICE},
    {"uber with opacity (a pass-through lobe), direct",
     "{\"tessera\":1," CAMERA "," FILM ",\"integrator\":{\"type\":\"direct\",\"max_depth\":3},"
     "\"materials\":{\"floor\":{\"type\":\"diffuse\"},\"u\":{\"type\":\"uber\",\"specular\":0,"
     "\"opacity\":0.5}},\"shapes\":[" FLOOR
     ",{\"type\":\"sphere\",\"center\":[0,0.5,0],\"radius\":0.5,\"material\":\"u\"}],"
     "\"lights\":[{\"type\":\"point\",\"position\":[1,3,1],\"intensity\":10}]}",
     TS_EFFECT_DELTA_LIGHTS | TS_EFFECT_DIFFUSE | TS_EFFECT_SPECULAR_TRANSMISSION | TS_EFFECT_INDIRECT |
         TS_EFFECT_LOBE_CHOICE},
    {"mix of a mirror and pbrt-v3's plastic (amount 1: the mirror's lobes only), path",
     "{\"tessera\":1," CAMERA "," FILM ",\"integrator\":{\"type\":\"path\",\"max_depth\":3},"
     "\"materials\":{\"m\":{\"type\":\"mirror\"},\"p\":{\"type\":\"plastic_pbrt3\"},"
     "\"floor\":{\"type\":\"mix\",\"materials\":[\"m\",\"p\"],\"amount\":1}},\"shapes\":[" FLOOR "],"
     "\"lights\":[{\"type\":\"point\",\"position\":[1,3,1],\"intensity\":10}]}",
     TS_EFFECT_DELTA_LIGHTS | TS_EFFECT_DIFFUSE | TS_EFFECT_GLOSSY | TS_EFFECT_SPECULAR_REFLECTION |
         TS_EFFECT_INDIRECT | TS_EFFECT_LOBE_CHOICE},
    {"a medium in a surface-less sphere and a camera in fog, under an area light and a sky, volpath",
     "{\"tessera\":1,\"camera\":{\"from\":[0,2,6],\"to\":[0,0.5,0],\"fov\":40,\"medium\":\"haze\"}," FILM
     ",\"integrator\":{\"type\":\"volpath\",\"max_depth\":5},"
     "\"media\":{\"fog\":{\"type\":\"homogeneous\",\"sigma_a\":[0.2,0.3,0.4],\"sigma_s\":[1,1.5,2],\"g\":0.4},"
     "\"haze\":{\"type\":\"grid\",\"sigma_a\":[0.01,0.01,0.01],\"sigma_s\":[0.04,0.04,0.04],\"nx\":2,\"ny\":1,"
     "\"nz\":1,\"density\":[1,0.5],\"p0\":[-20,-20,-20],\"p1\":[20,20,20]}},"
     "\"materials\":{\"floor\":{\"type\":\"diffuse\"},\"black\":{\"type\":\"diffuse\",\"reflectance\":0}},"
     "\"shapes\":[" FLOOR ",{\"type\":\"sphere\",\"center\":[0,0.7,0],\"radius\":0.7,\"material\":null,"
     "\"medium\":{\"inside\":\"fog\",\"outside\":\"haze\"}},{\"type\":\"sphere\",\"center\":[0,3,0],\"radius\":0.3,"
     "\"material\":\"black\",\"emission\":20}],\"lights\":[{\"type\":\"infinite\",\"radiance\":0.2}]}",
     TS_EFFECT_AREA_LIGHTS | TS_EFFECT_ENVIRONMENT | TS_EFFECT_DIFFUSE | TS_EFFECT_INDIRECT | TS_EFFECT_MEDIA},
    {"diffuse, point light, volpath without media",
     "{\"tessera\":1," CAMERA "," FILM ",\"integrator\":{\"type\":\"volpath\"},"
     "\"materials\":{\"floor\":{\"type\":\"plastic\",\"roughness\":0.2}},\"shapes\":[" FLOOR
     ",{\"type\":\"sphere\",\"center\":[0,0.5,0],\"radius\":0.5,\"material\":\"floor\"}],"
     "\"lights\":[{\"type\":\"point\",\"position\":[1,3,1],\"intensity\":10},{\"type\":\"infinite\",\"radiance\":0.3}]}",
     TS_EFFECT_DELTA_LIGHTS | TS_EFFECT_ENVIRONMENT | TS_EFFECT_DIFFUSE | TS_EFFECT_GLOSSY | TS_EFFECT_INDIRECT |
         TS_EFFECT_LOBE_CHOICE},
    {"path given a medium: it is not simulated, its surface-less sphere is passed through",
     "{\"tessera\":1," CAMERA "," FILM ",\"integrator\":{\"type\":\"path\"},"
     "\"media\":{\"fog\":{\"type\":\"homogeneous\"}},\"materials\":{\"floor\":{\"type\":\"diffuse\"}},"
     "\"shapes\":[" FLOOR ",{\"type\":\"sphere\",\"center\":[0,0.5,0],\"radius\":0.5,\"material\":null,"
     "\"medium\":{\"inside\":\"fog\"}}],\"lights\":[{\"type\":\"point\",\"position\":[1,3,1],\"intensity\":10}]}",
     TS_EFFECT_DELTA_LIGHTS | TS_EFFECT_DIFFUSE | TS_EFFECT_INDIRECT | TS_EFFECT_MEDIA},
    {"a sphere moving and a camera turning during the shutter, path",
     "{\"tessera\":1,\"camera\":{\"from\":[0,2,6],\"to\":[0,0.5,0],\"fov\":40,\"shutter\":[0,1],"
     "\"motion\":{\"start\":[],\"end\":[{\"rotate\":{\"angle\":3,\"axis\":[0,1,0]}}]}}," FILM
     ",\"integrator\":{\"type\":\"path\"},\"materials\":{\"floor\":{\"type\":\"diffuse\"}},\"shapes\":[" FLOOR
     ",{\"type\":\"sphere\",\"center\":[0,0.5,0],\"radius\":0.5,\"material\":\"floor\",\"motion\":{\"times\":[0,1],"
     "\"transform\":[{\"translate\":[0.5,0,0]}]}}],\"lights\":[{\"type\":\"point\",\"position\":[1,3,1],\"intensity\":10}]}",
     TS_EFFECT_DELTA_LIGHTS | TS_EFFECT_DIFFUSE | TS_EFFECT_INDIRECT | TS_EFFECT_MOTION},
    {"motion outside the shutter: none",
     "{\"tessera\":1,\"camera\":{\"from\":[0,2,6],\"to\":[0,0.5,0],\"fov\":40,\"shutter\":[2,3]}," FILM
     ",\"integrator\":{\"type\":\"path\"},\"materials\":{\"floor\":{\"type\":\"diffuse\"}},\"shapes\":[" FLOOR
     ",{\"type\":\"sphere\",\"center\":[0,0.5,0],\"radius\":0.5,\"material\":\"floor\",\"motion\":{\"times\":[0,1],"
     "\"transform\":[{\"translate\":[0.5,0,0]}]}}],\"lights\":[{\"type\":\"point\",\"position\":[1,3,1],\"intensity\":10}]}",
     TS_EFFECT_DELTA_LIGHTS | TS_EFFECT_DIFFUSE | TS_EFFECT_INDIRECT},
    {"nothing emits",
     "{\"tessera\":1," CAMERA "," FILM ",\"integrator\":{\"type\":\"path\"},"
     "\"materials\":{\"floor\":{\"type\":\"diffuse\"}},\"shapes\":[" FLOOR "]}",
     TS_EFFECT_DIFFUSE},
};

static void test_specialisation_is_bit_identical(void **state)
{
    (void)state;
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        char doc[4096];
        snprintf(doc, sizeof doc, cases[i].doc, "0");
        ts_scene *s = load(doc);
        char got[400], want[400];
        ts_effects_format(s->effects, got, sizeof got);
        ts_effects_format(cases[i].expected, want, sizeof want);
        if (s->effects != cases[i].expected) fail_msg("%s: effects %s, expected %s", cases[i].name, got, want);
        ts_film *a = render(s, true, 4), *b = render(s, false, 4);
        assert_memory_equal(a->pixels, b->pixels, sizeof *a->pixels * (size_t)a->width * a->height);
        print_message("%-60s %s: identical\n", cases[i].name, got);
        ts_film_destroy(a);
        ts_film_destroy(b);
        ts_scene_destroy(s);
    }
}

static void test_switching_indirect_off(void **state)
{
    (void)state;
    /* job.effects.indirect = false renders what max_depth 1 renders, sample for sample. */
    char a_doc[4096], b_doc[4096];
    snprintf(a_doc, sizeof a_doc,
             "{\"tessera\":1," CAMERA "," FILM ",\"integrator\":{\"type\":\"path\",\"max_depth\":6},"
             "\"materials\":{\"floor\":{\"type\":\"diffuse\"}},\"shapes\":[" FLOOR "],"
             "\"lights\":[{\"type\":\"point\",\"position\":[1,3,1],\"intensity\":10}],"
             "\"job\":{\"effects\":{\"indirect\":false}}}",
             "0");
    snprintf(b_doc, sizeof b_doc,
             "{\"tessera\":1," CAMERA "," FILM ",\"integrator\":{\"type\":\"path\",\"max_depth\":1},"
             "\"materials\":{\"floor\":{\"type\":\"diffuse\"}},\"shapes\":[" FLOOR "],"
             "\"lights\":[{\"type\":\"point\",\"position\":[1,3,1],\"intensity\":10}]}",
             "0");
    ts_scene *a = load(a_doc), *b = load(b_doc);
    assert_false(a->effects & TS_EFFECT_INDIRECT);
    ts_film *fa = render(a, false, 4), *fb = render(b, false, 4), *fg = render(a, true, 4);
    size_t bytes = sizeof *fa->pixels * (size_t)fa->width * fa->height;
    assert_memory_equal(fa->pixels, fb->pixels, bytes);
    assert_memory_equal(fa->pixels, fg->pixels, bytes); /* job switches hold in generic mode too */
    ts_film_destroy(fa);
    ts_film_destroy(fb);
    ts_film_destroy(fg);
    ts_scene_destroy(a);
    ts_scene_destroy(b);

    /* Only indirect and depth_of_field can be switched off; unknown keys are refused. */
    const char *bad = "{\"tessera\":1,\"camera\":{\"from\":[0,0,5],\"to\":[0,0,0]},\"job\":{\"effects\":{\"glossy\":false}}}";
    ts_scene *s = NULL;
    ts_error err = {0};
    assert_int_not_equal(ts_scene_load_text(bad, strlen(bad), NULL, "t", NULL, &s, &err), TS_OK);
    assert_non_null(strstr(err.message, "job.effects.glossy: only 'indirect' and 'depth_of_field' can be switched off"));
    const char *unknown = "{\"tessera\":1,\"camera\":{\"from\":[0,0,5],\"to\":[0,0,0]},\"job\":{\"effects\":{\"fog\":false}}}";
    assert_int_not_equal(ts_scene_load_text(unknown, strlen(unknown), NULL, "t", NULL, &s, &err), TS_OK);
    assert_non_null(strstr(err.message, "job.effects.fog: unknown effect"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_specialisation_is_bit_identical),
        cmocka_unit_test(test_switching_indirect_off),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
