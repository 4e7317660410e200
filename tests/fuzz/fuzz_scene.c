/* fuzz_scene.c — libFuzzer harness: whole scene documents (scene.h), the surface a
 * client posts: JSON parsing, validation, file references (resolved in this process's
 * private folder, which holds mesh.obj, mesh.ply, table.bsdf and sky.exr so scenes can
 * name them), and the scene build (transforms, shapes, lights, light distribution,
 * Embree accelerator). A scene that loads is also rendered: two samples of the four
 * pixels at the centre of its crop window, through the integrator it asks for, so
 * whatever the loader accepts is exercised by the code that trusts it. */
#include "fuzz_common.h"

#include "film/film.h"
#include "image/exr.h"
#include "image/image.h"
#include "integrators/integrator.h"
#include "render/render.h"
#include "scene/scene.h"
#include "json/scene_json.h"

static const char cube_obj[] = "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\n"
                               "v -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\nvt 0 0\nvt 1 1\n"
                               "f 1 4 3 2\nf 5 6 7 8\nf 1/1 2/2 6/1 5/2\nf 3 4 8 7\nf 2 3 7 6\nf 1 5 8 4\n";

static const char quad_ply[] = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                               "property float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
                               "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                               "-1 0 -1 0 1 0\n1 0 -1 0 1 0\n1 0 1 0 1 0\n-1 0 1 0 1 0\n4 0 3 2 1\n";

static void put_le32(unsigned char *p, uint32_t v)
{
    for (int i = 0; i < 4; i++) p[i] = (unsigned char)(v >> (8 * i));
}
static void put_f32(unsigned char *p, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    put_le32(p, u);
}

/* The smallest Fourier table: nodes μ = ±1, one luminance coefficient per series. */
static size_t make_bsdf(unsigned char *b)
{
    memset(b, 0, 136);
    memcpy(b, "SCATFUN\x01", 8);
    const uint32_t header[6] = {1, 2, 4, 1, 1, 1}; /* flags, nMu, nCoeffs, mMax, nChannels, nBases */
    for (int i = 0; i < 6; i++) put_le32(b + 8 + 4 * i, header[i]);
    put_f32(b + 44, 1.5f);
    unsigned char *p = b + 64;
    put_f32(p, -1), put_f32(p + 4, 1), p += 8;                       /* nodes */
    for (int i = 0; i < 4; i++, p += 4) put_f32(p, i % 2 ? 0.3f : 0); /* CDF rows */
    for (int i = 0; i < 4; i++, p += 8) put_le32(p, (uint32_t)i), put_le32(p + 4, 1);
    for (int i = 0; i < 4; i++, p += 4) put_f32(p, 0.15f); /* coefficients */
    return (size_t)(p - b);
}

static void write_fixtures(void)
{
    char path[128];
    fuzz_write_file("mesh.obj", cube_obj, sizeof cube_obj - 1, path, sizeof path);
    fuzz_write_file("mesh.ply", quad_ply, sizeof quad_ply - 1, path, sizeof path);
    unsigned char bsdf[136];
    fuzz_write_file("table.bsdf", bsdf, make_bsdf(bsdf), path, sizeof path);
    ts_image img;
    ts_error err = {0};
    const char *names[] = {"R", "G", "B"};
    if (ts_image_init(&img, 8, 4, 3, names, &err) != TS_OK) abort();
    for (int i = 0; i < 8 * 4 * 3; i++) img.data[i] = (float)(i % 7) * 0.25f;
    snprintf(path, sizeof path, "%s/sky.exr", fuzz_dir());
    if (ts_exr_write(path, &img, &err) != TS_OK) {
        fprintf(stderr, "fuzz_scene: %s\n", err.message);
        abort();
    }
    ts_image_fini(&img);
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc, (void)argv;
    write_fixtures();
    return 0;
}

static void render_centre(const ts_scene *s)
{
    int w = s->crop_x1 - s->crop_x0, h = s->crop_y1 - s->crop_y0;
    FUZZ_CHECK(w >= 1 && h >= 1 && s->crop_x0 >= 0 && s->crop_y0 >= 0 && s->crop_x1 <= s->width &&
               s->crop_y1 <= s->height);
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
    /* A server's kind of limits: generous for real scenes, small enough that a hostile
     * document is refused before it can exhaust libFuzzer's memory limit. */
    ts_scene_limits lim;
    ts_scene_limits_default(&lim);
    lim.max_triangles = 1u << 18;
    lim.max_shapes = 1u << 14;
    lim.max_lights = 1u << 14;
    lim.max_materials = 1u << 12;
    lim.max_file_bytes = 1u << 24;
    lim.max_memory = 256u << 20;
    ts_scene *s = NULL;
    ts_error err = {0};
    ts_status st = ts_scene_load_text((const char *)data, size, fuzz_dir(), "fuzz", &lim, &s, &err);
    if (st != TS_OK) {
        FUZZ_CHECK(s == NULL && err.status == st && err.message[0] != '\0');
        return 0;
    }
    FUZZ_CHECK(s != NULL && s->spp >= 1);
    render_centre(s);
    ts_scene_destroy(s);
    return 0;
}
