/* name_map.c — see name_map.h. */
#include "core/name_map.h"

#include <stdlib.h>
#include <string.h>

static uint32_t hash_name(const char *s)
{
    uint32_t h = 2166136261u; /* FNV-1a */
    for (; *s; s++) h = (h ^ (unsigned char)*s) * 16777619u;
    return h;
}

void ts_name_map_fini(ts_name_map *m)
{
    free(m->slots);
    *m = (ts_name_map){0};
}

static void place(ts_name_map_slot *slots, size_t cap, ts_name_map_slot e)
{
    size_t i = e.hash & (cap - 1);
    while (slots[i].name) i = (i + 1) & (cap - 1);
    slots[i] = e;
}

bool ts_name_map_put(ts_name_map *m, const char *name, uint32_t value)
{
    if (2 * (m->n + 1) > m->cap) {
        size_t cap = m->cap ? 2 * m->cap : 16;
        ts_name_map_slot *slots = calloc(cap, sizeof *slots);
        if (!slots) return false;
        for (size_t i = 0; i < m->cap; i++)
            if (m->slots[i].name) place(slots, cap, m->slots[i]);
        free(m->slots);
        m->slots = slots;
        m->cap = cap;
    }
    place(m->slots, m->cap, (ts_name_map_slot){name, hash_name(name), value});
    m->n++;
    return true;
}

uint32_t ts_name_map_get(const ts_name_map *m, const char *name)
{
    if (!m->cap) return TS_NAME_MAP_NONE;
    uint32_t h = hash_name(name);
    for (size_t i = h & (m->cap - 1); m->slots[i].name; i = (i + 1) & (m->cap - 1))
        if (m->slots[i].hash == h && strcmp(m->slots[i].name, name) == 0) return m->slots[i].value;
    return TS_NAME_MAP_NONE;
}
