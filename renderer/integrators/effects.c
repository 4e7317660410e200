/* effects.c — scene analysis into effects; see effects.h. */
#include "integrators/effects.h"

#include <stdio.h>
#include <string.h>

#include "materials/bsdf.h"
#include "materials/material_desc.h"
#include "scene/scene.h"

static const struct { uint32_t bit; const char *key, *text; } table[] = {
#define TS_EFFECT_ROW(name, bit, key, text) {name, key, text},
    TS_EFFECT_LIST(TS_EFFECT_ROW)
#undef TS_EFFECT_ROW
};

const char *ts_effect_key(uint32_t bit)
{
    for (size_t i = 0; i < sizeof table / sizeof *table; i++)
        if (table[i].bit == bit) return table[i].key;
    return NULL;
}

const char *ts_effect_description(uint32_t bit)
{
    for (size_t i = 0; i < sizeof table / sizeof *table; i++)
        if (table[i].bit == bit) return table[i].text;
    return NULL;
}

uint32_t ts_effect_from_key(const char *key)
{
    for (size_t i = 0; i < sizeof table / sizeof *table; i++)
        if (strcmp(table[i].key, key) == 0) return table[i].bit;
    return 0;
}

void ts_effects_format(uint32_t effects, char *buf, size_t n)
{
    size_t used = 0;
    buf[0] = '\0';
    for (size_t i = 0; i < sizeof table / sizeof *table && used < n; i++)
        if (effects & table[i].bit)
            used += (size_t)snprintf(buf + used, n - used, "%s%s", used ? ", " : "", table[i].key);
    if (!used) snprintf(buf, n, "none");
}

static uint32_t material_effects(const ts_material *m);

/* A mix has every lobe of both its materials (an amount of 0 or 1 only removes some):
 * the union of theirs, each classified as a material of its own (textured or not), and a
 * lobe choice when it can have more than one lobe. */
static uint32_t mix_effects(const ts_material *m)
{
    if (!m->mix[0] || !m->mix[1]) return 0;
    uint32_t fx = material_effects(m->mix[0]) | material_effects(m->mix[1]);
    if (fx && ts_material_max_lobes(m) > 1) fx |= TS_EFFECT_LOBE_CHOICE;
    return fx;
}

/* The lobes of m's BSDF at a canonical shading point (m untextured), so the
 * classification follows the BSDF code (e.g. its roughness-to-specular threshold). */
static uint32_t constant_material_effects(const ts_material *m)
{
    switch (m->type) {
    case TS_MATERIAL_DIFFUSE:
    case TS_MATERIAL_MIRROR:
        if (ts_rgb_is_black(m->reflectance.value)) return 0;
        break;
    case TS_MATERIAL_DIELECTRIC:
        if (ts_rgb_is_black(m->reflectance.value) && ts_rgb_is_black(m->transmittance.value)) return 0;
        break;
    case TS_MATERIAL_PLASTIC:
    case TS_MATERIAL_SUBSTRATE:
        if (ts_rgb_is_black(m->diffuse.value) && ts_rgb_is_black(m->specular.value)) return 0;
        break;
    case TS_MATERIAL_CONDUCTOR: break;
    case TS_MATERIAL_FOURIER: return TS_EFFECT_FOURIER;
    /* pbrt-v3's materials: their BSDF says (translucent's diffuse and glossy
     * transmission are diffuse and glossy; uber's pass-through and Kt lobes specular
     * transmission). */
    case TS_MATERIAL_PLASTIC_PBRT3:
    case TS_MATERIAL_UBER:
    case TS_MATERIAL_TRANSLUCENT: break;
    case TS_MATERIAL_MIX: return mix_effects(m);
    }
    ts_interaction si = {0};
    si.n = si.ns = (ts_vec3){0, 0, 1};
    si.dpdu = (ts_vec3){1, 0, 0};
    si.dpdv = (ts_vec3){0, 1, 0};
    si.wo = (ts_vec3){0, 0, 1};
    ts_bsdf b;
    ts_material_bsdf(m, &si, NULL, &b);
    uint32_t flags = ts_bsdf_flags(&b), fx = b.n_bxdfs > 1 ? TS_EFFECT_LOBE_CHOICE : 0;
    if (flags & TS_BXDF_DIFFUSE) fx |= TS_EFFECT_DIFFUSE;
    if (flags & TS_BXDF_GLOSSY) fx |= TS_EFFECT_GLOSSY;
    /* Lobe by lobe: uber's pass-through lobe beside its Lambertian is specular
     * transmission, not specular reflection. */
    for (int i = 0; i < b.n_bxdfs; i++) {
        uint32_t lf = b.bxdfs[i].flags;
        if ((lf & TS_BXDF_SPECULAR) && (lf & TS_BXDF_REFLECTION)) fx |= TS_EFFECT_SPECULAR_REFLECTION;
        if ((lf & TS_BXDF_SPECULAR) && (lf & TS_BXDF_TRANSMISSION)) fx |= TS_EFFECT_SPECULAR_TRANSMISSION;
    }
    return fx;
}

/* A textured parameter may take any value of its range at some point, so a textured
 * material is classified as the union over stand-in constants that between them raise
 * every lobe the range allows: each row's stand-in (materials/material_desc.c: colours
 * white — a black texel only removes lobes —, uber's opacity ½, σ 0, η 1.5), and a
 * textured roughness both 0 (specular lobes) and 1 (glossy ones). A bump map only turns
 * the shading normal (no lobe of its own). Never fewer effects than some point of the
 * surface shows. */
static uint32_t material_effects(const ts_material *m)
{
    if (!m->textured || m->type == TS_MATERIAL_MIX) return constant_material_effects(m);
    const ts_material_desc *d = ts_material_desc_of(m->type);
    ts_material c = *m;
    c.textured = false;
    for (int i = 0; d && i < d->n_params; i++) {
        const ts_material_param *p = &d->params[i];
        if (p->kind == TS_MPARAM_RGB && ts_mparam_rgb(&c, p)->tex)
            *ts_mparam_rgb(&c, p) = ts_material_rgb_gray(p->standin);
        if (p->kind == TS_MPARAM_FLOAT && ts_mparam_float(&c, p)->tex)
            *ts_mparam_float(&c, p) = ts_material_float_const(p->standin);
    }
    if (c.has_vroughness && c.vroughness.tex) { /* the roughness stand-ins below, on both axes */
        c.has_vroughness = false;
        if (!c.roughness.tex) c.roughness.tex = c.vroughness.tex;
    }
    if (!c.roughness.tex) return constant_material_effects(&c);
    c.roughness = ts_material_float_const(0);
    uint32_t fx = constant_material_effects(&c);
    c.roughness = ts_material_float_const(1);
    return fx | constant_material_effects(&c);
}

/* Whether anything moves while the shutter is open: a keyframe pair that differs over an
 * interval overlapping (shutter_open, shutter_close). Without it rays carry no time sample. */
static bool moves_in(const ts_anim_xform *a, float open, float close)
{
    return a && a->animated && a->end_time > open && a->start_time < close;
}

static bool scene_moves(const ts_scene *s)
{
    float open = s->camera.shutter_open, close = s->camera.shutter_close;
    if (!(close > open)) return false;
    if (s->camera.moving && moves_in(&s->camera.motion, open, close)) return true;
    for (uint32_t k = 0; k < s->n_instances; k++)
        if (moves_in(s->instances[k].motion, open, close)) return true;
    return false;
}

uint32_t ts_effects_analyse(const ts_scene *s)
{
    uint32_t fx = 0;
    for (uint32_t i = 0; i < s->n_lights; i++) {
        const ts_light *l = &s->lights[i];
        if (ts_rgb_is_black(l->color)) continue;
        switch (l->type) {
        case TS_LIGHT_POINT:
        case TS_LIGHT_SPOT:
        case TS_LIGHT_DISTANT: fx |= TS_EFFECT_DELTA_LIGHTS; break;
        case TS_LIGHT_AREA: fx |= TS_EFFECT_AREA_LIGHTS; break;
        case TS_LIGHT_INFINITE: fx |= TS_EFFECT_ENVIRONMENT; break;
        }
    }
    /* Only materials some shape uses count; each distinct material is classified once. */
    uint32_t last = TS_NONE;
    for (uint32_t i = 0; i < s->n_shapes; i++) {
        uint32_t m = s->shapes[i].material;
        if (m == TS_NONE || s->shapes[i].medium_transition) fx |= TS_EFFECT_MEDIA;
        if (m == last || m == TS_NONE) continue;
        last = m;
        fx |= material_effects(&s->materials[m]);
    }
    if (s->camera.lens_radius > 0) fx |= TS_EFFECT_DEPTH_OF_FIELD;
    if (scene_moves(s)) fx |= TS_EFFECT_MOTION;
    /* Media: a ray can be in one (the camera's, or behind a shape's medium interface), or
     * a shape has no surface and rays pass through it. */
    if (s->camera_medium != TS_NONE) fx |= TS_EFFECT_MEDIA;
    /* Light after more than one bounce needs light, something that scatters, and depth. */
    bool lit = (fx & TS_EFFECTS_LIGHTS) != 0;
    bool scatters = (fx & TS_EFFECTS_SCATTERING) != 0;
    /* volpath scatters in media too (a medium no ray reaches is no effect). */
    if (s->integrator.type == TS_INTEGRATOR_VOLPATH && (fx & TS_EFFECT_MEDIA)) scatters = true;
    if (lit && scatters) {
        const ts_integrator_desc *in = &s->integrator;
        if ((in->type == TS_INTEGRATOR_PATH || in->type == TS_INTEGRATOR_VOLPATH) && in->max_depth >= 2)
            fx |= TS_EFFECT_INDIRECT;
        if (in->type == TS_INTEGRATOR_DIRECT && in->max_depth >= 2 &&
            (fx & (TS_EFFECT_SPECULAR_REFLECTION | TS_EFFECT_SPECULAR_TRANSMISSION)))
            fx |= TS_EFFECT_INDIRECT;
    }
    return fx;
}
