/* scene_json_texture_write.h — textures written as scene format v1's "textures" section
 * (the inverse of scene_json_texture.h), for `tessera convert`.
 *
 * Design note: a texture is written from what the builder holds (textures/texture.h),
 * not from the text it was read from, so whatever front end made it, the document
 * loads into the same texture, field for field: numbers are written as the doubles of
 * their floats (cJSON prints them round-trip), matrices as their 16 doubles, and the
 * mapping's world → texture matrix as "world_to_texture" itself rather than as a
 * "transform" to be inverted (an inverse of an inverse is not the matrix bit for bit, and
 * pbrt-v3's solid textures take the CTM itself as world → texture). An image map is
 * written as the file name and options its MIP map was built from (the texture cache
 * keeps them: textures/texture_cache.h). Children that are named (written before) are
 * referred to by name; constant children are written in place; any other child is
 * written first under "<parent>.<key>".
 *
 * What v1 cannot hold is refused with one sentence naming the texture: a negative
 * colour constant (v1's colours are ≥ 0). One thread; the writer's table is freed by
 * ts_json_texture_writer_fini. */
#ifndef TS_SCENE_JSON_TEXTURE_WRITE_H
#define TS_SCENE_JSON_TEXTURE_WRITE_H

#include <stdint.h>

#include <cjson/cJSON.h>

#include "core/error.h"
#include "textures/texture.h"
#include "textures/texture_cache.h"

typedef struct ts_json_texture_writer {
    cJSON *textures;               /* the document's "textures" object (not owned) */
    const ts_texture_cache *cache; /* the scene's, where image maps came from */
    const ts_texture **written;    /* [i] was written under names[i] */
    char **names;
    uint32_t n, cap;
} ts_json_texture_writer;

void ts_json_texture_writer_init(ts_json_texture_writer *w, cJSON *textures, const ts_texture_cache *cache);
void ts_json_texture_writer_fini(ts_json_texture_writer *w);

/* The name t was written under, or NULL. */
const char *ts_json_texture_writer_name(const ts_json_texture_writer *w, const ts_texture *t);

/* Writes t as w->textures[name] (name + "#k" when the document has name already), its
 * unnamed non-constant children first. Writing a texture already written is a no-op. TS_ERR_UNSUPPORTED for what v1
 * cannot hold, TS_ERR_INTERNAL for an image map the cache does not know, TS_ERR_NOMEM. */
ts_status ts_json_texture_write(ts_json_texture_writer *w, const ts_texture *t, const char *name, ts_error *err);

/* A material parameter's JSON value: the name of its texture (written first if it is
 * not yet, under hint) — a string cJSON item — or NULL with err set. */
cJSON *ts_json_texture_ref(ts_json_texture_writer *w, const ts_texture *t, const char *hint, ts_error *err);

#endif
