/* texture_pbrt.h — pbrt-v3's Texture directives made into textures.
 *
 * Design note: ts_texture_pbrt_build makes every texture of a parsed pbrt-v3 scene
 * (pbrt3/pbrt_parser.h) in definition order, with pbrt-v3's parameter names, defaults
 * and meanings (pbrt-v3's src/textures/):
 *   constant      "value" 1
 *   scale         "tex1" 1, "tex2" 1
 *   mix           "tex1" 0, "tex2" 1, "amount" 0.5 (a float texture)
 *   bilerp        "v00" 0, "v01" 1, "v10" 0, "v11" 1, 2D mapping
 *   uv            2D mapping (color only)
 *   checkerboard  "dimension" 2 (or 3), "tex1" 1, "tex2" 0; 2D: mapping and "aamode"
 *                 "closedform" (or "none")
 *   dots          "inside" 1, "outside" 0, 2D mapping; as pbrt-v3 renders them: the dots
 *                 painted with "outside" and the rest with "inside" (its dots.cpp passes
 *                 the two swapped; the importer warns)
 *   fbm, wrinkled "octaves" 8, "roughness" 0.5
 *   windy         —
 *   marble        "octaves" 8, "roughness" 0.5, "scale" 1, "variation" 0.2 (color only)
 *   imagemap      "filename" (required), "wrap" "repeat" | "black" | "clamp",
 *                 "trilinear" false (EWA), "maxanisotropy" 8, "scale" 1, "gamma" (true
 *                 for .png and .tga), "invert" false (pbrt-v4's; pbrt-v3 has none), 2D
 *                 mapping
 *   2D mapping    "mapping" "uv" ("uscale" 1, "vscale" 1, "udelta" 0, "vdelta" 0) |
 *                 "spherical" | "cylindrical" (world→texture = the inverse of the
 *                 texture's CTM) | "planar" ("v1" (1,0,0), "v2" (0,1,0), "udelta" 0,
 *                 "vdelta" 0)
 *   3D mapping    the texture's CTM itself taken as world→texture, as pbrt-v3 does
 *                 (textures/texture_mapping.h)
 * A texture-valued parameter ("tex1", "amount", …) is a "texture" naming a texture of
 * the right kind in the scope where it was written, or a value ("float" for float
 * textures, "rgb"/"color" or "xyz" for colour ones) made a constant, or absent: the
 * default constant.
 *
 * Stricter than pbrt-v3, which prints an error and goes on with a default: an unknown
 * texture class, mapping, wrap or aamode, a float texture asked of "uv" or "marble", a
 * "checkerboard" of a dimension other than 2 or 3, a missing or unreadable image, a
 * singular transform, octaves outside 0 … 32, maxanisotropy outside (0, 64] and "ptex"
 * (not supported) are errors. Every error is one sentence naming where the scene wrote
 * it — "scene.pbrt:4:1: Texture \"wood\": …", with the parameter
 * ("\"string filename\": texture image 'wood.png': cannot open (no such file or
 * directory)") where one is at fault — and the parameters looked up are marked used, so
 * the importer can warn about the rest (ts_pbrt_params_next_unused).
 *
 * Memory: textures in the given arena, image maps in the given cache (which must outlive
 * them). Building is single-threaded; the result is immutable. */
#ifndef TS_TEXTURE_PBRT_H
#define TS_TEXTURE_PBRT_H

#include <stddef.h>
#include <stdint.h>

#include "core/arena.h"
#include "core/error.h"
#include "pbrt3/pbrt_parser.h"
#include "textures/texture.h"
#include "textures/texture_cache.h"

typedef struct ts_texture_pbrt {
    ts_arena *arena;         /* textures are made here (the scene's arena) */
    ts_texture_cache *cache; /* image maps */
    const char *base_dir;    /* image files are confined here (scene_path.h); NULL: none */
    uint64_t max_file_bytes; /* each image file; 0 = no limit */
    ts_pbrt_scene *scene;
    const ts_texture **textures; /* [i]: the texture of scene->textures[i] (arena) */
    size_t count;
} ts_texture_pbrt;

/* Makes every texture of scene into *tp (zeroed first). On failure the arena may hold
 * partial textures (freed with it) and the cache maps already made; *tp is unusable. */
ts_status ts_texture_pbrt_build(ts_texture_pbrt *tp, ts_pbrt_scene *scene, ts_arena *arena,
                                ts_texture_cache *cache, const char *base_dir, uint64_t max_file_bytes,
                                ts_error *err);

/* The float texture of parameter `name` of ps (a material's, say) as pbrt-v3's
 * TextureParams::GetFloatTexture finds it: a "texture" naming a float texture, a "float"
 * value, or the constant def. */
ts_status ts_texture_pbrt_float(const ts_texture_pbrt *tp, ts_pbrt_params *ps, const char *name, float def,
                                const ts_texture **out, ts_error *err);

/* The RGB texture of parameter `name` (GetSpectrumTexture): a "texture" naming a colour
 * texture, an "rgb"/"xyz" value, or the constant def. Spectral values are refused
 * (pbrt_params.h). */
ts_status ts_texture_pbrt_rgb(const ts_texture_pbrt *tp, ts_pbrt_params *ps, const char *name, ts_rgb def,
                              const ts_texture **out, ts_error *err);

#endif
