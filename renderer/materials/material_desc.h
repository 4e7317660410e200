/* material_desc.h — one description per material type: its parameters, their kinds,
 * ranges and defaults, its scene format v1 and pbrt-v3 names (docs/style.md, "A new type").
 *
 * Design note: every reader of a material goes through this table rather than a switch of
 * its own — the JSON front end (json/scene_json.c: the type names, the keys it accepts,
 * each parameter's kind, range and default), the pbrt-v3 importer (pbrt3/pbrt_import.c:
 * the pbrt-v3 material each type stands for, each parameter's pbrt-v3 name and default),
 * the JSON writer of `tessera convert` (the same keys, in the table's order), the builder's
 * checks (build/scene_builder.c: each parameter's range, stated once here), the texture
 * bookkeeping (material.c: which fields may hold a texture) and the effects analysis
 * (integrators/effects.c: the stand-in a textured parameter takes). The JSON front end
 * checks a constant against the same range before the builder does, only to name the
 * exact JSON path (an element of an RGB array) in its error; both read the range here.
 *
 * What the table cannot say as a row — a file (fourier), the names of other materials
 * (mix), the roughness family with its pbrt-v3 defaulting rules — is a flag of the type
 * the front ends act on, so each such rule is written once per front end, not per type.
 * The table is immutable and shared by all threads. */
#ifndef TS_MATERIAL_DESC_H
#define TS_MATERIAL_DESC_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "materials/material.h"

/* A parameter's kind: a ts_material_rgb, a ts_material_float, or an enum field (int)
 * named by `names`. */
typedef enum ts_mparam_kind {
    TS_MPARAM_RGB,
    TS_MPARAM_FLOAT,
    TS_MPARAM_ENUM,
} ts_mparam_kind;

/* The range a constant must lie in (a texture's values are clamped into it, material.h). */
typedef enum ts_mparam_range {
    TS_MRANGE_UNIT,     /* [0, 1] (per channel) */
    TS_MRANGE_NONNEG,   /* finite, ≥ 0 (per channel) */
    TS_MRANGE_POSITIVE, /* finite, > 0 */
    TS_MRANGE_ANGLE,    /* an angle in [0, 90] degrees */
} ts_mparam_range;

enum {
    TS_MPARAM_REQUIRED = 1u << 0,   /* scene format v1 requires the key */
    TS_MPARAM_OMIT_ZERO = 1u << 1,  /* the writer leaves a constant 0 out (v1's default) */
    TS_MPARAM_PBRT3_INDEX = 1u << 2, /* pbrt-v3 reads "float index" first; "eta" overrides it */
    TS_MPARAM_PBRT3_FLOAT_GREY = 1u << 3, /* pbrt-v3 reads a spectrum; a float is taken as its grey */
};

typedef struct ts_material_param {
    const char *key;   /* scene format v1's key; the builder's and the writer's name for it */
    ts_mparam_kind kind;
    ts_mparam_range range;
    uint16_t offset;   /* of the field in ts_material */
    uint8_t flags;     /* TS_MPARAM_* */
    float def;         /* v1's default (a grey for colours, an enum's index) */
    const char *pbrt3; /* pbrt-v3's parameter name; NULL: pbrt-v3 has none and gives `def` */
    float pbrt3_def;   /* pbrt-v3's default, unless pbrt3_def_rgb */
    void (*pbrt3_def_rgb)(ts_rgb *out); /* a colour default that is not a grey (metal's copper) */
    float standin;     /* the effects analysis's constant for a textured value (material_desc.c) */
    const char *const *names; /* TS_MPARAM_ENUM: v1's names, in the enum's order, NULL-ended */
} ts_material_param;

/* Type flags: the families a row cannot state. */
enum {
    TS_MDESC_ROUGH = 1u << 0,       /* "roughness" (α, or remapped) and "remap_roughness" */
    TS_MDESC_ANISO = 1u << 1,       /* "uroughness" / "vroughness": anisotropic */
    TS_MDESC_PBRT3_ROUGH = 1u << 2, /* pbrt-v3 reads "roughness" (its glass and substrate do not) */
    TS_MDESC_PBRT3_V_FOLLOWS_U = 1u << 3, /* pbrt-v3: a missing vroughness is uroughness (uber) */
    TS_MDESC_FILE = 1u << 4,        /* a table file: v1 "file", pbrt-v3 "bsdffile" (fourier) */
    TS_MDESC_MIX = 1u << 5,         /* two other materials: v1 "materials", pbrt-v3 namedmaterial1/2 */
};

typedef struct ts_material_desc {
    ts_material_type type;
    const char *name;  /* scene format v1's "type" */
    const char *pbrt3; /* the pbrt-v3 material read as this type; NULL: none */
    uint8_t flags;     /* TS_MDESC_* */
    float rough_def;   /* the roughness default, v1's and pbrt-v3's (TS_MDESC_ROUGH) */
    uint8_t max_lobes; /* the most lobes its BSDF has whatever the values (a mix: its two's sum) */
    uint8_t n_params;
    const ts_material_param *params;
} ts_material_desc;

/* Every type, in ts_material_type's order (index = type). */
#define TS_MATERIAL_TYPE_COUNT (TS_MATERIAL_MIX + 1)
extern const ts_material_desc ts_material_descs[TS_MATERIAL_TYPE_COUNT];

/* The description of type t; NULL when t is no type. */
const ts_material_desc *ts_material_desc_of(ts_material_type t);

/* The type whose v1 name / pbrt-v3 name is `name`; NULL when none. */
const ts_material_desc *ts_material_desc_by_name(const char *name);
const ts_material_desc *ts_material_desc_by_pbrt3(const char *name);

/* The field of row p in m. */
static inline ts_material_rgb *ts_mparam_rgb(ts_material *m, const ts_material_param *p)
{
    return (ts_material_rgb *)(void *)((char *)m + p->offset);
}
static inline const ts_material_rgb *ts_mparam_crgb(const ts_material *m, const ts_material_param *p)
{
    return (const ts_material_rgb *)(const void *)((const char *)m + p->offset);
}
static inline ts_material_float *ts_mparam_float(ts_material *m, const ts_material_param *p)
{
    return (ts_material_float *)(void *)((char *)m + p->offset);
}
static inline const ts_material_float *ts_mparam_cfloat(const ts_material *m, const ts_material_param *p)
{
    return (const ts_material_float *)(const void *)((const char *)m + p->offset);
}
static inline int *ts_mparam_enum(ts_material *m, const ts_material_param *p)
{
    return (int *)(void *)((char *)m + p->offset);
}

/* Sets every parameter of m's type (m->type set) to v1's defaults, roughness included
 * (vroughness equal to it); the other fields are left as they are. */
void ts_material_desc_defaults(ts_material *m);

/* The textures one shading of m evaluates at most, its own parameters and bump map only
 * (every parameter of m's type's description with a texture counted; the bump map three
 * times: at the point and its two offsets). A mix's materials are the builder's to add. */
uint64_t ts_material_texture_cost(const ts_material *m);

/* Whether any parameter of m has a texture (a parameter of m's type's description), or m has a
 * bump map. */
bool ts_material_uses_textures(const ts_material *m);

/* The most lobes m's BSDF can have whatever its parameters' values (a mix: the sum of
 * its two materials'; needs mix[] set). pbrt-v3's BSDF holds 8 and aborts beyond; the
 * builder refuses a mix above TS_BSDF_MAX_BXDFS (materials/bsdf.h) instead. */
int ts_material_max_lobes(const ts_material *m);

/* Whether constant v lies in range r (NaN never does). */
bool ts_mrange_ok(ts_mparam_range r, float v);

/* The words for range r in an error: "RGB in [0, 1]" (colour) or "a number in [0, 1]". */
const char *ts_mrange_words(ts_mparam_range r, bool rgb);

#endif
