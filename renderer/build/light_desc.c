/* light_desc.c — the table of light types (see light_desc.h).
 *
 * Design note: one block per type, its rows in the order the writer emits them; `def` is
 * scene format v1's default, `pbrt3`/`pbrt3_def` pbrt-v3's name and default (the Create
 * functions of pbrt-v3's src/lights). docs/design.md §4 lists the same keys for users. */
#include "build/light_desc.h"

#include <stddef.h>
#include <string.h>

#define OFF(field) ((uint16_t)offsetof(ts_light_desc, field))

static const ts_light_param point[] = {
    {"position", TS_LPARAM_POINT, OFF(from), TS_LPARAM_REQUIRED, {0, 0, 0}, "from", {0, 0, 0}},
    {"intensity", TS_LPARAM_RGB, OFF(color), TS_LPARAM_REQUIRED, {1}, "I", {1}},
};
static const ts_light_param spot[] = {
    {"from", TS_LPARAM_POINT, OFF(from), TS_LPARAM_REQUIRED, {0, 0, 0}, "from", {0, 0, 0}},
    {"to", TS_LPARAM_POINT, OFF(to), TS_LPARAM_REQUIRED | TS_LPARAM_NOT_FROM, {0, 0, 1}, "to", {0, 0, 1}},
    {"intensity", TS_LPARAM_RGB, OFF(color), TS_LPARAM_REQUIRED, {1}, "I", {1}},
    {"cone_angle", TS_LPARAM_ANGLE, OFF(cone_angle_deg), 0, {30}, "coneangle", {30}},
    {"cone_delta", TS_LPARAM_ANGLE, OFF(cone_delta_deg), TS_LPARAM_UPTO_ANGLE, {5}, "conedelta", {5}},
};
static const ts_light_param distant[] = {
    {"from", TS_LPARAM_POINT, OFF(from), 0, {0, 0, 0}, "from", {0, 0, 0}},
    {"to", TS_LPARAM_POINT, OFF(to), TS_LPARAM_NOT_FROM, {0, 0, 1}, "to", {0, 0, 1}},
    {"irradiance", TS_LPARAM_RGB, OFF(color), TS_LPARAM_REQUIRED, {1}, "L", {1}},
};

#define PARAMS(a) (uint8_t)(sizeof a / sizeof *a), a

const ts_light_type_desc ts_light_descs[TS_LIGHT_DESC_COUNT] = {
    {TS_LIGHT_POINT, "point", "point", 0, PARAMS(point)},
    {TS_LIGHT_SPOT, "spot", "spot", 0, PARAMS(spot)},
    {TS_LIGHT_DISTANT, "distant", "distant", 0, PARAMS(distant)},
    {TS_LIGHT_INFINITE, "infinite", "infinite", TS_LDESC_ENVIRONMENT, 0, NULL},
};

const ts_light_type_desc *ts_light_desc_by_name(const char *name)
{
    for (int i = 0; name && i < TS_LIGHT_DESC_COUNT; i++)
        if (strcmp(ts_light_descs[i].name, name) == 0) return &ts_light_descs[i];
    return NULL;
}

const ts_light_type_desc *ts_light_desc_by_pbrt3(const char *name)
{
    for (int i = 0; name && i < TS_LIGHT_DESC_COUNT; i++)
        if (strcmp(ts_light_descs[i].pbrt3, name) == 0) return &ts_light_descs[i];
    return NULL;
}
