/* test_assets.c — the embedded web UI (server/assets.h): lookup, content types, and that
 * the build embedded a page that loads its script and styles from /assets/. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <stdio.h>
#include <string.h>

#include "assets.h"
#include "integrators/effects.h"

static void test_index(void **state)
{
    (void)state;
    const srv_asset *root = srv_asset_find("/"), *index = srv_asset_find("/index.html");
    assert_non_null(root);
    assert_ptr_equal(root, index);
    assert_string_equal(root->content_type, "text/html; charset=utf-8");
    assert_true(root->size > 100);
    assert_int_equal(root->data[root->size], 0); /* NUL-terminated after its bytes */
    assert_non_null(strstr((const char *)root->data, "<title>tessera</title>"));
    assert_ptr_equal(srv_asset_find("/?access_token=x"), root);
}

static void test_referenced_assets(void **state)
{
    (void)state;
    /* Every ./assets/... the page references is embedded, with its content type. */
    const char *html = (const char *)srv_asset_find("/")->data;
    int found = 0;
    for (const char *p = strstr(html, "./assets/"); p; p = strstr(p + 1, "./assets/")) {
        char path[256];
        size_t n = strcspn(p + 1, "\"' >");
        assert_true(n < sizeof path);
        memcpy(path, p + 1, n);
        path[n] = '\0';
        const srv_asset *a = srv_asset_find(path);
        assert_non_null(a);
        const char *ext = strrchr(path, '.');
        if (!strcmp(ext, ".js")) assert_string_equal(a->content_type, "text/javascript; charset=utf-8");
        else if (!strcmp(ext, ".css")) assert_string_equal(a->content_type, "text/css; charset=utf-8");
        found++;
    }
    assert_true(found >= 2); /* the script and the style sheet */
}

/* Every effect a job's status can list (integrators/effects.h) has its words in the page's
 * script (EFFECT_TEXT in web/src/main.js: the job list shows them, the key as the title),
 * so none falls back to its identifier. */
static void test_effect_labels(void **state)
{
    (void)state;
    const char *html = (const char *)srv_asset_find("/")->data;
    const char *js = NULL;
    for (const char *p = strstr(html, "./assets/"); p && !js; p = strstr(p + 1, "./assets/")) {
        char path[256];
        size_t n = strcspn(p + 1, "\"' >");
        assert_true(n < sizeof path);
        memcpy(path, p + 1, n);
        path[n] = '\0';
        if (n > 3 && !strcmp(path + n - 3, ".js")) js = (const char *)srv_asset_find(path)->data;
    }
    assert_non_null(js);
    for (uint32_t b = 0; b < TS_EFFECT_COUNT; b++) {
        const char *key = ts_effect_key(1u << b);
        assert_non_null(key);
        char a[64], q[64];
        snprintf(a, sizeof a, "%s:\"", key); /* as Vite writes it */
        snprintf(q, sizeof q, "%s: '", key);  /* as the source has it */
        if (!strstr(js, a) && !strstr(js, q)) fail_msg("the web UI has no words for the effect \"%s\"", key);
    }
}

static void test_scenes(void **state)
{
    (void)state;
    const srv_asset *idx = srv_asset_find("/scenes/index.json");
    assert_non_null(idx);
    assert_string_equal(idx->content_type, "application/json");
    assert_non_null(strstr((const char *)idx->data, "cornell-box.json"));
    assert_non_null(srv_asset_find("/scenes/cornell-box.json"));
}

static void test_misses(void **state)
{
    (void)state;
    assert_null(srv_asset_find(NULL));
    assert_null(srv_asset_find(""));
    assert_null(srv_asset_find("index.html"));
    assert_null(srv_asset_find("/nope.js"));
    assert_null(srv_asset_find("/assets/../index.html"));
    assert_null(srv_asset_find("/api/v1/jobs"));
    assert_null(srv_asset_find("/index.htm"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_index),
        cmocka_unit_test(test_referenced_assets),
        cmocka_unit_test(test_effect_labels),
        cmocka_unit_test(test_scenes),
        cmocka_unit_test(test_misses),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
