/* scene_json_texture.h — scene format v1's "textures" section and texture-valued material
 * parameters (docs/design.md §4, §4d).
 *
 * Design note: "textures" is an object, name → texture, read in document order; a texture
 * may use (tex1, amount, …) only textures defined before it, so there are no cycles and
 * the nesting bound of textures/texture.h is met by construction where it can be. Each is
 * checked completely, then made in the scene's arena through the builder (image maps
 * through the scene's texture cache), so nothing is half-made: a failure leaves only
 * memory the builder frees. A material parameter that may be textured takes, besides its
 * constant, a string: the name of a texture in "textures" ("reflectance": "checks").
 * Every complaint is one sentence starting with the JSON path
 * ("textures.wood.file: texture image 'wood.png': cannot open …").
 *
 * The table of names is the loader's, freed with ts_json_textures_fini. One thread. */
#ifndef TS_SCENE_JSON_TEXTURE_H
#define TS_SCENE_JSON_TEXTURE_H

#include <stdint.h>

#include <cjson/cJSON.h>

#include "core/error.h"
#include "core/name_map.h"
#include "core/transform.h"
#include "materials/material.h"
#include "json/json_check.h"
#include "build/scene_builder.h"
#include "textures/texture.h"

typedef struct ts_json_textures {
    const char **names; /* into the document */
    const ts_texture **textures;
    uint32_t n, cap;
    ts_name_map index;  /* names → their indices (lookups in constant time) */
} ts_json_textures;

void ts_json_textures_init(ts_json_textures *t);
void ts_json_textures_fini(ts_json_textures *t);

/* The texture named name, or NULL. */
const ts_texture *ts_json_textures_find(const ts_json_textures *t, const char *name);

/* Reads the texture object tex at path (its name `name`, not yet in t) and adds it to t.
 * to_world is its "transform" (texture space → world; the caller reads it), whose inverse
 * the spherical and cylindrical mappings and solid textures look the world point up
 * through — unless the texture gives that matrix itself as "world_to_texture" (16
 * numbers; not with "transform"), as tessera convert writes it
 * (json/scene_json_texture_write.h). */
ts_status ts_json_texture_parse(ts_json_textures *t, ts_scene_builder *b, const cJSON *tex, const char *path,
                                const char *name, const ts_xform *to_world, ts_error *err);

/* A colour parameter obj[key]: an RGB in range (ts_json_rgb) or the name of a texture of
 * either kind. Absent: *out untouched. */
ts_status ts_json_material_rgb(const ts_json_textures *t, const cJSON *obj, const char *path, const char *key,
                               ts_jrange range, ts_material_rgb *out, ts_error *err);
/* A float parameter obj[key]: a number in range (ts_json_number) or the name of a float
 * texture. Absent: *out untouched. */
ts_status ts_json_material_float(const ts_json_textures *t, const cJSON *obj, const char *path,
                                 const char *key, ts_jrange range, ts_material_float *out, ts_error *err);

#endif
