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
#include <time.h>
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
    /* Adaptive renders hold different counts per pixel: no shard, no checkpoint EXR. */
    const char *a6[] = {"render", "--adaptive", "--shard", "0/2", NULL};
    assert_int_equal(run(a6), 2);
    assert_non_null(strstr(read_log(), "--adaptive goes without --shard"));
    const char *a7[] = {"render", "--adaptive", "--checkpoint", "c.exr", NULL};
    assert_int_equal(run(a7), 2);
    assert_non_null(strstr(read_log(), "--adaptive goes without --checkpoint"));
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

/* No ".tmp-tessera-" temporary of cli/outputs.c is left in the test's folder. */
static void assert_no_temporaries(void)
{
    char cmd[700];
    snprintf(cmd, sizeof cmd, "ls -a '%s' | grep -q 'tmp-tessera'", tmpdir);
    if (system(cmd) == 0) fail_msg("a temporary output file was left in %s", tmpdir);
}

/* Issue #32.3: a -o that cannot be written is refused before rendering, and with two -o
 * neither file is written. The render asks for 2^24 spp within a 60 s time limit: had it
 * rendered, it would have run for the whole minute; refused first, it returns at once (the
 * 20 s bound only tells "rendered" from "did not", by a factor of 3 on a loaded machine). */
static void test_outputs_checked_before_rendering(void **state)
{
    (void)state;
    char scene[512], good[512], bad[512], want[700];
    path_in_tmp(scene, sizeof scene, "out-check.json");
    write_file(scene, small_scene);
    path_in_tmp(good, sizeof good, "first.exr");
    path_in_tmp(bad, sizeof bad, "no-such-folder/second.png");
    const char *args[] = {"render", scene, "--spp", "16777216", "--time-limit", "60", "-o", good, "-o", bad, NULL};
    time_t t0 = time(NULL);
    assert_int_equal(run(args), 1);
    if (time(NULL) - t0 > 20) fail_msg("a bad -o was refused only after %lds of rendering", (long)(time(NULL) - t0));
    snprintf(want, sizeof want, "-o %s: the folder %s/no-such-folder does not exist", bad, tmpdir);
    if (!strstr(read_log(), want)) fail_msg("expected \"%s\" in: %s", want, read_log());
    assert_false(exists(good)); /* all the outputs or none */
    assert_no_temporaries();
    /* An output that is a folder. */
    const char *dir_out[] = {"render", scene, "--spp", "16777216", "--time-limit", "60", "-o", tmpdir, NULL};
    char folder_exr[512];
    path_in_tmp(folder_exr, sizeof folder_exr, "folder.exr");
    assert_int_equal(mkdir(folder_exr, 0755), 0);
    dir_out[7] = folder_exr;
    t0 = time(NULL);
    assert_int_equal(run(dir_out), 1);
    assert_true(time(NULL) - t0 <= 20);
    assert_non_null(strstr(read_log(), "is a folder"));
    assert_no_temporaries();
    /* merge: the outputs are checked before any shard is read (this one does not exist). */
    char shard[512];
    path_in_tmp(shard, sizeof shard, "missing-shard.exr");
    const char *merge[] = {"merge", shard, "-o", good, "-o", bad, NULL};
    assert_int_equal(run(merge), 1);
    if (!strstr(read_log(), want)) fail_msg("merge: expected \"%s\" in: %s", want, read_log());
    assert_false(exists(good));
    assert_no_temporaries();
    /* Both good: both written, nothing else left. */
    char png[512];
    path_in_tmp(png, sizeof png, "second.png");
    const char *ok[] = {"render", scene, "--spp", "2", "-o", good, "-o", png, NULL};
    assert_int_equal(run(ok), 0);
    assert_true(exists(good) && exists(png));
    assert_no_temporaries();
    unlink(good), unlink(png);
}

/* The string attribute name of the EXR at path ("" when absent). */
static void exr_string_attr(const char *path, const char *name, char *out, size_t n)
{
    ts_image img;
    ts_error err = {0};
    if (ts_exr_read(path, &img, &err)) fail_msg("cannot read %s: %s", path, err.message);
    const ts_image_attr *a = ts_image_attr_find(&img, name);
    snprintf(out, n, "%s", a && a->type == TS_ATTR_STRING ? a->s : "");
    ts_image_fini(&img);
}

/* Issue #32.4 and .7: a render is named as the server names its job — job.name, else the
 * scene's "name", else its file name — in the summary, the default output and the EXR;
 * "1 thread", not "1 threads". */
static void test_render_names_and_summary(void **state)
{
    (void)state;
    char scene[512], cwd[512], out[512], attr[256];
    path_in_tmp(scene, sizeof scene, "file-name.json");
    char text[2048];
    snprintf(text, sizeof text, "{\"name\":\"scene-name\",\"job\":{\"name\":\"job-name\"},%s", small_scene + 1);
    write_file(scene, text);
    assert_non_null(getcwd(cwd, sizeof cwd));
    assert_int_equal(chdir(tmpdir), 0);
    const char *noout[] = {"render", scene, "--spp", "2", "--threads", "1", NULL};
    int rc = run(noout);
    assert_int_equal(chdir(cwd), 0);
    assert_int_equal(rc, 0);
    if (!strstr(read_log(), "tessera: job-name: 48×32, 2 spp") || !strstr(read_log(), ", 1 thread, "))
        fail_msg("the summary names the job and says \"1 thread\": %s", read_log());
    path_in_tmp(out, sizeof out, "job-name.exr");
    assert_true(exists(out));
    exr_string_attr(out, "tessera_scene", attr, sizeof attr);
    assert_string_equal(attr, "job-name");
    /* Without job.name: the scene's name; two threads are "threads". */
    snprintf(text, sizeof text, "{\"name\":\"scene-name\",%s", small_scene + 1);
    write_file(scene, text);
    const char *named[] = {"render", scene, "--spp", "2", "--threads", "2", "-o", out, NULL};
    assert_int_equal(run(named), 0);
    if (!strstr(read_log(), "tessera: scene-name: ") || !strstr(read_log(), ", 2 threads, "))
        fail_msg("the summary names the scene: %s", read_log());
    exr_string_attr(out, "tessera_scene", attr, sizeof attr);
    assert_string_equal(attr, "scene-name");
    /* Neither: the file's name; the built-in scene is "cornell-box". */
    write_file(scene, small_scene);
    const char *unnamed[] = {"render", scene, "--spp", "2", "-o", out, NULL};
    assert_int_equal(run(unnamed), 0);
    exr_string_attr(out, "tessera_scene", attr, sizeof attr);
    assert_string_equal(attr, "file-name");
    const char *builtin[] = {"render", "--spp", "1", "-o", out, NULL};
    assert_int_equal(run(builtin), 0);
    exr_string_attr(out, "tessera_scene", attr, sizeof attr);
    assert_string_equal(attr, "cornell-box");
    unlink(out);
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
        cmocka_unit_test(test_outputs_checked_before_rendering),
        cmocka_unit_test(test_render_names_and_summary),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
