/* mesh_read.c — the mesh result and the readers' toolkit; see mesh_read.h. */
#include "mesh/mesh_read.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void ts_mesh_data_free(ts_mesh_data *m)
{
    if (!m) return;
    free(m->p);
    free(m->n);
    free(m->uv);
    free(m->index);
    *m = (ts_mesh_data){0};
}

ts_status ts_mesh_failv(const ts_mesh_reader *r, ts_status st, const char *where, const char *fmt, va_list ap)
{
    char msg[TS_ERROR_MAX];
    vsnprintf(msg, sizeof msg, fmt, ap);
    return ts_error_set(r->err, st, "mesh file '%s'%s: %s", r->name, where, msg);
}

ts_status ts_mesh_fail(const ts_mesh_reader *r, ts_status st, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    ts_status res = ts_mesh_failv(r, st, "", fmt, ap);
    va_end(ap);
    return res;
}

ts_status ts_mesh_fail_line(const ts_mesh_reader *r, unsigned long line, ts_status st, const char *fmt, ...)
{
    char where[48];
    snprintf(where, sizeof where, ", line %lu", line);
    va_list ap;
    va_start(ap, fmt);
    ts_status res = ts_mesh_failv(r, st, where, fmt, ap);
    va_end(ap);
    return res;
}

ts_status ts_mesh_nomem(const ts_mesh_reader *r) { return ts_mesh_fail(r, TS_ERR_NOMEM, "out of memory"); }

bool ts_mesh_grow(void **ptr, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap) return true;
    size_t nc = *cap ? *cap : 256;
    while (nc < need) {
        if (nc > SIZE_MAX / 2 / elem) return false;
        nc *= 2;
    }
    void *q = realloc(*ptr, nc * elem);
    if (!q) return false;
    *ptr = q;
    *cap = nc;
    return true;
}

bool ts_mesh_token_is(const char *s, const char *e, const char *word)
{
    size_t n = strlen(word);
    return (size_t)(e - s) == n && memcmp(s, word, n) == 0;
}

bool ts_mesh_parse_double(const char *s, const char *e, double *out)
{
    char *end;
    *out = strtod(s, &end);
    return end == e && e > s;
}

bool ts_mesh_to_float(double d, float *f)
{
    if (!(fabs(d) <= FLT_MAX)) return false;
    *f = (float)d;
    return true;
}

bool ts_mesh_parse_int(const char *s, const char *e, int64_t *out)
{
    bool neg = false;
    if (s < e && (*s == '-' || *s == '+')) neg = *s++ == '-';
    if (s == e) return false;
    uint64_t v = 0;
    for (; s < e; s++) {
        if (*s < '0' || *s > '9') return false;
        if (v > (uint64_t)INT64_MAX / 10) return false;
        v = v * 10 + (uint64_t)(*s - '0');
        if (v > (uint64_t)INT64_MAX) return false;
    }
    *out = neg ? -(int64_t)v : (int64_t)v;
    return true;
}

bool ts_mesh_normal_ok(const float *n) { return n[0] != 0 || n[1] != 0 || n[2] != 0; }
