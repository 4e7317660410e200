/* outputs.c — the -o files of `tessera render` and `tessera merge`; see outputs.h. */
#include "outputs.h"

#include <string.h>
#include <strings.h>

#include "tessera.h"

static const char *extension(const char *path)
{
    const char *dot = strrchr(path, '.');
    const char *slash = strrchr(path, '/');
    return dot && (!slash || dot > slash) ? dot + 1 : "";
}

bool cli_outputs_add(cli_outputs *o, const char *path)
{
    if (o->n == CLI_MAX_OUTPUTS) return false;
    o->path[o->n++] = path;
    return true;
}

bool cli_output_is_exr(const char *path) { return strcasecmp(extension(path), "exr") == 0; }

const char *cli_outputs_unsupported(const cli_outputs *o)
{
    for (int i = 0; i < o->n; i++)
        if (!cli_output_is_exr(o->path[i]) && strcasecmp(extension(o->path[i]), "png") != 0) return o->path[i];
    return NULL;
}

ts_status cli_outputs_write_shard(const cli_outputs *o, const ts_film *film, const ts_shard_info *info, ts_error *err)
{
    ts_status st = TS_OK;
    for (int i = 0; !st && i < o->n; i++) {
        if (cli_output_is_exr(o->path[i])) {
            st = ts_shard_write(o->path[i], film, info, err);
        } else {
            ts_image img;
            st = ts_film_to_image(film, TS_FILM_IMAGE_RGB, &img, err);
            if (!st) st = ts_png_write(o->path[i], &img, 0.0f, err);
            ts_image_fini(&img);
        }
    }
    return st;
}
