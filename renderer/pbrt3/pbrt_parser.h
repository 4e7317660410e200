/* pbrt_parser.h — pbrt-v3 scene files read into a resolved intermediate description.
 *
 * Design note: this is the parsing half of the pbrt-v3 front end; the importer maps the
 * ts_pbrt_scene it produces onto tessera's scene builder. The parser runs every directive
 * of pbrt-v3's format through pbrt-v3's graphics state — the current transformation
 * matrix (CTM) and its stacks, the attribute stack (material, area light, reverse
 * orientation, media, and the texture and named-material scopes), named coordinate
 * systems, object definitions — so that each entity of the result is fully resolved:
 * a shape carries its object-to-world matrix, orientation, material (an index), area
 * light (an index) and the object definition it belongs to; a texture parameter carries
 * the texture it named *in the scope where it was written*. What parameters mean is left
 * to the importer (pbrt_params.h), which also reports the unused ones.
 *
 * pbrt-v3's rules, as followed here:
 *  - Matrices are row-major, points column vectors (transform.h). Every transform
 *    directive post-multiplies the CTM (CTM = CTM · T). `Transform`/`ConcatTransform`
 *    take 16 numbers in column-major order (m[i][j] = v[4j + i], pbrt's transpose).
 *    `LookAt` multiplies in the world-to-camera matrix; `Camera` takes the CTM as
 *    world-to-camera (camera_to_world is its inverse) and names it "camera" for
 *    `CoordSysTransform "camera"`. `WorldBegin` resets the CTM and names "world".
 *    Named coordinate systems are global (not scoped), as in pbrt-v3.
 *  - `AttributeBegin/End` save and restore the CTM, the active transform and the
 *    graphics state, whose texture and named-material name spaces are scoped: a name
 *    defined inside a block is gone after its AttributeEnd. `TransformBegin/End` save
 *    only the CTM. `ObjectBegin/End` open an attribute block too. Blocks must nest.
 *  - `Include` and every file a scene names resolve against one folder — pbrt-v3's
 *    search directory, the folder of the top-level file (not of the including file) —
 *    confined there by scene_path.h; includes nest at most max_include_depth deep and a
 *    file may not include itself, directly or not.
 *  - `NamedMaterial` is resolved when a shape uses it; `Material` and
 *    `MakeNamedMaterial` parameters (textures, the "mix" material's two named materials)
 *    when they are written. Shapes with no material get pbrt-v3's default (material -1:
 *    "matte" with its default parameters).
 *  - Options (`Camera`, `Film`, `Sampler`, `PixelFilter`, `Integrator`, `Accelerator`,
 *    `TransformTimes`) come before `WorldBegin`; the scene description
 *    (attributes, shapes, lights, materials, textures, objects, `ReverseOrientation`)
 *    between `WorldBegin` and `WorldEnd`. pbrt-v3 prints an error and ignores a
 *    directive in the wrong block; here it is an error. Transform directives, `Include`
 *    and the media directives are allowed anywhere. Nothing may follow `WorldEnd`.
 *  - Motion blur as pbrt-v3: two CTMs, at TransformTimes' start and end time (default 0,
 *    1; an end before the start is refused); `ActiveTransform StartTime/EndTime/All`
 *    selects which of them the transform directives change (saved by TransformBegin and
 *    AttributeBegin), CoordinateSystem names both, CoordSysTransform sets both. A shape
 *    and an ObjectInstance carry the end CTM where it differs from the start one (NULL
 *    otherwise), the camera both; lights, textures and media take the start CTM, as
 *    pbrt-v3's. Media are recorded (MakeNamedMedium with its CTM,
 *    the MediumInterface names in force at each shape, light and the camera). An area light inside an object definition
 *    is dropped with a warning, as pbrt-v3 does.
 *
 * Errors (TS_ERR_INVALID unless said; TS_ERR_IO for a file that cannot be read,
 * TS_ERR_LIMIT past a limit, TS_ERR_NOMEM) are one sentence "<file>:<line>:<column>:
 * <directive>: <problem>"; on error nothing is returned and nothing is left allocated.
 * Memory: a ts_pbrt_scene and everything it points to live in its arena, freed by
 * ts_pbrt_scene_destroy. A scene is used by one thread at a time (lookups mark params). */
#ifndef TS_PBRT_PARSER_H
#define TS_PBRT_PARSER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "core/arena.h"
#include "core/cancel.h"
#include "core/error.h"
#include "pbrt3/pbrt_lexer.h"
#include "pbrt3/pbrt_params.h"
#include "core/transform.h"

typedef struct ts_pbrt_limits {
    uint64_t max_file_bytes; /* each file: the scene, an Include, a .spd; 0 = no limit */
    size_t max_memory;       /* the scene's arena, and separately the parser's own buffers; 0 = none */
    int max_include_depth;   /* files open at once, the top-level one included */
    size_t max_warnings;     /* warnings kept; later ones are only counted */
    ts_cancel *cancel;       /* polled every few thousand tokens (core/cancel.h); NULL: never */
} ts_pbrt_limits;

/* No size limits, includes 32 deep, 1000 warnings kept. */
void ts_pbrt_limits_default(ts_pbrt_limits *lim);

/* A directive of the options block: pbrt-v3's type name and its parameters. For one the
 * scene did not give, type is pbrt-v3's default ("perspective", "image", "halton",
 * "box", "path", "bvh"), params is empty and loc.file is NULL. */
typedef struct ts_pbrt_option {
    const char *type;
    ts_pbrt_params params;
    ts_pbrt_loc loc;
} ts_pbrt_option;

typedef struct ts_pbrt_texture {
    const char *name;
    bool is_float;          /* "float"; false for "color" / "spectrum" */
    const char *class_name; /* "imagemap", "checkerboard", "scale", … */
    ts_pbrt_params params;  /* its own texture parameters resolved where it was defined */
    const ts_mat4 *texture_to_world; /* the CTM at Texture */
    ts_pbrt_loc loc;
} ts_pbrt_texture;

typedef struct ts_pbrt_material {
    const char *name; /* MakeNamedMaterial's name; NULL for Material */
    const char *type; /* "matte", "plastic", …; "" or "none": no surface (pbrt-v3) */
    ts_pbrt_params params; /* for a named material, "string type" is among them (used) */
    int32_t mix[2];        /* type "mix": namedmaterial1 / namedmaterial2 as material indices; else -1 */
    ts_pbrt_loc loc;
} ts_pbrt_material;

typedef struct ts_pbrt_area_light {
    const char *type; /* "diffuse" / "area" */
    ts_pbrt_params params;
    ts_pbrt_loc loc;
} ts_pbrt_area_light;

typedef struct ts_pbrt_light {
    const char *type; /* "point", "spot", "distant", "infinite", … */
    ts_pbrt_params params;
    const ts_mat4 *light_to_world;
    const char *inside_medium, *outside_medium; /* MediumInterface names in force ("" none) */
    ts_pbrt_loc loc;
} ts_pbrt_light;

typedef struct ts_pbrt_shape {
    const char *type; /* "sphere", "trianglemesh", "plymesh", … */
    ts_pbrt_params params;
    /* The CTM at Shape: object to world, or, for a shape of an object definition, object
     * to the instance's space (an instance places it with its instance_to_world). */
    const ts_mat4 *object_to_world;
    const ts_mat4 *object_to_world_end; /* the CTM at the end time where it differs (animated), else NULL */
    bool reverse_orientation; /* ReverseOrientation in force (pbrt-v3 also flips normals when
                                 object_to_world swaps handedness; the importer applies both) */
    int32_t material;   /* index into materials; -1: pbrt-v3's default "matte" */
    int32_t area_light; /* index into area_lights, or -1 */
    int32_t object;     /* index into objects when defined inside ObjectBegin/End, else -1 */
    const char *inside_medium, *outside_medium;
    ts_pbrt_loc loc;
} ts_pbrt_shape;

typedef struct ts_pbrt_object {
    const char *name;
    size_t first_shape, shape_count;       /* its shapes: shapes[first_shape …] */
    const ts_mat4 *const *instance_to_world; /* one per ObjectInstance, in file order */
    size_t instance_count;
    ts_pbrt_loc loc;
} ts_pbrt_object;

typedef struct ts_pbrt_instance {
    int32_t object; /* index into objects */
    const ts_mat4 *instance_to_world;
    const ts_mat4 *instance_to_world_end; /* the end-time CTM where it differs, else NULL */
    ts_pbrt_loc loc;
} ts_pbrt_instance;

typedef struct ts_pbrt_medium {
    const char *name, *type; /* MakeNamedMedium's name and "string type" */
    ts_pbrt_params params;
    const ts_mat4 *medium_to_world;
    ts_pbrt_loc loc;
} ts_pbrt_medium;

typedef struct ts_pbrt_warning {
    ts_pbrt_loc loc;
    const char *message; /* "ActiveTransform EndTime: …" (no position in it) */
} ts_pbrt_warning;

typedef struct ts_pbrt_scene {
    ts_arena arena; /* owns everything below */
    /* Folder every file the scene names resolves against (pbrt-v3's search directory):
     * the top-level file's folder, or the caller's base_dir. */
    const char *base_dir;
    ts_pbrt_option camera, film, sampler, filter, integrator, accelerator;
    ts_mat4 world_to_camera; /* the CTM at Camera (identity if there was none) */
    ts_mat4 camera_to_world; /* its inverse */
    ts_mat4 world_to_camera_end, camera_to_world_end; /* the same at the end time */
    bool camera_animated;    /* the two differ */
    const char *camera_medium; /* outside medium at Camera ("" none) */
    double transform_start_time, transform_end_time; /* TransformTimes (0, 1); end ≥ start */
    ts_pbrt_loc transform_times_loc; /* where TransformTimes was given (file NULL: not) */

    ts_pbrt_texture *textures;
    size_t texture_count;
    ts_pbrt_material *materials;
    size_t material_count;
    ts_pbrt_area_light *area_lights;
    size_t area_light_count;
    ts_pbrt_light *lights;
    size_t light_count;
    ts_pbrt_shape *shapes; /* in file order; those of an object definition are contiguous */
    size_t shape_count;
    ts_pbrt_object *objects;
    size_t object_count;
    ts_pbrt_instance *instances; /* every ObjectInstance in file order (also per object above) */
    size_t instance_count;
    ts_pbrt_medium *media;
    size_t medium_count;
    ts_pbrt_warning *warnings;
    size_t warning_count;
    size_t warnings_dropped; /* beyond max_warnings */
    uint64_t bytes_parsed;   /* of every file read, for reports */
    /* The scene digest (docs/design.md §4c): SHA-256 over a domain string and then, for
     * every scene file read — the top-level text, each Include, each .spd — in the order
     * they were finished, its name as written (NUL-terminated), its size (8 bytes, little
     * endian) and its own SHA-256. */
    uint8_t digest[32];
} ts_pbrt_scene;

/* Parses the pbrt-v3 file at path (named by the user: not confined itself, and it may be
 * a symbolic link) and what it includes; files it names are confined to base_dir, or, if
 * base_dir is NULL, to the folder of the file's real path (as pbrt-v3 takes it). Positions name the top-level file as path is written. lim NULL:
 * ts_pbrt_limits_default. On success *out owns the scene. */
ts_status ts_pbrt_parse_file(const char *path, const char *base_dir, const ts_pbrt_limits *lim,
                             ts_pbrt_scene **out, ts_error *err);

/* The same for a scene held in memory (text[0, len), not copied), called name in
 * positions; base_dir NULL refuses every file reference (Include, .spd), as for a scene
 * posted to a server without an asset folder. */
ts_status ts_pbrt_parse_text(const char *text, size_t len, const char *name, const char *base_dir,
                             const ts_pbrt_limits *lim, ts_pbrt_scene **out, ts_error *err);

void ts_pbrt_scene_destroy(ts_pbrt_scene *scene);

#endif
