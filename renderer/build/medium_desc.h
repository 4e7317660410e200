/* medium_desc.h — one description per medium type: its parameters, their kinds and
 * defaults, its scene format v1 and pbrt-v3 names (docs/style.md, "A new type").
 *
 * Design note: the JSON front end (json/scene_json.c "media"), the pbrt-v3 importer
 * (MakeNamedMedium, pbrt3/pbrt_import.c) and `tessera convert`'s writer walk this table
 * for a type's keys, kinds and defaults, in its order; every range is the builder's
 * (ts_scene_builder_add_medium checks each field of ts_medium_desc: the front ends pass
 * the values as given). A grid's transform is the type's flag. The table is immutable
 * and thread-safe. */
#ifndef TS_MEDIUM_DESC_H
#define TS_MEDIUM_DESC_H

#include <stdint.h>

#include "build/scene_builder.h"

typedef enum ts_vparam_kind {
    TS_VPARAM_RGB,     /* ts_rgb, with a bool at has_offset saying whether it was given */
    TS_VPARAM_NUMBER,  /* double */
    TS_VPARAM_STRING,  /* const char * (pbrt-v3's "" is none) */
    TS_VPARAM_COUNT,   /* uint32_t, ≥ 1 (v1: required, at most 2^20) */
    TS_VPARAM_POINT,   /* ts_dvec3 */
    TS_VPARAM_DENSITY, /* const float * with its count in n_density (required in both formats) */
} ts_vparam_kind;

typedef struct ts_medium_param {
    const char *key; /* scene format v1's key, and pbrt-v3's name: the two formats share them */
    ts_vparam_kind kind;
    uint16_t offset;     /* of the field in ts_medium_desc */
    uint16_t has_offset; /* RGB: of its bool has_* */
    double def[3];       /* the default: a number, a grey, or a point */
} ts_medium_param;

enum { TS_VDESC_TRANSFORM = 1u << 0 /* the medium's space: v1 "transform", pbrt-v3 the CTM */ };

typedef struct ts_medium_type_desc {
    ts_medium_type type;
    const char *name;  /* scene format v1's "type" */
    const char *pbrt3; /* pbrt-v3's "string type" of MakeNamedMedium */
    uint8_t flags;
    uint8_t n_params;
    const ts_medium_param *params;
} ts_medium_type_desc;

#define TS_MEDIUM_DESC_COUNT 2
extern const ts_medium_type_desc ts_medium_descs[TS_MEDIUM_DESC_COUNT];

const ts_medium_type_desc *ts_medium_desc_by_name(const char *name);
const ts_medium_type_desc *ts_medium_desc_by_pbrt3(const char *name);

static inline void *ts_vparam_field(ts_medium_desc *d, const ts_medium_param *p) { return (char *)d + p->offset; }
static inline bool *ts_vparam_has(ts_medium_desc *d, const ts_medium_param *p)
{
    return (bool *)(void *)((char *)d + p->has_offset);
}

#endif
