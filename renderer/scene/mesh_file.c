/* mesh_file.c — Wavefront OBJ and PLY meshes; see mesh_file.h for the accepted formats.
 *
 * Design note: confinement and reading are scene_path.c's (one rule for every file a
 * scene names): the path is checked lexically, resolved with realpath inside the
 * scene's folder, opened with O_NOFOLLOW, must be a regular file, and its size is checked
 * against max_file_bytes before the buffer is allocated.
 *
 * The file is read whole into a NUL-terminated buffer, so strtod never runs off the end.
 * OBJ takes two passes: the first counts v/vt/vn statements so the attribute arrays are
 * allocated once, at a size checked against the limits, and positive indices can be
 * checked against the file's totals; the second parses, keeping face corners as
 * (v, vt, vn) triples. Corners are then deduplicated with an open-addressing hash table
 * (linear probing, load ≤ 1/2) and faces fanned into triangles. PLY reads the header into
 * element/property descriptions, gives each property a role (x, nx, u, vertex_indices,
 * or skip), checks element counts against the limits and the bytes left, and then reads
 * the elements in order through one cursor that is either a line reader (ASCII) or a
 * bounds-checked little-endian byte reader (binary). Nothing here is shared between
 * calls, so loads on different threads are independent. */
#include "scene/mesh_file.h"

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/hash.h"
#include "scene/scene_path.h"

#define NO_INDEX UINT32_MAX

/* ---- errors: every message starts "mesh file '<rel_path>'[, where]: " ---- */

typedef struct load_ctx {
    const char *name; /* rel_path as the scene wrote it */
    ts_mesh_limits lim;
    ts_error *err;
} load_ctx;

static ts_status failv(const load_ctx *c, ts_status st, const char *where, const char *fmt, va_list ap)
{
    char msg[TS_ERROR_MAX];
    vsnprintf(msg, sizeof msg, fmt, ap);
    return ts_error_set(c->err, st, "mesh file '%s'%s: %s", c->name, where, msg);
}

static ts_status fail(const load_ctx *c, ts_status st, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static ts_status fail(const load_ctx *c, ts_status st, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    ts_status r = failv(c, st, "", fmt, ap);
    va_end(ap);
    return r;
}

static ts_status fail_line(const load_ctx *c, unsigned long line, ts_status st, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static ts_status fail_line(const load_ctx *c, unsigned long line, ts_status st, const char *fmt, ...)
{
    char where[48];
    snprintf(where, sizeof where, ", line %lu", line);
    va_list ap;
    va_start(ap, fmt);
    ts_status r = failv(c, st, where, fmt, ap);
    va_end(ap);
    return r;
}

static ts_status nomem(const load_ctx *c) { return fail(c, TS_ERR_NOMEM, "out of memory"); }

/* Grows *ptr (of *cap elements of size elem) to hold at least need elements. */
static bool grow(void **ptr, size_t *cap, size_t need, size_t elem)
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

static bool over(uint64_t value, uint64_t limit) { return limit != 0 && value > limit; }

/* ---- small lexical helpers shared by both formats ---- */

static bool is_blank(char ch) { return ch == ' ' || ch == '\t' || ch == '\r' || ch == '\v' || ch == '\f'; }

static bool token_is(const char *s, const char *e, const char *word)
{
    size_t n = strlen(word);
    return (size_t)(e - s) == n && memcmp(s, word, n) == 0;
}

/* Parses [s, e) as a whole number (strtod; e must be followed by a non-numeric byte). */
static bool parse_double(const char *s, const char *e, double *out)
{
    char *end;
    *out = strtod(s, &end);
    return end == e && e > s;
}

/* Rounds d to a float; false if it is NaN, infinite or beyond the float range (the cast
 * alone would be undefined there). */
static bool to_float(double d, float *f)
{
    if (!(fabs(d) <= FLT_MAX)) return false;
    *f = (float)d;
    return true;
}

/* Parses [s, e) as an optionally signed decimal integer; false on syntax or overflow. */
static bool parse_int(const char *s, const char *e, int64_t *out)
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

/* A token shown in a message: at most 32 bytes. */
#define TOKEN_FMT       "%.*s"
#define TOKEN_ARG(s, e) (int)((e) - (s) > 32 ? 32 : (e) - (s)), (s)

/* Normalises n in place; false if its length is zero or not finite. */
static bool normalize3(float *n)
{
    double x = n[0], y = n[1], z = n[2], len = sqrt(x * x + y * y + z * z);
    if (!(len > 0) || !isfinite(len)) return false;
    n[0] = (float)(x / len);
    n[1] = (float)(y / len);
    n[2] = (float)(z / len);
    return true;
}

/* ==== Wavefront OBJ ==== */

/* Logical lines: a line whose last non-CR byte is '\' continues on the next one. */
typedef struct obj_lines {
    const char *p, *end;
    unsigned long next_line;
} obj_lines;

static bool obj_next_line(obj_lines *it, const char **ls, const char **le, unsigned long *line)
{
    if (it->p >= it->end) return false;
    *ls = it->p;
    *line = it->next_line;
    const char *s = it->p;
    for (;;) {
        const char *nl = memchr(s, '\n', (size_t)(it->end - s));
        if (!nl) {
            *le = it->end;
            it->p = it->end;
            return true;
        }
        it->next_line++;
        const char *q = nl;
        if (q > s && q[-1] == '\r') q--;
        if (q > s && q[-1] == '\\') {
            s = nl + 1;
            continue;
        }
        *le = nl;
        it->p = nl + 1;
        return true;
    }
}

/* Next token of [*s, e): skips blanks and '\'-newline continuations; '#' ends the line. */
static bool obj_token(const char **s, const char *e, const char **ts, const char **te)
{
    const char *p = *s;
    for (;;) {
        while (p < e && (is_blank(*p) || *p == '\n'))
            p++;
        if (p < e && *p == '\\' && p + 1 < e &&
            (p[1] == '\n' || (p[1] == '\r' && p + 2 < e && p[2] == '\n'))) {
            p++;
            continue;
        }
        break;
    }
    if (p >= e || *p == '#') {
        *s = e;
        return false;
    }
    *ts = p;
    while (p < e && !is_blank(*p) && *p != '\n' &&
           !(*p == '\\' && p + 1 < e && (p[1] == '\n' || (p[1] == '\r' && p + 2 < e && p[2] == '\n'))))
        p++;
    *te = p;
    *s = p;
    return true;
}

typedef struct obj_corner {
    uint32_t v, vt, vn;
} obj_corner;

typedef struct obj_state {
    const load_ctx *c;
    uint64_t nv, nvt, nvn; /* totals from the first pass */
    uint64_t iv, ivt, ivn; /* defined so far */
    float *pos, *tex, *nrm;
    obj_corner *corners;
    size_t n_corners, cap_corners;
    uint32_t *face_size;
    size_t n_faces, cap_faces;
    uint64_t n_triangles;
    bool all_vt, all_vn;
} obj_state;

/* Reads the numbers of a v/vt/vn statement: at least min_n, at most max_n (0 = any), the
 * first want stored as floats. */
static ts_status obj_numbers(obj_state *o, unsigned long line, const char *what, const char *s, const char *e,
                             unsigned min_n, unsigned max_n, float *dst, unsigned want)
{
    const char *ts, *te;
    unsigned k = 0;
    while (obj_token(&s, e, &ts, &te)) {
        double d;
        if (!parse_double(ts, te, &d))
            return fail_line(o->c, line, TS_ERR_INVALID, "%s: malformed number '" TOKEN_FMT "'", what,
                             TOKEN_ARG(ts, te));
        float f;
        if (!to_float(d, &f))
            return fail_line(o->c, line, TS_ERR_INVALID, "%s: '" TOKEN_FMT "' is not a finite number", what,
                             TOKEN_ARG(ts, te));
        if (k < want) dst[k] = f;
        k++;
        if (max_n && k > max_n)
            return fail_line(o->c, line, TS_ERR_INVALID, "%s: too many values (at most %u)", what, max_n);
    }
    if (k < min_n)
        return fail_line(o->c, line, TS_ERR_INVALID, "%s: expected %u numbers, found %u", what, min_n, k);
    for (; k < want; k++)
        dst[k] = 0;
    return TS_OK;
}

/* Turns a 1-based (or negative, relative) OBJ index into a 0-based one. */
static ts_status obj_resolve(obj_state *o, unsigned long line, int64_t raw, uint64_t so_far, uint64_t total,
                             const char *what, const char *plural, uint32_t *out)
{
    if (raw > 0 && (uint64_t)raw <= total) {
        *out = (uint32_t)(raw - 1);
        return TS_OK;
    }
    if (raw < 0 && (uint64_t)(-(raw + 1)) < so_far) {
        *out = (uint32_t)(so_far - (uint64_t)(-(raw + 1)) - 1);
        return TS_OK;
    }
    if (raw == 0)
        return fail_line(o->c, line, TS_ERR_INVALID, "%s index 0 is invalid (indices start at 1)", what);
    if (raw > 0)
        return fail_line(o->c, line, TS_ERR_INVALID, "%s index %lld out of range (file has %llu %s)", what,
                         (long long)raw, (unsigned long long)total, plural);
    return fail_line(o->c, line, TS_ERR_INVALID,
                     "%s index %lld out of range (%llu %s defined before this line)", what, (long long)raw,
                     (unsigned long long)so_far, plural);
}

/* Parses one corner token "v", "v/vt", "v//vn" or "v/vt/vn". */
static ts_status obj_corner_parse(obj_state *o, unsigned long line, const char *ts, const char *te,
                                  obj_corner *cr)
{
    const char *cut[3] = {ts, NULL, NULL}; /* part i is [cut[i], part_end[i]) */
    const char *part_end[3] = {te, te, te};
    int n_parts = 1;
    for (const char *q = ts; q < te; q++) {
        if (*q != '/') continue;
        if (n_parts == 3) goto malformed;
        part_end[n_parts - 1] = q;
        cut[n_parts++] = q + 1;
    }
    int64_t raw[3] = {0, 0, 0};
    bool has[3] = {false, false, false};
    for (int i = 0; i < n_parts; i++) {
        if (cut[i] == part_end[i]) {
            if (i == 1 && n_parts == 3) continue; /* "v//vn" */
            goto malformed;
        }
        if (!parse_int(cut[i], part_end[i], &raw[i])) goto malformed;
        has[i] = true;
    }
    ts_status st = obj_resolve(o, line, raw[0], o->iv, o->nv, "face", "vertices", &cr->v);
    if (st) return st;
    cr->vt = cr->vn = NO_INDEX;
    if (has[1] && (st = obj_resolve(o, line, raw[1], o->ivt, o->nvt, "texture coordinate",
                                    "texture coordinates", &cr->vt)))
        return st;
    if (has[2] && (st = obj_resolve(o, line, raw[2], o->ivn, o->nvn, "normal", "normals", &cr->vn)))
        return st;
    return TS_OK;
malformed:
    return fail_line(o->c, line, TS_ERR_INVALID, "malformed face vertex '" TOKEN_FMT "'", TOKEN_ARG(ts, te));
}

static ts_status obj_face(obj_state *o, unsigned long line, const char *s, const char *e)
{
    const char *ts, *te;
    size_t first = o->n_corners;
    uint32_t k = 0;
    while (obj_token(&s, e, &ts, &te)) {
        if (!grow((void **)&o->corners, &o->cap_corners, o->n_corners + 1, sizeof *o->corners))
            return nomem(o->c);
        obj_corner *cr = &o->corners[o->n_corners];
        ts_status st = obj_corner_parse(o, line, ts, te, cr);
        if (st) return st;
        if (cr->vt == NO_INDEX) o->all_vt = false;
        if (cr->vn == NO_INDEX) o->all_vn = false;
        o->n_corners++;
        if (++k == UINT32_MAX) return fail_line(o->c, line, TS_ERR_LIMIT, "face has too many vertices");
    }
    if (k < 3) {
        o->n_corners = first;
        return fail_line(o->c, line, TS_ERR_INVALID, "face has %u vertices (at least 3 needed)", k);
    }
    o->n_triangles += k - 2;
    if (over(o->n_triangles, o->c->lim.max_triangles) || o->n_triangles > UINT32_MAX)
        return fail_line(
            o->c, line, TS_ERR_LIMIT, "more than the limit of %llu triangles",
            (unsigned long long)(o->c->lim.max_triangles ? o->c->lim.max_triangles : UINT32_MAX));
    if (!grow((void **)&o->face_size, &o->cap_faces, o->n_faces + 1, sizeof *o->face_size))
        return nomem(o->c);
    o->face_size[o->n_faces++] = k;
    return TS_OK;
}

/* One hash-table slot: a (v, vt, vn) key and its output vertex (NO_INDEX = empty). */
typedef struct obj_slot {
    uint32_t v, vt, vn, out;
} obj_slot;

static bool obj_table_grow(obj_slot **tab, size_t *cap)
{
    size_t nc = *cap ? *cap * 2 : 1024;
    if (nc > SIZE_MAX / sizeof **tab) return false;
    obj_slot *t = malloc(nc * sizeof *t);
    if (!t) return false;
    for (size_t i = 0; i < nc; i++)
        t[i].out = NO_INDEX;
    for (size_t i = 0; i < *cap; i++) {
        obj_slot s = (*tab)[i];
        if (s.out == NO_INDEX) continue;
        size_t h = ts_hash4(s.v, s.vt, s.vn, 0) & (nc - 1);
        while (t[h].out != NO_INDEX)
            h = (h + 1) & (nc - 1);
        t[h] = s;
    }
    free(*tab);
    *tab = t;
    *cap = nc;
    return true;
}

/* Deduplicates the corners into output vertices and fans the faces into triangles. */
static ts_status obj_build(obj_state *o, ts_mesh_data *out)
{
    const load_ctx *c = o->c;
    bool use_vt = o->all_vt, use_vn = o->all_vn;
    obj_slot *tab = NULL;
    size_t cap = 0;
    uint32_t n_out = 0;
    ts_status st = TS_OK;
    if (!obj_table_grow(&tab, &cap)) return nomem(c);
    for (size_t i = 0; i < o->n_corners; i++) {
        obj_corner *cr = &o->corners[i];
        uint32_t vt = use_vt ? cr->vt : NO_INDEX, vn = use_vn ? cr->vn : NO_INDEX;
        size_t h = ts_hash4(cr->v, vt, vn, 0) & (cap - 1);
        while (tab[h].out != NO_INDEX && !(tab[h].v == cr->v && tab[h].vt == vt && tab[h].vn == vn))
            h = (h + 1) & (cap - 1);
        if (tab[h].out == NO_INDEX) {
            if (over((uint64_t)n_out + 1, c->lim.max_vertices) || n_out == UINT32_MAX - 1) {
                st = fail(c, TS_ERR_LIMIT, "more than the limit of %llu vertices",
                          (unsigned long long)(c->lim.max_vertices ? c->lim.max_vertices : UINT32_MAX - 1));
                goto fail_tab;
            }
            tab[h] = (obj_slot){cr->v, vt, vn, n_out++};
            cr->v = tab[h].out;
            if ((size_t)n_out * 2 > cap && !obj_table_grow(&tab, &cap)) {
                st = nomem(c);
                goto fail_tab;
            }
        } else {
            cr->v = tab[h].out;
        }
    }
    out->p = malloc((size_t)n_out * 3 * sizeof(float));
    out->uv = use_vt ? malloc((size_t)n_out * 2 * sizeof(float)) : NULL;
    out->n = use_vn ? malloc((size_t)n_out * 3 * sizeof(float)) : NULL;
    out->index = malloc((size_t)o->n_triangles * 3 * sizeof(uint32_t));
    if (!out->p || (use_vt && !out->uv) || (use_vn && !out->n) || !out->index) {
        st = nomem(c);
        goto fail_tab;
    }
    for (size_t i = 0; i < cap; i++) {
        const obj_slot *s = &tab[i];
        if (s->out == NO_INDEX) continue;
        memcpy(out->p + 3 * (size_t)s->out, o->pos + 3 * (size_t)s->v, 3 * sizeof(float));
        if (use_vt) memcpy(out->uv + 2 * (size_t)s->out, o->tex + 2 * (size_t)s->vt, 2 * sizeof(float));
        if (use_vn) memcpy(out->n + 3 * (size_t)s->out, o->nrm + 3 * (size_t)s->vn, 3 * sizeof(float));
    }
    size_t first = 0, t = 0;
    for (size_t f = 0; f < o->n_faces; f++) {
        for (uint32_t j = 1; j + 1 < o->face_size[f]; j++, t++) {
            out->index[3 * t + 0] = o->corners[first].v;
            out->index[3 * t + 1] = o->corners[first + j].v;
            out->index[3 * t + 2] = o->corners[first + j + 1].v;
        }
        first += o->face_size[f];
    }
    out->n_vertices = n_out;
    out->n_triangles = (uint32_t)o->n_triangles;
fail_tab:
    free(tab);
    return st;
}

static ts_status obj_parse(const load_ctx *c, const char *buf, size_t size, ts_mesh_data *out)
{
    obj_state o = {.c = c, .all_vt = true, .all_vn = true};
    const char *end = buf + size, *ls, *le, *ts, *te;
    unsigned long line;
    ts_status st = TS_OK;

    /* Pass 1: count the attribute statements. */
    obj_lines it = {buf, end, 1};
    while (obj_next_line(&it, &ls, &le, &line)) {
        const char *s = ls;
        if (!obj_token(&s, le, &ts, &te)) continue;
        if (token_is(ts, te, "v"))
            o.nv++;
        else if (token_is(ts, te, "vt"))
            o.nvt++;
        else if (token_is(ts, te, "vn"))
            o.nvn++;
    }
    if (over(o.nv, c->lim.max_vertices))
        return fail(c, TS_ERR_LIMIT, "file has %llu vertices, more than the limit of %llu",
                    (unsigned long long)o.nv, (unsigned long long)c->lim.max_vertices);
    if (o.nv >= UINT32_MAX || o.nvt >= UINT32_MAX || o.nvn >= UINT32_MAX)
        return fail(c, TS_ERR_LIMIT, "more than %u vertex attributes of one kind", UINT32_MAX - 1);
    /* + 1: malloc(0) may return NULL. Each statement takes ≥ 8 bytes of file, so these
     * sizes are bounded by a few times the file size. */
    o.pos = malloc(((size_t)o.nv * 3 + 1) * sizeof(float));
    o.tex = malloc(((size_t)o.nvt * 2 + 1) * sizeof(float));
    o.nrm = malloc(((size_t)o.nvn * 3 + 1) * sizeof(float));
    if (!o.pos || !o.tex || !o.nrm) {
        st = nomem(c);
        goto fail_arrays;
    }

    /* Pass 2: parse. */
    it = (obj_lines){buf, end, 1};
    while (obj_next_line(&it, &ls, &le, &line)) {
        const char *s = ls;
        if (!obj_token(&s, le, &ts, &te)) continue;
        if (token_is(ts, te, "v")) {
            st = obj_numbers(&o, line, "vertex", s, le, 3, 0, o.pos + 3 * o.iv, 3);
            o.iv++;
        } else if (token_is(ts, te, "vt")) {
            st = obj_numbers(&o, line, "texture coordinate", s, le, 1, 3, o.tex + 2 * o.ivt, 2);
            o.ivt++;
        } else if (token_is(ts, te, "vn")) {
            st = obj_numbers(&o, line, "normal", s, le, 3, 3, o.nrm + 3 * o.ivn, 3);
            if (!st && !normalize3(o.nrm + 3 * o.ivn))
                st = fail_line(c, line, TS_ERR_INVALID, "normal has zero length");
            o.ivn++;
        } else if (token_is(ts, te, "f")) {
            st = obj_face(&o, line, s, le);
        } else {
            /* Any other statement is ignored, but a keyword must look like one: this
             * turns a binary file with an .obj name into an error, not an empty mesh. */
            for (const char *q = ts; q < te; q++) {
                char ch = *q;
                if (!((ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || (ch >= '0' && ch <= '9') ||
                      ch == '_')) {
                    st = fail_line(c, line, TS_ERR_INVALID, "unexpected '" TOKEN_FMT "'", TOKEN_ARG(ts, te));
                    break;
                }
            }
        }
        if (st) goto fail_faces;
    }
    if (o.iv != o.nv || o.ivt != o.nvt || o.ivn != o.nvn) {
        st = fail(c, TS_ERR_INTERNAL, "attribute count changed between passes");
        goto fail_faces;
    }
    if (o.n_faces == 0) {
        st = fail(c, TS_ERR_INVALID, "file has no faces");
        goto fail_faces;
    }
    st = obj_build(&o, out);
fail_faces:
    free(o.corners);
    free(o.face_size);
fail_arrays:
    free(o.pos);
    free(o.tex);
    free(o.nrm);
    return st;
}

/* ==== PLY ==== */

typedef enum ply_type { PLY_I8, PLY_U8, PLY_I16, PLY_U16, PLY_I32, PLY_U32, PLY_F32, PLY_F64 } ply_type;

static const struct {
    const char *name;
    ply_type type;
} ply_type_names[] = {
    {"char", PLY_I8},   {"int8", PLY_I8},     {"uchar", PLY_U8},   {"uint8", PLY_U8},
    {"short", PLY_I16}, {"int16", PLY_I16},   {"ushort", PLY_U16}, {"uint16", PLY_U16},
    {"int", PLY_I32},   {"int32", PLY_I32},   {"uint", PLY_U32},   {"uint32", PLY_U32},
    {"float", PLY_F32}, {"float32", PLY_F32}, {"double", PLY_F64}, {"float64", PLY_F64},
};

static size_t ply_size(ply_type t)
{
    static const size_t sizes[] = {1, 1, 2, 2, 4, 4, 4, 8};
    return sizes[t];
}

static bool ply_is_int(ply_type t) { return t != PLY_F32 && t != PLY_F64; }

typedef enum ply_role {
    ROLE_SKIP,
    ROLE_X,
    ROLE_Y,
    ROLE_Z,
    ROLE_NX,
    ROLE_NY,
    ROLE_NZ,
    ROLE_U,
    ROLE_V,
    ROLE_INDICES,
} ply_role;

typedef struct ply_prop {
    const char *name;
    int name_len;
    bool is_list;
    ply_type count_type, type; /* count_type only for lists */
    ply_role role;
} ply_prop;

typedef struct ply_elem {
    const char *name;
    int name_len;
    uint64_t count;
    ply_prop *props;
    size_t n_props, cap_props;
} ply_elem;

typedef enum ply_format { PLY_NONE, PLY_ASCII, PLY_BINARY_LE } ply_format;

/* The data cursor: ASCII reads one element per line, binary reads bytes. */
typedef struct ply_in {
    const load_ctx *c;
    bool ascii;
    const char *base, *p, *end; /* p: next unread byte (binary) or next line (ASCII) */
    const char *lp, *le;        /* ASCII: rest of the current line */
    unsigned long line, next_line;
    const ply_elem *elem; /* for messages */
    uint64_t item;
} ply_in;

static ts_status ply_fail(const ply_in *in, ts_status st, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static ts_status ply_fail(const ply_in *in, ts_status st, const char *fmt, ...)
{
    char where[160];
    if (in->ascii)
        snprintf(where, sizeof where, ", line %lu", in->line);
    else
        snprintf(where, sizeof where, ", byte %llu (element '%.*s' #%llu)",
                 (unsigned long long)(in->p - in->base), in->elem->name_len > 32 ? 32 : in->elem->name_len,
                 in->elem->name, (unsigned long long)in->item);
    va_list ap;
    va_start(ap, fmt);
    ts_status r = failv(in->c, st, where, fmt, ap);
    va_end(ap);
    return r;
}

static ts_status ply_truncated(const ply_in *in) { return ply_fail(in, TS_ERR_INVALID, "file is truncated"); }

/* Starts element item in->item: ASCII moves to the next non-blank line. */
static ts_status ply_begin_item(ply_in *in)
{
    if (!in->ascii) return TS_OK;
    for (;;) {
        if (in->p >= in->end)
            return ply_fail(in, TS_ERR_INVALID,
                            "file is truncated: it ends after %llu of %llu '%.*s' elements",
                            (unsigned long long)in->item, (unsigned long long)in->elem->count,
                            in->elem->name_len, in->elem->name);
        const char *nl = memchr(in->p, '\n', (size_t)(in->end - in->p));
        in->lp = in->p;
        in->le = nl ? nl : in->end;
        in->p = nl ? nl + 1 : in->end;
        in->line = in->next_line++;
        const char *q = in->lp;
        while (q < in->le && is_blank(*q))
            q++;
        if (q < in->le) return TS_OK;
    }
}

static bool ply_ascii_token(ply_in *in, const char **ts, const char **te)
{
    const char *p = in->lp;
    while (p < in->le && is_blank(*p))
        p++;
    if (p >= in->le) {
        in->lp = p;
        return false;
    }
    *ts = p;
    while (p < in->le && !is_blank(*p))
        p++;
    *te = in->lp = p;
    return true;
}

static ts_status ply_end_item(ply_in *in)
{
    const char *ts, *te;
    if (in->ascii && ply_ascii_token(in, &ts, &te))
        return ply_fail(in, TS_ERR_INVALID, "unexpected extra value '" TOKEN_FMT "' in a '%.*s' element",
                        TOKEN_ARG(ts, te), in->elem->name_len, in->elem->name);
    return TS_OK;
}

static uint64_t le_bits(const char *p, size_t n)
{
    uint64_t v = 0;
    for (size_t i = n; i-- > 0;)
        v = (v << 8) | (unsigned char)p[i];
    return v;
}

/* Binary: decodes a little-endian scalar at p as a double (exact for every integer type). */
static double ply_decode(const char *p, ply_type t)
{
    uint64_t b = le_bits(p, ply_size(t));
    switch (t) {
    case PLY_I8:
        return (int8_t)(uint8_t)b;
    case PLY_U8:
        return (uint8_t)b;
    case PLY_I16:
        return (int16_t)(uint16_t)b;
    case PLY_U16:
        return (uint16_t)b;
    case PLY_I32:
        return (int32_t)(uint32_t)b;
    case PLY_U32:
        return (uint32_t)b;
    case PLY_F32: {
        uint32_t u = (uint32_t)b;
        float f;
        memcpy(&f, &u, sizeof f);
        return f;
    }
    case PLY_F64: {
        double d;
        memcpy(&d, &b, sizeof d);
        return d;
    }
    }
    return 0;
}

/* Reads one scalar as a double (any type). */
static ts_status ply_read_real(ply_in *in, ply_type t, double *out)
{
    if (in->ascii) {
        const char *ts, *te;
        if (!ply_ascii_token(in, &ts, &te))
            return ply_fail(in, TS_ERR_INVALID, "missing values in a '%.*s' element", in->elem->name_len,
                            in->elem->name);
        if (!parse_double(ts, te, out))
            return ply_fail(in, TS_ERR_INVALID, "malformed number '" TOKEN_FMT "'", TOKEN_ARG(ts, te));
        return TS_OK;
    }
    size_t n = ply_size(t);
    if ((size_t)(in->end - in->p) < n) return ply_truncated(in);
    *out = ply_decode(in->p, t);
    in->p += n;
    return TS_OK;
}

/* Reads one integer-typed scalar (list counts and indices). */
static ts_status ply_read_int(ply_in *in, ply_type t, int64_t *out)
{
    if (in->ascii) {
        const char *ts, *te;
        if (!ply_ascii_token(in, &ts, &te))
            return ply_fail(in, TS_ERR_INVALID, "missing values in a '%.*s' element", in->elem->name_len,
                            in->elem->name);
        if (!parse_int(ts, te, out))
            return ply_fail(in, TS_ERR_INVALID, "malformed integer '" TOKEN_FMT "'", TOKEN_ARG(ts, te));
        return TS_OK;
    }
    size_t n = ply_size(t);
    if ((size_t)(in->end - in->p) < n) return ply_truncated(in);
    *out = (int64_t)ply_decode(in->p, t);
    in->p += n;
    return TS_OK;
}

/* Reads a list count: a non-negative integer whose values fit in the bytes left. */
static ts_status ply_read_count(ply_in *in, const ply_prop *pr, int64_t *count)
{
    ts_status st = ply_read_int(in, pr->count_type, count);
    if (st) return st;
    if (*count < 0)
        return ply_fail(in, TS_ERR_INVALID, "list '%.*s' has a negative length %lld", pr->name_len, pr->name,
                        (long long)*count);
    if (!in->ascii && (uint64_t)*count > (uint64_t)(in->end - in->p) / ply_size(pr->type))
        return ply_truncated(in);
    /* ASCII: every value takes at least a character and a separator of this line. */
    if (in->ascii && (uint64_t)*count > (uint64_t)(in->le - in->lp + 1) / 2)
        return ply_fail(in, TS_ERR_INVALID, "list '%.*s' announces %lld values but the line holds fewer",
                        pr->name_len, pr->name, (long long)*count);
    return TS_OK;
}

static ts_status ply_skip(ply_in *in, const ply_prop *pr)
{
    int64_t count = 1;
    if (pr->is_list) {
        ts_status st = ply_read_count(in, pr, &count);
        if (st) return st;
    }
    if (!in->ascii) {
        size_t n = (size_t)count * ply_size(pr->type);
        if ((size_t)(in->end - in->p) < n) return ply_truncated(in);
        in->p += n;
        return TS_OK;
    }
    const char *ts, *te;
    for (int64_t i = 0; i < count; i++)
        if (!ply_ascii_token(in, &ts, &te))
            return ply_fail(in, TS_ERR_INVALID, "missing values in a '%.*s' element", in->elem->name_len,
                            in->elem->name);
    return TS_OK;
}

typedef struct ply_header {
    ply_format format;
    ply_elem *elems;
    size_t n_elems, cap_elems;
    ply_elem *vertex, *face;
    const char *data; /* first byte after end_header's newline */
    unsigned long data_line;
    bool has_normals, has_uv;
} ply_header;

static void ply_header_fini(ply_header *h)
{
    for (size_t i = 0; i < h->n_elems; i++)
        free(h->elems[i].props);
    free(h->elems);
}

static bool ply_parse_type(const char *s, const char *e, ply_type *t)
{
    for (size_t i = 0; i < sizeof ply_type_names / sizeof ply_type_names[0]; i++)
        if (token_is(s, e, ply_type_names[i].name)) {
            *t = ply_type_names[i].type;
            return true;
        }
    return false;
}

static ply_prop *ply_find(ply_elem *el, const char *name)
{
    for (size_t i = 0; i < el->n_props; i++)
        if (token_is(el->props[i].name, el->props[i].name + el->props[i].name_len, name))
            return &el->props[i];
    return NULL;
}

/* Parses the header lines up to end_header into h. */
static ts_status ply_parse_header(const load_ctx *c, const char *buf, size_t size, ply_header *h)
{
    const char *end = buf + size, *p = buf;
    unsigned long line = 0;
    for (;;) {
        if (p >= end) {
            return line == 0 ? fail(c, TS_ERR_INVALID, "file is empty")
                             : fail(c, TS_ERR_INVALID, "header has no 'end_header' line");
        }
        const char *nl = memchr(p, '\n', (size_t)(end - p));
        const char *ls = p, *le = nl ? nl : end;
        p = nl ? nl + 1 : end;
        line++;
        const char *tok[6][2];
        int nt = 0;
        for (const char *q = ls;;) {
            while (q < le && is_blank(*q))
                q++;
            if (q >= le) break;
            const char *ts = q;
            while (q < le && !is_blank(*q))
                q++;
            if (nt < 6) {
                tok[nt][0] = ts;
                tok[nt][1] = q;
            }
            nt++;
        }
#define TOK_IS(i, word) (nt > (i) && token_is(tok[i][0], tok[i][1], word))
        if (line == 1) {
            if (!(nt == 1 && TOK_IS(0, "ply")))
                return fail(c, TS_ERR_INVALID, "not a PLY file (no 'ply' first line)");
            continue;
        }
        if (nt == 0 || TOK_IS(0, "comment") || TOK_IS(0, "obj_info")) continue;
        if (TOK_IS(0, "end_header") && nt == 1) break;
        if (TOK_IS(0, "format")) {
            if (nt != 3 || !TOK_IS(2, "1.0"))
                return fail_line(c, line, TS_ERR_INVALID,
                                 "expected 'format <ascii|binary_little_endian> 1.0'");
            if (TOK_IS(1, "ascii"))
                h->format = PLY_ASCII;
            else if (TOK_IS(1, "binary_little_endian"))
                h->format = PLY_BINARY_LE;
            else if (TOK_IS(1, "binary_big_endian"))
                return fail_line(
                    c, line, TS_ERR_UNSUPPORTED,
                    "binary_big_endian PLY is not supported (use ascii or binary_little_endian)");
            else
                return fail_line(c, line, TS_ERR_INVALID, "unknown PLY format '" TOKEN_FMT "'",
                                 TOKEN_ARG(tok[1][0], tok[1][1]));
        } else if (TOK_IS(0, "element")) {
            int64_t count;
            if (nt != 3 || !parse_int(tok[2][0], tok[2][1], &count) || count < 0 || *tok[2][0] == '-')
                return fail_line(c, line, TS_ERR_INVALID, "expected 'element <name> <count>'");
            if (!grow((void **)&h->elems, &h->cap_elems, h->n_elems + 1, sizeof *h->elems)) return nomem(c);
            ply_elem *el = &h->elems[h->n_elems++];
            ptrdiff_t len = tok[1][1] - tok[1][0];
            *el = (ply_elem){.name = tok[1][0],
                             .name_len = len > INT_MAX / 2 ? INT_MAX / 2 : (int)len,
                             .count = (uint64_t)count};
            if (token_is(tok[1][0], tok[1][1], "vertex") || token_is(tok[1][0], tok[1][1], "face")) {
                ply_elem **slot = *tok[1][0] == 'v' ? &h->vertex : &h->face;
                if (*slot)
                    return fail_line(c, line, TS_ERR_INVALID, "second '%.*s' element", el->name_len,
                                     el->name);
                *slot = el;
            }
        } else if (TOK_IS(0, "property")) {
            if (h->n_elems == 0) return fail_line(c, line, TS_ERR_INVALID, "property before any element");
            ply_elem *el = &h->elems[h->n_elems - 1];
            ply_prop pr = {0};
            int name_tok;
            if (TOK_IS(1, "list")) {
                if (nt != 5 || !ply_parse_type(tok[2][0], tok[2][1], &pr.count_type) ||
                    !ply_parse_type(tok[3][0], tok[3][1], &pr.type))
                    return fail_line(c, line, TS_ERR_INVALID,
                                     "expected 'property list <count type> <type> <name>'");
                if (!ply_is_int(pr.count_type))
                    return fail_line(c, line, TS_ERR_INVALID, "a list count must have an integer type");
                pr.is_list = true;
                name_tok = 4;
            } else {
                if (nt != 3 || !ply_parse_type(tok[1][0], tok[1][1], &pr.type))
                    return fail_line(c, line, TS_ERR_INVALID, "expected 'property <type> <name>'");
                name_tok = 2;
            }
            pr.name = tok[name_tok][0];
            pr.name_len = (int)(tok[name_tok][1] - tok[name_tok][0] > INT_MAX / 2
                                    ? INT_MAX / 2
                                    : tok[name_tok][1] - tok[name_tok][0]);
            if (!grow((void **)&el->props, &el->cap_props, el->n_props + 1, sizeof *el->props))
                return nomem(c);
            el->props[el->n_props++] = pr;
        } else {
            return fail_line(c, line, TS_ERR_INVALID, "unexpected header line starting '" TOKEN_FMT "'",
                             TOKEN_ARG(tok[0][0], tok[0][1]));
        }
#undef TOK_IS
    }
    h->data = p;
    h->data_line = line + 1;
    if (h->format == PLY_NONE) return fail(c, TS_ERR_INVALID, "header has no 'format' line");
    return TS_OK;
}

/* Gives the vertex and face properties their roles and checks they are usable. */
static ts_status ply_assign_roles(const load_ctx *c, ply_header *h)
{
    if (!h->vertex) return fail(c, TS_ERR_INVALID, "PLY header has no 'vertex' element");
    if (!h->face) return fail(c, TS_ERR_INVALID, "PLY header has no 'face' element");
    static const char *const xyz[] = {"x", "y", "z", "nx", "ny", "nz"};
    for (int i = 0; i < 6; i++) {
        ply_prop *pr = ply_find(h->vertex, xyz[i]);
        if (!pr) {
            if (i < 3) return fail(c, TS_ERR_INVALID, "element 'vertex' has no property '%s'", xyz[i]);
            continue;
        }
        if (pr->is_list) return fail(c, TS_ERR_INVALID, "vertex property '%s' is a list", xyz[i]);
        pr->role = (ply_role)(ROLE_X + i);
    }
    bool nx = ply_find(h->vertex, "nx"), ny = ply_find(h->vertex, "ny"), nz = ply_find(h->vertex, "nz");
    if ((nx || ny || nz) && !(nx && ny && nz))
        return fail(c, TS_ERR_INVALID, "element 'vertex' has some but not all of nx, ny, nz");
    h->has_normals = nx;
    static const char *const uv_names[][2] = {
        {"u", "v"}, {"s", "t"}, {"texture_u", "texture_v"}, {"texture_s", "texture_t"}};
    for (size_t i = 0; i < sizeof uv_names / sizeof uv_names[0] && !h->has_uv; i++) {
        ply_prop *u = ply_find(h->vertex, uv_names[i][0]), *v = ply_find(h->vertex, uv_names[i][1]);
        if (!u || !v) continue;
        if (u->is_list || v->is_list)
            return fail(c, TS_ERR_INVALID, "vertex property '%s' is a list",
                        u->is_list ? uv_names[i][0] : uv_names[i][1]);
        u->role = ROLE_U;
        v->role = ROLE_V;
        h->has_uv = true;
    }
    ply_prop *ind = ply_find(h->face, "vertex_indices");
    if (!ind) ind = ply_find(h->face, "vertex_index");
    if (!ind) return fail(c, TS_ERR_INVALID, "element 'face' has no property 'vertex_indices'");
    if (!ind->is_list || !ply_is_int(ind->type))
        return fail(c, TS_ERR_INVALID, "face property 'vertex_indices' must be a list of integers");
    ind->role = ROLE_INDICES;
    return TS_OK;
}

/* Checks every element count against the limits and the bytes after the header. */
static ts_status ply_check_counts(const load_ctx *c, const ply_header *h, size_t data_bytes)
{
    if (over(h->vertex->count, c->lim.max_vertices) || h->vertex->count >= UINT32_MAX)
        return fail(c, TS_ERR_LIMIT, "file has %llu vertices, more than the limit of %llu",
                    (unsigned long long)h->vertex->count,
                    (unsigned long long)(c->lim.max_vertices ? c->lim.max_vertices : UINT32_MAX - 1));
    if (over(h->face->count, c->lim.max_triangles) || h->face->count >= UINT32_MAX)
        return fail(c, TS_ERR_LIMIT, "file has %llu faces, more than the limit of %llu triangles",
                    (unsigned long long)h->face->count,
                    (unsigned long long)(c->lim.max_triangles ? c->lim.max_triangles : UINT32_MAX - 1));
    /* Least bytes an item can take: binary, the scalars and list counts; ASCII, one
     * character and one separator per scalar or list count. */
    uint64_t left = h->format == PLY_ASCII ? (uint64_t)data_bytes + 1 : (uint64_t)data_bytes;
    for (size_t i = 0; i < h->n_elems; i++) {
        const ply_elem *el = &h->elems[i];
        uint64_t least = 0;
        for (size_t j = 0; j < el->n_props; j++) {
            const ply_prop *pr = &el->props[j];
            least += h->format == PLY_ASCII ? 2 : ply_size(pr->is_list ? pr->count_type : pr->type);
        }
        if (least == 0) continue;
        if (el->count > left / least)
            return fail(
                c, TS_ERR_INVALID,
                "file is truncated: %llu '%.*s' elements need at least %llu bytes each, but only %llu "
                "bytes are left",
                (unsigned long long)el->count, el->name_len, el->name, (unsigned long long)least,
                (unsigned long long)left);
        left -= el->count * least;
    }
    return TS_OK;
}

static ts_status ply_read_vertices(ply_in *in, const ply_header *h, ts_mesh_data *m)
{
    const ply_elem *el = h->vertex;
    for (uint64_t i = 0; i < el->count; i++) {
        in->item = i;
        ts_status st = ply_begin_item(in);
        if (st) return st;
        double val[ROLE_V + 1] = {0};
        for (size_t j = 0; j < el->n_props; j++) {
            const ply_prop *pr = &el->props[j];
            if (pr->role == ROLE_SKIP || pr->role == ROLE_INDICES) {
                if ((st = ply_skip(in, pr))) return st;
                continue;
            }
            const char *at = in->p;
            if ((st = ply_read_real(in, pr->type, &val[pr->role]))) return st;
            float unused;
            if (!to_float(val[pr->role], &unused)) {
                if (!in->ascii) in->p = at; /* point the message at the value */
                return ply_fail(in, TS_ERR_INVALID, "vertex %llu: '%.*s' is not a finite number (%g)",
                                (unsigned long long)i, pr->name_len, pr->name, val[pr->role]);
            }
        }
        if ((st = ply_end_item(in))) return st;
        for (int k = 0; k < 3; k++)
            m->p[3 * i + k] = (float)val[ROLE_X + k];
        if (m->n) {
            for (int k = 0; k < 3; k++)
                m->n[3 * i + k] = (float)val[ROLE_NX + k];
            if (!normalize3(m->n + 3 * i))
                return ply_fail(in, TS_ERR_INVALID, "vertex %llu has a zero-length normal",
                                (unsigned long long)i);
        }
        if (m->uv) {
            m->uv[2 * i] = (float)val[ROLE_U];
            m->uv[2 * i + 1] = (float)val[ROLE_V];
        }
    }
    return TS_OK;
}

static ts_status ply_read_faces(ply_in *in, const ply_header *h, ts_mesh_data *m, size_t *cap_tris)
{
    const ply_elem *el = h->face;
    const load_ctx *c = in->c;
    uint32_t nv = (uint32_t)h->vertex->count;
    for (uint64_t i = 0; i < el->count; i++) {
        in->item = i;
        ts_status st = ply_begin_item(in);
        if (st) return st;
        for (size_t j = 0; j < el->n_props; j++) {
            const ply_prop *pr = &el->props[j];
            if (pr->role != ROLE_INDICES) {
                if ((st = ply_skip(in, pr))) return st;
                continue;
            }
            int64_t k;
            if ((st = ply_read_count(in, pr, &k))) return st;
            if (k < 3)
                return ply_fail(in, TS_ERR_INVALID, "face %llu has %lld vertices (at least 3 needed)",
                                (unsigned long long)i, (long long)k);
            uint64_t tris = m->n_triangles + (uint64_t)(k - 2);
            if (over(tris, c->lim.max_triangles) || tris >= UINT32_MAX)
                return ply_fail(
                    in, TS_ERR_LIMIT, "more than the limit of %llu triangles",
                    (unsigned long long)(c->lim.max_triangles ? c->lim.max_triangles : UINT32_MAX - 1));
            if (!grow((void **)&m->index, cap_tris, (size_t)tris * 3, sizeof *m->index)) return nomem(c);
            uint32_t first = 0, prev = 0;
            for (int64_t q = 0; q < k; q++) {
                const char *at = in->p;
                int64_t idx;
                if ((st = ply_read_int(in, pr->type, &idx))) return st;
                if (idx < 0 || idx >= (int64_t)nv) {
                    if (!in->ascii) in->p = at;
                    return ply_fail(in, TS_ERR_INVALID, "face index %lld out of range (file has %u vertices)",
                                    (long long)idx, nv);
                }
                if (q == 0) {
                    first = (uint32_t)idx;
                } else if (q >= 2) {
                    uint32_t *t = m->index + 3 * (size_t)m->n_triangles++;
                    t[0] = first;
                    t[1] = prev;
                    t[2] = (uint32_t)idx;
                }
                prev = (uint32_t)idx;
            }
        }
        if ((st = ply_end_item(in))) return st;
    }
    return TS_OK;
}

static ts_status ply_skip_element(ply_in *in, const ply_elem *el)
{
    if (el->n_props == 0) return TS_OK; /* items of no properties take no bytes */
    bool fixed = !in->ascii;
    size_t stride = 0;
    for (size_t j = 0; j < el->n_props && fixed; j++) {
        fixed = !el->props[j].is_list;
        stride += ply_size(el->props[j].type);
    }
    if (fixed) { /* ply_check_counts bounded count·stride by the bytes left */
        in->item = 0;
        if (el->count > (uint64_t)(in->end - in->p) / stride) return ply_truncated(in);
        in->p += el->count * stride;
        return TS_OK;
    }
    for (uint64_t i = 0; i < el->count; i++) {
        in->item = i;
        ts_status st = ply_begin_item(in);
        for (size_t j = 0; j < el->n_props && !st; j++)
            st = ply_skip(in, &el->props[j]);
        if (!st) st = ply_end_item(in);
        if (st) return st;
    }
    return TS_OK;
}

static ts_status ply_parse(const load_ctx *c, const char *buf, size_t size, ts_mesh_data *out)
{
    ply_header h = {0};
    ts_mesh_data m = {0};
    size_t cap_tris = 0;
    ts_status st = ply_parse_header(c, buf, size, &h);
    if (!st) st = ply_assign_roles(c, &h);
    if (!st) st = ply_check_counts(c, &h, (size_t)(buf + size - h.data));
    if (st) goto fail_header;
    size_t nv = (size_t)h.vertex->count;
    m.p = malloc((nv * 3 + 1) * sizeof(float));
    m.n = h.has_normals ? malloc((nv * 3 + 1) * sizeof(float)) : NULL;
    m.uv = h.has_uv ? malloc((nv * 2 + 1) * sizeof(float)) : NULL;
    /* Start with one triangle per face; polygons grow it. */
    if (!m.p || (h.has_normals && !m.n) || (h.has_uv && !m.uv) ||
        !grow((void **)&m.index, &cap_tris, (size_t)h.face->count * 3 + 3, sizeof *m.index)) {
        st = nomem(c);
        goto fail_mesh;
    }
    ply_in in = {.c = c,
                 .ascii = h.format == PLY_ASCII,
                 .base = buf,
                 .p = h.data,
                 .end = buf + size,
                 .next_line = h.data_line};
    for (size_t i = 0; i < h.n_elems && !st; i++) {
        in.elem = &h.elems[i];
        if (in.elem == h.vertex)
            st = ply_read_vertices(&in, &h, &m);
        else if (in.elem == h.face)
            st = ply_read_faces(&in, &h, &m, &cap_tris);
        else
            st = ply_skip_element(&in, in.elem);
    }
    if (st) goto fail_mesh;
    if (m.n_triangles == 0) {
        st = fail(c, TS_ERR_INVALID, "file has no faces");
        goto fail_mesh;
    }
    m.n_vertices = (uint32_t)nv;
    *out = m;
    ply_header_fini(&h);
    return TS_OK;
fail_mesh:
    ts_mesh_data_free(&m);
fail_header:
    ply_header_fini(&h);
    return st;
}

/* ==== entry points ==== */

static bool ext_is(const char *ext, const char *want)
{
    for (; *ext && *want; ext++, want++) {
        char ch = *ext >= 'A' && *ext <= 'Z' ? (char)(*ext - 'A' + 'a') : *ext;
        if (ch != *want) return false;
    }
    return *ext == '\0' && *want == '\0';
}

/* Parses a whole NUL-terminated file image; *out is set only on success. */
static ts_status parse_buffer(const load_ctx *c, bool is_obj, const char *buf, size_t size, ts_mesh_data *out)
{
    ts_mesh_data m = {0};
    ts_status st = is_obj ? obj_parse(c, buf, size, &m) : ply_parse(c, buf, size, &m);
    if (!st)
        *out = m;
    else
        ts_mesh_data_free(&m);
    return st;
}

ts_status ts_mesh_file_load(const char *base_dir, const char *rel_path, const ts_mesh_limits *limits,
                            ts_mesh_data *out, ts_error *err)
{
    load_ctx c = {.name = rel_path ? rel_path : "", .err = err};
    if (limits) c.lim = *limits;
    if (!out) return fail(&c, TS_ERR_INVALID, "no output mesh given");
    *out = (ts_mesh_data){0};
    if (!*c.name) return fail(&c, TS_ERR_INVALID, "empty path");
    const char *slash = strrchr(c.name, '/'), *leaf = slash ? slash + 1 : c.name;
    const char *dot = strrchr(leaf, '.');
    bool is_obj = dot && ext_is(dot + 1, "obj"), is_ply = dot && ext_is(dot + 1, "ply");
    if (!is_obj && !is_ply) return fail(&c, TS_ERR_INVALID, "unknown extension (expected .obj or .ply)");
    char *buf;
    size_t size;
    ts_status st = ts_scene_path_read(base_dir && *base_dir ? base_dir : ".", c.name, "mesh file",
                                      c.lim.max_file_bytes, &buf, &size, err);
    if (st) return st;
    st = parse_buffer(&c, is_obj, buf, size, out);
    free(buf);
    return st;
}

ts_status ts_mesh_load_memory(const char *name, const void *bytes, size_t size, const ts_mesh_limits *limits,
                              ts_mesh_data *out, ts_error *err)
{
    load_ctx c = {.name = name ? name : "", .err = err};
    if (limits) c.lim = *limits;
    if (!out) return fail(&c, TS_ERR_INVALID, "no output mesh given");
    *out = (ts_mesh_data){0};
    const char *slash = strrchr(c.name, '/'), *leaf = slash ? slash + 1 : c.name;
    const char *dot = strrchr(leaf, '.');
    bool is_obj = dot && ext_is(dot + 1, "obj"), is_ply = dot && ext_is(dot + 1, "ply");
    if (!is_obj && !is_ply) return fail(&c, TS_ERR_INVALID, "unknown extension (expected .obj or .ply)");
    if (size == 0 || !bytes) return fail(&c, TS_ERR_INVALID, "file is empty");
    if (over(size, c.lim.max_file_bytes) || size >= SIZE_MAX)
        return fail(&c, TS_ERR_LIMIT, "file is %llu bytes, more than the limit of %llu", (unsigned long long)size,
                    (unsigned long long)(c.lim.max_file_bytes ? c.lim.max_file_bytes : SIZE_MAX - 1));
    /* The parsers rely on a terminating NUL (strtod), so parse a copy. */
    char *buf = malloc(size + 1);
    if (!buf) return nomem(&c);
    memcpy(buf, bytes, size);
    buf[size] = '\0';
    ts_status st = parse_buffer(&c, is_obj, buf, size, out);
    free(buf);
    return st;
}

void ts_mesh_data_free(ts_mesh_data *m)
{
    if (!m) return;
    free(m->p);
    free(m->n);
    free(m->uv);
    free(m->index);
    *m = (ts_mesh_data){0};
}
