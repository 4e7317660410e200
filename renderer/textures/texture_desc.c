/* texture_desc.c — the table of texture types (see texture_desc.h).
 *
 * Design note: one block per type, its rows in the order the writer emits them; `def` is
 * scene format v1's default, `pbrt3`/`pbrt3_def` pbrt-v3's name and default (the Create
 * functions of pbrt-v3's src/textures). The two formats agree on every default; they
 * differ only in the names of the dots texture (texture_desc.h). */
#include "textures/texture_desc.h"

#include <stddef.h>
#include <string.h>

#define OFF(field) ((uint16_t)offsetof(ts_texture, field))
#define ROW(key, kind, field, def, pname, pdef) {key, kind, OFF(field), def, pname, pdef}

static const ts_texture_param constant[] = {ROW("value", TS_TPARAM_VALUE, constant.value, 1, "value", 1)};
static const ts_texture_param scale[] = {
    ROW("tex1", TS_TPARAM_CHILD, scale.tex1, 1, "tex1", 1),
    ROW("tex2", TS_TPARAM_CHILD, scale.tex2, 1, "tex2", 1),
};
static const ts_texture_param mix[] = {
    ROW("tex1", TS_TPARAM_CHILD, mix.tex1, 0, "tex1", 0),
    ROW("tex2", TS_TPARAM_CHILD, mix.tex2, 1, "tex2", 1),
    ROW("amount", TS_TPARAM_AMOUNT, mix.amount, 0.5f, "amount", 0.5f),
};
static const ts_texture_param bilerp[] = {
    ROW("v00", TS_TPARAM_VALUE, bilerp.v00, 0, "v00", 0),
    ROW("v01", TS_TPARAM_VALUE, bilerp.v01, 1, "v01", 1),
    ROW("v10", TS_TPARAM_VALUE, bilerp.v10, 0, "v10", 0),
    ROW("v11", TS_TPARAM_VALUE, bilerp.v11, 1, "v11", 1),
};
static const ts_texture_param checker2d[] = {
    ROW("tex1", TS_TPARAM_CHILD, checkerboard2d.tex1, 1, "tex1", 1),
    ROW("tex2", TS_TPARAM_CHILD, checkerboard2d.tex2, 0, "tex2", 0),
};
static const ts_texture_param checker3d[] = {
    ROW("tex1", TS_TPARAM_CHILD, checkerboard3d.tex1, 1, "tex1", 1),
    ROW("tex2", TS_TPARAM_CHILD, checkerboard3d.tex2, 0, "tex2", 0),
};
/* pbrt-v3 passes its "inside" where DotsTexture takes the outside texture (and the other
 * way round): the rows read each field from the other name, with that name's default. */
static const ts_texture_param dots[] = {
    ROW("inside", TS_TPARAM_CHILD, dots.inside, 1, "outside", 0),
    ROW("outside", TS_TPARAM_CHILD, dots.outside, 0, "inside", 1),
};
static const ts_texture_param fbm[] = {ROW("octaves", TS_TPARAM_OCTAVES, fbm.octaves, 8, "octaves", 8)};
static const ts_texture_param marble[] = {
    ROW("octaves", TS_TPARAM_OCTAVES, marble.octaves, 8, "octaves", 8),
    ROW("scale", TS_TPARAM_NUMBER, marble.scale, 1, "scale", 1),
    ROW("variation", TS_TPARAM_NUMBER, marble.variation, 0.2f, "variation", 0.2f),
};

#define PARAMS(a) (uint8_t)(sizeof a / sizeof *a), a
#define NONE 0, NULL

const ts_texture_desc ts_texture_descs[TS_TEXTURE_TYPE_COUNT] = {
    {TS_TEXTURE_CONSTANT, "constant", "constant", TS_TDESC_CONSTANT, 0, 0, PARAMS(constant)},
    {TS_TEXTURE_SCALE, "scale", "scale", 0, 0, 0, PARAMS(scale)},
    {TS_TEXTURE_MIX, "mix", "mix", 0, 0, 0, PARAMS(mix)},
    {TS_TEXTURE_BILERP, "bilerp", "bilerp", TS_TDESC_MAP2D | TS_TDESC_MAP_FIRST, 0, OFF(bilerp.map), PARAMS(bilerp)},
    {TS_TEXTURE_UV, "uv", "uv", TS_TDESC_MAP2D | TS_TDESC_MAP_FIRST | TS_TDESC_RGB_ONLY, 0, OFF(uv.map), NONE},
    {TS_TEXTURE_CHECKERBOARD2D, "checkerboard", "checkerboard", TS_TDESC_MAP2D | TS_TDESC_AAMODE, 2,
     OFF(checkerboard2d.map), PARAMS(checker2d)},
    {TS_TEXTURE_CHECKERBOARD3D, "checkerboard", "checkerboard", TS_TDESC_MAP3D, 3, OFF(checkerboard3d.map),
     PARAMS(checker3d)},
    {TS_TEXTURE_DOTS, "dots", "dots", TS_TDESC_MAP2D, 0, OFF(dots.map), PARAMS(dots)},
    {TS_TEXTURE_FBM, "fbm", "fbm", TS_TDESC_MAP3D, 0, OFF(fbm.map), PARAMS(fbm)},
    {TS_TEXTURE_WRINKLED, "wrinkled", "wrinkled", TS_TDESC_MAP3D, 0, OFF(fbm.map), PARAMS(fbm)},
    {TS_TEXTURE_WINDY, "windy", "windy", TS_TDESC_MAP3D, 0, OFF(windy.map), NONE},
    {TS_TEXTURE_MARBLE, "marble", "marble", TS_TDESC_MAP3D | TS_TDESC_RGB_ONLY, 0, OFF(marble.map), PARAMS(marble)},
    {TS_TEXTURE_IMAGEMAP, "imagemap", "imagemap", TS_TDESC_MAP2D | TS_TDESC_MAP_FIRST | TS_TDESC_IMAGE, 0,
     OFF(image.map), NONE},
};

static const ts_texture_desc *find(const char *name, int dimension, bool pbrt3)
{
    for (int i = 0; name && i < TS_TEXTURE_TYPE_COUNT; i++) {
        const ts_texture_desc *d = &ts_texture_descs[i];
        if (strcmp(pbrt3 ? d->pbrt3 : d->name, name) == 0 && (!d->dimension || d->dimension == dimension)) return d;
    }
    return NULL;
}

const ts_texture_desc *ts_texture_desc_by_name(const char *name, int dimension) { return find(name, dimension, false); }
const ts_texture_desc *ts_texture_desc_by_pbrt3(const char *name, int dimension) { return find(name, dimension, true); }
