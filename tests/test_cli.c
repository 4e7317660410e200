/* test_cli.c — `tessera render` as a user runs it: exit statuses, messages, outputs, and
 * thread-count determinism of the written EXR (every channel bit-identical; the render-time
 * attribute is the only header field allowed to differ). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <fcntl.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "cli_support.h"
#include "image/exr.h"
#include "image/image.h"

static char tmpdir[256];
static char errlog[512];

static int run(const char *const *args) { return cli_run(errlog, args, NULL); }
static const char *read_log(void) { return cli_read_log(errlog); }

static void path_in_tmp(char *out, size_t n, const char *name) { snprintf(out, n, "%s/%s", tmpdir, name); }

static void write_file(const char *path, const char *text) { cli_write_file(path, text); }
static bool exists(const char *path) { return cli_exists(path); }

static int setup(void **state)
{
    (void)state;
    snprintf(tmpdir, sizeof tmpdir, "/tmp/tessera-cli-XXXXXX");
    if (!mkdtemp(tmpdir)) return -1;
    path_in_tmp(errlog, sizeof errlog, "stderr.txt");
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    char cmd[600];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
    return system(cmd) == 0 ? 0 : -1;
}

static const char *small_scene =
    "{\"tessera\":1,\"camera\":{\"from\":[0,1,5],\"to\":[0,0.5,0],\"fov\":40},\"film\":{\"width\":48,\"height\":"
    "32},\"sampler\":{\"spp\":4},\"integrator\":{\"type\":\"ao\"},\"materials\":{\"m\":{\"type\":\"diffuse\"}},"
    "\"shapes\":[{\"type\":\"sphere\",\"center\":[0,0.5,0],\"radius\":0.5,\"material\":\"m\"},{\"type\":\"disk\","
    "\"normal\":[0,1,0],\"radius\":5,\"material\":\"m\"}]}";

static void test_threads_give_identical_exr(void **state)
{
    (void)state;
    char scene[512], a[512], b[512], png[512];
    path_in_tmp(scene, sizeof scene, "small.json");
    path_in_tmp(a, sizeof a, "a.exr");
    path_in_tmp(b, sizeof b, "b.exr");
    path_in_tmp(png, sizeof png, "a.png");
    write_file(scene, small_scene);
    const char *args1[] = {"render", scene, "--threads", "1", "-o", a, "-o", png, "--quiet", NULL};
    const char *args2[] = {"render", scene, "--threads", "2", "-o", b, "--quiet", NULL};
    assert_int_equal(run(args1), 0);
    assert_int_equal(run(args2), 0);
    assert_true(exists(png));
    ts_image ia, ib;
    ts_error err = {0};
    assert_int_equal(ts_exr_read(a, &ia, &err), TS_OK);
    assert_int_equal(ts_exr_read(b, &ib, &err), TS_OK);
    assert_int_equal(ia.width, 48);
    assert_int_equal(ia.height, 32);
    assert_int_equal(ia.n_channels, ib.n_channels);
    assert_memory_equal(ia.data, ib.data, sizeof(float) * 48 * 32 * (size_t)ia.n_channels);
    const ts_image_attr *spp = ts_image_attr_find(&ia, "tessera_spp");
    assert_non_null(spp);
    assert_int_equal(spp->i, 4);
    assert_non_null(ts_image_attr_find(&ia, "tessera_render_time_s"));
    ts_image_fini(&ia);
    ts_image_fini(&ib);
}

static void test_bad_scene_exit_1_and_nothing_written(void **state)
{
    (void)state;
    char scene[512], out[512];
    path_in_tmp(scene, sizeof scene, "bad.json");
    path_in_tmp(out, sizeof out, "bad.exr");
    write_file(scene, "{\"tessera\":1,\"camera\":{\"from\":[0,0,5],\"to\":[0,0,0]},\"materials\":{\"m\":{\"type\":"
                      "\"diffuse\"}},\"shapes\":[{\"type\":\"sphere\",\"radius\":-1,\"material\":\"m\"}]}");
    const char *args[] = {"render", scene, "-o", out, NULL};
    assert_int_equal(run(args), 1);
    assert_non_null(strstr(read_log(), "shapes[0].radius: expected a positive number, got -1"));
    assert_false(exists(out));
    const char *missing[] = {"render", "/nonexistent/scene.json", "-o", out, NULL};
    assert_int_equal(run(missing), 1);
    assert_false(exists(out));
}

/* A 7 MiB name (or any string past its limit) is refused with its JSON path as the scene
 * loads, before any rendering; it used to render the whole scene and then fail to write
 * NAME.exr (a file name of 7 MiB). */
static void test_long_string_refused_before_rendering(void **state)
{
    (void)state;
    enum { NAME = 7 << 20 };
    char scene[512];
    path_in_tmp(scene, sizeof scene, "long.json");
    size_t n = strlen(small_scene) + NAME + 64;
    char *doc = malloc(n);
    assert_non_null(doc);
    int at = snprintf(doc, n, "{\"name\":\"");
    memset(doc + at, 'n', NAME);
    snprintf(doc + at + NAME, n - (size_t)at - NAME, "\",%s", small_scene + 1);
    write_file(scene, doc);
    free(doc);
    const char *args[] = {"render", scene, "--quiet", NULL};
    assert_int_equal(run(args), 1);
    assert_non_null(strstr(read_log(), "name: a string of 7340032 bytes is longer than the limit of 255"));
    /* Keys too: a material named with 300 bytes. */
    char doc2[2048], longname[301];
    memset(longname, 'm', 300);
    longname[300] = '\0';
    snprintf(doc2, sizeof doc2,
             "{\"tessera\":1,\"camera\":{\"from\":[0,0,5],\"to\":[0,0,0]},\"materials\":{\"%s\":{\"type\":"
             "\"diffuse\"}},\"shapes\":[{\"type\":\"sphere\",\"radius\":1,\"material\":\"m\"}]}",
             longname);
    write_file(scene, doc2);
    assert_int_equal(run(args), 1);
    assert_non_null(strstr(read_log(), "materials: a key of 300 bytes is longer than the limit of 255"));
}

static void test_usage_errors_exit_2(void **state)
{
    (void)state;
    const char *a1[] = {"render", "--spp", "zero", NULL};
    assert_int_equal(run(a1), 2);
    assert_non_null(strstr(read_log(), "--spp"));
    const char *a2[] = {"render", "-o", "out.tiff", NULL};
    assert_int_equal(run(a2), 2);
    assert_non_null(strstr(read_log(), ".exr or .png"));
    const char *a3[] = {"frobnicate", NULL};
    assert_int_equal(run(a3), 2);
    const char *a4[] = {"render", "--bogus", NULL};
    assert_int_equal(run(a4), 2);
    const char *a5[] = {NULL};
    assert_int_equal(run(a5), 2);
}

/* Every command words a usage error alike (server/usage.c): "tessera COMMAND: " and the
 * sentence as the first line of stderr, then the command's usage text (the short ones) or
 * where to find it. A '%' in a sentence comes out once. */
static void test_usage_error_lines(void **state)
{
    (void)state;
    static const struct {
        const char *args[4], *first, *then;
    } cases[] = {
        {{"frobnicate"}, "tessera: unknown command 'frobnicate'\n", "usage: tessera COMMAND [OPTIONS]\n"},
        {{"render", "--bogus"}, "tessera render: unknown option '--bogus'\n", "(tessera render --help lists the options)\n"},
        {{"render", "--target-error", "10"},
         "tessera render: --target-error: expected a relative error above 0 and below 1, as 0.01 or 1%, got '10'\n",
         "(tessera render --help lists the options)\n"},
        {{"convert", "a.pbrt", "b.pbrt"}, "tessera convert: expected one scene file\n",
         "(tessera convert --help lists the options)\n"},
        {{"merge", "x.exr"}, "tessera merge: no output: give -o MERGED.exr (mergeable again) and/or -o MERGED.png\n",
         "usage: tessera merge "},
        {{"serve", "--token", ""}, "tessera serve: --token: expected a non-empty token\n", "usage: tessera serve [OPTIONS]\n"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        assert_int_equal(run(cases[i].args), 2);
        const char *log = read_log();
        size_t n = strlen(cases[i].first);
        if (strncmp(log, cases[i].first, n) || strncmp(log + n, cases[i].then, strlen(cases[i].then)))
            fail_msg("tessera %s: stderr reads\n%.300s\nexpected\n%s%s…", cases[i].args[0], log, cases[i].first,
                     cases[i].then);
    }
}

/* What a new user meets: no -o writes NAME.exr and says so; merge needs -o; a shard needs
 * an EXR; --target-error takes 0.01 or 1% and refuses 1 or more; --help lists every option. */
static void test_honest_command_line(void **state)
{
    (void)state;
    char scene[512], cwd[512], out[512];
    path_in_tmp(scene, sizeof scene, "my scene.json"); /* the name gets a '-' for the space */
    write_file(scene, small_scene);
    assert_non_null(getcwd(cwd, sizeof cwd));
    assert_int_equal(chdir(tmpdir), 0);
    const char *noout[] = {"render", scene, "--spp", "2", NULL};
    int rc = run(noout);
    assert_int_equal(chdir(cwd), 0);
    assert_int_equal(rc, 0);
    path_in_tmp(out, sizeof out, "my-scene.exr");
    assert_true(exists(out));
    assert_non_null(strstr(read_log(), "the image goes to my-scene.exr"));

    const char *te_big[] = {"render", scene, "--target-error", "10", "-o", out, NULL};
    assert_int_equal(run(te_big), 2);
    assert_non_null(strstr(read_log(), "below 1"));
    const char *te_one[] = {"render", scene, "--target-error", "1", "-o", out, NULL};
    assert_int_equal(run(te_one), 2);
    const char *te_pct[] = {"render", scene, "--spp", "4096", "--target-error", "50%", "-o", out, NULL};
    assert_int_equal(run(te_pct), 0);
    assert_non_null(strstr(read_log(), "target error reached"));

    char png[512];
    path_in_tmp(png, sizeof png, "shard.png");
    const char *shard_png[] = {"render", scene, "--shard", "0/2", "-o", png, NULL};
    assert_int_equal(run(shard_png), 2);
    assert_non_null(strstr(read_log(), "EXR"));
    assert_false(exists(png));
    const char *merge_noout[] = {"merge", out, NULL};
    assert_int_equal(run(merge_noout), 2);
    assert_non_null(strstr(read_log(), "no output"));

    /* Every long option of render, with its unit or default. */
    const char *help[] = {"help", "render", NULL};
    char helplog[600];
    snprintf(helplog, sizeof helplog, "%s/help.txt", tmpdir);
    char cmd[1400];
    snprintf(cmd, sizeof cmd, "'%s' help render > '%s'", getenv("TS_BINARY"), helplog);
    assert_int_equal(system(cmd), 0);
    (void)help;
    const char *text = cli_read_log(helplog);
    const char *opts[] = {"--output", "--spp", "--time-limit SECONDS", "--target-error", "--threads", "--seed",
                          "--quiet", "--shard I/N", "--shard-count", "--checkpoint FILE", "--checkpoint-interval S",
                          "default 60", "1%"};
    for (size_t k = 0; k < sizeof opts / sizeof *opts; k++)
        if (!strstr(text, opts[k])) fail_msg("tessera help render does not mention '%s'", opts[k]);
}

static void test_builtin_default(void **state)
{
    (void)state;
    char out[512];
    path_in_tmp(out, sizeof out, "cornell.png");
    const char *args[] = {"render", "--spp", "1", "-o", out, NULL};
    assert_int_equal(run(args), 0);
    assert_true(exists(out));
    assert_non_null(strstr(read_log(), "cornell-box"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_threads_give_identical_exr),
        cmocka_unit_test(test_bad_scene_exit_1_and_nothing_written),
        cmocka_unit_test(test_long_string_refused_before_rendering),
        cmocka_unit_test(test_usage_errors_exit_2),
        cmocka_unit_test(test_usage_error_lines),
        cmocka_unit_test(test_honest_command_line),
        cmocka_unit_test(test_builtin_default),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
