/* text_buffer.h — a growing printf buffer for tests and benchmarks that write scene
 * documents (tests/test_light_bvh.c, bench/light_bvh.c).
 *
 * text_buffer b = {0}; text_put(&b, fmt, ...) appends, growing b.p as needed (b.p is
 * NUL-terminated after the first append; the caller frees it). Running out of memory
 * aborts: these are test programs, where it fails the run. Not thread-safe per buffer. */
#ifndef TS_TESTS_TEXT_BUFFER_H
#define TS_TESTS_TEXT_BUFFER_H

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>

typedef struct text_buffer {
    char *p;
    size_t n, cap;
} text_buffer;

static inline void text_put(text_buffer *b, const char *fmt, ...)
{
    va_list ap;
    for (;;) {
        va_start(ap, fmt);
        int k = b->p ? vsnprintf(b->p + b->n, b->cap - b->n, fmt, ap) : -1;
        va_end(ap);
        if (b->p && k >= 0 && (size_t)k < b->cap - b->n) {
            b->n += (size_t)k;
            return;
        }
        b->cap = b->cap * 2 + (size_t)(k > 0 ? k : 0) + 64;
        char *p = realloc(b->p, b->cap);
        if (!p) abort();
        b->p = p;
    }
}

#endif
