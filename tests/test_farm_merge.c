/* test_farm_merge.c — farm shards as an operator uses them (docs/design.md §7):
 * `tessera render --shard` + `tessera merge` equal one render, a tree of merges equals a
 * flat one, bad merges are refused with their sentences, missing ranges are named,
 * `--shard auto` reads the scheduler's variables, and a shard killed with SIGTERM and
 * then SIGKILL resumes from its checkpoint to the same film. Also the library pieces: the
 * SHARD image layout's round-trip precision and the scene digest's canonical form.
 *
 * Bounds. docs/design.md §8 asks for the mean over pixels within 1e-6 relative and every
 * pixel within 1e-5 relative. What the code reaches is far tighter: a shard stores each sum
 * with relative error < 2^-47 (film_image.h) and merging adds N partial sums in double,
 * so a merged pixel differs from the single render by a few 2^-52 relative; the tests
 * assert 1e-12 per pixel (and 1e-13 on the mean) and print the largest difference seen. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <cjson/cJSON.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "cli_support.h"
#include "core/hash.h"
#include "film/film_image.h"
#include "image/exr.h"
#include "render/shard.h"
#include "json/scene_digest.h"

static char tmpdir[256];
static char errlog[512];

#define PIXEL_BOUND 1e-12
#define MEAN_BOUND 1e-13

/* ---------------------------------------------------------------- helpers */

static pid_t start(const char *const *args, const char *const *env) { return cli_start(errlog, args, env); }
static int finish(pid_t pid) { return cli_finish(pid); }
static int run_env(const char *const *args, const char *const *env) { return cli_run(errlog, args, env); }
static int run(const char *const *args) { return run_env(args, NULL); }
static const char *read_log(void) { return cli_read_log(errlog); }

/* Asserts the last command's stderr contains want (prints the log when it does not). */
static void log_has(const char *want)
{
    const char *log = read_log();
    if (!strstr(log, want)) fail_msg("expected in stderr: \"%s\"\nstderr was:\n%s", want, log);
}

static const char *tmp(const char *name)
{
    static char bufs[64][512]; /* a ring: callers keep at most a few dozen names at once */
    static int next;
    char *b = bufs[next++ % 64];
    snprintf(b, 512, "%s/%s", tmpdir, name);
    return b;
}

static void write_file(const char *path, const char *text) { cli_write_file(path, text); }
static bool exists(const char *path) { return cli_exists(path); }

/* A scene document of the source tree (rel from its root), parsed; the caller deletes it. */
static cJSON *source_doc(const char *rel)
{
    const char *src = getenv("TS_SOURCE_DIR");
    assert_non_null(src);
    char in[512];
    snprintf(in, sizeof in, "%s/%s", src, rel);
    FILE *f = fopen(in, "r");
    assert_non_null(f);
    static char text[1 << 16];
    size_t n = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[n] = '\0';
    cJSON *doc = cJSON_Parse(text);
    assert_non_null(doc);
    return doc;
}

/* The Cornell box shrunk for tests: w×h pixels, spp, a filter, optional crop. */
static void write_cornell(const char *path, int w, int h, int spp, const char *filter, const char *crop, int red)
{
    cJSON *doc = source_doc("scenes/cornell-box.json");
    cJSON *film = cJSON_GetObjectItem(doc, "film");
    cJSON_ReplaceItemInObject(film, "width", cJSON_CreateNumber(w));
    cJSON_ReplaceItemInObject(film, "height", cJSON_CreateNumber(h));
    cJSON *flt = cJSON_GetObjectItem(film, "filter");
    cJSON_ReplaceItemInObject(flt, "type", cJSON_CreateString(filter));
    cJSON_ReplaceItemInObject(flt, "radius", cJSON_CreateNumber(strcmp(filter, "box") == 0 ? 0.5 : 1.5));
    if (crop) cJSON_AddItemToObject(film, "crop", cJSON_Parse(crop));
    cJSON_ReplaceItemInObject(cJSON_GetObjectItem(doc, "sampler"), "spp", cJSON_CreateNumber(spp));
    if (red) { /* a different scene: the red wall a little darker */
        cJSON *mats = cJSON_GetObjectItem(doc, "materials");
        for (cJSON *m = mats->child; m; m = m->next)
            if (strcmp(m->string, "red") == 0)
                cJSON_ReplaceItemInObject(m, "reflectance", cJSON_Parse("[0.5,0.05,0.05]"));
    }
    char *out = cJSON_Print(doc);
    write_file(path, out);
    cJSON_free(out);
    cJSON_Delete(doc);
}

/* Largest per-pixel relative difference of the resolved colours of two shard files, and
 * the relative difference of their means; both must cover the same window. */
static void compare_shards(const char *a, const char *b, double *max_pixel, double *mean_rel)
{
    ts_shard_info ia, ib;
    ts_film *fa, *fb;
    ts_error err = {0};
    if (ts_shard_read(a, &ia, &fa, &err)) fail_msg("%s", err.message);
    if (ts_shard_read(b, &ib, &fb, &err)) fail_msg("%s", err.message);
    assert_int_equal(fa->width, fb->width);
    assert_int_equal(fa->height, fb->height);
    assert_int_equal(fa->x0, fb->x0);
    assert_int_equal(fa->y0, fb->y0);
    double worst = 0, sa = 0, sb = 0;
    for (int y = fa->y0; y < fa->y0 + fa->height; y++)
        for (int x = fa->x0; x < fa->x0 + fa->width; x++) {
            assert_true(ts_film_pixel_at(fa, x, y)->count == ts_film_pixel_at(fb, x, y)->count);
            for (int c = 0; c < 3; c++) {
                /* The double means, not the float ones: the bound is about the sums. */
                const ts_film_pixel *qa = ts_film_pixel_at(fa, x, y), *qb = ts_film_pixel_at(fb, x, y);
                double ma = qa->weight ? qa->sum[c] / qa->weight : 0, mb = qb->weight ? qb->sum[c] / qb->weight : 0;
                double scale = fmax(fabs(ma), fabs(mb));
                double d = scale > 0 ? fabs(ma - mb) / scale : 0;
                if (d > worst) worst = d;
                sa += ma, sb += mb;
            }
        }
    *max_pixel = worst;
    *mean_rel = sb != 0 ? fabs(sa - sb) / fabs(sb) : fabs(sa);
    ts_film_destroy(fa);
    ts_film_destroy(fb);
}

static int setup(void **state)
{
    (void)state;
    snprintf(tmpdir, sizeof tmpdir, "/tmp/tessera-farm-XXXXXX");
    if (!mkdtemp(tmpdir)) return -1;
    snprintf(errlog, sizeof errlog, "%s/stderr.txt", tmpdir);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    char cmd[600];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
    return system(cmd) == 0 ? 0 : -1;
}

/* ---------------------------------------------------------------- library pieces */

/* Random sums through the SHARD layout and back: relative error < 2^-47 for Σw·L, Σw·L²
 * and Σw, < 2^-24 for Σw², counts exact (film_image.h). Seeded PCG: deterministic. */
static void test_shard_layout_round_trip(void **state)
{
    (void)state;
    ts_error err = {0};
    ts_film *f = ts_film_create(40, 30, 3, 2, 17, 13, &err);
    assert_non_null(f);
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 12345, 1);
    for (int i = 0; i < f->width * f->height; i++) {
        int n = (int)(ts_pcg32_next(&rng) % 200);
        for (int k = 0; k < n; k++) {
            float w = (float)ts_pcg32_float(&rng) * (i % 5 == 0 ? -1.0f : 1.0f) + 0.01f;
            ts_rgb L = {(float)ldexp(ts_pcg32_float(&rng), (int)(ts_pcg32_next(&rng) % 40) - 20), ts_pcg32_float(&rng),
                        i % 7 == 0 ? 0.0f : 1e5f * ts_pcg32_float(&rng)};
            ts_film_add_sample(f, f->x0 + i % f->width, f->y0 + i / f->width, L, w);
        }
    }
    /* A pixel whose weights cancel exactly (stores Σw·L as a pair). */
    ts_film_add_sample(f, 3, 2, (ts_rgb){1, 2, 3}, 0.5f);
    ts_film_add_sample(f, 3, 2, (ts_rgb){4, 5, 6}, -0.5f);
    ts_image img;
    assert_int_equal(ts_film_to_image(f, TS_FILM_IMAGE_SHARD, &img, &err), TS_OK);
    assert_int_equal(img.n_channels, 16);
    assert_true(ts_film_image_is_shard(&img));
    ts_film *g = ts_film_from_image(&img, 40, 30, 3, 2, &err);
    assert_non_null(g);
    double worst = 0, worst_sq = 0;
    for (int i = 0; i < f->width * f->height; i++) {
        const ts_film_pixel *a = &f->pixels[i], *b = &g->pixels[i];
        assert_true(a->count == b->count);
        double vals[7][2] = {{a->sum[0], b->sum[0]}, {a->sum[1], b->sum[1]}, {a->sum[2], b->sum[2]},
                             {a->sum_sq[0], b->sum_sq[0]}, {a->sum_sq[1], b->sum_sq[1]},
                             {a->sum_sq[2], b->sum_sq[2]}, {a->weight, b->weight}};
        for (int k = 0; k < 7; k++) {
            double d = vals[k][0] != 0 ? fabs(vals[k][0] - vals[k][1]) / fabs(vals[k][0]) : fabs(vals[k][1]);
            if (d > worst) worst = d;
        }
        double d = a->weight_sq ? fabs(a->weight_sq - b->weight_sq) / a->weight_sq : b->weight_sq;
        if (d > worst_sq) worst_sq = d;
    }
    printf("SHARD layout round trip: largest relative error %.3g (bound 2^-47 = %.3g), weight_sq %.3g\n", worst,
           ldexp(1, -47), worst_sq);
    assert_true(worst < ldexp(1, -47));
    assert_true(worst_sq <= ldexp(1, -24));
    /* Missing channel: refused by name. */
    strcpy(img.channel_names[3], "sumX");
    assert_null(ts_film_from_image(&img, 40, 30, 3, 2, &err));
    assert_non_null(strstr(err.message, "channel 'sum.R.lo' is missing"));
    ts_image_fini(&img);
    ts_film_destroy(f);
    ts_film_destroy(g);
}

static void test_scene_digest_canonical(void **state)
{
    (void)state;
    ts_error err = {0};
    const char *a = "{\"b\": [1, 2.5, -0, 1e2], \"a\": {\"y\": \"q\\\"\", \"x\": true}, \"tessera\": 1}";
    const char *b = "{\"tessera\":1.0,\"a\":{\"x\":true,\"y\":\"q\\u0022\"},\"b\":[1,2.50,0,100],"
                    "\"job\":{\"spp\":3}}";
    cJSON *doc = cJSON_Parse(a);
    char *text;
    size_t len;
    assert_int_equal(ts_scene_canonical_text(doc, &text, &len, &err), TS_OK);
    assert_string_equal(text, "{\"a\":{\"x\":true,\"y\":\"q\\\"\"},\"b\":[1,2.5,0,100],\"tessera\":1}");
    free(text);
    cJSON_Delete(doc);
    char ha[65], hb[65], hc[65];
    assert_int_equal(ts_scene_digest_text(a, strlen(a), ha, &err), TS_OK);
    assert_int_equal(ts_scene_digest_text(b, strlen(b), hb, &err), TS_OK);
    assert_string_equal(ha, hb); /* order, spacing, number spelling and "job" do not count */
    const char *c = "{\"tessera\":1,\"a\":{\"x\":true,\"y\":\"q\\\"\"},\"b\":[1,2.5,0,101]}";
    assert_int_equal(ts_scene_digest_text(c, strlen(c), hc, &err), TS_OK);
    assert_string_not_equal(ha, hc);
    /* film.crop does not count (region shards of one image share a digest); film.width does. */
    const char *d1 = "{\"film\":{\"width\":8,\"crop\":[0,0.5,0,1]}}", *d2 = "{\"film\":{\"width\":8}}",
               *d3 = "{\"film\":{\"width\":9}}";
    assert_int_equal(ts_scene_digest_text(d1, strlen(d1), ha, &err), TS_OK);
    assert_int_equal(ts_scene_digest_text(d2, strlen(d2), hb, &err), TS_OK);
    assert_int_equal(ts_scene_digest_text(d3, strlen(d3), hc, &err), TS_OK);
    assert_string_equal(ha, hb);
    assert_string_not_equal(ha, hc);
    /* SHA-256 of "{}" (FIPS 180 test vectors are for other strings; this one is checkable
     * with `printf '{}' | sha256sum`). */
    assert_int_equal(ts_scene_digest_text("{ }", 3, ha, &err), TS_OK);
    assert_string_equal(ha, "44136fa355b3678a1146ad16f7e8649e94fb4fc21fe77e8310c060f61caaff8a");
}

static void test_shard_ranges(void **state)
{
    (void)state;
    /* The ranges of N shards tile [0, S) exactly, each ⌊I·S/N⌋. */
    for (uint32_t n = 1; n <= 9; n++) {
        uint32_t next = 0;
        for (uint32_t i = 0; i < n; i++) {
            ts_sample_range r = ts_shard_range(i, n, 21);
            assert_int_equal(r.begin, next);
            assert_int_equal(r.begin, i * 21 / n);
            next = r.end;
        }
        assert_int_equal(next, 21);
    }
    uint32_t i, n;
    char how[256];
    ts_error err = {0};
    assert_int_equal(ts_shard_parse("2/8", &i, &n, &err), TS_OK);
    assert_int_equal(i, 2);
    assert_int_equal(n, 8);
    assert_int_equal(ts_shard_parse("8/8", &i, &n, &err), TS_ERR_INVALID);
    assert_non_null(strstr(err.message, "numbered 0 to 7"));
    assert_int_equal(ts_shard_auto("3", NULL, NULL, NULL, 4, &i, &n, how, sizeof how, &err), TS_OK);
    assert_int_equal(i, 3);
    assert_non_null(strstr(how, "JOB_COMPLETION_INDEX=3"));
    assert_int_equal(ts_shard_auto("3", NULL, NULL, NULL, 0, &i, &n, how, sizeof how, &err), TS_ERR_INVALID);
    assert_non_null(strstr(err.message, "pass --shard-count"));
    assert_int_equal(ts_shard_auto(NULL, "5", "4", "3", 0, &i, &n, how, sizeof how, &err), TS_OK);
    assert_int_equal(i, 2);
    assert_int_equal(n, 4);
    assert_non_null(strstr(how, "SLURM_ARRAY_TASK_ID=5"));
    assert_int_equal(ts_shard_auto(NULL, NULL, NULL, NULL, 0, &i, &n, how, sizeof how, &err), TS_ERR_INVALID);
    assert_non_null(strstr(err.message, "neither JOB_COMPLETION_INDEX"));
}

/* ---------------------------------------------------------------- merges through the CLI */

static void render_shard(const char *scene, const char *shard, const char *out)
{
    const char *args[] = {"render", scene, "--shard", shard, "-o", out, "--quiet", NULL};
    int rc = run(args);
    if (rc) fail_msg("render --shard %s: exit %d\n%s", shard, rc, read_log());
}

static void merge_files_opt(const char *const *files, int n, const char *out, bool partial)
{
    const char *args[40] = {"merge"};
    int k = 1;
    if (partial) args[k++] = "--allow-partial";
    for (int i = 0; i < n; i++) args[k++] = files[i];
    args[k++] = "-o", args[k++] = out, args[k] = NULL;
    int rc = run(args);
    if (rc) fail_msg("merge: exit %d\n%s", rc, read_log());
}

static void merge_files(const char *const *files, int n, const char *out) { merge_files_opt(files, n, out, false); }

/* N = 1, 2, 3, 7 shards of 21 spp (uneven splits) merged equal the single render (box
 * filter; the gaussian filter's non-unit weights for N = 3). */
static void test_merge_equals_single_render(void **state)
{
    (void)state;
    const char *filters[] = {"box", "gaussian"};
    double worst_pixel = 0, worst_mean = 0;
    for (int fi = 0; fi < 2; fi++) {
        char scene[512], full[512];
        snprintf(scene, sizeof scene, "%s", tmp(fi ? "cornell-gauss.json" : "cornell-box.json"));
        snprintf(full, sizeof full, "%s", tmp("full.exr"));
        write_cornell(scene, 24, 24, 21, filters[fi], NULL, 0);
        render_shard(scene, "0/1", full); /* shard 0 of 1 is the whole render, in the shard layout */
        static const int ns[] = {1, 2, 3, 7};
        for (int k = 0; k < 4; k++) {
            int n = ns[k];
            if (fi == 1 && n != 3) continue;
            char names[7][512];
            const char *files[7];
            for (int i = 0; i < n; i++) {
                char spec[16], name[64];
                snprintf(spec, sizeof spec, "%d/%d", i, n);
                snprintf(name, sizeof name, "s%d-of-%d.exr", i, n);
                snprintf(names[i], sizeof names[i], "%s", tmp(name));
                files[i] = names[i];
                render_shard(scene, spec, files[i]);
            }
            const char *merged = tmp("merged.exr");
            merge_files(files, n, merged);
            log_has("21 spp of 21 (samples [0,21))");
            double px, mean;
            compare_shards(merged, full, &px, &mean);
            printf("N = %d (%s filter): largest pixel difference %.3g relative, mean %.3g relative\n", n,
                   filters[fi], px, mean);
            assert_true(px <= PIXEL_BOUND);
            assert_true(mean <= MEAN_BOUND);
            if (px > worst_pixel) worst_pixel = px;
            if (mean > worst_mean) worst_mean = mean;
            if (n == 7) { /* a tree of merges equals the flat merge */
                const char *left = tmp("left.exr"), *right = tmp("right.exr"), *tree = tmp("tree.exr");
                const char *l[] = {files[0], files[1], files[2]}, *r[] = {files[3], files[4], files[5], files[6]};
                merge_files_opt(l, 3, left, true); /* each subtree alone is partial */
                merge_files_opt(r, 4, right, true);
                const char *both[] = {right, left};
                merge_files(both, 2, tree);
                compare_shards(tree, merged, &px, &mean);
                printf("tree of merges vs flat: largest pixel difference %.3g relative\n", px);
                assert_true(px <= PIXEL_BOUND);
            }
        }
    }
    printf("merge vs single render: worst pixel %.3g, worst mean %.3g (asserted %g and %g)\n", worst_pixel,
           worst_mean, PIXEL_BOUND, MEAN_BOUND);
}

/* Region shards (film crop) of the same scene merge into the full image. */
static void test_region_shards(void **state)
{
    (void)state;
    const char *full_scene = tmp("cornell-full.json"), *top = tmp("cornell-top.json"), *bottom = tmp("cornell-bot.json");
    write_cornell(full_scene, 16, 16, 8, "box", NULL, 0);
    write_cornell(top, 16, 16, 8, "box", "[0,1,0,0.5]", 0);
    write_cornell(bottom, 16, 16, 8, "box", "[0,1,0.5,1]", 0);
    render_shard(full_scene, "0/1", tmp("region-full.exr"));
    render_shard(top, "0/1", tmp("region-top.exr"));
    render_shard(bottom, "0/2", tmp("region-bot0.exr"));
    const char *partial[] = {"merge", tmp("region-top.exr"), tmp("region-bot0.exr"), "-o", tmp("r.exr"), NULL};
    assert_int_equal(run(partial), 1);
    log_has("samples [4,8) of pixels x [0,16), y [8,16)");
    render_shard(bottom, "1/2", tmp("region-bot1.exr"));
    const char *files[] = {tmp("region-top.exr"), tmp("region-bot0.exr"), tmp("region-bot1.exr")};
    merge_files(files, 3, tmp("region-merged.exr"));
    double px, mean;
    compare_shards(tmp("region-merged.exr"), tmp("region-full.exr"), &px, &mean);
    printf("region shards: largest pixel difference %.3g relative\n", px);
    assert_true(px <= PIXEL_BOUND);
}

static void test_bad_merges_refused(void **state)
{
    (void)state;
    const char *scene = tmp("bad-a.json"), *other = tmp("bad-b.json");
    write_cornell(scene, 16, 16, 8, "box", NULL, 0);
    write_cornell(other, 16, 16, 8, "box", NULL, 1);
    const char *s0 = tmp("b0.exr"), *s1 = tmp("b1.exr"), *o1 = tmp("o1.exr"), *seed1 = tmp("seed1.exr");
    render_shard(scene, "0/2", s0);
    render_shard(scene, "1/2", s1);
    render_shard(other, "1/2", o1);
    const char *seed_args[] = {"render", scene, "--shard", "1/2", "--seed", "7", "-o", seed1, "--quiet", NULL};
    assert_int_equal(run(seed_args), 0);
    const char *out = tmp("bad-out.exr");

    const char *diff_scene[] = {"merge", s0, o1, "-o", out, NULL};
    assert_int_equal(run(diff_scene), 1);
    log_has("are of different scenes");
    log_has(o1);
    const char *diff_seed[] = {"merge", s0, seed1, "-o", out, NULL};
    assert_int_equal(run(diff_seed), 1);
    log_has("were rendered with different seeds (0 and 7)");
    /* Overlap: shard 0 of 2 is [0,4); shard 1 of 3 is [2,5). */
    const char *t1 = tmp("t1.exr");
    render_shard(scene, "1/3", t1);
    const char *overlap[] = {"merge", s0, s1, t1, "-o", out, NULL};
    assert_int_equal(run(overlap), 1);
    log_has("overlap: both hold samples [2,4) of the same pixels");
    /* A truncated shard. */
    const char *cut = tmp("truncated.exr");
    FILE *f = fopen(s1, "rb");
    static unsigned char bytes[1 << 20];
    size_t n = fread(bytes, 1, sizeof bytes, f);
    fclose(f);
    f = fopen(cut, "wb");
    fwrite(bytes, 1, n / 2, f);
    fclose(f);
    const char *truncated[] = {"merge", s0, cut, "-o", out, NULL};
    assert_int_equal(run(truncated), 1);
    log_has("truncated.exr");
    log_has("truncated");
    /* A plain RGB EXR. */
    const char *plain = tmp("plain.exr");
    const char *render_plain[] = {"render", scene, "-o", plain, "--quiet", NULL};
    assert_int_equal(run(render_plain), 0);
    const char *not_shard[] = {"merge", s0, plain, "-o", out, NULL};
    assert_int_equal(run(not_shard), 1);
    log_has("plain.exr is not a tessera shard");
    assert_false(exists(out));
    /* Missing ranges named; merged anyway with --allow-partial. */
    const char *t0 = tmp("t0.exr"), *t2 = tmp("t2.exr");
    render_shard(scene, "0/3", t0);
    render_shard(scene, "2/3", t2);
    const char *missing[] = {"merge", t0, t2, "-o", out, NULL};
    assert_int_equal(run(missing), 1);
    log_has("samples [2,5) of every pixel");
    log_has("--allow-partial");
    assert_false(exists(out));
    const char *partial[] = {"merge", t0, t2, "--allow-partial", "-o", out, NULL};
    assert_int_equal(run(partial), 0);
    log_has("5 spp of 8 (samples [0,2) [5,8))");
    assert_true(exists(out));
    /* The partial merge plus the missing piece is the whole render. */
    const char *whole[] = {"merge", out, t1, "-o", tmp("whole.exr"), NULL};
    assert_int_equal(run(whole), 0);
    log_has("8 spp of 8 (samples [0,8))");
}

/* Film "scale" (film.scale) is an output factor, never in the sums: shards of a scaled
 * scene hold the same sums as the unscaled scene's, their merge records the scale
 * (tessera_film_scale) and a plain render's pixels are the unscaled ones times it. */
static void test_film_scale_shards(void **state)
{
    (void)state;
    const char *plain = tmp("scale1.json"), *scaled = tmp("scale2.json");
    write_cornell(plain, 16, 16, 6, "gaussian", NULL, 0);
    write_cornell(scaled, 16, 16, 6, "gaussian", NULL, 0);
    {
        FILE *f = fopen(scaled, "r");
        static char text[1 << 16];
        size_t n = fread(text, 1, sizeof text - 1, f);
        fclose(f);
        text[n] = '\0';
        cJSON *doc = cJSON_Parse(text);
        cJSON_AddNumberToObject(cJSON_GetObjectItem(doc, "film"), "scale", 2);
        char *out = cJSON_Print(doc);
        write_file(scaled, out);
        cJSON_free(out);
        cJSON_Delete(doc);
    }
    render_shard(plain, "0/1", tmp("p-full.exr"));
    render_shard(scaled, "0/2", tmp("s0.exr"));
    render_shard(scaled, "1/2", tmp("s1.exr"));
    const char *files[] = {tmp("s0.exr"), tmp("s1.exr")};
    merge_files(files, 2, tmp("s-merged.exr"));
    double px, mean;
    compare_shards(tmp("s-merged.exr"), tmp("p-full.exr"), &px, &mean);
    printf("scaled shards merged vs the unscaled render: sums differ by %.3g relative at most\n", px);
    assert_true(px <= PIXEL_BOUND);
    ts_shard_info info;
    ts_film *film;
    ts_error err = {0};
    if (ts_shard_read(tmp("s-merged.exr"), &info, &film, &err)) fail_msg("%s", err.message);
    assert_true(info.film_scale == 2 && film->scale == 2);
    ts_film_destroy(film);
    /* Plain EXRs: every value twice the unscaled one (×2 is exact), and the attribute. */
    const char *r1[] = {"render", plain, "-o", tmp("p.exr"), "--quiet", NULL},
               *r2[] = {"render", scaled, "-o", tmp("s.exr"), "--quiet", NULL};
    assert_int_equal(run(r1), 0);
    assert_int_equal(run(r2), 0);
    ts_image a = {0}, b = {0};
    if (ts_exr_read(tmp("p.exr"), &a, &err) || ts_exr_read(tmp("s.exr"), &b, &err)) fail_msg("%s", err.message);
    const ts_image_attr *at = ts_image_attr_find(&b, "tessera_film_scale");
    assert_true(at && at->type == TS_ATTR_DOUBLE && at->d == 2);
    int red = -1;
    for (int c = 0; c < a.n_channels; c++)
        if (!strcmp(a.channel_names[c], "R")) red = c;
    assert_true(red >= 0 && a.n_channels == b.n_channels);
    size_t differ = 0, lit = 0;
    for (size_t i = 0; i < (size_t)a.width * a.height; i++) {
        float pa = a.data[i * a.n_channels + red], pb = b.data[i * b.n_channels + red];
        differ += pb != 2 * pa;
        lit += pa > 0;
    }
    assert_true(lit > 0);
    assert_int_equal(differ, 0);
    ts_image_fini(&a);
    ts_image_fini(&b);
    /* A shard of the scaled scene does not merge with one of the unscaled scene. */
    render_shard(plain, "1/2", tmp("p1.exr"));
    const char *mixed[] = {"merge", tmp("s0.exr"), tmp("p1.exr"), "-o", tmp("mixed.exr"), NULL};
    assert_int_equal(run(mixed), 1);
}

/* Shards of a media scene (proto/examples/media.json: volpath, a camera in haze, a
 * homogeneous sphere and a grid, their surface-less boundaries) merge like every other
 * effect's: the merged sums within the bounds above of the single render's, and the image
 * a merge gives (its film as a plain EXR's channels, as the server publishes a farm job's)
 * bit for bit the plain `tessera render` EXR of the whole scene. Tracking draws from a
 * stream per pixel sample (media/medium.h), so a sample's walk is the same in any shard. */
static void test_media_shards(void **state)
{
    (void)state;
    cJSON *doc = source_doc("proto/examples/media.json");
    cJSON *film = cJSON_GetObjectItem(doc, "film");
    cJSON_ReplaceItemInObject(film, "width", cJSON_CreateNumber(24));
    cJSON_ReplaceItemInObject(film, "height", cJSON_CreateNumber(16));
    cJSON_AddItemToObject(film, "filter", cJSON_Parse("{\"type\":\"box\",\"radius\":0.5}"));
    cJSON_ReplaceItemInObject(cJSON_GetObjectItem(doc, "sampler"), "spp", cJSON_CreateNumber(7));
    char *out = cJSON_Print(doc);
    const char *scene = tmp("media.json");
    write_file(scene, out);
    cJSON_free(out);
    cJSON_Delete(doc);

    render_shard(scene, "0/1", tmp("media-full.exr"));
    const char *files[3];
    char names[3][512];
    for (int i = 0; i < 3; i++) {
        char spec[8], name[32];
        snprintf(spec, sizeof spec, "%d/3", i);
        snprintf(name, sizeof name, "media-s%d.exr", i);
        snprintf(names[i], sizeof names[i], "%s", tmp(name));
        files[i] = names[i];
        render_shard(scene, spec, files[i]);
    }
    merge_files(files, 3, tmp("media-merged.exr"));
    log_has("7 spp of 7 (samples [0,7))");
    double px, mean;
    compare_shards(tmp("media-merged.exr"), tmp("media-full.exr"), &px, &mean);
    printf("media shards merged vs the single render: largest pixel difference %.3g relative, mean %.3g\n", px, mean);
    assert_true(px <= PIXEL_BOUND);
    assert_true(mean <= MEAN_BOUND);

    const char *plain[] = {"render", scene, "-o", tmp("media-plain.exr"), "--quiet", NULL};
    assert_int_equal(run(plain), 0);
    ts_shard_info info;
    ts_film *merged;
    ts_error err = {0};
    if (ts_shard_read(tmp("media-merged.exr"), &info, &merged, &err)) fail_msg("%s", err.message);
    ts_image a = {0}, b = {0};
    if (ts_film_to_image(merged, TS_FILM_IMAGE_STATS, &a, &err)) fail_msg("%s", err.message);
    if (ts_exr_read(tmp("media-plain.exr"), &b, &err)) fail_msg("%s", err.message);
    assert_int_equal(a.width, b.width);
    assert_int_equal(a.height, b.height);
    assert_int_equal(a.n_channels, b.n_channels);
    size_t pixels = (size_t)a.width * a.height, values = pixels * a.n_channels, differ = 0;
    for (int c = 0; c < a.n_channels; c++) { /* by name: an EXR file keeps its channels sorted */
        int cb = ts_image_channel(&b, a.channel_names[c]);
        if (cb < 0) fail_msg("the render's EXR lacks channel %s", a.channel_names[c]);
        for (size_t i = 0; i < pixels; i++)
            differ += memcmp(&a.data[i * a.n_channels + c], &b.data[i * b.n_channels + cb], sizeof(float)) != 0;
    }
    printf("media: the merge's image vs the single render's EXR: %zu of %zu values differ\n", differ, values);
    assert_int_equal(differ, 0);
    double lit = 0;
    for (size_t i = 0; i < values; i++) lit += a.data[i] > 0;
    assert_true(lit > 0);
    ts_image_fini(&a);
    ts_image_fini(&b);
    ts_film_destroy(merged);
}

static void test_shard_auto(void **state)
{
    (void)state;
    const char *scene = tmp("auto.json"), *out = tmp("auto.exr");
    write_cornell(scene, 8, 8, 8, "box", NULL, 0);
    const char *args[] = {"render", scene, "--shard", "auto", "-o", out, NULL};
    assert_int_equal(run(args), 2);
    log_has("neither JOB_COMPLETION_INDEX (Kubernetes Indexed Job) nor SLURM_ARRAY_TASK_ID");
    const char *k8s[] = {"JOB_COMPLETION_INDEX=1", NULL};
    assert_int_equal(run_env(args, k8s), 2);
    log_has("pass --shard-count");
    const char *args_n[] = {"render", scene, "--shard", "auto", "--shard-count", "4", "-o", out, NULL};
    assert_int_equal(run_env(args_n, k8s), 0);
    log_has("shard 1/4 from JOB_COMPLETION_INDEX=1 and --shard-count 4 (Kubernetes Indexed Job): samples [2,4) of 8");
    const char *slurm[] = {"SLURM_ARRAY_TASK_ID=3", "SLURM_ARRAY_TASK_COUNT=4", "SLURM_ARRAY_TASK_MIN=0", NULL};
    assert_int_equal(run_env(args, slurm), 0);
    log_has("shard 3/4 from SLURM_ARRAY_TASK_ID=3");
    log_has("samples [6,8) of 8");
}

/* ---------------------------------------------------------------- preemption */

static time_t mtime_ns(const char *path, long *ns)
{
    struct stat st;
    if (stat(path, &st) != 0) return 0;
    *ns = st.st_mtim.tv_nsec;
    return st.st_mtim.tv_sec;
}

/* Waits (up to 60 s) until path exists with an mtime other than (sec, ns). */
static bool wait_for_new_checkpoint(const char *path, time_t sec, long ns, pid_t pid)
{
    for (int i = 0; i < 6000; i++) {
        long n2 = 0;
        time_t s2 = mtime_ns(path, &n2);
        if (s2 && (s2 != sec || n2 != ns)) return true;
        if (waitpid(pid, NULL, WNOHANG) == pid) return false;
        usleep(10000);
    }
    return false;
}

static void test_sigterm_sigkill_resume(void **state)
{
    (void)state;
    const char *scene = tmp("ckpt.json"), *ref = tmp("ckpt-ref.exr"), *out = tmp("ckpt-out.exr"),
               *ckpt = tmp("ckpt-state.exr");
    /* Long enough (about 2 s on 2 quiet cores, 0.2 s checkpoints) that both signals land
     * mid-render. */
    write_cornell(scene, 32, 32, 1600, "box", NULL, 0);
    const char *ref_args[] = {"render", scene, "--shard", "1/2", "-o", ref, "--quiet", NULL};
    assert_int_equal(run(ref_args), 0);
    const char *args[] = {"render", scene, "--shard", "1/2", "--checkpoint", ckpt, "--checkpoint-interval", "0.2",
                          "-o", out, NULL};
    /* 1: SIGTERM once a first checkpoint exists: saves and exits 128 + 15. */
    pid_t pid = start(args, NULL);
    assert_true(wait_for_new_checkpoint(ckpt, 0, 0, pid));
    kill(pid, SIGTERM);
    assert_int_equal(finish(pid), 128 + SIGTERM);
    log_has("saved samples [800,");
    assert_false(exists(out));
    long ns = 0;
    time_t sec = mtime_ns(ckpt, &ns);
    /* 2: restart, then SIGKILL after it has written a newer checkpoint. */
    pid = start(args, NULL);
    assert_true(wait_for_new_checkpoint(ckpt, sec, ns, pid));
    usleep(50000);
    kill(pid, SIGKILL);
    assert_int_equal(finish(pid), 128 + SIGKILL);
    log_has("resuming from checkpoint");
    assert_false(exists(out));
    /* 3: restart to the end. */
    pid = start(args, NULL);
    assert_int_equal(finish(pid), 0);
    log_has("resuming from checkpoint");
    assert_true(exists(out));
    assert_false(exists(ckpt)); /* removed once the output holds everything */
    double px, mean;
    compare_shards(out, ref, &px, &mean);
    printf("resumed twice vs uninterrupted: largest pixel difference %.3g relative\n", px);
    assert_true(px <= PIXEL_BOUND);
    /* A checkpoint of another shard is refused, not silently used. */
    const char *other[] = {"render", scene, "--shard", "0/2", "--checkpoint", ckpt, "-o", out, "--quiet", NULL};
    ts_shard_info info;
    ts_film *f;
    ts_error err = {0};
    assert_int_equal(ts_shard_read(ref, &info, &f, &err), TS_OK);
    info.ranges[0].end = info.ranges[0].begin + 3;
    assert_int_equal(ts_shard_write(ckpt, f, &info, &err), TS_OK);
    ts_film_destroy(f);
    assert_int_equal(run(other), 1);
    log_has("not a beginning of this shard's [0,800)");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_shard_layout_round_trip),
        cmocka_unit_test(test_scene_digest_canonical),
        cmocka_unit_test(test_shard_ranges),
        cmocka_unit_test(test_merge_equals_single_render),
        cmocka_unit_test(test_region_shards),
        cmocka_unit_test(test_bad_merges_refused),
        cmocka_unit_test(test_film_scale_shards),
        cmocka_unit_test(test_media_shards),
        cmocka_unit_test(test_shard_auto),
        cmocka_unit_test(test_sigterm_sigkill_resume),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
