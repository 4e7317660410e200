/* test_pbrt_parser.c — the pbrt-v3 parsing layer (renderer/pbrt3/pbrt_*.h): tokens and
 * their positions (also across the lexer's 1 MiB chunks), every parameter type and the
 * lookup API, the transform conventions checked numerically against pbrt-v3's
 * definitions, attribute and name scoping, object instancing, Include (relative paths,
 * cycles, depth, confinement), motion and media warnings, every error sentence, and the
 * published pbrt-v3 scenes of the shared scene collection beside the source tree (found
 * through TS_SOURCE_DIR; skipped where it is absent; never copied into the repository).
 * Scenes are written inline; the files Include and .spd need go to a temporary folder. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "pbrt3/pbrt_parser.h"
#include "tmp_folder.h"

/* Writes ts_tmp_dir/rel (folders made as needed). */
static void write_file(const char *rel, const char *text)
{
    ts_tmp_write(rel, text, strlen(text), NULL, 0);
}

static ts_pbrt_scene *parse_ok(const char *text)
{
    ts_pbrt_scene *s = NULL;
    ts_error err = {0};
    ts_status st = ts_pbrt_parse_text(text, strlen(text), "t.pbrt", ts_tmp_dir, NULL, &s, &err);
    if (st) fail_msg("parse failed: %s", err.message);
    assert_non_null(s);
    return s;
}

/* The text must be refused with a message containing want (and status, if not TS_OK). */
static void expect_error_status(const char *text, ts_status status, const char *want)
{
    ts_pbrt_scene *s = NULL;
    ts_error err = {0};
    ts_status st = ts_pbrt_parse_text(text, strlen(text), "t.pbrt", ts_tmp_dir, NULL, &s, &err);
    if (st == TS_OK) fail_msg("parsed, but should fail with \"%s\":\n%s", want, text);
    assert_null(s);
    assert_int_equal(err.status, st);
    if (status != TS_OK && st != status) fail_msg("status %d, expected %d: %s", st, status, err.message);
    if (!strstr(err.message, want)) fail_msg("expected \"%s\" in the message \"%s\"", want, err.message);
}

static void expect_error(const char *text, const char *want) { expect_error_status(text, TS_OK, want); }

#define WORLD(body) "WorldBegin\n" body "WorldEnd\n"

static void assert_near(double a, double b, double tol)
{
    if (!(fabs(a - b) <= tol)) fail_msg("%.17g is not within %g of %.17g", a, tol, b);
}

static void assert_mat_near(const ts_mat4 *a, const double b[4][4], double tol)
{
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            if (!(fabs(a->m[i][j] - b[i][j]) <= tol))
                fail_msg("m[%d][%d] = %.17g, expected %.17g", i, j, a->m[i][j], b[i][j]);
}

static ts_dvec3 apply(const ts_mat4 *m, double x, double y, double z)
{
    ts_xform t = {*m, ts_mat4_identity()};
    return ts_xform_point(&t, (ts_dvec3){x, y, z});
}

static bool has_warning(const ts_pbrt_scene *s, const char *want)
{
    for (size_t i = 0; i < s->warning_count; i++)
        if (strstr(s->warnings[i].message, want)) return true;
    return false;
}

/* ---------------------------------------------------------------- lexer ---- */

static void test_lexer_tokens_and_positions(void **state)
{
    (void)state;
    const char *text = "Shape \"sphere\" # a comment \"not a string\"\n"
                       "  [ 1 -2.5 .5 5. +3e2 ] \"a\\\"b\\\\c\\n\" true\n"
                       "\tWorldEnd";
    ts_pbrt_lexer *lx;
    ts_error err = {0};
    assert_int_equal(ts_pbrt_lexer_from_memory(text, strlen(text), "x.pbrt", &lx, &err), TS_OK);
    struct {
        ts_pbrt_token_kind kind;
        unsigned line, col;
        const char *text;
        double number;
    } want[] = {
        {TS_PBRT_TOKEN_WORD, 1, 1, "Shape", 0},    {TS_PBRT_TOKEN_STRING, 1, 7, "sphere", 0},
        {TS_PBRT_TOKEN_LBRACKET, 2, 3, NULL, 0},   {TS_PBRT_TOKEN_NUMBER, 2, 5, NULL, 1},
        {TS_PBRT_TOKEN_NUMBER, 2, 7, NULL, -2.5},  {TS_PBRT_TOKEN_NUMBER, 2, 12, NULL, 0.5},
        {TS_PBRT_TOKEN_NUMBER, 2, 15, NULL, 5},    {TS_PBRT_TOKEN_NUMBER, 2, 18, NULL, 300},
        {TS_PBRT_TOKEN_RBRACKET, 2, 23, NULL, 0},  {TS_PBRT_TOKEN_STRING, 2, 25, "a\"b\\c\n", 0},
        {TS_PBRT_TOKEN_WORD, 2, 37, "true", 0},    {TS_PBRT_TOKEN_WORD, 3, 2, "WorldEnd", 0},
        {TS_PBRT_TOKEN_EOF, 3, 10, NULL, 0},
    };
    for (size_t i = 0; i < sizeof want / sizeof want[0]; i++) {
        ts_pbrt_token t;
        assert_int_equal(ts_pbrt_lexer_next(lx, &t, &err), TS_OK);
        if (t.kind != want[i].kind || t.loc.line != want[i].line || t.loc.column != want[i].col)
            fail_msg("token %zu: kind %d at %u:%u, expected kind %d at %u:%u", i, t.kind, t.loc.line, t.loc.column,
                     want[i].kind, want[i].line, want[i].col);
        if (want[i].text) assert_string_equal(t.text, want[i].text);
        if (t.kind == TS_PBRT_TOKEN_NUMBER) assert_true(t.number == want[i].number);
        assert_string_equal(t.loc.file, "x.pbrt");
    }
    ts_pbrt_token t;
    assert_int_equal(ts_pbrt_lexer_next(lx, &t, &err), TS_OK); /* EOF again */
    assert_int_equal(t.kind, TS_PBRT_TOKEN_EOF);
    ts_pbrt_lexer_destroy(lx);
}

static void test_lexer_numbers(void **state)
{
    (void)state;
    /* Exact conversion: the fast path and strtod must agree with the correctly rounded value. */
    const char *good[] = {"0.1",   "-0.1", "1e-3",   "6.02214076e23", "123456789012345678901234", "3.4028234e38",
                          "1e-320", ".5e1", "-0",    "0.000000000000000000000000001", "9007199254740993",
                          "1E+2"};
    for (size_t i = 0; i < sizeof good / sizeof good[0]; i++) {
        double v;
        if (!ts_pbrt_parse_number(good[i], strlen(good[i]), &v)) fail_msg("'%s' refused", good[i]);
        assert_true(v == strtod(good[i], NULL));
    }
    const char *bad[] = {"1.2.3", "12abc", "-", ".", "1e", "1e+", "--1", "+-1", "1e999", "0x10", "nan", "inf", ""};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        double v;
        if (ts_pbrt_parse_number(bad[i], strlen(bad[i]), &v)) fail_msg("'%s' accepted as %g", bad[i], v);
    }
}

static void lexer_expect_error(const char *text, const char *want)
{
    ts_pbrt_lexer *lx;
    ts_error err = {0};
    assert_int_equal(ts_pbrt_lexer_from_memory(text, strlen(text), "x.pbrt", &lx, &err), TS_OK);
    ts_status st = TS_OK;
    ts_pbrt_token t;
    for (int i = 0; i < 100 && !st; i++) {
        st = ts_pbrt_lexer_next(lx, &t, &err);
        if (!st && t.kind == TS_PBRT_TOKEN_EOF) break;
    }
    ts_pbrt_lexer_destroy(lx);
    if (!st) fail_msg("no error for %s", text);
    if (!strstr(err.message, want)) fail_msg("expected \"%s\" in \"%s\"", want, err.message);
}

static void test_lexer_errors(void **state)
{
    (void)state;
    lexer_expect_error("Shape \"sphere", "x.pbrt:1:7: unterminated string");
    lexer_expect_error("Shape \"sph\nere\"", "x.pbrt:1:7: unterminated string (a string must end on the line it starts)");
    lexer_expect_error("  \"a\\qb\"", "x.pbrt:1:5: unknown escape '\\q' in a string");
    lexer_expect_error("\n\n   1.2.3", "x.pbrt:3:4: bad number '1.2.3'");
    lexer_expect_error("Shape {", "x.pbrt:1:7: unexpected character '{'");
    lexer_expect_error("Sha$pe", "x.pbrt:1:4: unexpected character '$'");
    lexer_expect_error("a \x01", "x.pbrt:1:3: unexpected byte 0x01");
    lexer_expect_error("1e999", "x.pbrt:1:1: bad number '1e999'");
}

/* A file of several MiB: tokens straddle the 1 MiB chunks, a string longer than a chunk
 * grows the buffer, and positions stay right to the end. */
static void test_lexer_streaming_file(void **state)
{
    (void)state;
    char path[512];
    snprintf(path, sizeof path, "%s/big.pbrt", ts_tmp_dir);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    const int n = 400000; /* ~3.5 MB of numbers, 10 a line */
    for (int i = 0; i < n; i++) fprintf(f, "%d.25%c", i, i % 10 == 9 ? '\n' : ' ');
    fputc('"', f);
    for (int i = 0; i < 1500000; i++) fputc('a' + i % 26, f);
    fputs("\"\n   1.2.3\n", f);
    assert_int_equal(fclose(f), 0);
    ts_pbrt_lexer *lx;
    ts_error err = {0};
    assert_int_equal(ts_pbrt_lexer_open(path, true, "big.pbrt", 0, &lx, &err), TS_OK);
    ts_pbrt_token t;
    for (int i = 0; i < n; i++) {
        assert_int_equal(ts_pbrt_lexer_next(lx, &t, &err), TS_OK);
        assert_int_equal(t.kind, TS_PBRT_TOKEN_NUMBER);
        if (t.number != i + 0.25) fail_msg("number %d read as %.17g", i, t.number);
        assert_int_equal(t.loc.line, (unsigned)(i / 10 + 1));
    }
    assert_int_equal(ts_pbrt_lexer_next(lx, &t, &err), TS_OK);
    assert_int_equal(t.kind, TS_PBRT_TOKEN_STRING);
    assert_int_equal(t.len, 1500000);
    assert_true(t.text[0] == 'a' && t.text[1499999] == 'a' + 1499999 % 26);
    assert_int_not_equal(ts_pbrt_lexer_next(lx, &t, &err), TS_OK);
    char want[64];
    snprintf(want, sizeof want, "big.pbrt:%d:4: bad number '1.2.3'", n / 10 + 2);
    assert_string_equal(err.message, want);
    ts_pbrt_lexer_destroy(lx);
    unlink(path);
}

/* ----------------------------------------------------------- parameters ---- */

static void test_params_every_type(void **state)
{
    (void)state;
    write_file("k.spd", "# wavelength value\n400 0.25\n500 0.5 # green\n600 0.75\n");
    ts_pbrt_scene *s = parse_ok(WORLD(
        "Texture \"tx\" \"color\" \"constant\" \"rgb value\" [0.1 0.2 0.3]\n"
        "Shape \"test\" \"integer i\" [1 -2 3] \"float f\" 2.5 \"point2 p2\" [1 2 3 4] \"vector2 v2\" [5 6]\n"
        "  \"point3 p3\" [1 2 3] \"point p\" [4 5 6 7 8 9] \"vector3 v3\" [0 0 1] \"vector v\" [1 0 0]\n"
        "  \"normal3 n3\" [0 1 0] \"normal n\" [0 0 -1] \"rgb c1\" [0.1 0.2 0.3] \"color c2\" [1 1 1]\n"
        "  \"xyz x\" [0.9505 1 1.089] \"blackbody b1\" 6500 \"blackbody b2\" [3000 2.5]\n"
        "  \"spectrum s1\" [300 0.1 800 0.9] \"spectrum s2\" \"k.spd\" \"bool q\" \"true\" \"bool u\" false\n"
        "  \"bool arr\" [true \"false\" true] \"string str\" [\"a\" \"b c\"] \"texture t\" \"tx\"\n"));
    assert_int_equal(s->shape_count, 1);
    ts_pbrt_params *ps = &s->shapes[0].params;
    assert_int_equal(ps->count, 22);
    assert_string_equal(ps->directive, "Shape");
    assert_string_equal(ps->directive_arg, "test");
    ts_error err = {0};
    const int32_t *ints;
    size_t n;
    assert_int_equal(ts_pbrt_find_ints(ps, "i", &ints, &n, &err), TS_OK);
    assert_int_equal(n, 3);
    assert_int_equal(ints[1], -2);
    float f;
    assert_int_equal(ts_pbrt_find_float(ps, "f", 0, &f, &err), TS_OK);
    assert_true(f == 2.5f);
    const float *v;
    assert_int_equal(ts_pbrt_find_point2s(ps, "p2", &v, &n, &err), TS_OK);
    assert_int_equal(n, 2);
    assert_true(v[3] == 4);
    assert_int_equal(ts_pbrt_params_get(ps, "v2")->type, TS_PBRT_PARAM_VECTOR2);
    assert_int_equal(ts_pbrt_find_point3s(ps, "p", &v, &n, &err), TS_OK);
    assert_int_equal(n, 2);
    assert_true(v[5] == 9);
    ts_vec3 p3;
    assert_int_equal(ts_pbrt_find_point3(ps, "p3", (ts_vec3){0, 0, 0}, &p3, &err), TS_OK);
    assert_true(p3.x == 1 && p3.y == 2 && p3.z == 3);
    assert_int_equal(ts_pbrt_find_vector3(ps, "v", (ts_vec3){0, 0, 0}, &p3, &err), TS_OK);
    assert_true(p3.x == 1);
    assert_int_equal(ts_pbrt_find_vector3s(ps, "v3", &v, &n, &err), TS_OK);
    assert_int_equal(n, 1);
    assert_int_equal(ts_pbrt_find_normal3s(ps, "n", &v, &n, &err), TS_OK);
    assert_true(n == 1 && v[2] == -1);
    assert_int_equal(ts_pbrt_params_get(ps, "n3")->type, TS_PBRT_PARAM_NORMAL3);
    assert_string_equal(ts_pbrt_params_get(ps, "n3")->type_name, "normal3");
    ts_rgb c;
    assert_int_equal(ts_pbrt_find_rgb(ps, "c1", (ts_rgb){0, 0, 0}, &c, &err), TS_OK);
    assert_true(c.r == 0.1f && c.g == 0.2f && c.b == 0.3f);
    assert_string_equal(ts_pbrt_params_get(ps, "c2")->type_name, "color");
    /* D65 white in XYZ is (1, 1, 1) in linear sRGB, to the matrix's 4 digits. */
    assert_int_equal(ts_pbrt_find_rgb(ps, "x", (ts_rgb){0, 0, 0}, &c, &err), TS_OK);
    assert_near(c.r, 1, 2e-3);
    assert_near(c.g, 1, 2e-3);
    assert_near(c.b, 1, 2e-3);
    ts_pbrt_param *b1 = ts_pbrt_params_get(ps, "b1"), *b2 = ts_pbrt_params_get(ps, "b2");
    assert_true(b1->type == TS_PBRT_PARAM_BLACKBODY && b1->n == 1 && b1->floats[0] == 6500);
    assert_true(b2->n == 2 && b2->floats[1] == 2.5f);
    assert_int_equal(ts_pbrt_find_rgb(ps, "b1", (ts_rgb){0, 0, 0}, &c, &err), TS_ERR_UNSUPPORTED);
    assert_non_null(strstr(err.message, "\"blackbody b1\" is a spectral value"));
    ts_pbrt_param *s1 = ts_pbrt_params_get(ps, "s1"), *s2 = ts_pbrt_params_get(ps, "s2");
    assert_true(s1->type == TS_PBRT_PARAM_SPECTRUM && s1->n == 4 && s1->floats[2] == 800 && !s1->strings);
    assert_true(s2->n == 6 && s2->floats[0] == 400 && s2->floats[5] == 0.75f);
    assert_string_equal(s2->strings[0], "k.spd");
    assert_int_equal(ts_pbrt_param_values(s2), 3);
    bool q;
    assert_int_equal(ts_pbrt_find_bool(ps, "q", false, &q, &err), TS_OK);
    assert_true(q);
    assert_int_equal(ts_pbrt_find_bool(ps, "u", true, &q, &err), TS_OK);
    assert_false(q);
    ts_pbrt_param *arr = ts_pbrt_params_get(ps, "arr");
    assert_true(arr->n == 3 && arr->bools[0] && !arr->bools[1] && arr->bools[2]);
    const char *const *strs;
    assert_int_equal(ts_pbrt_find_strings(ps, "str", &strs, &n, &err), TS_OK);
    assert_true(n == 2 && strcmp(strs[1], "b c") == 0);
    ts_pbrt_param *t = ts_pbrt_params_get(ps, "t");
    assert_int_equal(t->type, TS_PBRT_PARAM_TEXTURE);
    assert_string_equal(t->strings[0], "tx");
    assert_int_equal(t->texture_spectrum, 0);
    assert_int_equal(t->texture_float, -1);
    size_t cursor = 0; /* every parameter was asked for */
    assert_null(ts_pbrt_params_next_unused(ps, &cursor));
    ts_pbrt_scene_destroy(s);
}

static void test_params_lookup_contract(void **state)
{
    (void)state;
    ts_pbrt_scene *s = parse_ok(WORLD("Shape \"sphere\" \"float radius\" [1 2] \"integer n\" 3 \"string a\" \"x\"\n"
                                      "  \"float zmin\" -1 \"float radius\" [2 3]\n"));
    ts_pbrt_params *ps = &s->shapes[0].params;
    assert_int_equal(ps->count, 4); /* the second radius replaced the first */
    assert_true(has_warning(s, "Shape \"sphere\": parameter \"radius\" is given twice; the last one counts"));
    ts_error err = {0};
    float f = 0;
    assert_int_equal(ts_pbrt_find_float(ps, "radius", 1, &f, &err), TS_ERR_INVALID);
    assert_string_equal(err.message, "t.pbrt:3:19: Shape \"sphere\": \"float radius\" expects 1 value, got 2");
    assert_int_equal(ts_pbrt_find_float(ps, "n", 1, &f, &err), TS_ERR_INVALID);
    assert_string_equal(err.message, "t.pbrt:2:37: Shape \"sphere\": \"integer n\" has the wrong type (expected \"float n\")");
    assert_int_equal(ts_pbrt_find_float(ps, "phimax", 360, &f, &err), TS_OK);
    assert_true(f == 360);
    const float *v;
    size_t n = 9;
    assert_int_equal(ts_pbrt_find_point3s(ps, "P", &v, &n, &err), TS_OK);
    assert_true(v == NULL && n == 0);
    assert_int_equal(ts_pbrt_find_point3s(ps, "a", &v, &n, &err), TS_ERR_INVALID);
    assert_non_null(strstr(err.message, "\"string a\" has the wrong type (expected \"point3 a\")"));
    size_t cursor = 0;
    const ts_pbrt_param *u = ts_pbrt_params_next_unused(ps, &cursor);
    assert_non_null(u);
    assert_string_equal(u->name, "zmin");
    assert_null(ts_pbrt_params_next_unused(ps, &cursor));
    ts_pbrt_scene_destroy(s);
}

/* ----------------------------------------------------------- transforms ---- */

/* LookAt 0 0 5  0 0 0  0 1 0: pbrt-v3's camera-to-world has the columns right = cross(up,
 * dir) = (-1, 0, 0), up' = cross(dir, right) = (0, 1, 0), dir = (0, 0, -1) and the eye. */
static void test_lookat_camera(void **state)
{
    (void)state;
    ts_pbrt_scene *s = parse_ok("LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 45\n" WORLD(""));
    const double c2w[4][4] = {{-1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, -1, 5}, {0, 0, 0, 1}};
    const double w2c[4][4] = {{-1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, -1, 5}, {0, 0, 0, 1}};
    assert_mat_near(&s->camera_to_world, c2w, 1e-15);
    assert_mat_near(&s->world_to_camera, w2c, 1e-15);
    assert_string_equal(s->camera.type, "perspective");
    assert_non_null(s->camera.loc.file);
    assert_int_equal(s->camera.loc.line, 2);
    ts_pbrt_scene_destroy(s);

    /* A general view: camera_to_world maps the camera origin to the eye, +z to the unit
     * viewing direction, and +y into the plane of up and the direction; the two matrices
     * are inverses. */
    s = parse_ok("LookAt 1 2 3  4 6 3  0 0 1\nCamera \"perspective\"\n" WORLD(""));
    ts_dvec3 o = apply(&s->camera_to_world, 0, 0, 0), z = apply(&s->camera_to_world, 0, 0, 1),
             y = apply(&s->camera_to_world, 0, 1, 0), x = apply(&s->camera_to_world, 1, 0, 0);
    assert_near(o.x, 1, 1e-12), assert_near(o.y, 2, 1e-12), assert_near(o.z, 3, 1e-12);
    assert_near(z.x - o.x, 0.6, 1e-12), assert_near(z.y - o.y, 0.8, 1e-12), assert_near(z.z - o.z, 0, 1e-12);
    assert_near(y.x - o.x, 0, 1e-12), assert_near(y.y - o.y, 0, 1e-12), assert_near(y.z - o.z, 1, 1e-12);
    /* right = cross(up, dir) = cross((0,0,1), (0.6,0.8,0)) = (-0.8, 0.6, 0) */
    assert_near(x.x - o.x, -0.8, 1e-12), assert_near(x.y - o.y, 0.6, 1e-12);
    ts_mat4 id = ts_mat4_mul(&s->world_to_camera, &s->camera_to_world);
    const double I[4][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};
    assert_mat_near(&id, I, 1e-12);
    ts_pbrt_scene_destroy(s);

    /* Scale -1 1 1 before LookAt (as veach-mis has): CTM = S · L, L's first row negated. */
    s = parse_ok("Scale -1 1 1\nLookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\n" WORLD(""));
    const double w2c2[4][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, -1, 5}, {0, 0, 0, 1}};
    assert_mat_near(&s->world_to_camera, w2c2, 1e-15);
    ts_pbrt_scene_destroy(s);

    /* No Camera: pbrt-v3's defaults. */
    s = parse_ok(WORLD(""));
    assert_string_equal(s->camera.type, "perspective");
    assert_null(s->camera.loc.file);
    assert_string_equal(s->film.type, "image");
    assert_string_equal(s->sampler.type, "halton");
    assert_string_equal(s->filter.type, "box");
    assert_string_equal(s->integrator.type, "path");
    assert_string_equal(s->accelerator.type, "bvh");
    assert_mat_near(&s->camera_to_world, I, 0);
    ts_pbrt_scene_destroy(s);
}

static void test_transform_conventions(void **state)
{
    (void)state;
    /* Transform takes column-major values: the last four are the translation. */
    ts_pbrt_scene *s = parse_ok(WORLD("Transform [1 0 0 0  0 1 0 0  0 0 1 0  5 6 7 1]\nShape \"a\"\n"
                                      "Transform [0 1 0 0  -1 0 0 0  0 0 1 0  0 0 0 1]\nShape \"b\"\n"
                                      "Identity Translate 1 2 3 Scale 2 2 2 Shape \"c\"\n"
                                      "Identity Translate 1 0 0 ConcatTransform [2 0 0 0 0 2 0 0 0 0 2 0 0 0 1 1] Shape \"d\"\n"
                                      "Identity Rotate 90 0 0 1 Shape \"e\"\n"));
    const double a[4][4] = {{1, 0, 0, 5}, {0, 1, 0, 6}, {0, 0, 1, 7}, {0, 0, 0, 1}};
    assert_mat_near(s->shapes[0].object_to_world, a, 0);
    /* the first column (0 1 0 0) is where x goes: x → +y */
    const double b[4][4] = {{0, -1, 0, 0}, {1, 0, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};
    assert_mat_near(s->shapes[1].object_to_world, b, 0);
    /* CTM = T · S: a point is scaled, then translated */
    ts_dvec3 c = apply(s->shapes[2].object_to_world, 1, 1, 1);
    assert_true(c.x == 3 && c.y == 4 && c.z == 5);
    ts_dvec3 d = apply(s->shapes[3].object_to_world, 1, 1, 1);
    assert_true(d.x == 3 && d.y == 2 && d.z == 3);
    ts_dvec3 e = apply(s->shapes[4].object_to_world, 1, 0, 0);
    assert_near(e.x, 0, 1e-15), assert_near(e.y, 1, 1e-15);
    ts_pbrt_scene_destroy(s);
}

static void test_coordinate_systems(void **state)
{
    (void)state;
    ts_pbrt_scene *s = parse_ok("LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\n"
                                "Translate 9 9 9 CoordinateSystem \"nine\"\n" WORLD(
                                    "AttributeBegin\n  CoordSysTransform \"camera\"\n  LightSource \"point\"\n"
                                    "  Translate 1 0 0 CoordinateSystem \"inner\"\nAttributeEnd\n"
                                    "CoordSysTransform \"nine\" Shape \"a\"\n"
                                    "CoordSysTransform \"inner\" Shape \"b\"\n"
                                    "Translate 3 0 0 CoordSysTransform \"world\" Shape \"c\"\n"
                                    "CoordSysTransform \"nowhere\" Shape \"d\"\n"));
    assert_int_equal(s->light_count, 1);
    const double c2w[4][4] = {{-1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, -1, 5}, {0, 0, 0, 1}};
    assert_mat_near(s->lights[0].light_to_world, c2w, 1e-15);
    /* "nine" was named before WorldBegin, after LookAt: it is L · T(9, 9, 9), and L maps
     * (9, 9, 9) to (-9, 9, -9 + 5) */
    ts_dvec3 a = apply(s->shapes[0].object_to_world, 0, 0, 0);
    assert_true(a.x == -9 && a.y == 9 && a.z == -4);
    /* named systems are global: "inner" survives its AttributeEnd (pbrt-v3) */
    ts_dvec3 b = apply(s->shapes[1].object_to_world, 0, 0, 0);
    assert_near(b.x, -1, 1e-15), assert_near(b.z, 5, 1e-15);
    ts_dvec3 c = apply(s->shapes[2].object_to_world, 0, 0, 0);
    assert_true(c.x == 0 && c.y == 0 && c.z == 0);
    assert_true(has_warning(s, "CoordSysTransform: no coordinate system is named \"nowhere\""));
    ts_pbrt_scene_destroy(s);

    s = parse_ok(WORLD("CoordSysTransform \"camera\"\n"));
    assert_true(has_warning(s, "no coordinate system is named \"camera\" (\"camera\" is named by Camera)"));
    ts_pbrt_scene_destroy(s);
}

/* ---------------------------------------------------------- attributes ---- */

static void test_attribute_scoping(void **state)
{
    (void)state;
    ts_pbrt_scene *s = parse_ok(WORLD(
        "Material \"plastic\"\n"
        "AttributeBegin\n"
        "  Material \"matte\" ReverseOrientation AreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\n"
        "  Translate 1 0 0 Shape \"a\"\n"
        "  TransformBegin Translate 0 1 0 Material \"glass\" Shape \"b\" TransformEnd\n"
        "  Shape \"c\"\n"
        "AttributeEnd\n"
        "Shape \"d\"\n"
        "Shape \"e\"\n"));
    assert_int_equal(s->shape_count, 5);
    assert_int_equal(s->material_count, 3);
    const ts_pbrt_shape *sh = s->shapes;
    assert_string_equal(s->materials[sh[0].material].type, "matte");
    assert_true(sh[0].reverse_orientation && sh[0].area_light == 0);
    assert_string_equal(s->area_lights[0].type, "diffuse");
    assert_string_equal(s->materials[sh[1].material].type, "glass");
    ts_dvec3 b = apply(sh[1].object_to_world, 0, 0, 0);
    assert_true(b.x == 1 && b.y == 1);
    /* TransformEnd restores the CTM only: the glass material stays */
    assert_string_equal(s->materials[sh[2].material].type, "glass");
    ts_dvec3 c = apply(sh[2].object_to_world, 0, 0, 0);
    assert_true(c.x == 1 && c.y == 0);
    /* AttributeEnd restores everything */
    assert_string_equal(s->materials[sh[3].material].type, "plastic");
    assert_true(!sh[3].reverse_orientation && sh[3].area_light == -1);
    assert_true(ts_xform_is_identity(&(ts_xform){*sh[3].object_to_world, ts_mat4_identity()}));
    assert_ptr_equal(sh[3].object_to_world, sh[4].object_to_world); /* the CTM is shared, not copied */
    assert_true(sh[2].object == -1);
    ts_pbrt_scene_destroy(s);

    s = parse_ok(WORLD("Shape \"sphere\"\n"));
    assert_int_equal(s->shapes[0].material, -1); /* pbrt-v3's default matte */
    ts_pbrt_scene_destroy(s);
}

static void test_texture_and_material_scoping(void **state)
{
    (void)state;
    ts_pbrt_scene *s = parse_ok(WORLD(
        "Texture \"t\" \"float\" \"constant\" \"float value\" 0.5\n"
        "Texture \"t\" \"color\" \"constant\" \"rgb value\" [1 0 0]\n"
        "MakeNamedMaterial \"m\" \"string type\" \"matte\" \"texture Kd\" \"t\" \"texture sigma\" \"t\"\n"
        "AttributeBegin\n"
        "  Texture \"t\" \"color\" \"scale\" \"texture tex1\" \"t\" \"rgb tex2\" [2 2 2]\n"
        "  MakeNamedMaterial \"m\" \"string type\" \"plastic\" \"texture Kd\" \"t\"\n"
        "  NamedMaterial \"m\" Shape \"a\"\n"
        "  MakeNamedMaterial \"only-inside\" \"string type\" \"mirror\"\n"
        "AttributeEnd\n"
        "NamedMaterial \"m\" Shape \"b\"\n"
        "NamedMaterial \"later\" MakeNamedMaterial \"later\" \"string type\" \"metal\" Shape \"c\"\n"
        "MakeNamedMaterial \"x\" \"string type\" \"mix\" \"string namedmaterial1\" \"m\" \"string namedmaterial2\" \"later\"\n"
        "  \"float amount\" 0.3\n"
        "NamedMaterial \"x\" Shape \"d\"\n"));
    assert_int_equal(s->texture_count, 3);
    assert_true(s->textures[0].is_float && !s->textures[1].is_float);
    /* the inner "t" refers to the outer color "t" (its own name is not yet bound) */
    ts_pbrt_param *tex1 = ts_pbrt_params_get(&s->textures[2].params, "tex1");
    assert_int_equal(tex1->texture_spectrum, 1);
    assert_int_equal(tex1->texture_float, 0);
    const ts_pbrt_material *a = &s->materials[s->shapes[0].material];
    assert_string_equal(a->type, "plastic");
    assert_int_equal(ts_pbrt_params_get((ts_pbrt_params *)&a->params, "Kd")->texture_spectrum, 2);
    const ts_pbrt_material *b = &s->materials[s->shapes[1].material];
    assert_string_equal(b->type, "matte");
    assert_string_equal(b->name, "m");
    ts_pbrt_param *kd = ts_pbrt_params_get((ts_pbrt_params *)&b->params, "Kd");
    assert_true(kd->texture_spectrum == 1 && kd->texture_float == 0);
    assert_true(ts_pbrt_params_get((ts_pbrt_params *)&b->params, "type")->used);
    assert_true(has_warning(s, "MakeNamedMaterial \"m\" redefines the named material \"m\""));
    assert_true(has_warning(s, "Texture \"t\" redefines the spectrum texture \"t\""));
    /* NamedMaterial resolves where it is written (pbrt-v3's pbrtNamedMaterial): "later" is not
     * defined yet, so the material in force ("m", matte) stays, with a warning. */
    assert_string_equal(s->materials[s->shapes[2].material].type, "matte");
    assert_true(has_warning(s, "NamedMaterial \"later\": no material of that name is defined here; the material "
                               "in force stays"));
    const ts_pbrt_material *x = &s->materials[s->shapes[3].material];
    assert_string_equal(x->type, "mix");
    assert_string_equal(s->materials[x->mix[0]].type, "matte");
    assert_string_equal(s->materials[x->mix[1]].type, "metal");
    ts_pbrt_scene_destroy(s);

    expect_error(WORLD("AttributeBegin Texture \"in\" \"float\" \"constant\" AttributeEnd\n"
                       "Material \"matte\" \"texture sigma\" \"in\"\n"),
                 "t.pbrt:3:18: Material \"matte\": \"texture sigma\" names texture \"in\", which is not defined here");
    /* A name defined only inside an attribute block is unknown after it: the material in
     * force (the default, -1) stays. */
    s = parse_ok(WORLD("AttributeBegin MakeNamedMaterial \"in\" \"string type\" \"mirror\" AttributeEnd\n"
                       "NamedMaterial \"in\"\nShape \"sphere\"\n"));
    assert_int_equal(s->shapes[0].material, -1);
    assert_true(s->warning_count == 1 && s->warnings[0].loc.line == 3 && s->warnings[0].loc.column == 1);
    ts_pbrt_scene_destroy(s);
    expect_error(WORLD("MakeNamedMaterial \"x\" \"string type\" \"mix\" \"string namedmaterial1\" \"nope\"\n"
                       "  \"string namedmaterial2\" \"nope\"\n"),
                 "t.pbrt:2:43: MakeNamedMaterial \"x\": \"string namedmaterial1\" names material \"nope\", which is "
                 "not defined here");
    expect_error(WORLD("Material \"mix\"\n"), "t.pbrt:2:1: Material \"mix\": a mix material needs \"string namedmaterial1\"");
}

/* ----------------------------------------------------------- instancing ---- */

static void test_object_instancing(void **state)
{
    (void)state;
    ts_pbrt_scene *s = parse_ok(WORLD(
        "AttributeBegin\n"
        "  ObjectBegin \"tree\"\n"
        "    Material \"matte\" Translate 0 1 0\n"
        "    Shape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]\n"
        "    AreaLightSource \"diffuse\" Shape \"sphere\"\n"
        "  ObjectEnd\n"
        "AttributeEnd\n"
        "Shape \"disk\"\n"
        "AttributeBegin Translate 10 0 0 ObjectInstance \"tree\" AttributeEnd\n"
        "AttributeBegin Translate 20 0 0 ObjectInstance \"tree\" AttributeEnd\n"
        "ObjectBegin \"empty\" ObjectEnd\n"));
    assert_int_equal(s->shape_count, 3); /* defined once, never copied per instance */
    assert_int_equal(s->object_count, 2);
    const ts_pbrt_object *o = &s->objects[0];
    assert_string_equal(o->name, "tree");
    assert_true(o->first_shape == 0 && o->shape_count == 2);
    assert_true(s->shapes[0].object == 0 && s->shapes[1].object == 0 && s->shapes[2].object == -1);
    assert_int_equal(s->shapes[1].area_light, -1); /* dropped inside an object, as pbrt-v3 */
    assert_true(has_warning(s, "area lights are not supported inside object definitions"));
    assert_int_equal(o->instance_count, 2);
    assert_int_equal(s->instance_count, 2);
    ts_dvec3 p0 = apply(o->instance_to_world[0], 0, 0, 0), p1 = apply(o->instance_to_world[1], 0, 0, 0);
    assert_true(p0.x == 10 && p1.x == 20);
    ts_dvec3 sp = apply(s->shapes[0].object_to_world, 0, 0, 0); /* object space → instance space */
    assert_true(sp.y == 1);
    /* the object's material is scoped to its definition */
    assert_int_equal(s->shapes[2].material, -1);
    assert_int_equal(s->objects[1].shape_count, 0);
    assert_int_equal(s->objects[1].instance_count, 0);
    ts_pbrt_scene_destroy(s);
}

/* -------------------------------------------------------------- Include ---- */

static ts_status parse_file(const char *rel, const ts_pbrt_limits *lim, ts_pbrt_scene **s, ts_error *err)
{
    char path[512];
    snprintf(path, sizeof path, "%s/%s", ts_tmp_dir, rel);
    return ts_pbrt_parse_file(path, NULL, lim, s, err);
}

static void test_include(void **state)
{
    (void)state;
    /* pbrt-v3 resolves every Include against the top-level file's folder (its search
     * directory), also inside an included file of a subfolder. */
    write_file("inc/main.pbrt", "Camera \"perspective\"\nWorldBegin\nInclude \"geo/a.pbrt\"\nShape \"main\"\nWorldEnd\n");
    write_file("inc/geo/a.pbrt", "Translate 1 0 0\nShape \"a\"\nInclude \"geo/b.pbrt\"\n");
    write_file("inc/geo/b.pbrt", "# b\nShape \"b\"");
    ts_pbrt_scene *s = NULL;
    ts_error err = {0};
    if (parse_file("inc/main.pbrt", NULL, &s, &err)) fail_msg("%s", err.message);
    assert_int_equal(s->shape_count, 3);
    assert_string_equal(s->shapes[0].type, "a");
    assert_string_equal(s->shapes[0].loc.file, "geo/a.pbrt");
    assert_int_equal(s->shapes[0].loc.line, 2);
    assert_string_equal(s->shapes[1].loc.file, "geo/b.pbrt");
    assert_int_equal(s->shapes[1].loc.line, 2);
    assert_non_null(strstr(s->shapes[2].loc.file, "inc/main.pbrt"));
    ts_dvec3 m = apply(s->shapes[2].object_to_world, 0, 0, 0); /* an Include does not scope the CTM */
    assert_true(m.x == 1);
    assert_non_null(strstr(s->base_dir, "inc"));
    ts_pbrt_scene_destroy(s);

    /* the top-level file is the user's: a symbolic link to it is followed, and its folder
     * is the target's (pbrt-v3 takes the folder of the file's real path); a missing file
     * is named as given */
    char target[512], link[512];
    snprintf(target, sizeof target, "%s/inc/main.pbrt", ts_tmp_dir);
    snprintf(link, sizeof link, "%s/link.pbrt", ts_tmp_dir);
    assert_int_equal(symlink(target, link), 0);
    assert_int_equal(parse_file("link.pbrt", NULL, &s, &err), TS_OK);
    assert_int_equal(s->shape_count, 3); /* its Includes resolve in inc/, the target's folder */
    ts_pbrt_scene_destroy(s);
    assert_int_equal(parse_file("nope.pbrt", NULL, &s, &err), TS_ERR_IO);
    assert_non_null(strstr(err.message, "nope.pbrt': cannot open (no such file or directory)"));

    /* errors inside an included file name it */
    write_file("inc/bad.pbrt", "WorldBegin\nInclude \"geo/c.pbrt\"\nWorldEnd\n");
    write_file("inc/geo/c.pbrt", "Shape \"x\"\n  \"float r\" [1 2\nWorldEnd\n");
    assert_int_not_equal(parse_file("inc/bad.pbrt", NULL, &s, &err), TS_OK);
    assert_null(s);
    assert_string_equal(err.message,
                        "geo/c.pbrt:2:13: Shape \"x\": \"float r\" has a '[' that is never closed (found WorldEnd at 3:1)");

    /* a cycle */
    write_file("inc/cyc.pbrt", "WorldBegin\nInclude \"cyc1.pbrt\"\nWorldEnd\n");
    write_file("inc/cyc1.pbrt", "Include \"cyc2.pbrt\"\n");
    write_file("inc/cyc2.pbrt", "Shape \"s\"\n  Include \"cyc1.pbrt\"\n");
    assert_int_not_equal(parse_file("inc/cyc.pbrt", NULL, &s, &err), TS_OK);
    assert_non_null(strstr(err.message, "cyc2.pbrt:2:11: Include \"cyc1.pbrt\": include cycle (cyc1.pbrt -> cyc2.pbrt -> cyc1.pbrt)"));
    write_file("inc/self.pbrt", "WorldBegin\nInclude \"self.pbrt\"\nWorldEnd\n");
    assert_int_not_equal(parse_file("inc/self.pbrt", NULL, &s, &err), TS_OK);
    assert_non_null(strstr(err.message, "self.pbrt:2:9: Include \"self.pbrt\": include cycle ("));

    /* depth */
    write_file("inc/d0.pbrt", "WorldBegin\nInclude \"d1.pbrt\"\nWorldEnd\n");
    write_file("inc/d1.pbrt", "Include \"d2.pbrt\"\n");
    write_file("inc/d2.pbrt", "Include \"d3.pbrt\"\n");
    write_file("inc/d3.pbrt", "Shape \"deep\"\n");
    ts_pbrt_limits lim;
    ts_pbrt_limits_default(&lim);
    lim.max_include_depth = 4;
    assert_int_equal(parse_file("inc/d0.pbrt", &lim, &s, &err), TS_OK);
    ts_pbrt_scene_destroy(s);
    lim.max_include_depth = 3;
    assert_int_equal(parse_file("inc/d0.pbrt", &lim, &s, &err), TS_ERR_LIMIT);
    assert_string_equal(err.message, "d2.pbrt:1:9: Include \"d3.pbrt\": includes nest more than 3 files deep");

    /* missing, outside, and no folder at all */
    expect_error_status(WORLD("Include \"missing.pbrt\"\n"), TS_ERR_IO,
                        "t.pbrt:2:9: Include: 'missing.pbrt': cannot open (no such file or directory)");
    expect_error(WORLD("Include \"../x.pbrt\"\n"), "t.pbrt:2:9: Include: '../x.pbrt': path leaves the scene's folder");
    expect_error(WORLD("Include \"/etc/passwd\"\n"), "Include: '/etc/passwd': absolute paths are not allowed");
    expect_error(WORLD("Include 3\n"), "t.pbrt:2:9: Include: expected a file name in quotes, got the number 3");
    const char *text = WORLD("Include \"inc/geo/b.pbrt\"\n");
    assert_int_not_equal(ts_pbrt_parse_text(text, strlen(text), "posted", NULL, NULL, &s, &err), TS_OK);
    assert_string_equal(err.message, "posted:2:9: Include: 'inc/geo/b.pbrt': this scene may not refer to files (no "
                                     "asset folder is configured)");
    assert_int_equal(ts_pbrt_parse_text(text, strlen(text), "posted", ts_tmp_dir, NULL, &s, &err), TS_OK);
    assert_int_equal(s->shape_count, 1);
    ts_pbrt_scene_destroy(s);
}

/* -------------------------------------------------- options, motion, media ---- */

static void test_options_motion_media(void **state)
{
    (void)state;
    ts_pbrt_scene *s = parse_ok(
        "Film \"image\" \"integer xresolution\" [64] \"integer yresolution\" 32 \"string filename\" \"x.exr\"\n"
        "Sampler \"sobol\" \"integer pixelsamples\" 16\nPixelFilter \"gaussian\" \"float xwidth\" 2\n"
        "Integrator \"directlighting\" \"integer maxdepth\" [5]\nAccelerator \"kdtree\"\nTransformTimes 0.25 0.75\n"
        "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [1 1 1]\n"
        "MediumInterface \"\" \"fog\"\nCamera \"orthographic\"\n" WORLD(
            "ActiveTransform StartTime Translate 1 0 0\nActiveTransform EndTime Translate 5 0 0\n"
            "ActiveTransform All\nMediumInterface \"fog\"\nShape \"sphere\"\n"
            "AttributeBegin ActiveTransform EndTime AttributeEnd Translate 0 1 0 Shape \"moved\"\n"));
    int32_t xres = 0;
    ts_error err = {0};
    assert_int_equal(ts_pbrt_find_int(&s->film.params, "xresolution", 0, &xres, &err), TS_OK);
    assert_int_equal(xres, 64);
    assert_string_equal(s->sampler.type, "sobol");
    assert_string_equal(s->filter.type, "gaussian");
    assert_string_equal(s->integrator.type, "directlighting");
    assert_string_equal(s->accelerator.type, "kdtree");
    assert_string_equal(s->camera.type, "orthographic");
    assert_true(s->transform_start_time == 0.25 && s->transform_end_time == 0.75);
    assert_int_equal(s->medium_count, 1);
    assert_string_equal(s->media[0].name, "fog");
    assert_string_equal(s->media[0].type, "homogeneous");
    assert_string_equal(s->camera_medium, "fog");
    /* Media are recorded for the importer, without a warning (they are rendered). */
    assert_false(has_warning(s, "MakeNamedMedium"));
    assert_false(has_warning(s, "MediumInterface"));
    /* Motion blur: the two CTMs, each changed only while active, no warning. */
    assert_false(has_warning(s, "ActiveTransform"));
    ts_dvec3 p = apply(s->shapes[0].object_to_world, 0, 0, 0);
    assert_true(p.x == 1);
    assert_non_null(s->shapes[0].object_to_world_end);
    p = apply(s->shapes[0].object_to_world_end, 0, 0, 0);
    assert_true(p.x == 5);
    assert_string_equal(s->shapes[0].inside_medium, "fog");
    assert_string_equal(s->shapes[0].outside_medium, "fog");
    /* the active transform is restored by AttributeEnd */
    p = apply(s->shapes[1].object_to_world, 0, 0, 0);
    assert_true(p.x == 1 && p.y == 1);
    p = apply(s->shapes[1].object_to_world_end, 0, 0, 0);
    assert_true(p.x == 5 && p.y == 1);
    ts_pbrt_scene_destroy(s);
}

/* ---------------------------------------------------------------- errors ---- */

static void test_error_sentences(void **state)
{
    (void)state;
    write_file("odd.spd", "400 1 500\n");
    write_file("bad.spd", "400 x\n");
    static const struct {
        const char *text, *want;
    } cases[] = {
        {"Foo 1 2\n", "t.pbrt:1:1: unknown directive 'Foo'"},
        {"\"float x\" 1\n", "t.pbrt:1:1: expected a directive, got the string \"float x\""},
        {WORLD("true\n"), "t.pbrt:2:1: expected a directive, got true (a value outside a parameter list)"},
        {WORLD("AttributeEnd\n"), "t.pbrt:2:1: AttributeEnd without a matching AttributeBegin"},
        {WORLD("TransformEnd\n"), "t.pbrt:2:1: TransformEnd without a matching TransformBegin"},
        {WORLD("ObjectEnd\n"), "t.pbrt:2:1: ObjectEnd without a matching ObjectBegin"},
        {WORLD("TransformBegin\nAttributeEnd\n"),
         "t.pbrt:3:1: AttributeEnd, but the innermost open block is the TransformBegin at t.pbrt:2:1"},
        {WORLD("ObjectBegin \"o\"\n AttributeEnd\n"),
         "t.pbrt:3:2: AttributeEnd, but the innermost open block is the ObjectBegin at t.pbrt:2:1"},
        {WORLD("AttributeBegin\n"), "t.pbrt:3:1: WorldEnd, but the AttributeBegin at t.pbrt:2:1 has no AttributeEnd"},
        {"WorldBegin\nAttributeBegin\n", "t.pbrt:3:1: the file ends inside the AttributeBegin at t.pbrt:2:1 (no "
                                         "AttributeEnd, no WorldEnd)"},
        {"WorldBegin\n", "t.pbrt:2:1: the file ends without WorldEnd"},
        {"Camera \"perspective\"\n", "t.pbrt:2:1: the file ends without WorldBegin"},
        {WORLD("") "Shape \"s\"\n", "t.pbrt:3:1: Shape after WorldEnd (a file holds one scene; nothing may follow WorldEnd)"},
        {WORLD("Camera \"perspective\"\n"), "t.pbrt:2:1: Camera is an option and must come before WorldBegin"},
        {WORLD("WorldBegin\n"), "t.pbrt:2:1: WorldBegin is an option and must come before WorldBegin"},
        {"Shape \"sphere\"\n" WORLD(""), "t.pbrt:1:1: Shape must come after WorldBegin"},
        {"AttributeBegin\n" WORLD(""), "t.pbrt:1:1: AttributeBegin must come after WorldBegin"},
        {WORLD("Shape \"sphere\" \"float radius\" \"abc\"\n"),
         "t.pbrt:2:31: Shape \"sphere\": \"float radius\" expects numbers, got the string \"abc\""},
        {WORLD("Shape \"sphere\" \"string name\" 5\n"),
         "t.pbrt:2:30: Shape \"sphere\": \"string name\" expects a quoted string, got the number 5"},
        {WORLD("Shape \"sphere\" \"float radius\" [1\n"),
         "t.pbrt:2:31: Shape \"sphere\": \"float radius\" has a '[' that is never closed (found WorldEnd at 3:1)"},
        {"WorldBegin\nShape \"sphere\" \"float radius\" [1 2",
         "t.pbrt:2:31: Shape \"sphere\": \"float radius\" has a '[' that is never closed (the file ends first)"},
        {WORLD("Shape \"sphere\" \"float radius\" [1 [ 2]\n"),
         "t.pbrt:2:31: Shape \"sphere\": \"float radius\" has a '[' that is never closed (found '[' at 2:34)"},
        {WORLD("Shape \"sphere\" \"float radius\"\n"),
         "t.pbrt:2:16: Shape \"sphere\": \"float radius\" has no value (found WorldEnd)"},
        {WORLD("Shape \"sphere\" \"float radius\" []\n"), "t.pbrt:2:16: Shape \"sphere\": \"float radius\" has no values"},
        {WORLD("Shape \"sphere\" \"floot radius\" 1\n"),
         "t.pbrt:2:16: Shape \"sphere\": \"floot radius\" has an unknown parameter type \"floot\""},
        {WORLD("Shape \"sphere\" \"float\" 1\n"),
         "t.pbrt:2:16: Shape \"sphere\": \"float\" is not a parameter declaration (expected \"type name\")"},
        {WORLD("Shape \"sphere\" \"float a b\" 1\n"), "\"float a b\" is not a parameter declaration"},
        {WORLD("Shape \"mesh\" \"integer indices\" [0 1.5 2]\n"),
         "t.pbrt:2:35: Shape \"mesh\": \"integer indices\" expects integers, got 1.5"},
        {WORLD("Shape \"mesh\" \"integer indices\" [0 3e9]\n"), "\"integer indices\" expects integers, got 3000000000"},
        {WORLD("Shape \"mesh\" \"point3 P\" [0 1 2 3]\n"),
         "t.pbrt:2:14: Shape \"mesh\": \"point3 P\" expects a multiple of 3 values, got 4"},
        {WORLD("Shape \"mesh\" \"float uv\" [1e39]\n"), "\"float uv\" value 1e+39 is out of range for a float"},
        {WORLD("Shape \"mesh\" \"point2 uv\" [0 1 2]\n"), "\"point2 uv\" expects a multiple of 2 values, got 3"},
        {WORLD("LightSource \"point\" \"blackbody I\" [5000 1 2]\n"),
         "t.pbrt:2:21: LightSource \"point\": \"blackbody I\" expects 1 or 2 values (temperature [scale]), got 3"},
        {WORLD("Material \"matte\" \"spectrum Kd\" [400 1 500]\n"),
         "t.pbrt:2:18: Material \"matte\": \"spectrum Kd\" expects (wavelength, value) pairs, got 3 values"},
        {WORLD("Material \"matte\" \"spectrum Kd\" \"odd.spd\"\n"),
         "\"spectrum Kd\" spectrum file 'odd.spd' holds 3 numbers; it needs (wavelength, value) pairs"},
        {WORLD("Material \"matte\" \"spectrum Kd\" \"bad.spd\"\n"),
         "t.pbrt:2:18: Material \"matte\": \"spectrum Kd\" bad.spd:1:5: expected a number, got x"},
        {WORLD("Material \"matte\" \"spectrum Kd\" \"none.spd\"\n"),
         "t.pbrt:2:18: Material \"matte\": \"spectrum Kd\" spectrum file 'none.spd': cannot open (no such file or directory)"},
        {WORLD("Material \"matte\" \"spectrum Kd\" [\"a.spd\" \"b.spd\"]\n"), "\"spectrum Kd\" expects 1 spectrum file name, got 2"},
        {WORLD("Material \"matte\" \"spectrum Kd\" [400 \"a.spd\"]\n"), "\"spectrum Kd\" mixes strings and numbers"},
        {WORLD("Material \"matte\" \"texture Kd\" [\"a\" \"b\"]\n"), "\"texture Kd\" expects 1 texture name, got 2"},
        {WORLD("Material \"matte\" \"texture Kd\" \"nope\"\n"),
         "t.pbrt:2:18: Material \"matte\": \"texture Kd\" names texture \"nope\", which is not defined here"},
        {WORLD("Material \"matte\" \"bool b\" \"maybe\"\n"),
         "t.pbrt:2:27: Material \"matte\": \"bool b\" expects true or false, got the string \"maybe\""},
        {WORLD("Material \"matte\" \"bool b\" 1\n"), "\"bool b\" expects true or false, got the number 1"},
        {WORLD("MakeNamedMaterial \"m\" \"rgb Kd\" [1 1 1]\n"),
         "t.pbrt:2:1: MakeNamedMaterial \"m\" has no \"string type\" parameter"},
        {WORLD("MakeNamedMedium \"m\" \"rgb sigma_a\" [1 1 1]\n"),
         "t.pbrt:2:1: MakeNamedMedium \"m\" has no \"string type\" parameter"},
        {WORLD("Texture \"t\" \"colour\" \"constant\"\n"),
         "t.pbrt:2:13: Texture \"t\": the type must be \"float\", \"color\" or \"spectrum\", got \"colour\""},
        {WORLD("Texture \"t\" \"color\"\n"), "t.pbrt:3:1: Texture: expected a texture class in quotes, got WorldEnd"},
        {WORLD("ObjectInstance \"nope\"\n"), "t.pbrt:2:1: ObjectInstance \"nope\": no object of that name is defined"},
        {WORLD("ObjectBegin \"a\"\nObjectBegin \"b\"\n"),
         "t.pbrt:3:1: ObjectBegin \"b\" inside the definition of object \"a\" (t.pbrt:2:1)"},
        {WORLD("ObjectBegin \"a\" ObjectEnd\nObjectBegin \"a\"\n"),
         "t.pbrt:3:1: ObjectBegin \"a\": an object of that name is already defined at t.pbrt:2:1"},
        {WORLD("ObjectBegin \"a\" ObjectEnd ObjectBegin \"b\" ObjectInstance \"a\"\n"),
         "t.pbrt:2:43: ObjectInstance \"a\" inside the definition of object \"b\""},
        {"Scale 1 0 1\nCamera \"perspective\"\n",
         "t.pbrt:2:1: Camera: the current transformation is singular (it has no inverse)"},
        {WORLD("Rotate 30 0 0 0\n"), "t.pbrt:2:1: Rotate: the axis (0, 0, 0) has no direction"},
        {WORLD("Transform [1 0 0 0 0 1 0 0 0 0 1 0]\n"),
         "t.pbrt:2:11: Transform expects [ 16 numbers ], got 12 and then ']'"},
        {WORLD("ConcatTransform 1 0 0 0\n"), "t.pbrt:2:17: ConcatTransform expects [ 16 numbers ], got the number 1"},
        {WORLD("Transform [1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1 5]\n"), "Transform expects [ 16 numbers ], got more"},
        {WORLD("Translate 1 2\n"), "t.pbrt:3:1: Translate expects 3 numbers, got WorldEnd after 2"},
        {WORLD("LookAt 0 0 0 0 0 1 0 1\n"), "t.pbrt:3:1: LookAt expects 9 numbers, got WorldEnd after 8"},
        {WORLD("Shape sphere\n"), "t.pbrt:2:7: Shape: expected a shape type in quotes, got sphere"},
        {WORLD("ActiveTransform Sometimes\n"), "t.pbrt:2:17: ActiveTransform expects All, StartTime or EndTime, got Sometimes"},
        {WORLD("Shape \"a\" \"floot\xff x\" 1\n"), "Shape \"a\": \"floot? x\" has an unknown parameter type \"floot?\""},
        {WORLD("Shape \"unterminated\n"), "t.pbrt:2:7: unterminated string"},
        {WORLD("Shape 1.2.3\n"), "t.pbrt:2:7: bad number '1.2.3'"},
    };
    int failures = 0;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        ts_pbrt_scene *s = NULL;
        ts_error err = {0};
        ts_status st = ts_pbrt_parse_text(cases[i].text, strlen(cases[i].text), "t.pbrt", ts_tmp_dir, NULL, &s, &err);
        if (st == TS_OK || s || err.status != st || !strstr(err.message, cases[i].want)) {
            print_error("case %zu: status %d, message \"%s\"; expected \"%s\"\n", i, st, err.message, cases[i].want);
            failures++;
        }
        ts_pbrt_scene_destroy(s);
    }
    assert_int_equal(failures, 0);
}

static void test_limits(void **state)
{
    (void)state;
    ts_pbrt_limits lim;
    ts_pbrt_limits_default(&lim);
    lim.max_memory = 1 << 20;
    /* ~2 M floats need 8 MB: past the limit, refused as out of memory, nothing leaked */
    size_t n = 2000000;
    char *text = malloc(n * 2 + 200);
    assert_non_null(text);
    char *p = text + sprintf(text, "WorldBegin Shape \"m\" \"float uv\" [");
    for (size_t i = 0; i < n; i++) *p++ = '1', *p++ = ' ';
    strcpy(p, "] WorldEnd\n");
    ts_pbrt_scene *s = NULL;
    ts_error err = {0};
    assert_int_equal(ts_pbrt_parse_text(text, strlen(text), "t.pbrt", NULL, &lim, &s, &err), TS_ERR_NOMEM);
    assert_null(s);
    assert_non_null(strstr(err.message, "out of memory (or past the scene's memory limit of 1048576 bytes)"));
    lim.max_memory = 0;
    assert_int_equal(ts_pbrt_parse_text(text, strlen(text), "t.pbrt", NULL, &lim, &s, &err), TS_OK);
    assert_int_equal(s->shapes[0].params.items[0].n, n);
    ts_pbrt_scene_destroy(s);
    free(text);

    write_file("big-include.pbrt", "Shape \"a\" \"float x\" [1 2 3 4 5 6 7 8 9 10]\n");
    lim.max_file_bytes = 16;
    const char *t2 = WORLD("Include \"big-include.pbrt\"\n");
    assert_int_equal(ts_pbrt_parse_text(t2, strlen(t2), "t.pbrt", ts_tmp_dir, &lim, &s, &err), TS_ERR_LIMIT);
    assert_string_equal(err.message,
                        "t.pbrt:2:9: Include: 'big-include.pbrt': file is 43 bytes, more than the limit of 16");

    lim.max_file_bytes = 0;
    lim.max_warnings = 2;
    s = parse_ok(WORLD("CoordSysTransform \"a\" CoordSysTransform \"b\" CoordSysTransform \"c\"\n"));
    ts_pbrt_scene_destroy(s);
    const char *t3 = WORLD("CoordSysTransform \"a\" CoordSysTransform \"b\" CoordSysTransform \"c\"\n");
    assert_int_equal(ts_pbrt_parse_text(t3, strlen(t3), "t.pbrt", ts_tmp_dir, &lim, &s, &err), TS_OK);
    assert_int_equal(s->warning_count, 2);
    assert_int_equal(s->warnings_dropped, 1);
    ts_pbrt_scene_destroy(s);
}

/* ---------------------------------------------------- shared pbrt-v3 scenes ---- */

/* Counts each published scene is known to hold (pbrt-v3's own parse of the same files);
 * a scene not listed must still parse and hold a shape and a light. */
static const struct {
    const char *name;
    size_t shapes, lights, area_lights, materials;
} known[] = {
    {"checkerboard", 2, 2, 0, 2},        {"f10-1ac", 2, 1, 0, 2},     {"f7-19a", 1, 2, 0, 1},
    {"killeroo-simple", 5, 0, 1, 4},     {"spheres-texfilt", 3, 1, 0, 3}, {"teapot-area-light", 2293, 1, 1, 3},
    {"veach-mis", 10, 0, 5, 10},
};

static void test_shared_scenes(void **state)
{
    (void)state;
    const char *src = getenv("TS_SOURCE_DIR");
    char dir[1024];
    snprintf(dir, sizeof dir, "%s/../shared/scenes/pbrt-v3", src ? src : ".");
    DIR *d = opendir(dir);
    if (!d) {
        print_message("no %s: the shared pbrt-v3 scenes are not on this machine\n", dir);
        skip();
    }
    int parsed = 0;
    struct dirent *e;
    while ((e = readdir(d))) {
        if (e->d_name[0] == '.') continue;
        char path[2400];
        snprintf(path, sizeof path, "%s/%s/%s.pbrt", dir, e->d_name, e->d_name);
        if (access(path, R_OK) != 0) continue;
        ts_pbrt_scene *s = NULL;
        ts_error err = {0};
        if (ts_pbrt_parse_file(path, NULL, NULL, &s, &err)) fail_msg("%s: %s", e->d_name, err.message);
        parsed++;
        bool listed = false;
        for (size_t i = 0; i < sizeof known / sizeof known[0]; i++) {
            if (strcmp(known[i].name, e->d_name) != 0) continue;
            listed = true;
            if (s->shape_count != known[i].shapes || s->light_count != known[i].lights ||
                s->area_light_count != known[i].area_lights || s->material_count != known[i].materials)
                fail_msg("%s: %zu shapes, %zu lights, %zu area lights, %zu materials; expected %zu, %zu, %zu, %zu",
                         e->d_name, s->shape_count, s->light_count, s->area_light_count, s->material_count,
                         known[i].shapes, known[i].lights, known[i].area_lights, known[i].materials);
        }
        if (!listed) assert_true(s->shape_count > 0 && s->light_count + s->area_light_count > 0);
        for (size_t i = 0; i < s->shape_count; i++) {
            const ts_pbrt_shape *sh = &s->shapes[i];
            assert_true(sh->material >= -1 && sh->material < (int32_t)s->material_count);
            assert_true(sh->area_light >= -1 && sh->area_light < (int32_t)s->area_light_count);
        }
        print_message("%s: %zu shapes, %zu lights, %zu area lights, %zu materials, %zu textures, %zu warnings\n",
                      e->d_name, s->shape_count, s->light_count, s->area_light_count, s->material_count,
                      s->texture_count, s->warning_count);
        ts_pbrt_scene_destroy(s);
    }
    closedir(d);
    assert_true(parsed >= 1);
}

/* Specific facts of two of them: killeroo-simple's two Includes and area light, and
 * teapot-area-light's CoordSysTransform "camera" light. */
static void test_shared_scene_details(void **state)
{
    (void)state;
    const char *src = getenv("TS_SOURCE_DIR");
    char path[1024];
    snprintf(path, sizeof path, "%s/../shared/scenes/pbrt-v3/killeroo-simple/killeroo-simple.pbrt", src ? src : ".");
    if (access(path, R_OK) != 0) skip();
    ts_pbrt_scene *s = NULL;
    ts_error err = {0};
    if (ts_pbrt_parse_file(path, NULL, NULL, &s, &err)) fail_msg("%s", err.message);
    size_t from_include = 0;
    for (size_t i = 0; i < s->shape_count; i++)
        if (strcmp(s->shapes[i].loc.file, "geometry/killeroo.pbrt") == 0) from_include++;
    assert_int_equal(from_include, 2);
    assert_int_equal(s->shapes[0].area_light, 0);
    ts_pbrt_scene_destroy(s);

    snprintf(path, sizeof path, "%s/../shared/scenes/pbrt-v3/teapot-area-light/teapot-area-light.pbrt", src ? src : ".");
    if (access(path, R_OK) != 0) skip();
    if (ts_pbrt_parse_file(path, NULL, NULL, &s, &err)) fail_msg("%s", err.message);
    assert_int_equal(s->light_count, 1);
    const ts_mat4 *l = s->lights[0].light_to_world;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) assert_near(l->m[i][j], s->camera_to_world.m[i][j], 0);
    ts_pbrt_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lexer_tokens_and_positions),
        cmocka_unit_test(test_lexer_numbers),
        cmocka_unit_test(test_lexer_errors),
        cmocka_unit_test(test_lexer_streaming_file),
        cmocka_unit_test(test_params_every_type),
        cmocka_unit_test(test_params_lookup_contract),
        cmocka_unit_test(test_lookat_camera),
        cmocka_unit_test(test_transform_conventions),
        cmocka_unit_test(test_coordinate_systems),
        cmocka_unit_test(test_attribute_scoping),
        cmocka_unit_test(test_texture_and_material_scoping),
        cmocka_unit_test(test_object_instancing),
        cmocka_unit_test(test_include),
        cmocka_unit_test(test_options_motion_media),
        cmocka_unit_test(test_error_sentences),
        cmocka_unit_test(test_limits),
        cmocka_unit_test(test_shared_scenes),
        cmocka_unit_test(test_shared_scene_details),
    };
    return cmocka_run_group_tests(tests, ts_tmp_group_setup, ts_tmp_group_teardown);
}
