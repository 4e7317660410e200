/* texture_desc.h — one description per texture type: its parameters, their kinds and
 * defaults, its scene format v1 and pbrt-v3 names (docs/style.md, "A new type").
 *
 * Design note: the JSON front end (json/scene_json_texture.c), the pbrt-v3 importer's
 * Texture directives (pbrt3/texture_pbrt.c) and `tessera convert`'s texture writer
 * (json/scene_json_texture_write.c) walk this table for a type's keys, kinds, defaults and
 * order; ts_texture_make (texture.c) checks what they make. A row names a field of
 * ts_texture's union by its offset. What a row cannot say is the type's flag: its 2D or
 * 3D mapping, RGB only, a constant (the texture is its value), a checkerboard's
 * dimension and anti-aliasing mode, an image map's file and options. pbrt-v3's dots
 * texture reads its "inside" parameter into the outside texture and "outside" into the
 * inside one (pbrt-v3's textures/dots.cpp), which the rows say by their pbrt-v3 names.
 * The table is immutable and thread-safe. */
#ifndef TS_TEXTURE_DESC_H
#define TS_TEXTURE_DESC_H

#include <stdint.h>

#include "textures/texture.h"

typedef enum ts_tparam_kind {
    TS_TPARAM_CHILD,   /* const ts_texture *: a texture of the texture's kind, or a constant of it */
    TS_TPARAM_AMOUNT,  /* const ts_texture *: a float texture, or a number */
    TS_TPARAM_VALUE,   /* ts_rgb: a constant of the texture's kind (a float one's as a grey) */
    TS_TPARAM_NUMBER,  /* float: a finite number */
    TS_TPARAM_OCTAVES, /* int octaves in [0, TS_NOISE_MAX_OCTAVES], then its float ω: "roughness" */
} ts_tparam_kind;

typedef struct ts_texture_param {
    const char *key;   /* scene format v1's key */
    ts_tparam_kind kind;
    uint16_t offset;   /* of the field in ts_texture */
    float def;         /* v1's default (octaves: its count; ω's default is 0.5 in both formats) */
    const char *pbrt3; /* pbrt-v3's parameter name */
    float pbrt3_def;
} ts_texture_param;

enum {
    TS_TDESC_MAP2D = 1u << 0,     /* a 2D mapping: v1 "mapping", pbrt-v3 "mapping" and its parameters */
    TS_TDESC_MAP3D = 1u << 1,     /* a 3D mapping: world → texture */
    TS_TDESC_MAP_FIRST = 1u << 2, /* the writer puts the mapping before the rows */
    TS_TDESC_RGB_ONLY = 1u << 3,  /* an RGB texture only, as in pbrt-v3 */
    TS_TDESC_CONSTANT = 1u << 4,  /* the texture is its one VALUE row (ts_texture_constant_*) */
    TS_TDESC_IMAGE = 1u << 5,     /* an image map: file, wrap, filtering, scale, gamma, invert */
    TS_TDESC_AAMODE = 1u << 6,    /* the 2D checkerboard's "aamode": closedform or none */
};

typedef struct ts_texture_desc {
    ts_texture_type type;
    const char *name;  /* scene format v1's "type" */
    const char *pbrt3; /* pbrt-v3's texture class */
    uint8_t flags;     /* TS_TDESC_* */
    uint8_t dimension; /* a checkerboard's "dimension" (2 or 3), else 0 */
    uint16_t map_offset; /* of the mapping in ts_texture (MAP2D, MAP3D) */
    uint8_t n_params;
    const ts_texture_param *params;
} ts_texture_desc;

#define TS_TEXTURE_TYPE_COUNT (TS_TEXTURE_IMAGEMAP + 1)
/* Every type, in ts_texture_type's order (index = type); the two checkerboards share a name. */
extern const ts_texture_desc ts_texture_descs[TS_TEXTURE_TYPE_COUNT];

/* The type of v1 name / pbrt-v3 class `name` (a checkerboard: of `dimension`, 2 or 3;
 * ignored for the others), or NULL. */
const ts_texture_desc *ts_texture_desc_by_name(const char *name, int dimension);
const ts_texture_desc *ts_texture_desc_by_pbrt3(const char *name, int dimension);

static inline const ts_texture **ts_tparam_texture(ts_texture *t, const ts_texture_param *p)
{
    return (const ts_texture **)(void *)((char *)t + p->offset);
}
static inline ts_rgb *ts_tparam_rgb(ts_texture *t, const ts_texture_param *p)
{
    return (ts_rgb *)(void *)((char *)t + p->offset);
}
static inline float *ts_tparam_float(ts_texture *t, const ts_texture_param *p)
{
    return (float *)(void *)((char *)t + p->offset);
}
static inline int *ts_tparam_octaves(ts_texture *t, const ts_texture_param *p)
{
    return (int *)(void *)((char *)t + p->offset);
}
/* The ω that follows an OCTAVES row's count. */
static inline float *ts_tparam_omega(ts_texture *t, const ts_texture_param *p)
{
    return (float *)(void *)((char *)t + p->offset + sizeof(int));
}
static inline ts_texture_mapping2d *ts_tdesc_map2d(ts_texture *t, const ts_texture_desc *d)
{
    return (ts_texture_mapping2d *)(void *)((char *)t + d->map_offset);
}
static inline ts_texture_mapping3d *ts_tdesc_map3d(ts_texture *t, const ts_texture_desc *d)
{
    return (ts_texture_mapping3d *)(void *)((char *)t + d->map_offset);
}

#endif
