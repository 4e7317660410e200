/* material_desc.c — the table of material types (see material_desc.h).
 *
 * Design note: one block per type, its rows in the order the writer emits them. A row's
 * `def` is scene format v1's default and `pbrt3`/`pbrt3_def` pbrt-v3's name and default
 * for the same field (the Create functions of pbrt-v3's src/materials); docs/design.md §4d
 * lists the same parameters for users. The effects stand-in (integrators/effects.c) is the
 * constant that raises every lobe the range allows: colours white, except uber's opacity,
 * whose ½ keeps its pass-through lobe and every other; σ 0 and η 1.5 change no lobe's kind. */
#include "materials/material_desc.h"

#include <math.h>
#include <string.h>

#include "materials/bsdf.h"
#include "spectrum/spectrum.h"
#include "textures/texture.h"

static void copper_eta(ts_rgb *out)
{
    ts_rgb k;
    ts_spectrum_copper(out, &k);
}

static void copper_k(ts_rgb *out)
{
    ts_rgb eta;
    ts_spectrum_copper(&eta, out);
}

#define OFF(field) ((uint16_t)offsetof(ts_material, field))
#define RGB(key, range, field, flags, def, pname, pdef) \
    {key, TS_MPARAM_RGB, range, OFF(field), flags, def, pname, pdef, NULL, 1, NULL}
#define FLOAT(key, range, field, flags, def, pname, pdef, standin) \
    {key, TS_MPARAM_FLOAT, range, OFF(field), flags, def, pname, pdef, NULL, standin, NULL}

static const char *const distributions[] = {"ggx", "beckmann", NULL};

static const ts_material_param diffuse[] = {
    RGB("reflectance", TS_MRANGE_UNIT, reflectance, 0, 0.5f, "Kd", 0.5f),
    FLOAT("sigma", TS_MRANGE_ANGLE, sigma_deg, TS_MPARAM_OMIT_ZERO, 0, "sigma", 0, 0),
};
static const ts_material_param mirror[] = {
    RGB("reflectance", TS_MRANGE_UNIT, reflectance, 0, 1, "Kr", 0.9f),
};
static const ts_material_param dielectric[] = {
    FLOAT("eta", TS_MRANGE_POSITIVE, eta, TS_MPARAM_PBRT3_INDEX, 1.5f, "eta", 1.5f, 1.5f),
    RGB("reflectance", TS_MRANGE_UNIT, reflectance, 0, 1, "Kr", 1),
    RGB("transmittance", TS_MRANGE_UNIT, transmittance, 0, 1, "Kt", 1),
};
static const ts_material_param conductor[] = {
    {"eta", TS_MPARAM_RGB, TS_MRANGE_NONNEG, OFF(conductor_eta), TS_MPARAM_REQUIRED, 0, "eta", 0, copper_eta, 1, NULL},
    {"k", TS_MPARAM_RGB, TS_MRANGE_NONNEG, OFF(conductor_k), TS_MPARAM_REQUIRED, 0, "k", 0, copper_k, 1, NULL},
    /* pbrt-v3's metal is GGX (TrowbridgeReitz): no pbrt-v3 name, v1's default. */
    {"distribution", TS_MPARAM_ENUM, TS_MRANGE_NONNEG, OFF(distribution), 0, TS_MICROFACET_GGX, NULL, 0, NULL, 0,
     distributions},
};
static const ts_material_param plastic[] = {
    RGB("diffuse", TS_MRANGE_UNIT, diffuse, 0, 0.25f, NULL, 0),
    RGB("specular", TS_MRANGE_UNIT, specular, 0, 0.25f, NULL, 0),
};
static const ts_material_param substrate[] = {
    RGB("diffuse", TS_MRANGE_UNIT, diffuse, 0, 0.5f, "Kd", 0.5f),
    RGB("specular", TS_MRANGE_UNIT, specular, 0, 0.5f, "Ks", 0.5f),
};
static const ts_material_param plastic_pbrt3[] = {
    RGB("diffuse", TS_MRANGE_UNIT, diffuse, 0, 0.25f, "Kd", 0.25f),
    RGB("specular", TS_MRANGE_UNIT, specular, 0, 0.25f, "Ks", 0.25f),
};
static const ts_material_param uber[] = {
    RGB("diffuse", TS_MRANGE_UNIT, diffuse, 0, 0.25f, "Kd", 0.25f),
    RGB("specular", TS_MRANGE_UNIT, specular, 0, 0.25f, "Ks", 0.25f),
    RGB("reflectance", TS_MRANGE_UNIT, reflectance, 0, 0, "Kr", 0),
    RGB("transmittance", TS_MRANGE_UNIT, transmittance, 0, 0, "Kt", 0),
    {"opacity", TS_MPARAM_RGB, TS_MRANGE_UNIT, OFF(opacity), 0, 1, "opacity", 1, NULL, 0.5f, NULL},
    FLOAT("eta", TS_MRANGE_POSITIVE, eta, TS_MPARAM_PBRT3_INDEX, 1.5f, "eta", 1.5f, 1.5f),
};
static const ts_material_param translucent[] = {
    RGB("diffuse", TS_MRANGE_UNIT, diffuse, 0, 0.25f, "Kd", 0.25f),
    RGB("specular", TS_MRANGE_UNIT, specular, 0, 0.25f, "Ks", 0.25f),
    RGB("reflectance", TS_MRANGE_UNIT, reflectance, 0, 0.5f, "reflect", 0.5f),
    RGB("transmittance", TS_MRANGE_UNIT, transmittance, 0, 0.5f, "transmit", 0.5f),
};
static const ts_material_param mix[] = {
    RGB("amount", TS_MRANGE_UNIT, amount, TS_MPARAM_PBRT3_FLOAT_GREY, 0.5f, "amount", 0.5f),
};

#define PARAMS(a) (uint8_t)(sizeof a / sizeof *a), a

const ts_material_desc ts_material_descs[TS_MATERIAL_TYPE_COUNT] = {
    {TS_MATERIAL_DIFFUSE, "diffuse", "matte", 0, 0, 1, PARAMS(diffuse)},
    {TS_MATERIAL_MIRROR, "mirror", "mirror", 0, 0, 1, PARAMS(mirror)},
    /* pbrt-v3's glass reads uroughness and vroughness only. */
    {TS_MATERIAL_DIELECTRIC, "dielectric", "glass", TS_MDESC_ROUGH | TS_MDESC_ANISO, 0, 2, PARAMS(dielectric)},
    {TS_MATERIAL_CONDUCTOR, "conductor", "metal", TS_MDESC_ROUGH | TS_MDESC_ANISO | TS_MDESC_PBRT3_ROUGH, 0.01f, 1,
     PARAMS(conductor)},
    /* v1's coupled plastic (material.c); pbrt-v3's plastic is plastic_pbrt3. */
    {TS_MATERIAL_PLASTIC, "plastic", NULL, TS_MDESC_ROUGH, 0.1f, 2, PARAMS(plastic)},
    {TS_MATERIAL_SUBSTRATE, "substrate", "substrate", TS_MDESC_ROUGH | TS_MDESC_ANISO, 0.1f, 2, PARAMS(substrate)},
    {TS_MATERIAL_FOURIER, "fourier", "fourier", TS_MDESC_FILE, 0, 1, 0, NULL},
    {TS_MATERIAL_PLASTIC_PBRT3, "plastic_pbrt3", "plastic", TS_MDESC_ROUGH | TS_MDESC_PBRT3_ROUGH, 0.1f, 2,
     PARAMS(plastic_pbrt3)},
    {TS_MATERIAL_UBER, "uber", "uber",
     TS_MDESC_ROUGH | TS_MDESC_ANISO | TS_MDESC_PBRT3_ROUGH | TS_MDESC_PBRT3_V_FOLLOWS_U, 0.1f, 5, PARAMS(uber)},
    {TS_MATERIAL_TRANSLUCENT, "translucent", "translucent", TS_MDESC_ROUGH | TS_MDESC_PBRT3_ROUGH, 0.1f, 4,
     PARAMS(translucent)},
    {TS_MATERIAL_MIX, "mix", "mix", TS_MDESC_MIX, 0, 0, PARAMS(mix)},
};

const ts_material_desc *ts_material_desc_of(ts_material_type t)
{
    return (unsigned)t < TS_MATERIAL_TYPE_COUNT ? &ts_material_descs[t] : NULL;
}

const ts_material_desc *ts_material_desc_by_name(const char *name)
{
    for (int i = 0; name && i < TS_MATERIAL_TYPE_COUNT; i++)
        if (strcmp(ts_material_descs[i].name, name) == 0) return &ts_material_descs[i];
    return NULL;
}

const ts_material_desc *ts_material_desc_by_pbrt3(const char *name)
{
    for (int i = 0; name && i < TS_MATERIAL_TYPE_COUNT; i++)
        if (ts_material_descs[i].pbrt3 && strcmp(ts_material_descs[i].pbrt3, name) == 0) return &ts_material_descs[i];
    return NULL;
}

void ts_material_desc_defaults(ts_material *m)
{
    const ts_material_desc *d = ts_material_desc_of(m->type);
    if (!d) return;
    for (int i = 0; i < d->n_params; i++) {
        const ts_material_param *p = &d->params[i];
        switch (p->kind) {
        case TS_MPARAM_RGB: *ts_mparam_rgb(m, p) = ts_material_rgb_gray(p->def); break;
        case TS_MPARAM_FLOAT: *ts_mparam_float(m, p) = ts_material_float_const(p->def); break;
        case TS_MPARAM_ENUM: *ts_mparam_enum(m, p) = (int)p->def; break;
        }
    }
    if (d->flags & TS_MDESC_ROUGH) {
        m->roughness = m->vroughness = ts_material_float_const(d->rough_def);
        m->has_vroughness = false;
        m->remap_roughness = false;
    }
}

/* The textures of m's parameters (its type's rows and roughness family,
 * material_desc.h) into t[]; returns how many slots were filled (NULL for a constant). */
static int parameter_textures(const ts_material *m, const struct ts_texture *t[32])
{
    const ts_material_desc *d = ts_material_desc_of(m->type);
    int n = 0;
    if (!d) return 0;
    for (int i = 0; i < d->n_params && n < 30; i++) {
        const ts_material_param *p = &d->params[i];
        if (p->kind == TS_MPARAM_RGB) t[n++] = ts_mparam_crgb(m, p)->tex;
        else if (p->kind == TS_MPARAM_FLOAT) t[n++] = ts_mparam_cfloat(m, p)->tex;
    }
    if (d->flags & TS_MDESC_ROUGH) t[n++] = m->roughness.tex;
    if (m->has_vroughness) t[n++] = m->vroughness.tex;
    return n;
}

bool ts_material_uses_textures(const ts_material *m)
{
    const struct ts_texture *t[32];
    int n = parameter_textures(m, t);
    for (int i = 0; i < n; i++)
        if (t[i]) return true;
    return m->bump != NULL;
}

uint64_t ts_material_texture_cost(const ts_material *m)
{
    const struct ts_texture *t[32];
    int n = parameter_textures(m, t);
    uint64_t cost = 0;
    for (int i = 0; i < n; i++)
        if (t[i]) cost += t[i]->cost;
    if (m->bump) cost += 3ull * m->bump->cost;
    return cost;
}

int ts_material_max_lobes(const ts_material *m)
{
    const ts_material_desc *d = ts_material_desc_of(m->type);
    if (!d) return TS_BSDF_MAX_BXDFS;
    if (d->flags & TS_MDESC_MIX)
        return (m->mix[0] ? ts_material_max_lobes(m->mix[0]) : 0) + (m->mix[1] ? ts_material_max_lobes(m->mix[1]) : 0);
    return d->max_lobes;
}

bool ts_mrange_ok(ts_mparam_range r, float v)
{
    switch (r) {
    case TS_MRANGE_UNIT: return v >= 0 && v <= 1;
    case TS_MRANGE_NONNEG: return v >= 0 && isfinite(v);
    case TS_MRANGE_POSITIVE: return v > 0 && isfinite(v);
    case TS_MRANGE_ANGLE: return v >= 0 && v <= 90;
    }
    return false;
}

const char *ts_mrange_words(ts_mparam_range r, bool rgb)
{
    switch (r) {
    case TS_MRANGE_UNIT: return rgb ? "RGB in [0, 1]" : "a number in [0, 1]";
    case TS_MRANGE_NONNEG: return rgb ? "finite RGB ≥ 0" : "a finite number ≥ 0";
    case TS_MRANGE_POSITIVE: return rgb ? "finite RGB > 0" : "a finite number > 0";
    case TS_MRANGE_ANGLE: return "an angle in [0, 90] degrees";
    }
    return "a value";
}
