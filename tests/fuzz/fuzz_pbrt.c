/* fuzz_pbrt.c — libFuzzer harness: pbrt-v3 scene text (pbrt3/pbrt_parser.h), the surface
 * of the pbrt-v3 front end: tokens, parameter lists, every directive and the graphics
 * state, Include and .spd files (resolved in this process's private folder, which holds
 * inc.pbrt, loop.pbrt — it includes itself — deep1.pbrt … deep9.pbrt, and k.spd), under
 * a server's kind of limits. A refused input must leave no scene and one UTF-8 sentence
 * that starts with a position; a parsed one must keep the header's promises: every index
 * (material, area light, object, texture) in range, object definitions contiguous, value
 * counts that fit their types; and every parameter must answer every lookup without
 * crashing, after which none is left unused. */
#include "fuzz_common.h"

#include "pbrt3/pbrt_parser.h"

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc, (void)argv;
    char path[256];
    static const char inc[] = "AttributeBegin Translate 1 0 0 Shape \"sphere\" \"float radius\" 0.5 AttributeEnd\n"
                              "Texture \"inc\" \"float\" \"constant\" \"float value\" 0.25\n";
    fuzz_write_file("inc.pbrt", inc, sizeof inc - 1, path, sizeof path);
    static const char loop[] = "Shape \"disk\"\nInclude \"loop.pbrt\"\n";
    fuzz_write_file("loop.pbrt", loop, sizeof loop - 1, path, sizeof path);
    for (int i = 1; i <= 9; i++) {
        char name[32], text[64];
        snprintf(name, sizeof name, "deep%d.pbrt", i);
        int n = i < 9 ? snprintf(text, sizeof text, "Include \"deep%d.pbrt\"\n", i + 1)
                      : snprintf(text, sizeof text, "Shape \"sphere\"\n");
        fuzz_write_file(name, text, (size_t)n, path, sizeof path);
    }
    static const char spd[] = "# wavelength value\n400 0.1\n550 0.5\n700 0.9\n";
    fuzz_write_file("k.spd", spd, sizeof spd - 1, path, sizeof path);
    return 0;
}

static bool utf8_clean(const char *s)
{
    char copy[TS_ERROR_MAX];
    snprintf(copy, sizeof copy, "%s", s);
    ts_pbrt_sanitize_utf8(copy);
    return strcmp(copy, s) == 0;
}

static void check_params(ts_pbrt_params *ps, const ts_pbrt_scene *s)
{
    FUZZ_CHECK(ps->count == 0 || ps->items);
    FUZZ_CHECK(ps->directive && ps->directive_arg);
    for (size_t i = 0; i < ps->count; i++) {
        const ts_pbrt_param *p = &ps->items[i];
        FUZZ_CHECK(p->name && p->type_name && p->n >= 1 && p->loc.file && p->loc.line >= 1);
        FUZZ_CHECK(p->n % ts_pbrt_param_arity(p->type) == 0);
        for (size_t j = 0; j < i; j++) FUZZ_CHECK(strcmp(ps->items[j].name, p->name) != 0);
        switch (p->type) {
        case TS_PBRT_PARAM_INTEGER: FUZZ_CHECK(p->ints != NULL); break;
        case TS_PBRT_PARAM_BOOL: FUZZ_CHECK(p->bools != NULL); break;
        case TS_PBRT_PARAM_STRING: FUZZ_CHECK(p->strings != NULL); break;
        case TS_PBRT_PARAM_TEXTURE:
            FUZZ_CHECK(p->n == 1 && p->strings && p->strings[0]);
            FUZZ_CHECK(p->texture_float >= 0 || p->texture_spectrum >= 0);
            FUZZ_CHECK(p->texture_float < (int32_t)s->texture_count && p->texture_spectrum < (int32_t)s->texture_count);
            if (p->texture_float >= 0) FUZZ_CHECK(s->textures[p->texture_float].is_float);
            if (p->texture_spectrum >= 0) FUZZ_CHECK(!s->textures[p->texture_spectrum].is_float);
            break;
        case TS_PBRT_PARAM_BLACKBODY: FUZZ_CHECK(p->floats && (p->n == 1 || p->n == 2)); break;
        default: FUZZ_CHECK(p->floats != NULL); break;
        }
    }
    /* Every lookup of every name: errors are fine, crashes and silence are not. */
    for (size_t i = 0; i < ps->count; i++) {
        const char *name = ps->items[i].name;
        ts_error err = {0};
        float f;
        int32_t k;
        bool b;
        const char *str;
        ts_vec3 v = {0, 0, 0};
        ts_rgb c;
        const float *fa;
        const int32_t *ia;
        const char *const *sa;
        size_t n;
        ts_status st = ts_pbrt_find_float(ps, name, 0, &f, &err);
        FUZZ_CHECK(st == TS_OK || (err.message[0] && utf8_clean(err.message)));
        (void)ts_pbrt_find_int(ps, name, 0, &k, &err);
        (void)ts_pbrt_find_bool(ps, name, false, &b, &err);
        (void)ts_pbrt_find_string(ps, name, NULL, &str, &err);
        (void)ts_pbrt_find_point3(ps, name, v, &v, &err);
        (void)ts_pbrt_find_vector3(ps, name, v, &v, &err);
        st = ts_pbrt_find_rgb(ps, name, (ts_rgb){0, 0, 0}, &c, &err);
        FUZZ_CHECK(st == TS_OK || st == TS_ERR_INVALID || st == TS_ERR_UNSUPPORTED);
        (void)ts_pbrt_find_floats(ps, name, &fa, &n, &err);
        (void)ts_pbrt_find_ints(ps, name, &ia, &n, &err);
        (void)ts_pbrt_find_point2s(ps, name, &fa, &n, &err);
        (void)ts_pbrt_find_point3s(ps, name, &fa, &n, &err);
        (void)ts_pbrt_find_vector3s(ps, name, &fa, &n, &err);
        (void)ts_pbrt_find_normal3s(ps, name, &fa, &n, &err);
        st = ts_pbrt_find_strings(ps, name, &sa, &n, &err);
        if (st == TS_OK && sa) FUZZ_CHECK(n == ps->items[i].n);
    }
    size_t cursor = 0;
    FUZZ_CHECK(ts_pbrt_params_next_unused(ps, &cursor) == NULL);
}

static void check_scene(ts_pbrt_scene *s)
{
    FUZZ_CHECK(s->camera.type && s->film.type && s->sampler.type && s->filter.type && s->integrator.type &&
               s->accelerator.type);
    ts_pbrt_option *opts[] = {&s->camera, &s->film, &s->sampler, &s->filter, &s->integrator, &s->accelerator};
    for (size_t i = 0; i < 6; i++)
        if (opts[i]->loc.file) check_params(&opts[i]->params, s);
    for (size_t i = 0; i < s->texture_count; i++) {
        FUZZ_CHECK(s->textures[i].texture_to_world && s->textures[i].name && s->textures[i].class_name);
        check_params(&s->textures[i].params, s);
    }
    for (size_t i = 0; i < s->material_count; i++) {
        const ts_pbrt_material *m = &s->materials[i];
        FUZZ_CHECK(m->type);
        for (int j = 0; j < 2; j++) {
            FUZZ_CHECK(m->mix[j] >= -1 && m->mix[j] < (int32_t)i);
            if (strcmp(m->type, "mix") == 0) FUZZ_CHECK(m->mix[j] >= 0);
        }
        check_params(&s->materials[i].params, s);
    }
    for (size_t i = 0; i < s->area_light_count; i++) check_params(&s->area_lights[i].params, s);
    for (size_t i = 0; i < s->light_count; i++) {
        FUZZ_CHECK(s->lights[i].light_to_world && s->lights[i].inside_medium && s->lights[i].outside_medium);
        check_params(&s->lights[i].params, s);
    }
    for (size_t i = 0; i < s->medium_count; i++) {
        FUZZ_CHECK(s->media[i].type && s->media[i].medium_to_world);
        check_params(&s->media[i].params, s);
    }
    for (size_t i = 0; i < s->shape_count; i++) {
        ts_pbrt_shape *sh = &s->shapes[i];
        FUZZ_CHECK(sh->type && sh->object_to_world && sh->loc.file);
        FUZZ_CHECK(sh->material >= -1 && sh->material < (int32_t)s->material_count);
        FUZZ_CHECK(sh->area_light >= -1 && sh->area_light < (int32_t)s->area_light_count);
        FUZZ_CHECK(sh->object >= -1 && sh->object < (int32_t)s->object_count);
        if (sh->object >= 0) FUZZ_CHECK(sh->area_light == -1);
        check_params(&sh->params, s);
    }
    size_t instances = 0, prev_end = 0;
    for (size_t i = 0; i < s->object_count; i++) {
        const ts_pbrt_object *o = &s->objects[i];
        FUZZ_CHECK(o->name && o->first_shape >= prev_end && o->first_shape + o->shape_count <= s->shape_count);
        for (size_t j = 0; j < o->shape_count; j++) FUZZ_CHECK(s->shapes[o->first_shape + j].object == (int32_t)i);
        for (size_t j = 0; j < o->instance_count; j++) FUZZ_CHECK(o->instance_to_world[j] != NULL);
        prev_end = o->first_shape + o->shape_count;
        instances += o->instance_count;
    }
    FUZZ_CHECK(instances == s->instance_count);
    for (size_t i = 0; i < s->instance_count; i++)
        FUZZ_CHECK(s->instances[i].object >= 0 && s->instances[i].object < (int32_t)s->object_count &&
                   s->instances[i].instance_to_world);
    FUZZ_CHECK(s->warning_count <= 64);
    for (size_t i = 0; i < s->warning_count; i++)
        FUZZ_CHECK(s->warnings[i].message && s->warnings[i].loc.file && utf8_clean(s->warnings[i].message));
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    ts_pbrt_limits lim;
    ts_pbrt_limits_default(&lim);
    lim.max_file_bytes = 1u << 20;
    lim.max_memory = 64u << 20;
    lim.max_include_depth = 8;
    lim.max_warnings = 64;
    ts_pbrt_scene *s = NULL;
    ts_error err = {0};
    ts_status st = ts_pbrt_parse_text((const char *)data, size, "fuzz.pbrt", fuzz_dir(), &lim, &s, &err);
    if (st != TS_OK) {
        FUZZ_CHECK(s == NULL && err.status == st && err.message[0] != '\0');
        FUZZ_CHECK(utf8_clean(err.message));
        /* A position first: "<file>:<line>:<column>: " (or a file's own "'<file>': …"). */
        FUZZ_CHECK(strchr(err.message, ':') != NULL);
        return 0;
    }
    FUZZ_CHECK(s != NULL);
    check_scene(s);
    ts_pbrt_scene_destroy(s);
    return 0;
}
