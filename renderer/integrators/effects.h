/* effects.h — which light-transport effects a scene calls for.
 *
 * Design note: after loading, the scene and its job request are analysed into a set of
 * effects (the way Cycles derives KERNEL_FEATURE_* flags from a scene), and the
 * integrators test these flags to skip what cannot contribute: emission lookups where
 * nothing emits, environment lookups without an environment, light sampling without
 * lights, specular-chain and refraction bookkeeping without specular lobes, the lens
 * without depth of field, bounces that cannot carry light, and the random numbers of
 * what is skipped: next-event estimation draws no BSDF sample when every light is a
 * delta light, and no lobe is picked where every material has a single lobe. A skipped
 * value's sample dimension is still consumed (the sampler's values depend only on the
 * dimension's number), so later dimensions stay where they were. The specialisation never
 * changes an estimate: every skipped computation would have added exactly zero, and the
 * sample dimensions a path consumes are the same either way (tests/test_effects.c renders
 * with the analysis forced off and on and compares bit for bit). A job may also switch
 * effects off on purpose (`job.effects`), which does change the image. Pure functions. */
#ifndef TS_EFFECTS_H
#define TS_EFFECTS_H

#include <stddef.h>
#include <stdint.h>

#define TS_EFFECT_LIST(X)                                                        \
    X(TS_EFFECT_DELTA_LIGHTS, 0, "delta_lights", "point, spot or distant lights") \
    X(TS_EFFECT_AREA_LIGHTS, 1, "area_lights", "emitting shapes")                 \
    X(TS_EFFECT_ENVIRONMENT, 2, "environment", "an infinite light")               \
    X(TS_EFFECT_DIFFUSE, 3, "diffuse", "diffuse reflection or transmission")                 \
    X(TS_EFFECT_GLOSSY, 4, "glossy", "glossy reflection or transmission")         \
    X(TS_EFFECT_SPECULAR_REFLECTION, 5, "specular_reflection", "mirror-like reflection") \
    X(TS_EFFECT_SPECULAR_TRANSMISSION, 6, "specular_transmission", "refraction through smooth dielectrics") \
    X(TS_EFFECT_FOURIER, 7, "fourier", "measured (Fourier) BSDFs")                \
    X(TS_EFFECT_DEPTH_OF_FIELD, 8, "depth_of_field", "a thin-lens camera")        \
    X(TS_EFFECT_INDIRECT, 9, "indirect", "light after more than one bounce")       \
    X(TS_EFFECT_LOBE_CHOICE, 10, "lobe_choice", "materials of several lobes, one picked per sample") \
    X(TS_EFFECT_MEDIA, 11, "media", "participating media, or shapes that only bound one") \
    X(TS_EFFECT_MOTION, 12, "motion", "motion blur: moving shapes, instances or camera during an open shutter")

enum {
#define TS_EFFECT_ENUM(name, bit, key, text) name = 1u << bit,
    TS_EFFECT_LIST(TS_EFFECT_ENUM)
#undef TS_EFFECT_ENUM
};
#define TS_EFFECT_COUNT 13
#define TS_EFFECTS_ALL ((1u << TS_EFFECT_COUNT) - 1)
/* Lobes that scatter light at all. */
#define TS_EFFECTS_SCATTERING                                                                          \
    (TS_EFFECT_DIFFUSE | TS_EFFECT_GLOSSY | TS_EFFECT_SPECULAR_REFLECTION | TS_EFFECT_SPECULAR_TRANSMISSION | \
     TS_EFFECT_FOURIER)
#define TS_EFFECTS_LIGHTS (TS_EFFECT_DELTA_LIGHTS | TS_EFFECT_AREA_LIGHTS | TS_EFFECT_ENVIRONMENT)

struct ts_scene;

/* The effects the scene (with its integrator settings) calls for, before job switches. */
uint32_t ts_effects_analyse(const struct ts_scene *s);

/* Key of one effect bit ("indirect"), or NULL; and the bit of a key, or 0. */
const char *ts_effect_key(uint32_t bit);
const char *ts_effect_description(uint32_t bit);
uint32_t ts_effect_from_key(const char *key);

/* "diffuse, area_lights, indirect" — the keys of the set bits, comma-separated. */
void ts_effects_format(uint32_t effects, char *buf, size_t n);

#endif
