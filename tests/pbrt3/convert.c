/* convert.c — the pbrt3_convert test: every scene of the shared pbrt-v3 collection
 * converted to scene format v1 (`tessera convert`'s ts_scene_convert_pbrt_path) renders
 * bit-identically to the scene read from its .pbrt — textured ones (checkerboard,
 * spheres-texfilt, f10-1ac: image maps, a checkerboard, uv scales) included.
 *
 *   pbrt3_convert DIR     exit 0 pass, 1 fail, 77 skipped (DIR absent)
 *
 * DIR is ../shared/scenes/pbrt-v3 (or pbrt-v3-next: pbrt3_convert_next; a scene its table in
 * tests/pbrt3/corpus_scenes.c lists as refused at load is an expected failure, and its
 * conversion a loud one) beside the source tree (CMake passes it); its scenes are
 * read in place (the document is loaded from memory with the scene's folder as its
 * base, where its file names resolve), never copied. Each is rendered at 2 spp with its
 * own resolution, the .pbrt on 2 threads and the document on 1 (renders are
 * thread-count independent, docs/design.md §6), and every pixel's RGB is compared bit for
 * bit: deterministic, no false failures. */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "corpus_scenes.h"
#include "render/render.h"
#include "json/scene_json.h"
#include "load/scene_load.h"

static void quiet(void *ctx, const char *msg) { (void)ctx, (void)msg; }

static ts_film *render(const ts_scene *s, int threads, ts_error *err)
{
    ts_film *f = ts_film_create(s->width, s->height, s->crop_x0, s->crop_y0, s->crop_x1 - s->crop_x0,
                                s->crop_y1 - s->crop_y0, err);
    if (!f) return NULL;
    f->scale = s->film_scale;
    ts_render_stats stats = {0};
    ts_render_request req = {s, s->integrator.type, f, 0, 2, threads, NULL, NULL, NULL};
    if (ts_render(&req, &stats, err)) {
        ts_film_destroy(f);
        return NULL;
    }
    return f;
}

/* 0: identical; 1: differs or fails (said on stdout). */
static int one(const char *dir, const char *name)
{
    char folder[4096], path[4200];
    snprintf(folder, sizeof folder, "%s/%s", dir, name);
    snprintf(path, sizeof path, "%s/%s.pbrt", folder, name);
    ts_error err = {0};
    char *json = NULL;
    size_t len = 0;
    ts_scene *a = NULL, *b = NULL;
    ts_film *fa = NULL, *fb = NULL;
    int rc = 1;
    if (ts_scene_convert_pbrt_path(path, NULL, quiet, NULL, &json, &len, &err)) {
        printf("%-18s FAIL convert: %s\n", name, err.message);
        return 1;
    }
    if (ts_scene_load_path(path, NULL, quiet, NULL, &a, &err) ||
        ts_scene_load_text(json, len, folder, name, NULL, &b, &err)) {
        printf("%-18s FAIL load: %s\n", name, err.message);
        goto done;
    }
    if (a->width != b->width || a->height != b->height || a->textured != b->textured) {
        printf("%-18s FAIL the document's film (%u × %u) or textured flag differs\n", name, b->width, b->height);
        goto done;
    }
    /* Each light's samples (pbrt-v3's nsamples under directlighting) must come through
     * the document as they are; then both renders take at most 2 per light (f10-1ac asks
     * for 512: two of its 2-spp renders would take minutes), the same in both. */
    if (a->n_lights != b->n_lights) {
        printf("%-18s FAIL the document has %u lights, the .pbrt %u\n", name, b->n_lights, a->n_lights);
        goto done;
    }
    for (uint32_t i = 0; i < a->n_lights; i++) {
        if (a->lights[i].samples != b->lights[i].samples) {
            printf("%-18s FAIL light %u takes %u samples in the document, %u in the .pbrt\n", name, i,
                   b->lights[i].samples, a->lights[i].samples);
            goto done;
        }
        if (a->lights[i].samples > 2) a->lights[i].samples = b->lights[i].samples = 2;
    }
    if (!(fa = render(a, 2, &err)) || !(fb = render(b, 1, &err))) {
        printf("%-18s FAIL render: %s\n", name, err.message);
        goto done;
    }
    long differ = 0, pixels = 0;
    double sum = 0;
    for (int y = a->crop_y0; y < a->crop_y1; y++)
        for (int x = a->crop_x0; x < a->crop_x1; x++) {
            ts_rgb p = ts_film_pixel_rgb(fa, x, y), q = ts_film_pixel_rgb(fb, x, y);
            differ += memcmp(&p, &q, sizeof p) != 0;
            sum += p.r + p.g + p.b;
            pixels++;
        }
    if (differ || !(sum > 0)) {
        printf("%-18s FAIL %ld of %ld pixels differ (image sum %g)\n", name, differ, pixels, sum);
        goto done;
    }
    printf("%-18s ok: %ld pixels identical, %zu bytes of JSON%s\n", name, pixels, len,
           a->textured ? ", textured" : "");
    rc = 0;
done:
    ts_film_destroy(fa);
    ts_film_destroy(fb);
    ts_scene_destroy(a);
    ts_scene_destroy(b);
    free(json);
    return rc;
}

static int by_name(const void *x, const void *y) { return strcmp(*(char *const *)x, *(char *const *)y); }

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: pbrt3_convert DIR\n");
        return 2;
    }
    DIR *d = opendir(argv[1]);
    if (!d) {
        printf("SKIPPED: %s is absent\n", argv[1]);
        return 77;
    }
    char *names[256];
    int n = 0;
    for (struct dirent *e; (e = readdir(d)) && n < 256;) {
        if (e->d_name[0] == '.') continue;
        char p[4200];
        struct stat st;
        snprintf(p, sizeof p, "%s/%s/%s.pbrt", argv[1], e->d_name, e->d_name);
        if (stat(p, &st) == 0) names[n++] = strdup(e->d_name);
    }
    closedir(d);
    qsort(names, (size_t)n, sizeof *names, by_name);
    int failed = 0, textured = 0, xfail = 0;
    for (int i = 0; i < n; i++) {
        /* A scene listed as refused at load (tests/pbrt3/corpus_scenes.c) is expected to fail
         * here; converting it identically is then a loud failure, to take it off the list. */
        const corpus_scene *cs = ts_corpus_scene_named(argv[1], names[i]);
        int bad = one(argv[1], names[i]);
        if (cs && cs->refused) {
            printf("%-18s %s; needs: %s\n", names[i],
                   bad ? "XFAIL" : "XPASS (UNEXPECTED: listed as refused in tests/pbrt3/corpus_scenes.c; remove it)",
                   cs->expected);
            xfail += bad;
            bad = !bad;
        }
        failed += bad;
        textured += strcmp(names[i], "checkerboard") == 0 || strcmp(names[i], "spheres-texfilt") == 0 ||
                    strcmp(names[i], "f10-1ac") == 0;
        free(names[i]);
    }
    if (n == 0) {
        printf("SKIPPED: no scenes in %s\n", argv[1]);
        return 77;
    }
    printf("%d of %d scenes converted to identical renders, %d expected failures (%d of the 3 textured ones of "
           "pbrt-v3/ present)\n",
           n - failed - xfail, n, xfail, textured);
    return failed ? 1 : 0;
}
