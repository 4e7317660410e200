/* fuzz_exr.c — libFuzzer harness: the EXR files tessera reads (exr.h): any EXR through
 * ts_exr_read_memory; an image that loads is then taken as a lat-long environment map
 * (ts_envmap_from_image, what ts_envmap_load does) and queried, and, written to this
 * process's private folder, read as a farm shard and added to a merge (shard.h), the
 * path `tessera merge` takes. */
#include "fuzz_common.h"

#include <math.h>

#include "film/film.h"
#include "image/exr.h"
#include "image/image.h"
#include "lights/envmap.h"
#include "render/shard.h"

static void check_image(const ts_image *img)
{
    FUZZ_CHECK(img->width >= 1 && img->height >= 1 && img->data);
    FUZZ_CHECK((int64_t)img->width * img->height <= TS_IMAGE_MAX_PIXELS);
    FUZZ_CHECK(img->n_channels >= 1 && img->n_channels <= TS_IMAGE_MAX_CHANNELS);
    FUZZ_CHECK(img->n_attrs >= 0 && img->n_attrs <= TS_IMAGE_MAX_ATTRS);
    for (int c = 0; c < img->n_channels; c++)
        FUZZ_CHECK(memchr(img->channel_names[c], '\0', sizeof img->channel_names[c]) != NULL);
    /* Every sample is readable (ASan): touch the first and the last. */
    volatile float first = img->data[0],
                   last = img->data[(size_t)img->width * (size_t)img->height * (size_t)img->n_channels - 1];
    (void)first, (void)last;
}

static void use_envmap(const ts_image *img, uint64_t state)
{
    ts_envmap *m = NULL;
    ts_error err = {0};
    if (ts_envmap_from_image(img, "fuzz.exr", &m, &err) != TS_OK) {
        FUZZ_CHECK(m == NULL && err.message[0] != '\0');
        return;
    }
    for (int k = 0; k < 8; k++) {
        ts_vec2 u = {fuzz_unit(&state), fuzz_unit(&state)};
        if (k == 0) u = (ts_vec2){0, 0};
        if (k == 1) u = (ts_vec2){0.99999994f, 0.99999994f};
        ts_vec3 w;
        float pdf = 0;
        if (ts_envmap_sample(m, u, &w, &pdf)) {
            FUZZ_CHECK(pdf > 0 && isfinite(pdf));
            (void)ts_envmap_lookup(m, w);
            FUZZ_CHECK(!(ts_envmap_pdf(m, w) < 0));
        }
        (void)ts_envmap_lookup_uv(m, u);
    }
    ts_envmap_destroy(m);
}

static void use_shard(const uint8_t *data, size_t size)
{
    char path[128];
    fuzz_write_file("shard.exr", data, size, path, sizeof path);
    ts_shard_info info;
    ts_film *film = NULL;
    ts_error err = {0};
    if (ts_shard_read(path, &info, &film, &err) == TS_OK) {
        FUZZ_CHECK(film != NULL);
        ts_film_destroy(film);
    } else {
        FUZZ_CHECK(film == NULL && err.message[0] != '\0');
    }
    ts_merge *mg = ts_merge_create(&err);
    FUZZ_CHECK(mg != NULL);
    if (ts_merge_add_file(mg, path, &err) == TS_OK) {
        char missing[256];
        (void)ts_merge_missing(mg, missing, sizeof missing);
        int n_files = 0;
        (void)ts_merge_result(mg, &info, &n_files);
    }
    ts_merge_destroy(mg);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    ts_image img = {0};
    ts_error err = {0};
    ts_status st = ts_exr_read_memory(data, size, &img, &err);
    if (st != TS_OK) {
        FUZZ_CHECK(img.data == NULL && err.status == st && err.message[0] != '\0');
        return 0;
    }
    check_image(&img);
    use_envmap(&img, fuzz_hash(data, size));
    ts_image_fini(&img);
    use_shard(data, size);
    return 0;
}
