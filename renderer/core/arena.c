/* arena.c — bump allocator; see arena.h. */
#include "core/arena.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

struct ts_arena_block {
    ts_arena_block *next;
    size_t size, used;
    _Alignas(16) unsigned char data[];
};

void ts_arena_init(ts_arena *a, size_t limit)
{
    a->head = NULL;
    a->used_total = 0;
    a->limit = limit;
}

void *ts_arena_alloc(ts_arena *a, size_t size, size_t align)
{
    if (align < 16) align = 16;
    if (size == 0) size = 1;
    if (size > SIZE_MAX / 2) return NULL;
    if (a->limit && (size > a->limit || a->used_total > a->limit - size)) return NULL;
    ts_arena_block *b = a->head;
    size_t offset = 0;
    if (b) offset = (b->used + align - 1) & ~(align - 1);
    if (!b || offset + size > b->size) {
        size_t want = b ? b->size * 2 : 64 * 1024;
        if (want < size + align) want = size + align;
        ts_arena_block *nb = malloc(sizeof *nb + want);
        if (!nb) return NULL;
        nb->next = a->head;
        nb->size = want;
        nb->used = 0;
        a->head = b = nb;
        offset = ((uintptr_t)b->data % align) ? align - (uintptr_t)b->data % align : 0;
    }
    void *p = b->data + offset;
    b->used = offset + size;
    a->used_total += size;
    memset(p, 0, size);
    return p;
}

void *ts_arena_calloc(ts_arena *a, size_t n, size_t size)
{
    if (size && n > SIZE_MAX / size) return NULL;
    return ts_arena_alloc(a, n * size, 16);
}

char *ts_arena_strdup(ts_arena *a, const char *s)
{
    size_t n = strlen(s) + 1;
    char *p = ts_arena_alloc(a, n, 1);
    if (p) memcpy(p, s, n);
    return p;
}

void ts_arena_fini(ts_arena *a)
{
    ts_arena_block *b = a->head;
    while (b) {
        ts_arena_block *next = b->next;
        free(b);
        b = next;
    }
    a->head = NULL;
    a->used_total = 0;
}
