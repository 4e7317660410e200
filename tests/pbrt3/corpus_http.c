/* corpus_http.c — the pbrt3_corpus_http test: every scene of the shared pbrt-v3 collection
 * posted as a bundle to a real `tessera serve` renders to the same pixels as pbrt3_corpus
 * renders it, and bad bundles of those scenes are refused.
 *
 *   pbrt3_corpus_http DIR       the test (exit 0 pass, 1 fail, 77 skipped: DIR absent);
 *                               DIR ../shared/scenes/pbrt-v3 or …/pbrt-v3-next, whose scenes
 *                               listed as refused at load must get 400 (corpus_scenes.c)
 *
 * Why bit-identical is enough. pbrt3_corpus (tests/pbrt3/corpus.c) renders each scene K = 8
 * times (seeds 0 … 7, the sampler's spp set to pbrt-v3's reference spp S so textures are
 * filtered as in pbrt-v3's image) and holds them to pbrt-v3's image statistically. A render
 * is a deterministic function of the scene, the sampler (seed, S) and the samples taken:
 * the same scene gives the same bits whatever the thread count or the order tiles and
 * passes run in (docs/design.md §6). So if the HTTP path — tar, unpack into the job's
 * folder, pbrt-v3 import from there, the scheduler's passes, the EXR encoder — gives pixels
 * bit-identical to pbrt3_corpus's render with seed 0 (the seed a pbrt-v3 file imports
 * with), it renders the scene pbrt3_corpus measured, and that comparison carries over to it
 * without K more renders. Each job renders N = 4 spp (POST …?spp=4: three passes of the
 * scheduler, ending at 1, 2 and 4 spp) and is compared with ts_corpus_render of the same
 * scene, seed 0, 4 spp, the very function pbrt3_corpus renders with; a larger N would only
 * cost time (pbrt3_corpus's own spp per scene would take about 30 s more). Any difference in
 * what the bundle path loads — a file, a parameter, the sampler's spp, the seed, the
 * summation order — changes some pixel's bits; there is no tolerance and so no false
 * failure. All 7 channels of the served EXR (R, G, B, their variances, the sample count) are
 * compared.
 *
 * The bundle is the scene's folder as it is, without NAME-pbrt3.exr (pbrt-v3's image), with
 * NAME.pbrt as the bundle's scene.pbrt, its pixelsamples raised to S (the file pbrt-v3
 * rendered for its reference, REFERENCES.md, and the sampler pbrt3_corpus sets) and each
 * light's nsamples lowered to the cap pbrt3_corpus's renders take (ts_corpus_cap_lights). One scene
 * is posted gzip-compressed (application/gzip), the rest as application/x-tar. The tars are
 * written in memory by libarchive; nothing of ../shared is copied anywhere but the
 * server's --data folder, a temporary one removed at the end.
 *
 * Warnings: each job's status lists the import's warnings ("Sampler \"halton\": is mapped
 * to tessera's Owen-scrambled Sobol sampler …"), exactly the sentences loading the same
 * scene.pbrt in-process gives, and the server's log (JSON lines) has one job.warning line
 * with the job's id for each.
 *
 * Bad bundles: a scene's bundle without a PLY mesh, an image texture, an environment map or
 * an included file it names gets 400 with a sentence naming scene.pbrt:LINE:COLUMN (the
 * line that names the file) and the missing file; after each, --data's incoming/ is empty
 * and jobs/ holds only the accepted jobs. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <archive.h>
#include <archive_entry.h>
#include <curl/curl.h> /* curl_global_init */
#include <dirent.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "corpus_scenes.h"
#include "film/film_image.h"
#include "image/exr.h"
#include "server_harness.h"

#define HTTP_SPP 4
#define GZIP_SCENE "veach-mis"

static const char *corpus_dir;

/* ---------------------------------------------------------------- files */

static char *read_file(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f) fail_msg("cannot open %s", path);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *buf = malloc((size_t)n + 1);
    assert_non_null(buf);
    assert_true(fread(buf, 1, (size_t)n, f) == (size_t)n);
    fclose(f);
    buf[n] = '\0';
    *len = (size_t)n;
    return buf;
}

typedef struct file_list {
    char **rel; /* paths relative to the scene's folder */
    int n, cap;
} file_list;

static int cmp_str(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

/* Every regular file below root/rel (rel "" for root itself), as paths relative to root. */
static void walk(const char *root, const char *rel, file_list *out)
{
    char path[4096];
    snprintf(path, sizeof path, "%s%s%s", root, rel[0] ? "/" : "", rel);
    DIR *d = opendir(path);
    if (!d) fail_msg("cannot list %s", path);
    for (struct dirent *e; (e = readdir(d));) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
        char sub[4096], full[8200];
        snprintf(sub, sizeof sub, "%s%s%s", rel, rel[0] ? "/" : "", e->d_name);
        snprintf(full, sizeof full, "%s/%s", root, sub);
        struct stat sb;
        assert_int_equal(lstat(full, &sb), 0);
        if (S_ISDIR(sb.st_mode)) {
            walk(root, sub, out);
        } else if (S_ISREG(sb.st_mode)) {
            if (out->n == out->cap) {
                out->cap = out->cap ? 2 * out->cap : 16;
                out->rel = realloc(out->rel, (size_t)out->cap * sizeof *out->rel);
                assert_non_null(out->rel);
            }
            out->rel[out->n++] = strdup(sub);
        }
    }
    closedir(d);
}

static void file_list_free(file_list *l)
{
    for (int i = 0; i < l->n; i++) free(l->rel[i]);
    free(l->rel);
}

/* NAME.pbrt's text with its one Sampler's pixelsamples (outside comments) set to spp. */
static char *with_pixelsamples(const char *text, int spp)
{
    static const char key[] = "\"integer pixelsamples\"";
    const char *found = NULL;
    int hits = 0;
    for (const char *at = strstr(text, key); at; at = strstr(at + 1, key)) {
        const char *line = at;
        while (line > text && line[-1] != '\n') line--;
        if (memchr(line, '#', (size_t)(at - line))) continue; /* a comment */
        found = at, hits++;
    }
    if (hits != 1) fail_msg("expected one \"integer pixelsamples\" outside comments, found %d", hits);
    const char *p = found + strlen(key);
    while (*p == ' ' || *p == '\t' || *p == '[') p++;
    const char *q = p;
    while (*q >= '0' && *q <= '9') q++;
    assert_true(q > p);
    size_t head = (size_t)(p - text), n = head + 16 + strlen(q);
    char *out = malloc(n);
    assert_non_null(out);
    snprintf(out, n, "%.*s%d%s", (int)head, text, spp, q);
    return out;
}

/* text with every light's "integer nsamples" (outside comments) at most cap. */
static char *with_light_cap(char *text, uint32_t cap)
{
    static const char key[] = "\"integer nsamples\"";
    for (char *at = strstr(text, key); at; at = strstr(at + 1, key)) {
        const char *line = at;
        while (line > text && line[-1] != '\n') line--;
        if (memchr(line, '#', (size_t)(at - line))) continue; /* a comment */
        char *p = at + strlen(key);
        while (*p == ' ' || *p == '\t' || *p == '\n' || *p == '[') p++;
        char *q = p;
        while (*q >= '0' && *q <= '9') q++;
        assert_true(q > p);
        if (strtoul(p, NULL, 10) <= cap) continue;
        size_t head = (size_t)(p - text), n = head + 16 + strlen(q);
        char *out = malloc(n);
        assert_non_null(out);
        snprintf(out, n, "%.*s%u%s", (int)head, text, cap, q);
        at = out + (at - text);
        free(text);
        text = out;
    }
    return text;
}

/* ---------------------------------------------------------------- bundles */

typedef struct bundle {
    unsigned char *data;
    size_t len;
} bundle;

/* A pax tar (gzip-compressed when gzip) of scene.pbrt = scene_text and the files of
 * dir/name except NAME.pbrt, NAME-pbrt3.exr and `omit` (NULL: none). */
static bundle make_bundle(const char *name, const char *scene_text, const char *omit, bool gzip)
{
    char root[4096], skip_pbrt[300], skip_ref[300];
    snprintf(root, sizeof root, "%s/%s", corpus_dir, name);
    snprintf(skip_pbrt, sizeof skip_pbrt, "%s.pbrt", name);
    snprintf(skip_ref, sizeof skip_ref, "%s-pbrt3.exr", name);
    file_list files = {0};
    walk(root, "", &files);
    qsort(files.rel, (size_t)files.n, sizeof *files.rel, cmp_str);
    size_t cap = strlen(scene_text) + 65536;
    for (int i = 0; i < files.n; i++) {
        char full[8200];
        snprintf(full, sizeof full, "%s/%s", root, files.rel[i]);
        struct stat sb;
        assert_int_equal(stat(full, &sb), 0);
        cap += (size_t)sb.st_size + 2048;
    }
    bundle b = {malloc(cap), 0};
    assert_non_null(b.data);
    struct archive *a = archive_write_new();
    archive_write_set_format_pax_restricted(a);
    if (gzip) archive_write_add_filter_gzip(a);
    archive_write_set_bytes_in_last_block(a, 1);
    assert_int_equal(archive_write_open_memory(a, b.data, cap, &b.len), ARCHIVE_OK);
    for (int i = -1; i < files.n; i++) {
        const char *rel = i < 0 ? "scene.pbrt" : files.rel[i];
        if (i >= 0 && (!strcmp(rel, skip_pbrt) || !strcmp(rel, skip_ref) || (omit && !strcmp(rel, omit)))) continue;
        size_t len = strlen(scene_text);
        char *data = NULL;
        if (i >= 0) {
            char full[8200];
            snprintf(full, sizeof full, "%s/%s", root, rel);
            data = read_file(full, &len);
        }
        struct archive_entry *ae = archive_entry_new();
        archive_entry_set_pathname(ae, rel);
        archive_entry_set_filetype(ae, AE_IFREG);
        archive_entry_set_perm(ae, 0644);
        archive_entry_set_size(ae, (la_int64_t)len);
        assert_int_equal(archive_write_header(a, ae), ARCHIVE_OK);
        assert_true(archive_write_data(a, data ? data : scene_text, len) == (la_ssize_t)len);
        archive_entry_free(ae);
        free(data);
    }
    assert_int_equal(archive_write_close(a), ARCHIVE_OK);
    archive_write_free(a);
    file_list_free(&files);
    return b;
}

/* ---------------------------------------------------------------- HTTP */

/* POSTs the bundle to /api/v1/jobs?spp=HTTP_SPP as type; the status, *out the body (caller frees). */
static long post_bundle(const test_server *s, const bundle *b, const char *type, char **out)
{
    char path[64];
    snprintf(path, sizeof path, "/api/v1/jobs?spp=%d", HTTP_SPP);
    return ts_http_post_body(s, path, b->data, b->len, type, NULL, out);
}

/* ---------------------------------------------------------------- warnings */

typedef struct warning_list {
    char *msg[64];
    int n;
} warning_list;

static void collect(void *ctx, const char *msg)
{
    warning_list *w = ctx;
    if (w->n < 64) w->msg[w->n++] = strdup(msg);
}

static void warning_list_free(warning_list *w)
{
    for (int i = 0; i < w->n; i++) free(w->msg[i]);
    w->n = 0;
}

/* How many of the log's JSON lines are a job.warning of job id with this message. */
static int log_warning_lines(const char *log, const char *id, const char *message)
{
    int n = 0;
    for (const char *line = log; *line;) {
        const char *end = strchr(line, '\n');
        size_t len = end ? (size_t)(end - line) : strlen(line);
        cJSON *o = cJSON_ParseWithLength(line, len);
        const cJSON *ev = cJSON_GetObjectItemCaseSensitive(o, "event"), *jid = cJSON_GetObjectItemCaseSensitive(o, "id"),
                    *msg = cJSON_GetObjectItemCaseSensitive(o, "message");
        n += cJSON_IsString(ev) && !strcmp(ev->valuestring, "job.warning") && cJSON_IsString(jid) &&
             !strcmp(jid->valuestring, id) && cJSON_IsString(msg) && !strcmp(msg->valuestring, message);
        cJSON_Delete(o);
        line += len + (end != NULL);
    }
    return n;
}

/* ---------------------------------------------------------------- the test */

typedef struct scene_job {
    const corpus_scene *cs;
    int ref_spp;
    char *text; /* scene.pbrt as posted */
    char id[32];
} scene_job;

/* Where the importer places a missing file: the parameter whose value names it ("string
 * filename", "string mapname": the position of its opening quote), or for an Include, the
 * file's own string; as "scene.pbrt:LINE:COLUMN:". */
static void position_naming(const char *text, const char *file, char *out, size_t n)
{
    char quoted[300];
    snprintf(quoted, sizeof quoted, "\"%s\"", file);
    const char *at = strstr(text, quoted);
    if (!at) fail_msg("no string names \"%s\"", file);
    const char *p = at;
    while (p > text && (p[-1] == ' ' || p[-1] == '\t' || p[-1] == '\n' || p[-1] == '['))
        p--;
    if (p > text && p[-1] == '"') { /* the parameter's declaration before the value */
        const char *q = p - 1;
        while (q > text && q[-1] != '"')
            q--;
        if (q > text && !strncmp(q, "string ", 7)) at = q - 1;
    }
    int line = 1;
    const char *line_start = text;
    for (const char *c = text; c < at; c++)
        if (*c == '\n') line++, line_start = c + 1;
    snprintf(out, n, "scene.pbrt:%d:%d:", line, (int)(at - line_start) + 1);
}

static void test_bad_bundles(const test_server *srv, const char *data, const scene_job *jobs, int n_jobs, int accepted)
{
    /* A missing PLY mesh, image texture, environment map, included file and Fourier table. */
    static const struct { const char *scene, *omit; } bad[] = {
        {"veach-mis", "geometry/floor.ply"},
        {"spheres-texfilt", "textures/lines.png"},
        {"f10-1ac", "textures/20060807_wells6_hd.exr"},
        {"killeroo-simple", "geometry/killeroo.pbrt"},
        {"fourier-spheres", "bsdfs/paint.bsdf"}, /* pbrt-v3-next */
    };
    for (size_t b = 0; b < sizeof bad / sizeof bad[0]; b++) {
        const scene_job *sj = NULL;
        for (int i = 0; i < n_jobs; i++)
            if (!strcmp(jobs[i].cs->name, bad[b].scene) && jobs[i].id[0]) sj = &jobs[i];
        if (!sj) continue; /* not in this collection */
        bundle bu = make_bundle(bad[b].scene, sj->text, bad[b].omit, false);
        char *body;
        long st = post_bundle(srv, &bu, "application/x-tar", &body);
        free(bu.data);
        cJSON *o = cJSON_Parse(body);
        const char *msg = ts_json_str(o, "error");
        char where[64];
        position_naming(sj->text, bad[b].omit, where, sizeof where);
        if (st != 400 || !msg || strncmp(msg, where, strlen(where)) != 0 || !strstr(msg, bad[b].omit))
            fail_msg("%s without %s: expected 400 starting '%s' and naming the file, got %ld: %s", bad[b].scene,
                     bad[b].omit, where, st, body);
        printf("%s without %s: 400: %s\n", bad[b].scene, bad[b].omit, msg);
        cJSON_Delete(o);
        free(body);
        char what[300];
        snprintf(what, sizeof what, "after %s without %s", bad[b].scene, bad[b].omit);
        ts_assert_bundles_left(data, accepted, what);
    }
}

static void test_corpus_over_http(void **state)
{
    (void)state;
    char data[512];
    snprintf(data, sizeof data, "%s/ts_pbrt3_http_XXXXXX",
             getenv("TMPDIR") && getenv("TMPDIR")[0] ? getenv("TMPDIR") : "/tmp");
    assert_non_null(mkdtemp(data));
    const char *args[] = {"--threads", "2", "--data", data, "--log-format", "json", NULL};
    test_server srv;
    ts_server_start(&srv, args);
    int n;
    const corpus_scene *scenes = ts_corpus_scenes_of(corpus_dir, &n);
    assert_non_null(scenes);
    scene_job *jobs = calloc((size_t)n, sizeof *jobs);
    assert_non_null(jobs);
    int accepted = 0, failures = 0;
    /* Every scene posted first: the server renders while this process does. A scene listed
     * as refused at load (corpus_scenes.c) must get 400 (XFAIL); 201 is a loud failure, to
     * take it off the list. */
    for (int i = 0; i < n; i++) {
        scene_job *j = &jobs[i];
        j->cs = &scenes[i];
        double ref_s;
        if (!ts_corpus_reference_entry(corpus_dir, j->cs->name, &j->ref_spp, &ref_s))
            fail_msg("%s: no reference entry in REFERENCES.md", j->cs->name);
        char path[4096];
        snprintf(path, sizeof path, "%s/%s/%s.pbrt", corpus_dir, j->cs->name, j->cs->name);
        size_t len;
        char *orig = read_file(path, &len);
        j->text = with_light_cap(with_pixelsamples(orig, j->ref_spp), j->cs->light_cap ? j->cs->light_cap : 1);
        free(orig);
        bool gzip = !strcmp(j->cs->name, GZIP_SCENE);
        bundle b = make_bundle(j->cs->name, j->text, NULL, gzip);
        char *body;
        long st = post_bundle(&srv, &b, gzip ? "application/gzip" : "application/x-tar", &body);
        if (j->cs->refused) {
            bool xfail = st == 400;
            printf("%s: %s: POST %ld: %s; needs: %s\n", j->cs->name,
                   xfail ? "XFAIL" : "XPASS (UNEXPECTED: listed as refused in tests/pbrt3/corpus_scenes.c; remove it)",
                   st, body, j->cs->expected);
            failures += !xfail;
            accepted += st == 201; /* its job stays in --data */
            free(body);
            free(b.data);
            free(j->text), j->text = NULL;
            j->id[0] = '\0'; /* not compared */
            continue;
        }
        if (st != 201) fail_msg("%s: POST: %ld %s", j->cs->name, st, body);
        accepted++;
        cJSON *o = cJSON_Parse(body);
        snprintf(j->id, sizeof j->id, "%s", ts_json_str(o, "id"));
        assert_int_equal((int)ts_json_num(o, "spp_target"), HTTP_SPP);
        cJSON_Delete(o);
        free(body);
        printf("%s: posted (%zu bytes%s), job %s\n", j->cs->name, b.len, gzip ? ", gzip" : "", j->id);
        free(b.data);
    }
    ts_assert_bundles_left(data, accepted, "after the good bundles");
    test_bad_bundles(&srv, data, jobs, n, accepted);
    for (int i = 0; i < n; i++) {
        scene_job *j = &jobs[i];
        if (!j->id[0]) continue; /* refused, above */
        const char *name = j->cs->name;
        /* pbrt3_corpus's render with seed 0, at the HTTP job's spp. */
        ts_error err = {0};
        ts_scene *s = NULL;
        if (ts_corpus_load(corpus_dir, name, j->ref_spp, NULL, NULL, &s, &err)) fail_msg("%s: %s", name, err.message);
        ts_corpus_cap_lights(s, j->cs);
        double secs = 0, cpu_secs = 0;
        ts_film *film = ts_corpus_render(s, 0, HTTP_SPP, &secs, &cpu_secs, &err);
        if (!film) fail_msg("%s: render: %s", name, err.message);
        ts_image want;
        if (ts_film_to_image(film, TS_FILM_IMAGE_STATS, &want, &err)) fail_msg("%s: %s", name, err.message);
        ts_film_destroy(film);
        ts_scene_destroy(s);
        /* The warnings the posted scene.pbrt gives, loaded in place. */
        char folder[4096];
        snprintf(folder, sizeof folder, "%s/%s", corpus_dir, name);
        warning_list warn = {0};
        if (ts_scene_load_pbrt_text(j->text, strlen(j->text), folder, "scene.pbrt", NULL, collect, &warn, &s, &err))
            fail_msg("%s: scene.pbrt: %s", name, err.message);
        ts_scene_destroy(s);
        /* The job's image. */
        cJSON *done = ts_wait_done(&srv, j->id, 120);
        if (strcmp(ts_json_str(done, "state"), "done") != 0)
            fail_msg("%s: job %s ended %s", name, j->id, ts_json_str(done, "state"));
        cJSON_Delete(done);
        char url[128];
        snprintf(url, sizeof url, "/api/v1/jobs/%s/image.exr", j->id);
        http_resp r;
        ts_http(&srv, "GET", url, NULL, 0, NULL, &r);
        assert_int_equal(r.status, 200);
        ts_image got;
        if (ts_exr_read_memory((const unsigned char *)r.body, r.len, &got, &err)) fail_msg("%s: %s", name, err.message);
        ts_http_free(&r);
        /* Channel by channel, matched by name (an EXR lists them sorted). */
        long differ = 0, first = -1;
        int first_c = 0, map[16];
        bool same_shape = got.width == want.width && got.height == want.height && got.n_channels == want.n_channels &&
                          want.n_channels <= 16;
        for (int c = 0; same_shape && c < want.n_channels; c++) {
            map[c] = -1;
            for (int g = 0; g < got.n_channels; g++)
                if (!strcmp(got.channel_names[g], want.channel_names[c])) map[c] = g;
            same_shape = map[c] >= 0;
        }
        size_t pixels = (size_t)want.width * want.height;
        for (size_t px = 0; same_shape && px < pixels; px++)
            for (int c = 0; c < want.n_channels; c++)
                if (memcmp(&got.data[px * got.n_channels + map[c]], &want.data[px * want.n_channels + c], sizeof(float))) {
                    if (first < 0) first = (long)px, first_c = c;
                    differ++;
                }
        /* The job's warnings: the same sentences, in order, in its status and its log lines. */
        snprintf(url, sizeof url, "/api/v1/jobs/%s", j->id);
        cJSON *status = ts_http_json(&srv, url, 200);
        const cJSON *arr = cJSON_GetObjectItemCaseSensitive(status, "warnings");
        int listed = cJSON_IsArray(arr) ? cJSON_GetArraySize(arr) : -1, matched = 0, logged = 0;
        size_t log_len;
        char *log = read_file(srv.log, &log_len);
        for (int w = 0; w < warn.n; w++) {
            const cJSON *item = cJSON_GetArrayItem(arr, w);
            matched += cJSON_IsString(item) && !strcmp(item->valuestring, warn.msg[w]);
            logged += log_warning_lines(log, j->id, warn.msg[w]) == 1;
        }
        free(log);
        cJSON_Delete(status);
        bool ok = same_shape && differ == 0 && listed == warn.n && matched == warn.n && logged == warn.n && warn.n > 0;
        printf("%s: %s: %d × %d × %d channels %s (%ld values differ", name, ok ? "PASS" : "FAIL", want.width,
               want.height, want.n_channels, same_shape ? "as rendered in-process" : "SHAPE DIFFERS", differ);
        if (first >= 0)
            printf(", first pixel (%ld, %ld) %s", first % want.width, first / want.width, want.channel_names[first_c]);
        printf("); in-process render %.2f s; %d warnings expected, %d listed, %d matched, %d logged%s%s\n", secs,
               warn.n, listed, matched, logged, warn.n ? ": " : "", warn.n ? warn.msg[0] : "");
        failures += !ok;
        warning_list_free(&warn);
        ts_image_fini(&got);
        ts_image_fini(&want);
        free(j->text);
    }
    free(jobs);
    assert_int_equal(ts_server_stop(&srv, SIGTERM), 0);
    char cmd[700];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", data);
    assert_int_equal(system(cmd), 0);
    if (failures)
        fail_msg("%d of %d scenes failed over HTTP (pixels, warnings or log lines, or a listed refusal that loads)",
                 failures, n);
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: %s DIR\n", argv[0]);
        return 2;
    }
    corpus_dir = argv[1];
    if (!ts_corpus_present(corpus_dir)) return 77;
    curl_global_init(CURL_GLOBAL_DEFAULT);
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_corpus_over_http)};
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    curl_global_cleanup();
    return rc ? 1 : 0;
}
