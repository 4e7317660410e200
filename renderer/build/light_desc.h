/* light_desc.h — one description per light type: its parameters, their kinds, ranges and
 * defaults, its scene format v1 and pbrt-v3 names (docs/style.md, "A new type").
 *
 * Design note: the lights a scene declares (area lights come from shapes) are read by the
 * JSON front end (json/scene_json.c), the pbrt-v3 importer (pbrt3/pbrt_import.c) and
 * written by `tessera convert`'s writer; all three walk this table, row by row, for a
 * type's keys, kinds, defaults and ranges, and the builder (build/scene_builder.c) checks
 * the same ranges (its construction of the runtime light stays a switch: that is the
 * light's own code, as ts_material_bsdf is a material's). What a row cannot say — the
 * infinite light's radiance-or-map choice, its transform and sample count — is the
 * type's flag, read by each front end once. The table is immutable and thread-safe. */
#ifndef TS_LIGHT_DESC_H
#define TS_LIGHT_DESC_H

#include <stdbool.h>
#include <stdint.h>

#include "core/transform.h"
#include "core/vecmath.h"
#include "lights/light.h"

struct ts_envmap; /* lights/envmap.h */

/* A light as the front ends give it to the builder (ts_scene_builder_add_light). */
typedef struct ts_light_desc {
    ts_light_type type;          /* point, spot, distant or infinite (area lights come from shapes) */
    ts_rgb color;                /* point/spot intensity, distant irradiance, infinite radiance (or
                                    the map's scale); each channel ≥ 0 */
    ts_vec3 from, to;            /* point: from is the position; spot: from is the apex, aimed at
                                    to; distant: the light travels from → to (from ≠ to) */
    double cone_angle_deg;       /* spot: in (0, 180] */
    double cone_delta_deg;       /* spot: in [0, cone_angle_deg] */
    const struct ts_envmap *map; /* infinite: from ts_scene_builder_load_envmap, or NULL */
    ts_xform to_world;           /* infinite: map space → world */
    uint32_t samples;            /* its samples per camera sample under direct's strategy all
                                    (pbrt-v3's nsamples), in [1, 4096]; 0: the integrator's
                                    samples_per_light */
} ts_light_desc;


typedef enum ts_lparam_kind {
    TS_LPARAM_POINT, /* a ts_vec3 position (pbrt-v3: transformed by the light's CTM) */
    TS_LPARAM_RGB,   /* a ts_rgb, each channel finite ≥ 0 (pbrt-v3: times its "scale") */
    TS_LPARAM_ANGLE, /* a double in degrees: (0, 180], or [0, cone_angle] with TS_LPARAM_UPTO_ANGLE */
} ts_lparam_kind;

enum {
    TS_LPARAM_REQUIRED = 1u << 0,   /* scene format v1 requires the key (pbrt-v3 never does) */
    TS_LPARAM_NOT_FROM = 1u << 1,   /* a point that must differ from "from" */
    TS_LPARAM_UPTO_ANGLE = 1u << 2, /* an angle in [0, cone_angle] */
};

typedef struct ts_light_param {
    const char *key;   /* scene format v1's key; the builder's name for it */
    ts_lparam_kind kind;
    uint16_t offset;   /* of the field in ts_light_desc */
    uint8_t flags;     /* TS_LPARAM_* */
    double def[3];     /* v1's default: a point, or def[0] a grey or an angle */
    const char *pbrt3; /* pbrt-v3's parameter name */
    double pbrt3_def[3];
} ts_light_param;

enum {
    TS_LDESC_ENVIRONMENT = 1u << 0, /* v1 radiance | map (+ scale), transform, samples; pbrt-v3 L, mapname, nsamples */
};

typedef struct ts_light_type_desc {
    ts_light_type type;
    const char *name;  /* scene format v1's "type" */
    const char *pbrt3; /* pbrt-v3's LightSource name */
    uint8_t flags;     /* TS_LDESC_* */
    uint8_t n_params;
    const ts_light_param *params;
} ts_light_type_desc;

#define TS_LIGHT_DESC_COUNT 4
extern const ts_light_type_desc ts_light_descs[TS_LIGHT_DESC_COUNT];

/* The type of v1 name / pbrt-v3 name `name`, or NULL. */
const ts_light_type_desc *ts_light_desc_by_name(const char *name);
const ts_light_type_desc *ts_light_desc_by_pbrt3(const char *name);

static inline ts_vec3 *ts_lparam_point(ts_light_desc *d, const ts_light_param *p)
{
    return (ts_vec3 *)(void *)((char *)d + p->offset);
}
static inline ts_rgb *ts_lparam_rgb(ts_light_desc *d, const ts_light_param *p)
{
    return (ts_rgb *)(void *)((char *)d + p->offset);
}
static inline double *ts_lparam_angle(ts_light_desc *d, const ts_light_param *p)
{
    return (double *)(void *)((char *)d + p->offset);
}

/* Whether angle v is in row p's range, given the light's cone angle (TS_LPARAM_UPTO_ANGLE). */
static inline bool ts_lparam_angle_ok(const ts_light_param *p, double v, double cone_angle)
{
    return (p->flags & TS_LPARAM_UPTO_ANGLE) ? v >= 0 && v <= cone_angle : v > 0 && v <= 180;
}

#endif
