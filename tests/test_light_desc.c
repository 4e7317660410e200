/* test_light_desc.c — the one description per light type (build/light_desc.h) against the
 * places that must agree with it without reading it, and through the readers that do:
 *  - the JSON schema (proto/scene.schema.json): each type's keys, its required keys, each
 *    row's default, and the angles' bounds;
 *  - pbrt-v3's defaults, written out here from pbrt-v3's src/lights (an independent copy);
 *  - the JSON front end and the builder, generically over the rows: an angle outside its
 *    range and a "to" equal to "from" are refused, naming the row's key.
 * Every check is exact; there is no false-failure rate to name. */
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

#include "build/light_desc.h"
#include "build/scene_builder.h"
#include "doc_rows.h"
#include "json/scene_json.h"
#include "scene/scene.h"

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
    for (int t = 0; t < TS_LIGHT_DESC_COUNT; t++) {
        const ts_light_type_desc *d = &ts_light_descs[t];
        if (d->flags & TS_LDESC_ENVIRONMENT) continue; /* radiance-or-map: test_envmap's */
        const cJSON *alt = doc_rows_schema_alt(schema, "light", d->name);
        if (!alt) fail_msg("the schema has no light of type %s", d->name);
        const cJSON *props = cJSON_GetObjectItemCaseSensitive(alt, "properties");
        assert_int_equal(cJSON_GetArraySize(props), 1 + d->n_params);
        for (int i = 0; i < d->n_params; i++) {
            const ts_light_param *p = &d->params[i];
            const cJSON *sp = cJSON_GetObjectItemCaseSensitive(props, p->key);
            if (!sp) fail_msg("%s: the table has %s, the schema does not", d->name, p->key);
            bool req = (p->flags & TS_LPARAM_REQUIRED) != 0;
            if (req != doc_rows_schema_required(alt, p->key))
                fail_msg("%s.%s: required in %s only", d->name, p->key, req ? "the table" : "the schema");
            const cJSON *def = cJSON_GetObjectItemCaseSensitive(sp, "default");
            if (req) {
                if (def) fail_msg("%s.%s: required, with a default in the schema", d->name, p->key);
                continue;
            }
            if (!def) fail_msg("%s.%s: the schema gives no default", d->name, p->key);
            if (p->kind == TS_LPARAM_POINT) {
                for (int k = 0; k < 3; k++)
                    if (cJSON_GetArrayItem(def, k)->valuedouble != p->def[k])
                        fail_msg("%s.%s: the schema's default differs from the table's", d->name, p->key);
            } else if (def->valuedouble != p->def[0]) {
                fail_msg("%s.%s: the table's default is %g, the schema's %g", d->name, p->key, p->def[0], def->valuedouble);
            }
            if (p->kind == TS_LPARAM_ANGLE) {
                const cJSON *bound = cJSON_GetObjectItemCaseSensitive(
                    sp, (p->flags & TS_LPARAM_UPTO_ANGLE) ? "minimum" : "exclusiveMinimum");
                if (!cJSON_IsNumber(bound) || bound->valuedouble != 0)
                    fail_msg("%s.%s: the schema does not state the table's lower bound", d->name, p->key);
                if (!(p->flags & TS_LPARAM_UPTO_ANGLE) &&
                    cJSON_GetObjectItemCaseSensitive(sp, "maximum")->valuedouble != 180)
                    fail_msg("%s.%s: the schema's maximum is not 180", d->name, p->key);
            }
        }
    }
    cJSON_Delete(schema);
}

/* pbrt-v3's CreatePointLight, CreateSpotLight, CreateDistantLight. */
static void test_pbrt3_defaults(void **state)
{
    (void)state;
    static const struct {
        const char *light, *param;
        double def[3];
    } want[] = {
        {"point", "I", {1}},          {"point", "from", {0, 0, 0}},    {"spot", "I", {1}},
        {"spot", "from", {0, 0, 0}},  {"spot", "to", {0, 0, 1}},       {"spot", "coneangle", {30}},
        {"spot", "conedelta", {5}},   {"distant", "L", {1}},           {"distant", "from", {0, 0, 0}},
        {"distant", "to", {0, 0, 1}},
    };
    int rows = 0;
    for (size_t k = 0; k < sizeof want / sizeof *want; k++) {
        const ts_light_type_desc *d = ts_light_desc_by_pbrt3(want[k].light);
        assert_non_null(d);
        const ts_light_param *p = NULL;
        for (int i = 0; i < d->n_params; i++)
            if (strcmp(d->params[i].pbrt3, want[k].param) == 0) p = &d->params[i];
        if (!p) fail_msg("%s: no row reads pbrt-v3's %s", want[k].light, want[k].param);
        int n = p->kind == TS_LPARAM_POINT ? 3 : 1;
        for (int i = 0; i < n; i++)
            if (p->pbrt3_def[i] != want[k].def[i])
                fail_msg("%s.%s: the table's pbrt-v3 default differs from pbrt-v3's", want[k].light, want[k].param);
        rows++;
    }
    int all = 0;
    for (int t = 0; t < TS_LIGHT_DESC_COUNT; t++)
        all += ts_light_descs[t].n_params;
    assert_int_equal(all, rows);
}

#define HEAD "{\"tessera\":1,\"camera\":{\"from\":[0,0,5],\"to\":[0,0,0]},\"film\":{\"width\":4,\"height\":4},"

/* An angle out of range, and "to" at "from", through the JSON front end and the builder. */
static void test_ranges_refused(void **state)
{
    (void)state;
    static const struct {
        const char *light, *want;
    } cases[] = {
        {"{\"type\":\"spot\",\"from\":[0,1,0],\"to\":[0,0,0],\"intensity\":1,\"cone_angle\":181}", "lights[0].cone_angle"},
        {"{\"type\":\"spot\",\"from\":[0,1,0],\"to\":[0,0,0],\"intensity\":1,\"cone_angle\":0}", "lights[0].cone_angle"},
        {"{\"type\":\"spot\",\"from\":[0,1,0],\"to\":[0,0,0],\"intensity\":1,\"cone_delta\":31}", "lights[0].cone_delta"},
        {"{\"type\":\"spot\",\"from\":[0,1,0],\"to\":[0,1,0],\"intensity\":1}", "lights[0].to: must differ"},
        {"{\"type\":\"distant\",\"to\":[0,0,0],\"irradiance\":1}", "lights[0].to: must differ"},
        {"{\"type\":\"point\",\"position\":[0,0,0]}", "lights[0].intensity"},
    };
    for (size_t k = 0; k < sizeof cases / sizeof *cases; k++) {
        char doc[1024];
        snprintf(doc, sizeof doc, HEAD "\"lights\":[%s]}", cases[k].light);
        ts_scene *s = NULL;
        ts_error err = {0};
        if (ts_scene_load_text(doc, strlen(doc), NULL, "t", NULL, &s, &err) == TS_OK)
            fail_msg("%s accepted", cases[k].light);
        if (!strstr(err.message, cases[k].want)) fail_msg("\"%s\" names no %s", err.message, cases[k].want);
    }
    /* The builder, called directly: each angle row's range and the NOT_FROM row. */
    ts_scene_builder *b = NULL;
    ts_error err = {0};
    assert_int_equal(ts_scene_builder_create(NULL, NULL, &b, &err), TS_OK);
    ts_light_desc ok = {.type = TS_LIGHT_SPOT, .color = {1, 1, 1}, .from = {0, 1, 0}, .to = {0, 0, 0},
                        .cone_angle_deg = 30, .cone_delta_deg = 5, .to_world = ts_xform_identity()};
    assert_int_equal(ts_scene_builder_add_light(b, &ok, &err), TS_OK);
    const ts_light_type_desc *spot = ts_light_desc_by_name("spot");
    for (int i = 0; i < spot->n_params; i++) {
        const ts_light_param *p = &spot->params[i];
        ts_light_desc bad = ok;
        if (p->kind == TS_LPARAM_ANGLE) *ts_lparam_angle(&bad, p) = (p->flags & TS_LPARAM_UPTO_ANGLE) ? 31 : 190;
        else if (p->flags & TS_LPARAM_NOT_FROM) *ts_lparam_point(&bad, p) = bad.from;
        else continue;
        ts_error e = {0};
        if (ts_scene_builder_add_light(b, &bad, &e) == TS_OK) fail_msg("spot.%s out of range accepted", p->key);
        if (strncmp(e.message, p->key, strlen(p->key)) != 0) fail_msg("\"%s\" does not start with %s", e.message, p->key);
    }
    ts_scene_builder_destroy(b);
}

/* docs/pbrt-v3.md's Lights table names every pbrt-v3 parameter each type reads. */
static void test_docs_name_every_parameter(void **state)
{
    (void)state;
    char *doc = doc_rows_load();
    if (!doc) fail_msg("cannot read docs/pbrt-v3.md (TS_SOURCE_DIR)");
    char row[8192];
    for (int t = 0; t < TS_LIGHT_DESC_COUNT; t++) {
        const ts_light_type_desc *d = &ts_light_descs[t];
        if (!doc_rows_find(doc, "## Lights", d->pbrt3, row, sizeof row)) fail_msg("docs/pbrt-v3.md has no row for %s", d->pbrt3);
        for (int i = 0; i < d->n_params; i++)
            if (!doc_rows_names(row, d->params[i].pbrt3))
                fail_msg("docs/pbrt-v3.md's %s row does not name `%s`", d->pbrt3, d->params[i].pbrt3);
        if (!doc_rows_names(row, "scale")) fail_msg("docs/pbrt-v3.md's %s row does not name `scale`", d->pbrt3);
    }
    free(doc);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_schema_agrees),
        cmocka_unit_test(test_pbrt3_defaults),
        cmocka_unit_test(test_ranges_refused),
        cmocka_unit_test(test_docs_name_every_parameter),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
