/* mesh_read.h — what reading a mesh file produces, and what the readers share.
 *
 * Design note: every mesh reader (mesh_obj.h, mesh_ply.h) turns a whole in-memory file
 * image into the same plain indexed triangle list, ts_mesh_data, in the file's object
 * space, under the same limits, and words its errors the same way: "mesh file '<name>'
 * [, where]: <problem>", where <name> is the path as the scene wrote it and <where> is a
 * line or a byte offset. The dispatcher by extension and the path confinement are
 * mesh_file.h's; the scene builder transforms and copies the result into its arena.
 *
 * The second half of this header is the readers' toolkit (error sentences, growable
 * arrays, number tokens), for mesh_obj.c and mesh_ply.c only. Nothing here keeps state
 * between calls; everything is thread-safe. Numbers are parsed with strtod, so LC_NUMERIC
 * must be the "C" locale (it is unless the program calls setlocale). */
#ifndef TS_MESH_READ_H
#define TS_MESH_READ_H

#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "core/cancel.h"
#include "core/error.h"

/* Upper bounds on what a file may make the loader allocate; 0 = no limit. max_vertices
 * bounds the output vertices and, for OBJ, also the number of `v` statements. */
typedef struct ts_mesh_limits {
    uint64_t max_vertices, max_triangles, max_file_bytes;
    ts_cancel *cancel; /* polled every TS_MESH_POLL items (core/cancel.h); NULL: never stops */
} ts_mesh_limits;

typedef struct ts_mesh_data {
    uint32_t n_vertices, n_triangles;
    float *p;        /* 3·n_vertices, malloc-owned */
    float *n;        /* 3·n_vertices normals, non-zero, of any length (as written), or NULL */
    float *uv;       /* 2·n_vertices, or NULL */
    uint32_t *index; /* 3·n_triangles, every index < n_vertices */
} ts_mesh_data;

/* Frees the arrays of m (NULL or zeroed is fine) and zeroes it. */
void ts_mesh_data_free(ts_mesh_data *m);

/* ---- the readers' toolkit ---- */

/* One read: the file's name for messages, the limits (0 = none) and the caller's error. */
typedef struct ts_mesh_reader {
    const char *name; /* the path as the scene wrote it */
    ts_mesh_limits lim;
    ts_error *err;
} ts_mesh_reader;

/* "mesh file '<name>'<where>: <fmt…>" into r->err; returns st. */
ts_status ts_mesh_failv(const ts_mesh_reader *r, ts_status st, const char *where, const char *fmt,
                        va_list ap);
ts_status ts_mesh_fail(const ts_mesh_reader *r, ts_status st, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* The same with ", line <line>" as the place. */
ts_status ts_mesh_fail_line(const ts_mesh_reader *r, unsigned long line, ts_status st, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
ts_status ts_mesh_nomem(const ts_mesh_reader *r);

/* Every TS_MESH_POLL-th item (line, element) of a read polls r->lim.cancel: TS_OK, or
 * TS_ERR_CANCELLED with the sentence in r->err. */
#define TS_MESH_POLL 16384u
static inline ts_status ts_mesh_poll(const ts_mesh_reader *r, uint64_t item)
{
    return item % TS_MESH_POLL ? TS_OK : ts_cancel_check(r->lim.cancel, r->err);
}

/* Grows the malloc'd array *ptr (of *cap elements of size elem) to hold at least need
 * elements, doubling from 256; false (nothing changed) when out of memory or too large. */
bool ts_mesh_grow(void **ptr, size_t *cap, size_t need, size_t elem);

/* value beyond limit, where limit 0 means none. */
static inline bool ts_mesh_over(uint64_t value, uint64_t limit) { return limit != 0 && value > limit; }

/* Blanks separating tokens on a line (not '\n'). */
static inline bool ts_mesh_is_blank(char ch)
{
    return ch == ' ' || ch == '\t' || ch == '\r' || ch == '\v' || ch == '\f';
}

/* The token [s, e) is exactly word. */
bool ts_mesh_token_is(const char *s, const char *e, const char *word);
/* Parses [s, e) as a whole number (strtod; e must be followed by a non-numeric byte). */
bool ts_mesh_parse_double(const char *s, const char *e, double *out);
/* Rounds d to a float; false if it is NaN, infinite or beyond the float range (the cast
 * alone would be undefined there). */
bool ts_mesh_to_float(double d, float *f);
/* Parses [s, e) as an optionally signed decimal integer; false on syntax or overflow. */
bool ts_mesh_parse_int(const char *s, const char *e, int64_t *out);
/* Whether the vertex normal n (finite floats, checked by the reader) can shade: false for
 * the zero vector. Normals keep their lengths, which weight their interpolation as in
 * pbrt-v3's triangles (docs/design.md §4, shapes). */
bool ts_mesh_normal_ok(const float *n);

/* A token shown in a message: at most 32 bytes. */
#define TS_MESH_TOKEN_FMT       "%.*s"
#define TS_MESH_TOKEN_ARG(s, e) (int)((e) - (s) > 32 ? 32 : (e) - (s)), (s)

#endif
