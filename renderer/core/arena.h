/* arena.h — a bump allocator for per-scene and per-job memory.
 *
 * Design note: a scene is built once and freed whole (docs/design.md §6), so its many small
 * pieces come from one arena and teardown is ts_arena_fini. Blocks grow geometrically;
 * allocations are aligned to 16 bytes (or more if asked) and zeroed. Not thread-safe:
 * an arena is filled by one thread while a scene is built, then only read. */
#ifndef TS_ARENA_H
#define TS_ARENA_H

#include <stddef.h>

typedef struct ts_arena_block ts_arena_block;

typedef struct ts_arena {
    ts_arena_block *head; /* newest block first */
    size_t used_total;    /* bytes handed out, for reporting */
    size_t limit;         /* 0 = unlimited; allocations beyond it fail (NULL) */
} ts_arena;

void ts_arena_init(ts_arena *a, size_t limit);
/* Zeroed memory of size bytes aligned to align (a power of two ≤ 4096), or NULL when out
 * of memory or past the arena's limit. Owned by the arena. */
void *ts_arena_alloc(ts_arena *a, size_t size, size_t align);
/* Overflow-checked n × size allocation. */
void *ts_arena_calloc(ts_arena *a, size_t n, size_t size);
/* Copy of a NUL-terminated string, or NULL. */
char *ts_arena_strdup(ts_arena *a, const char *s);
void ts_arena_fini(ts_arena *a);

#endif
