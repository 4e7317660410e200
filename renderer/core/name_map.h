/* name_map.h — names to indices in expected constant time, so that a scene of n named
 * materials, textures or objects loads in time linear in n (a list searched for each name
 * made it quadratic: 60000 materials in 1.7 MB of JSON took 21 s).
 *
 * Design note: open addressing with linear probing over (hash, name, value) slots, grown
 * to twice its size at half full; names are not copied (they must outlive the map: arena
 * or document strings). One thread at a time. */
#ifndef TS_NAME_MAP_H
#define TS_NAME_MAP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef struct ts_name_map_slot {
    const char *name; /* NULL: empty */
    uint32_t hash, value;
} ts_name_map_slot;

typedef struct ts_name_map {
    ts_name_map_slot *slots;
    size_t cap, n; /* cap a power of two, or 0 */
} ts_name_map;

#define TS_NAME_MAP_NONE UINT32_MAX

/* Zeroed is empty. */
void ts_name_map_fini(ts_name_map *m);
/* name → value, name not in m yet; false when out of memory (m unchanged). */
bool ts_name_map_put(ts_name_map *m, const char *name, uint32_t value);
/* name's value, or TS_NAME_MAP_NONE. */
uint32_t ts_name_map_get(const ts_name_map *m, const char *name);

#endif
