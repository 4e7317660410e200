/* test_material_desc.c — the one description per material type (materials/material_desc.h)
 * against the places that must agree with it without reading it, and through every reader
 * that does:
 *  - the JSON schema (proto/scene.schema.json): each type's keys, each row's default and
 *    range, exactly — so the schema users validate against cannot drift from the table;
 *  - pbrt-v3's own defaults, written out here from pbrt-v3's src/materials (an independent
 *    copy: a row whose pbrt-v3 default is mistyped fails);
 *  - the JSON front end and the builder, generically over the table: for every row a value
 *    inside its range lands in the row's field, and one outside it is refused with the
 *    row's key in the JSON path (so a new type's rows are tested by being added).
 * Every check is exact; there is no false-failure rate to name. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
// clang-format off
#include <cmocka.h>
// clang-format on

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "build/scene_builder.h"
#include "doc_rows.h"
#include "json/scene_json.h"
#include "materials/bsdf.h"
#include "materials/material_desc.h"
#include "scene/scene.h"

/* The schema's words for a row's range: which $ref or bound it uses. */
static void check_schema_range(const ts_material_param *p, const cJSON *prop, const char *type)
{
    char *text = cJSON_PrintUnformatted(prop);
    assert_non_null(text);
    bool ok = true;
    switch (p->range) {
    case TS_MRANGE_UNIT:
        ok = p->kind == TS_MPARAM_RGB ? strstr(text, "rgb_unit_or_texture") != NULL
                                      : strstr(text, "\"maximum\":1") != NULL;
        break;
    case TS_MRANGE_NONNEG:
        ok = p->kind == TS_MPARAM_ENUM ||
             (p->kind == TS_MPARAM_RGB ? strstr(text, "rgb_or_texture") != NULL && !strstr(text, "rgb_unit")
                                       : strstr(text, "\"minimum\":0") != NULL);
        break;
    case TS_MRANGE_POSITIVE: ok = strstr(text, "\"exclusiveMinimum\":0") != NULL; break;
    case TS_MRANGE_ANGLE: ok = strstr(text, "\"maximum\":90") != NULL && strstr(text, "\"minimum\":0") != NULL; break;
    }
    if (!ok) fail_msg("%s.%s: the schema's %s does not state the table's range", type, p->key, text);
    free(text);
}

static void test_schema_agrees(void **state)
{
    (void)state;
    cJSON *schema = doc_rows_schema();
    assert_non_null(schema);
    for (int t = 0; t < TS_MATERIAL_TYPE_COUNT; t++) {
        const ts_material_desc *d = &ts_material_descs[t];
        assert_int_equal(d->type, t);
        const cJSON *props = cJSON_GetObjectItemCaseSensitive(doc_rows_schema_alt(schema, "material", d->name), "properties");
        if (!props) fail_msg("the schema has no material of type %s", d->name);
        /* The keys the table makes the JSON front end accept (scene_json.c). */
        const char *keys[40];
        int n = 0;
        keys[n++] = "type";
        keys[n++] = "bumpmap";
        keys[n++] = "texture_clamp";
        for (int i = 0; i < d->n_params; i++)
            keys[n++] = d->params[i].key;
        if (d->flags & TS_MDESC_ROUGH) keys[n++] = "roughness", keys[n++] = "remap_roughness";
        if (d->flags & TS_MDESC_ANISO) keys[n++] = "uroughness", keys[n++] = "vroughness";
        if (d->flags & TS_MDESC_FILE) keys[n++] = "file";
        if (d->flags & TS_MDESC_MIX) keys[n++] = "materials";
        for (int i = 0; i < n; i++)
            if (!cJSON_GetObjectItemCaseSensitive(props, keys[i]))
                fail_msg("%s: the table has key %s, the schema does not", d->name, keys[i]);
        const cJSON *prop;
        cJSON_ArrayForEach(prop, props)
        {
            bool found = false;
            for (int i = 0; i < n && !found; i++)
                found = strcmp(keys[i], prop->string) == 0;
            if (!found) fail_msg("%s: the schema has key %s, the table does not", d->name, prop->string);
        }
        for (int i = 0; i < d->n_params; i++) {
            const ts_material_param *p = &d->params[i];
            const cJSON *sp = cJSON_GetObjectItemCaseSensitive(props, p->key);
            check_schema_range(p, sp, d->name);
            const cJSON *def = cJSON_GetObjectItemCaseSensitive(sp, "default");
            if (p->flags & TS_MPARAM_REQUIRED) {
                if (def) fail_msg("%s.%s: required in the table, with a default in the schema", d->name, p->key);
                continue;
            }
            if (!def) fail_msg("%s.%s: the schema gives no default", d->name, p->key);
            if (p->kind == TS_MPARAM_ENUM) {
                assert_true(cJSON_IsString(def));
                assert_string_equal(def->valuestring, p->names[(int)p->def]);
            } else if (!cJSON_IsNumber(def) || (float)def->valuedouble != p->def) {
                fail_msg("%s.%s: the table's default is %g, the schema's %s", d->name, p->key, p->def,
                         cJSON_IsNumber(def) ? "another number" : "not a number");
            }
        }
        if (d->flags & TS_MDESC_ROUGH) {
            const cJSON *def = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(props, "roughness"),
                                                                "default");
            if (!cJSON_IsNumber(def) || (float)def->valuedouble != d->rough_def)
                fail_msg("%s.roughness: the table's default is %g, the schema's differs", d->name, d->rough_def);
        }
    }
    cJSON_Delete(schema);
}

/* pbrt-v3's defaults as its Create functions (src/materials/<name>.cpp) have them. */
static void test_pbrt3_defaults(void **state)
{
    (void)state;
    static const struct {
        const char *pbrt3, *param;
        float def;
    } want[] = {
        {"matte", "Kd", 0.5f},         {"matte", "sigma", 0},          {"mirror", "Kr", 0.9f},
        {"glass", "Kr", 1},            {"glass", "Kt", 1},             {"glass", "eta", 1.5f},
        {"plastic", "Kd", 0.25f},      {"plastic", "Ks", 0.25f},       {"substrate", "Kd", 0.5f},
        {"substrate", "Ks", 0.5f},     {"uber", "Kd", 0.25f},          {"uber", "Ks", 0.25f},
        {"uber", "Kr", 0},             {"uber", "Kt", 0},              {"uber", "opacity", 1},
        {"uber", "eta", 1.5f},         {"translucent", "Kd", 0.25f},   {"translucent", "Ks", 0.25f},
        {"translucent", "reflect", 0.5f}, {"translucent", "transmit", 0.5f}, {"mix", "amount", 0.5f},
    };
    static const struct {
        const char *pbrt3;
        float rough;
    } rough[] = {{"plastic", 0.1f}, {"glass", 0}, {"metal", 0.01f}, {"substrate", 0.1f}, {"uber", 0.1f},
                 {"translucent", 0.1f}};
    int rows = 0;
    for (size_t k = 0; k < sizeof want / sizeof *want; k++) {
        const ts_material_desc *d = ts_material_desc_by_pbrt3(want[k].pbrt3);
        if (!d) fail_msg("no type reads pbrt-v3's %s", want[k].pbrt3);
        const ts_material_param *p = NULL;
        for (int i = 0; i < d->n_params; i++)
            if (d->params[i].pbrt3 && strcmp(d->params[i].pbrt3, want[k].param) == 0) p = &d->params[i];
        if (!p) fail_msg("%s: no row reads pbrt-v3's %s", want[k].pbrt3, want[k].param);
        if (p->pbrt3_def != want[k].def || p->pbrt3_def_rgb)
            fail_msg("%s.%s: the table's pbrt-v3 default is %g, pbrt-v3's %g", want[k].pbrt3, want[k].param,
                     p->pbrt3_def, want[k].def);
        rows++;
    }
    for (size_t k = 0; k < sizeof rough / sizeof *rough; k++) {
        const ts_material_desc *d = ts_material_desc_by_pbrt3(rough[k].pbrt3);
        assert_non_null(d);
        assert_true(d->flags & TS_MDESC_ROUGH);
        if (d->rough_def != rough[k].rough)
            fail_msg("%s: roughness default %g, pbrt-v3's %g", rough[k].pbrt3, d->rough_def, rough[k].rough);
    }
    /* metal's eta and k are copper's spectrum, not greys. */
    const ts_material_desc *metal = ts_material_desc_by_pbrt3("metal");
    assert_non_null(metal);
    for (int i = 0; i < metal->n_params; i++)
        if (metal->params[i].kind == TS_MPARAM_RGB) assert_non_null(metal->params[i].pbrt3_def_rgb);
    /* Every row with a pbrt-v3 name is in the list above, but metal's copper ones. */
    int named = 0;
    for (int t = 0; t < TS_MATERIAL_TYPE_COUNT; t++)
        for (int i = 0; i < ts_material_descs[t].n_params; i++)
            named += ts_material_descs[t].pbrt3 && ts_material_descs[t].params[i].pbrt3 &&
                     !ts_material_descs[t].params[i].pbrt3_def_rgb;
    assert_int_equal(named, rows);
}

#define HEAD                                                                                           \
    "{\"tessera\":1,\"camera\":{\"from\":[0,0,5],\"to\":[0,0,0]},\"film\":{\"width\":4,\"height\":4}," \
    "\"lights\":[{\"type\":\"point\",\"position\":[0,0,3],\"intensity\":1}],"
#define TAIL                                                                                                   \
    "\"shapes\":[{\"type\":\"sphere\",\"center\":[0,0,0],\"radius\":1,\"material\":\"m\"}]}"

/* The materials every type's document starts with: what a mix names. */
#define BASE "\"a\":{\"type\":\"diffuse\"},\"b\":{\"type\":\"mirror\"},"

static ts_status load(const ts_material_desc *d, const char *key, const char *value, ts_scene **s, ts_error *err)
{
    char doc[2048];
    char extra[256] = "";
    if (d->flags & TS_MDESC_MIX) snprintf(extra, sizeof extra, ",\"materials\":[\"a\",\"b\"]");
    if (d->flags & TS_MDESC_FILE) return TS_ERR_UNSUPPORTED; /* a table file: test_fourier_bsdf's */
    char required[512] = "";
    for (int i = 0; i < d->n_params; i++)
        if ((d->params[i].flags & TS_MPARAM_REQUIRED) && strcmp(d->params[i].key, key) != 0) {
            size_t n = strlen(required);
            snprintf(required + n, sizeof required - n, ",\"%s\":0.5", d->params[i].key);
        }
    snprintf(doc, sizeof doc, HEAD "\"materials\":{" BASE "\"m\":{\"type\":\"%s\"%s%s,\"%s\":%s}}," TAIL, d->name,
             extra, required, key, value);
    return ts_scene_load_text(doc, strlen(doc), NULL, "t", NULL, s, err);
}

static const ts_material *find(const ts_scene *s)
{
    for (uint32_t i = 0; i < s->n_materials; i++)
        if (s->material_names[i] && strcmp(s->material_names[i], "m") == 0) return &s->materials[i];
    fail_msg("no material m");
    return NULL;
}

/* For every row: an in-range value lands in the row's field; one outside its range is
 * refused, the error naming the row's JSON path. */
static void test_rows_through_the_front_end(void **state)
{
    (void)state;
    int checked = 0;
    for (int t = 0; t < TS_MATERIAL_TYPE_COUNT; t++) {
        const ts_material_desc *d = &ts_material_descs[t];
        for (int i = 0; i < d->n_params; i++) {
            const ts_material_param *p = &d->params[i];
            ts_scene *s = NULL;
            ts_error err = {0};
            const char *good = p->kind == TS_MPARAM_ENUM ? NULL : p->range == TS_MRANGE_ANGLE ? "45" : "0.75";
            char enum_value[64];
            if (p->kind == TS_MPARAM_ENUM) {
                snprintf(enum_value, sizeof enum_value, "\"%s\"", p->names[1]);
                good = enum_value;
            }
            ts_status st = load(d, p->key, good, &s, &err);
            if (st == TS_ERR_UNSUPPORTED) continue;
            if (st) fail_msg("%s.%s = %s refused: %s", d->name, p->key, good, err.message);
            const ts_material *m = find(s);
            assert_int_equal(m->type, d->type);
            switch (p->kind) {
            case TS_MPARAM_RGB: {
                const ts_material_rgb *v = ts_mparam_crgb(m, p);
                assert_null(v->tex);
                assert_true(v->value.r == 0.75f && v->value.g == 0.75f && v->value.b == 0.75f);
                break;
            }
            case TS_MPARAM_FLOAT:
                assert_true(ts_mparam_cfloat(m, p)->value == (p->range == TS_MRANGE_ANGLE ? 45.0f : 0.75f));
                break;
            case TS_MPARAM_ENUM:
                assert_int_equal(*(const int *)(const void *)((const char *)m + p->offset), 1);
                break;
            }
            ts_scene_destroy(s);
            s = NULL;
            /* Outside the range: -1 is outside every numeric range, 91 outside the angle's. */
            const char *bad = p->kind == TS_MPARAM_ENUM ? "\"none\"" : p->range == TS_MRANGE_ANGLE ? "91" : "-1";
            st = load(d, p->key, bad, &s, &err);
            if (st == TS_OK) fail_msg("%s.%s = %s accepted", d->name, p->key, bad);
            char want[128];
            snprintf(want, sizeof want, "materials.m.%s", p->key);
            if (!strstr(err.message, want)) fail_msg("%s.%s = %s: \"%s\" names no %s", d->name, p->key, bad, err.message, want);
            assert_null(s);
            checked++;
        }
    }
    assert_true(checked >= 25);
}

/* The builder itself (its callers need not be the JSON front end): each row's range
 * refused with the row's key, from a material that is otherwise the type's defaults. */
static void test_rows_through_the_builder(void **state)
{
    (void)state;
    ts_scene_builder *b = NULL;
    ts_error err = {0};
    assert_int_equal(ts_scene_builder_create(NULL, NULL, &b, &err), TS_OK);
    int checked = 0;
    for (int t = 0; t < TS_MATERIAL_TYPE_COUNT; t++) {
        const ts_material_desc *d = &ts_material_descs[t];
        if (d->flags & (TS_MDESC_FILE | TS_MDESC_MIX)) continue;
        ts_material m = {.type = d->type};
        ts_material_desc_defaults(&m);
        for (int i = 0; i < d->n_params; i++)
            if (d->params[i].flags & TS_MPARAM_REQUIRED) *ts_mparam_rgb(&m, &d->params[i]) = ts_material_rgb_gray(1);
        if (ts_scene_builder_add_material(b, NULL, &m, NULL, &err)) fail_msg("%s defaults: %s", d->name, err.message);
        for (int i = 0; i < d->n_params; i++) {
            const ts_material_param *p = &d->params[i];
            ts_material bad = m;
            float v = p->range == TS_MRANGE_ANGLE ? 91 : p->range == TS_MRANGE_UNIT ? 1.5f : -1;
            if (p->kind == TS_MPARAM_RGB) ts_mparam_rgb(&bad, p)->value.g = v;
            else if (p->kind == TS_MPARAM_FLOAT) ts_mparam_float(&bad, p)->value = v;
            else *ts_mparam_enum(&bad, p) = 7;
            ts_error e = {0};
            if (ts_scene_builder_add_material(b, NULL, &bad, NULL, &e) == TS_OK)
                fail_msg("%s.%s = %g accepted by the builder", d->name, p->key, v);
            if (strncmp(e.message, p->key, strlen(p->key)) != 0 || e.message[strlen(p->key)] != ':')
                fail_msg("%s.%s: \"%s\" does not start with the key", d->name, p->key, e.message);
            checked++;
        }
    }
    ts_scene_builder_destroy(b);
    assert_true(checked >= 25);
}

/* Each type's max_lobes is what its BSDF reaches with every colour grey ½ (some type's
 * lobe is left out when black), rough and smooth, and is never exceeded. */
static void test_max_lobes(void **state)
{
    (void)state;
    ts_interaction si = {0};
    si.n = si.ns = (ts_vec3){0, 0, 1};
    si.dpdu = (ts_vec3){1, 0, 0};
    si.dpdv = (ts_vec3){0, 1, 0};
    si.wo = (ts_vec3){0, 0.6f, 0.8f};
    for (int t = 0; t < TS_MATERIAL_TYPE_COUNT; t++) {
        const ts_material_desc *d = &ts_material_descs[t];
        if (d->flags & (TS_MDESC_FILE | TS_MDESC_MIX)) continue;
        int most = 0;
        for (int rough = 0; rough < 2; rough++) {
            ts_material m = {.type = d->type};
            ts_material_desc_defaults(&m);
            for (int i = 0; i < d->n_params; i++)
                if (d->params[i].kind == TS_MPARAM_RGB) *ts_mparam_rgb(&m, &d->params[i]) = ts_material_rgb_gray(0.5f);
            m.roughness = m.vroughness = ts_material_float_const(rough ? 0.3f : 0);
            ts_bsdf b;
            ts_material_bsdf(&m, &si, NULL, &b);
            if (b.n_bxdfs > d->max_lobes) fail_msg("%s: %d lobes, max_lobes %d", d->name, b.n_bxdfs, d->max_lobes);
            if (b.n_bxdfs > most) most = b.n_bxdfs;
        }
        if (most != d->max_lobes) fail_msg("%s: at most %d lobes seen, max_lobes says %d", d->name, most, d->max_lobes);
    }
}

/* docs/pbrt-v3.md's Materials table names every pbrt-v3 parameter each type reads. */
static void test_docs_name_every_parameter(void **state)
{
    (void)state;
    char *doc = doc_rows_load();
    if (!doc) fail_msg("cannot read docs/pbrt-v3.md (TS_SOURCE_DIR)");
    char row[8192];
    for (int t = 0; t < TS_MATERIAL_TYPE_COUNT; t++) {
        const ts_material_desc *d = &ts_material_descs[t];
        if (!d->pbrt3) continue;
        if (!doc_rows_find(doc, "## Materials", d->pbrt3, row, sizeof row)) fail_msg("docs/pbrt-v3.md has no row for %s", d->pbrt3);
        for (int i = 0; i < d->n_params; i++)
            if (d->params[i].pbrt3 && !doc_rows_names(row, d->params[i].pbrt3))
                fail_msg("docs/pbrt-v3.md's %s row does not name `%s`", d->pbrt3, d->params[i].pbrt3);
        if ((d->flags & TS_MDESC_PBRT3_ROUGH) && !doc_rows_names(row, "roughness"))
            fail_msg("docs/pbrt-v3.md's %s row does not name `roughness`", d->pbrt3);
        if ((d->flags & TS_MDESC_ANISO) && !(doc_rows_names(row, "uroughness") && doc_rows_names(row, "vroughness")))
            fail_msg("docs/pbrt-v3.md's %s row does not name `uroughness` and `vroughness`", d->pbrt3);
        if ((d->flags & TS_MDESC_FILE) && !doc_rows_names(row, "bsdffile")) fail_msg("fourier: `bsdffile` undocumented");
        if ((d->flags & TS_MDESC_MIX) && !(doc_rows_names(row, "namedmaterial1") && doc_rows_names(row, "namedmaterial2")))
            fail_msg("mix: `namedmaterial1/2` undocumented");
    }
    free(doc);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_schema_agrees),
        cmocka_unit_test(test_pbrt3_defaults),
        cmocka_unit_test(test_rows_through_the_front_end),
        cmocka_unit_test(test_rows_through_the_builder),
        cmocka_unit_test(test_max_lobes),
        cmocka_unit_test(test_docs_name_every_parameter),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
