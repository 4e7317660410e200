/* fuzz_pbrt_import.c — libFuzzer harness: pbrt-v3 scene text through the whole pbrt-v3
 * front end (load/scene_load.h): parsing, the mapping onto the scene builder
 * (pbrt_import.h: every camera, film, filter, sampler, integrator, shape, light and
 * material mapping, spectra), the files a scene names (this process's private folder holds
 * mesh.ply, sky.exr, table.bsdf, k.spd and inc.pbrt), and the build, under a server's kind
 * of limits. A refused input must leave no scene and one UTF-8 sentence; every warning
 * must be a UTF-8 sentence too. A scene that loads is rendered (two samples of the four
 * pixels at the centre of its crop window), and converted to JSON v1
 * (ts_scene_convert_pbrt_path on the same bytes; textured materials are refused there for
 * now), which must load as a JSON scene with the same film, shape and light counts. */
#include "fuzz_common.h"

#include <unistd.h>

#include <cjson/cJSON.h>

#include "film/film.h"
#include "image/exr.h"
#include "image/image.h"
#include "render/render.h"
#include "pbrt3/pbrt_lexer.h"
#include "json/scene_json.h"
#include "load/scene_load.h"

static const char quad_ply[] = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                               "property float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
                               "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                               "-1 0 -1 0 1 0\n1 0 -1 0 1 0\n1 0 1 0 1 0\n-1 0 1 0 1 0\n4 0 3 2 1\n";

static void put_le32(unsigned char *p, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}
static void put_f32(unsigned char *p, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    put_le32(p, u);
}

/* The smallest Fourier table (as fuzz_scene makes it). */
static size_t make_bsdf(unsigned char *b)
{
    memset(b, 0, 136);
    memcpy(b, "SCATFUN\x01", 8);
    const uint32_t header[6] = {1, 2, 4, 1, 1, 1};
    for (int i = 0; i < 6; i++)
        put_le32(b + 8 + 4 * i, header[i]);
    put_f32(b + 44, 1.5f);
    unsigned char *p = b + 64;
    put_f32(p, -1), put_f32(p + 4, 1), p += 8;
    for (int i = 0; i < 4; i++, p += 4)
        put_f32(p, i % 2 ? 0.3f : 0);
    for (int i = 0; i < 4; i++, p += 8)
        put_le32(p, (uint32_t)i), put_le32(p + 4, 1);
    for (int i = 0; i < 4; i++, p += 4)
        put_f32(p, 0.15f);
    return (size_t)(p - b);
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc, (void)argv;
    char path[256];
    fuzz_write_file("mesh.ply", quad_ply, sizeof quad_ply - 1, path, sizeof path);
    unsigned char bsdf[136];
    fuzz_write_file("table.bsdf", bsdf, make_bsdf(bsdf), path, sizeof path);
    static const char spd[] = "# wavelength value\n400 0.1\n550 0.5\n700 0.9\n";
    fuzz_write_file("k.spd", spd, sizeof spd - 1, path, sizeof path);
    static const char inc[] =
        "AttributeBegin Translate 1 0 0 Shape \"sphere\" \"float radius\" 0.5 AttributeEnd\n";
    fuzz_write_file("inc.pbrt", inc, sizeof inc - 1, path, sizeof path);
    ts_image img;
    ts_error err = {0};
    const char *names[] = {"R", "G", "B"};
    if (ts_image_init(&img, 8, 4, 3, names, &err) != TS_OK) abort();
    for (int i = 0; i < 8 * 4 * 3; i++)
        img.data[i] = (float)(i % 7) * 0.25f;
    snprintf(path, sizeof path, "%s/sky.exr", fuzz_dir());
    if (ts_exr_write(path, &img, &err) != TS_OK) abort();
    ts_image_fini(&img);
    return 0;
}

static bool utf8_clean(const char *s)
{
    char copy[TS_ERROR_MAX + 64];
    snprintf(copy, sizeof copy, "%s", s);
    ts_pbrt_sanitize_utf8(copy);
    return strcmp(copy, s) == 0;
}

static void on_warning(void *ctx, const char *msg)
{
    (void)ctx;
    FUZZ_CHECK(msg && msg[0] && utf8_clean(msg));
}

static void render_centre(const ts_scene *s)
{
    int w = s->crop_x1 - s->crop_x0, h = s->crop_y1 - s->crop_y0;
    FUZZ_CHECK(w >= 1 && h >= 1);
    int tw = w < 2 ? w : 2, th = h < 2 ? h : 2;
    int x0 = s->crop_x0 + (w - tw) / 2, y0 = s->crop_y0 + (h - th) / 2;
    ts_error err = {0};
    ts_film *film = ts_film_create(s->width, s->height, x0, y0, tw, th, &err);
    FUZZ_CHECK(film != NULL);
    ts_render_request req = {.scene = s,
                             .integrator = s->integrator.type,
                             .film = film,
                             .sample_begin = 0,
                             .sample_end = s->spp < 2 ? s->spp : 2,
                             .threads = 1};
    ts_counters c = {0};
    ts_render_tile(&req, x0, y0, tw, th, &c);
    ts_film_destroy(film);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    ts_scene_limits lim;
    ts_scene_limits_default(&lim);
    lim.max_width = lim.max_height = 256;
    lim.max_pixels = 1u << 14;
    lim.max_spp = 64;
    lim.max_triangles = 1u << 16;
    lim.max_shapes = 1u << 12;
    lim.max_lights = 1u << 12;
    lim.max_materials = 1u << 10;
    lim.max_file_bytes = 1u << 20;
    lim.max_memory = 128u << 20;
    ts_scene *s = NULL;
    ts_error err = {0};
    ts_status st = ts_scene_load_pbrt_text((const char *)data, size, fuzz_dir(), "fuzz.pbrt", &lim,
                                           on_warning, NULL, &s, &err);
    if (st != TS_OK) {
        FUZZ_CHECK(s == NULL && err.status == st && err.message[0] != '\0' && utf8_clean(err.message));
        return 0;
    }
    FUZZ_CHECK(s != NULL && s->spp >= 1 && strlen(s->digest) == 64);
    render_centre(s);

    /* The same bytes as a file, converted: the document loads as JSON v1, the same scene. */
    char path[256];
    fuzz_write_file("in.pbrt", data, size, path, sizeof path);
    char *json = NULL;
    size_t len = 0;
    st = ts_scene_convert_pbrt_path(path, &lim, NULL, NULL, &json, &len, &err);
    /* gone before the next input, which could otherwise Include it */
    unlink(path);
    /* The refusals a loading scene may meet: textured materials are not written yet, and a
     * name that is not UTF-8 text cannot be written as JSON. */
    if (st == TS_ERR_UNSUPPORTED &&
        (strstr(err.message, "not converted to JSON yet") || strstr(err.message, "not UTF-8 text, which JSON"))) {
        ts_scene_destroy(s);
        return 0;
    }
    if (st) fprintf(stderr, "fuzz_pbrt_import: the file does not convert: %s\n", err.message);
    FUZZ_CHECK(st == TS_OK && json);
    ts_scene *j = NULL;
    st = ts_scene_load_text(json, len, fuzz_dir(), "fuzz", &lim, &j, &err);
    if (st) fprintf(stderr, "fuzz_pbrt_import: the conversion does not load: %s\n", err.message);
    FUZZ_CHECK(st == TS_OK);
    FUZZ_CHECK(j->width == s->width && j->height == s->height && j->n_shapes == s->n_shapes &&
               j->n_lights == s->n_lights && j->spp == s->spp);
    ts_scene_destroy(j);
    free(json);
    ts_scene_destroy(s);
    return 0;
}
