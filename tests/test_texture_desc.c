/* test_texture_desc.c — the one description per texture type (textures/texture_desc.h)
 * against the JSON schema (proto/scene.schema.json: each type's keys and each row's
 * default, exactly) and against pbrt-v3's defaults and names, written out here from
 * pbrt-v3's src/textures (an independent copy, the dots swap included). Every check is
 * exact; there is no false-failure rate to name. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
// clang-format off
#include <cmocka.h>
// clang-format on

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "doc_rows.h"
#include "textures/texture_desc.h"

static cJSON *load_schema(void)
{
    cJSON *s = doc_rows_schema();
    if (!s) fail_msg("cannot read proto/scene.schema.json (TS_SOURCE_DIR)");
    return s;
}

static void test_schema_agrees(void **state)
{
    (void)state;
    cJSON *schema = load_schema();
    for (int t = 0; t < TS_TEXTURE_TYPE_COUNT; t++) {
        const ts_texture_desc *d = &ts_texture_descs[t];
        assert_int_equal(d->type, t);
        const cJSON *props = cJSON_GetObjectItemCaseSensitive(doc_rows_schema_alt(schema, "texture", d->name), "properties");
        if (!props) fail_msg("the schema has no texture of type %s", d->name);
        /* The keys the JSON front end takes for this type (json/scene_json_texture.c); a
         * checkerboard's are its 2D description's, which the schema lists. */
        const ts_texture_desc *k = d->dimension ? ts_texture_desc_by_name(d->name, 2) : d;
        const char *keys[32];
        int n = 0;
        keys[n++] = "type", keys[n++] = "kind", keys[n++] = "transform", keys[n++] = "world_to_texture";
        if (k->dimension) keys[n++] = "dimension";
        if (k->flags & TS_TDESC_MAP2D) keys[n++] = "mapping";
        for (int i = 0; i < k->n_params; i++) {
            keys[n++] = k->params[i].key;
            if (k->params[i].kind == TS_TPARAM_OCTAVES) keys[n++] = "roughness";
        }
        if (k->flags & TS_TDESC_AAMODE) keys[n++] = "aamode";
        if (k->flags & TS_TDESC_IMAGE) {
            const char *image[] = {"file", "wrap", "trilinear", "max_anisotropy", "scale", "gamma", "invert"};
            for (int i = 0; i < 7; i++)
                keys[n++] = image[i];
        }
        if (cJSON_GetArraySize(props) != n) fail_msg("%s: the schema has %d keys, the table %d", d->name, cJSON_GetArraySize(props), n);
        for (int i = 0; i < n; i++)
            if (!cJSON_GetObjectItemCaseSensitive(props, keys[i]))
                fail_msg("%s: the table has %s, the schema does not", d->name, keys[i]);
        for (int i = 0; i < d->n_params; i++) {
            const ts_texture_param *p = &d->params[i];
            const cJSON *def = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(props, p->key), "default");
            if (!cJSON_IsNumber(def) || (float)def->valuedouble != p->def)
                fail_msg("%s.%s: the table's default is %g, the schema's differs", d->name, p->key, p->def);
            if (p->kind == TS_TPARAM_OCTAVES) {
                def = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(props, "roughness"), "default");
                if (!cJSON_IsNumber(def) || def->valuedouble != 0.5) fail_msg("%s.roughness: default not 0.5", d->name);
            }
        }
        if (d->dimension) {
            const cJSON *def = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(props, "dimension"), "default");
            assert_true(cJSON_IsNumber(def) && def->valuedouble == 2);
        }
    }
    cJSON_Delete(schema);
}

/* pbrt-v3's Create*Texture functions: which parameter fills which field, and its default. */
static void test_pbrt3_names_and_defaults(void **state)
{
    (void)state;
    static const struct {
        const char *cls, *key, *pbrt3;
        float def;
    } want[] = {
        {"constant", "value", "value", 1},    {"scale", "tex1", "tex1", 1},          {"scale", "tex2", "tex2", 1},
        {"mix", "tex1", "tex1", 0},           {"mix", "tex2", "tex2", 1},            {"mix", "amount", "amount", 0.5f},
        {"bilerp", "v00", "v00", 0},          {"bilerp", "v01", "v01", 1},           {"bilerp", "v10", "v10", 0},
        {"bilerp", "v11", "v11", 1},          {"checkerboard", "tex1", "tex1", 1},   {"checkerboard", "tex2", "tex2", 0},
        /* DotsTexture(map, tex1 = "inside", tex2 = "outside") takes (inside, outside) as
         * (outsideDot, insideDot): the field "inside" is filled from pbrt-v3's "outside". */
        {"dots", "inside", "outside", 0},     {"dots", "outside", "inside", 1},      {"fbm", "octaves", "octaves", 8},
        {"wrinkled", "octaves", "octaves", 8}, {"marble", "octaves", "octaves", 8},  {"marble", "scale", "scale", 1},
        {"marble", "variation", "variation", 0.2f},
    };
    int rows = 0;
    for (size_t k = 0; k < sizeof want / sizeof *want; k++) {
        const ts_texture_desc *d = ts_texture_desc_by_pbrt3(want[k].cls, 2);
        assert_non_null(d);
        const ts_texture_param *p = NULL;
        for (int i = 0; i < d->n_params; i++)
            if (strcmp(d->params[i].key, want[k].key) == 0) p = &d->params[i];
        if (!p) fail_msg("%s: no row %s", want[k].cls, want[k].key);
        if (strcmp(p->pbrt3, want[k].pbrt3) != 0 || p->pbrt3_def != want[k].def)
            fail_msg("%s.%s: read from pbrt-v3's \"%s\" (default %g), pbrt-v3 fills it from \"%s\" (default %g)",
                     want[k].cls, want[k].key, p->pbrt3, p->pbrt3_def, want[k].pbrt3, want[k].def);
        rows++;
    }
    int all = 0;
    for (int t = 0; t < TS_TEXTURE_TYPE_COUNT; t++)
        if (ts_texture_descs[t].type != TS_TEXTURE_CHECKERBOARD3D) all += ts_texture_descs[t].n_params;
    assert_int_equal(all, rows);
    /* The 3D checkerboard reads the same names as the 2D one. */
    const ts_texture_desc *c2 = ts_texture_desc_by_pbrt3("checkerboard", 2), *c3 = ts_texture_desc_by_pbrt3("checkerboard", 3);
    assert_true(c2 != c3 && c3->type == TS_TEXTURE_CHECKERBOARD3D && c3->n_params == c2->n_params);
    for (int i = 0; i < c2->n_params; i++) {
        assert_string_equal(c2->params[i].pbrt3, c3->params[i].pbrt3);
        assert_true(c2->params[i].pbrt3_def == c3->params[i].pbrt3_def);
    }
}

/* docs/pbrt-v3.md's Textures table names every pbrt-v3 parameter each class reads. */
static void test_docs_name_every_parameter(void **state)
{
    (void)state;
    char *doc = doc_rows_load();
    if (!doc) fail_msg("cannot read docs/pbrt-v3.md (TS_SOURCE_DIR)");
    char row[8192];
    for (int t = 0; t < TS_TEXTURE_TYPE_COUNT; t++) {
        const ts_texture_desc *d = &ts_texture_descs[t];
        if (!doc_rows_find(doc, "## Textures", d->pbrt3, row, sizeof row)) fail_msg("docs/pbrt-v3.md has no row for %s", d->pbrt3);
        for (int i = 0; i < d->n_params; i++) {
            if (!doc_rows_names(row, d->params[i].pbrt3))
                fail_msg("docs/pbrt-v3.md's %s row does not name `%s`", d->pbrt3, d->params[i].pbrt3);
            if (d->params[i].kind == TS_TPARAM_OCTAVES && !doc_rows_names(row, "roughness"))
                fail_msg("docs/pbrt-v3.md's %s row does not name `roughness`", d->pbrt3);
        }
        if (d->dimension && !doc_rows_names(row, "dimension")) fail_msg("checkerboard: `dimension` undocumented");
        if ((d->flags & TS_TDESC_AAMODE) && !doc_rows_names(row, "aamode")) fail_msg("checkerboard: `aamode` undocumented");
        static const char *const image[] = {"filename", "maxanisotropy", "trilinear", "wrap", "scale", "gamma", "invert"};
        for (size_t i = 0; (d->flags & TS_TDESC_IMAGE) && i < sizeof image / sizeof *image; i++)
            if (!doc_rows_names(row, image[i])) fail_msg("imagemap: `%s` undocumented", image[i]);
    }
    free(doc);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_schema_agrees),
        cmocka_unit_test(test_pbrt3_names_and_defaults),
        cmocka_unit_test(test_docs_name_every_parameter),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
