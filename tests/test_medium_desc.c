/* test_medium_desc.c — the one description per medium type (build/medium_desc.h) against
 * the JSON schema (proto/scene.schema.json: each type's keys, its required keys and each
 * row's default) and against pbrt-v3's names (MakeNamedMedium's "homogeneous" and
 * "heterogeneous") and defaults, written out here from pbrt-v3's src/core/api.cpp and
 * media/grid.cpp (an independent copy). Every check is exact. */
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

#include "build/medium_desc.h"
#include "doc_rows.h"

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
    for (int t = 0; t < TS_MEDIUM_DESC_COUNT; t++) {
        const ts_medium_type_desc *d = &ts_medium_descs[t];
        const cJSON *alt = doc_rows_schema_alt(schema, "medium", d->name);
        if (!alt) fail_msg("the schema has no medium of type %s", d->name);
        const cJSON *props = cJSON_GetObjectItemCaseSensitive(alt, "properties");
        int n = 1 + d->n_params + ((d->flags & TS_VDESC_TRANSFORM) ? 1 : 0);
        if (cJSON_GetArraySize(props) != n) fail_msg("%s: the schema has %d keys, the table %d", d->name, cJSON_GetArraySize(props), n);
        if ((d->flags & TS_VDESC_TRANSFORM) && !cJSON_GetObjectItemCaseSensitive(props, "transform"))
            fail_msg("%s: the schema has no transform", d->name);
        for (int i = 0; i < d->n_params; i++) {
            const ts_medium_param *p = &d->params[i];
            const cJSON *sp = cJSON_GetObjectItemCaseSensitive(props, p->key);
            if (!sp) fail_msg("%s: the table has %s, the schema does not", d->name, p->key);
            bool req = p->kind == TS_VPARAM_COUNT || p->kind == TS_VPARAM_DENSITY;
            if (req != doc_rows_schema_required(alt, p->key)) fail_msg("%s.%s: required in one of the table and the schema only", d->name, p->key);
            const cJSON *def = cJSON_GetObjectItemCaseSensitive(sp, "default");
            if (p->kind == TS_VPARAM_NUMBER && (!cJSON_IsNumber(def) || def->valuedouble != p->def[0]))
                fail_msg("%s.%s: the schema's default differs from the table's %g", d->name, p->key, p->def[0]);
            if (p->kind == TS_VPARAM_POINT)
                for (int k = 0; k < 3; k++)
                    if (!cJSON_IsArray(def) || cJSON_GetArrayItem(def, k)->valuedouble != p->def[k])
                        fail_msg("%s.%s: the schema's default differs from the table's", d->name, p->key);
        }
    }
    cJSON_Delete(schema);
}

static void test_pbrt3_names_and_defaults(void **state)
{
    (void)state;
    assert_int_equal(ts_medium_desc_by_pbrt3("homogeneous")->type, TS_MEDIUM_HOMOGENEOUS);
    assert_int_equal(ts_medium_desc_by_pbrt3("heterogeneous")->type, TS_MEDIUM_GRID);
    assert_null(ts_medium_desc_by_pbrt3("grid"));
    static const struct {
        const char *key;
        double def[3];
    } want[] = {{"scale", {1}}, {"g", {0}}, {"sigma_a", {0}}, {"sigma_s", {0}}, {"nx", {1}}, {"ny", {1}},
                {"nz", {1}},    {"p0", {0, 0, 0}}, {"p1", {1, 1, 1}}};
    const ts_medium_type_desc *grid = ts_medium_desc_by_pbrt3("heterogeneous");
    for (size_t k = 0; k < sizeof want / sizeof *want; k++) {
        const ts_medium_param *p = NULL;
        for (int i = 0; i < grid->n_params; i++)
            if (strcmp(grid->params[i].key, want[k].key) == 0) p = &grid->params[i];
        if (!p) fail_msg("heterogeneous: no row %s", want[k].key);
        for (int i = 0; i < 3; i++)
            if (p->def[i] != want[k].def[i]) fail_msg("heterogeneous.%s: default differs from pbrt-v3's", want[k].key);
    }
}

/* docs/pbrt-v3.md's MakeNamedMedium row names every parameter of both types. */
static void test_docs_name_every_parameter(void **state)
{
    (void)state;
    char *doc = doc_rows_load();
    if (!doc) fail_msg("cannot read docs/pbrt-v3.md (TS_SOURCE_DIR)");
    char row[8192];
    if (!doc_rows_find(doc, "## Directives", "MakeNamedMedium", row, sizeof row)) fail_msg("no MakeNamedMedium row");
    for (int t = 0; t < TS_MEDIUM_DESC_COUNT; t++) {
        const ts_medium_type_desc *d = &ts_medium_descs[t];
        if (!doc_rows_names(row, d->pbrt3)) fail_msg("the MakeNamedMedium row does not name `%s`", d->pbrt3);
        for (int i = 0; i < d->n_params; i++)
            if (!doc_rows_names(row, d->params[i].key))
                fail_msg("the MakeNamedMedium row does not name `%s` (%s)", d->params[i].key, d->pbrt3);
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
