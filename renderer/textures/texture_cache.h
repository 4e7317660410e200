/* texture_cache.h — the MIP maps of a scene's image textures, each built once.
 *
 * Design note: pbrt-v3 keeps one MIPMap per (file, filtering, wrap, scale, gamma) and
 * shares it between the textures that name it; so does this cache, keyed by the file's
 * canonical path (textures naming one file by two spellings share it), the channel count
 * (1 for float textures, 3 for RGB), the wrap mode (it shapes the pyramid), scale and
 * gamma. Filtering (trilinear or EWA, max anisotropy) is the texture's, not the map's.
 * Files are found through renderer/core/scene_path.h — relative to the scene's folder
 * and confined to it, at most max_file_bytes each — then decoded
 * (textures/texture_image.h) and MIP-mapped (textures/mipmap.h).
 *
 * Memory: image data lives outside the scene's arena, in the cache, which owns every map
 * and frees them all in ts_texture_cache_destroy; textures hold const pointers into it,
 * so the cache must outlive them. max_bytes (0 = none) bounds the maps' bytes together,
 * checked before each map is allocated. Not thread-safe while being filled (a scene is
 * built by one thread); afterwards the maps are immutable and read by every thread. */
#ifndef TS_TEXTURE_CACHE_H
#define TS_TEXTURE_CACHE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "core/error.h"
#include "textures/mipmap.h"

typedef struct ts_texture_cache ts_texture_cache;

/* An empty cache whose maps may take max_bytes in all (0 = unlimited); NULL when out of
 * memory. */
ts_texture_cache *ts_texture_cache_create(size_t max_bytes);
/* Frees every map and the cache; NULL is a no-op. */
void ts_texture_cache_destroy(ts_texture_cache *c);

typedef struct ts_texture_image_options {
    int n_channels; /* 3: RGB; 1: float (luminance) */
    bool gamma;     /* decode sRGB (ts_texture_image_default_gamma gives pbrt-v3's default) */
    float scale;    /* finite */
    ts_texture_wrap wrap;
} ts_texture_image_options;

/* The map of filename (relative to base_dir, confined there; base_dir NULL refuses every
 * file) with these options: the cached one, or a new one read, decoded and built now.
 * Errors are the sentences of scene_path.h ("texture image 'x.png': cannot open (no such
 * file or directory)"), of the decoders and of ts_mipmap_create, each naming the file as
 * written; TS_ERR_LIMIT when the cache's budget would be exceeded. *out NULL on failure
 * and the cache unchanged. */
ts_status ts_texture_cache_get(ts_texture_cache *c, const char *base_dir, const char *filename,
                               uint64_t max_file_bytes, const ts_texture_image_options *opt,
                               const ts_mipmap **out, ts_error *err);

/* Where map (one of c's) came from: the file name as the first texture naming it wrote
 * it (valid while c lives) and the options it was built with; false when c holds no such
 * map. For writing a scene's textures back out (json/scene_json_texture_write.h). */
bool ts_texture_cache_source(const ts_texture_cache *c, const ts_mipmap *map, const char **filename,
                             ts_texture_image_options *opt);

/* Bytes held by the cache's maps, and how many maps it holds. */
size_t ts_texture_cache_bytes(const ts_texture_cache *c);
size_t ts_texture_cache_count(const ts_texture_cache *c);

#endif
