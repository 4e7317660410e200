/* medium_desc.c — the table of medium types (see medium_desc.h).
 *
 * Design note: rows in the order the writer emits them; the defaults are pbrt-v3's
 * (GetMediumScatteringProperties' σa, σs of 0 unless a preset, scale 1, g 0; the grid's
 * nx = ny = nz = 1, p0 (0, 0, 0), p1 (1, 1, 1)), which scene format v1 shares. */
#include "build/medium_desc.h"

#include <stddef.h>
#include <string.h>

#define OFF(field) ((uint16_t)offsetof(ts_medium_desc, field))
#define COMMON                                                                      \
    {"sigma_a", TS_VPARAM_RGB, OFF(sigma_a), OFF(has_sigma_a), {0}},               \
    {"sigma_s", TS_VPARAM_RGB, OFF(sigma_s), OFF(has_sigma_s), {0}},               \
    {"scale", TS_VPARAM_NUMBER, OFF(scale), 0, {1}}, {"g", TS_VPARAM_NUMBER, OFF(g), 0, {0}}, \
    {"preset", TS_VPARAM_STRING, OFF(preset), 0, {0}}

static const ts_medium_param homogeneous[] = {COMMON};
static const ts_medium_param grid[] = {
    COMMON,
    {"nx", TS_VPARAM_COUNT, OFF(nx), 0, {1}},
    {"ny", TS_VPARAM_COUNT, OFF(ny), 0, {1}},
    {"nz", TS_VPARAM_COUNT, OFF(nz), 0, {1}},
    {"density", TS_VPARAM_DENSITY, OFF(density), 0, {0}},
    {"p0", TS_VPARAM_POINT, OFF(p0), 0, {0, 0, 0}},
    {"p1", TS_VPARAM_POINT, OFF(p1), 0, {1, 1, 1}},
};

#define PARAMS(a) (uint8_t)(sizeof a / sizeof *a), a

const ts_medium_type_desc ts_medium_descs[TS_MEDIUM_DESC_COUNT] = {
    {TS_MEDIUM_HOMOGENEOUS, "homogeneous", "homogeneous", 0, PARAMS(homogeneous)},
    {TS_MEDIUM_GRID, "grid", "heterogeneous", TS_VDESC_TRANSFORM, PARAMS(grid)},
};

const ts_medium_type_desc *ts_medium_desc_by_name(const char *name)
{
    for (int i = 0; name && i < TS_MEDIUM_DESC_COUNT; i++)
        if (strcmp(ts_medium_descs[i].name, name) == 0) return &ts_medium_descs[i];
    return NULL;
}

const ts_medium_type_desc *ts_medium_desc_by_pbrt3(const char *name)
{
    for (int i = 0; name && i < TS_MEDIUM_DESC_COUNT; i++)
        if (strcmp(ts_medium_descs[i].pbrt3, name) == 0) return &ts_medium_descs[i];
    return NULL;
}
