/* mesh_ply.c — PLY meshes; see mesh_ply.h for the accepted formats. */
#include "mesh/mesh_ply.h"

#include <limits.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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
    const ts_mesh_reader *c;
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
    ts_status r = ts_mesh_failv(in->c, st, where, fmt, ap);
    va_end(ap);
    return r;
}

static ts_status ply_truncated(const ply_in *in) { return ply_fail(in, TS_ERR_INVALID, "file is truncated"); }

/* Starts element item in->item: ASCII moves to the next non-blank line. */
static ts_status ply_begin_item(ply_in *in)
{
    ts_status polled = ts_mesh_poll(in->c, in->item);
    if (polled) return polled;
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
        while (q < in->le && ts_mesh_is_blank(*q))
            q++;
        if (q < in->le) return TS_OK;
    }
}

static bool ply_ascii_token(ply_in *in, const char **ts, const char **te)
{
    const char *p = in->lp;
    while (p < in->le && ts_mesh_is_blank(*p))
        p++;
    if (p >= in->le) {
        in->lp = p;
        return false;
    }
    *ts = p;
    while (p < in->le && !ts_mesh_is_blank(*p))
        p++;
    *te = in->lp = p;
    return true;
}

static ts_status ply_end_item(ply_in *in)
{
    const char *ts, *te;
    if (in->ascii && ply_ascii_token(in, &ts, &te))
        return ply_fail(in, TS_ERR_INVALID,
                        "unexpected extra value '" TS_MESH_TOKEN_FMT "' in a '%.*s' element",
                        TS_MESH_TOKEN_ARG(ts, te), in->elem->name_len, in->elem->name);
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
        if (!ts_mesh_parse_double(ts, te, out))
            return ply_fail(in, TS_ERR_INVALID, "malformed number '" TS_MESH_TOKEN_FMT "'",
                            TS_MESH_TOKEN_ARG(ts, te));
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
        if (!ts_mesh_parse_int(ts, te, out))
            return ply_fail(in, TS_ERR_INVALID, "malformed integer '" TS_MESH_TOKEN_FMT "'",
                            TS_MESH_TOKEN_ARG(ts, te));
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
        if (ts_mesh_token_is(s, e, ply_type_names[i].name)) {
            *t = ply_type_names[i].type;
            return true;
        }
    return false;
}

static ply_prop *ply_find(ply_elem *el, const char *name)
{
    for (size_t i = 0; i < el->n_props; i++)
        if (ts_mesh_token_is(el->props[i].name, el->props[i].name + el->props[i].name_len, name))
            return &el->props[i];
    return NULL;
}

/* Parses the header lines up to end_header into h. */
static ts_status ply_parse_header(const ts_mesh_reader *c, const char *buf, size_t size, ply_header *h)
{
    const char *end = buf + size, *p = buf;
    unsigned long line = 0;
    for (;;) {
        if (p >= end) {
            return line == 0 ? ts_mesh_fail(c, TS_ERR_INVALID, "file is empty")
                             : ts_mesh_fail(c, TS_ERR_INVALID, "header has no 'end_header' line");
        }
        const char *nl = memchr(p, '\n', (size_t)(end - p));
        const char *ls = p, *le = nl ? nl : end;
        p = nl ? nl + 1 : end;
        line++;
        const char *tok[6][2];
        int nt = 0;
        for (const char *q = ls;;) {
            while (q < le && ts_mesh_is_blank(*q))
                q++;
            if (q >= le) break;
            const char *ts = q;
            while (q < le && !ts_mesh_is_blank(*q))
                q++;
            if (nt < 6) {
                tok[nt][0] = ts;
                tok[nt][1] = q;
            }
            nt++;
        }
#define TOK_IS(i, word) (nt > (i) && ts_mesh_token_is(tok[i][0], tok[i][1], word))
        if (line == 1) {
            if (!(nt == 1 && TOK_IS(0, "ply")))
                return ts_mesh_fail(c, TS_ERR_INVALID, "not a PLY file (no 'ply' first line)");
            continue;
        }
        if (nt == 0 || TOK_IS(0, "comment") || TOK_IS(0, "obj_info")) continue;
        if (TOK_IS(0, "end_header") && nt == 1) break;
        if (TOK_IS(0, "format")) {
            if (nt != 3 || !TOK_IS(2, "1.0"))
                return ts_mesh_fail_line(c, line, TS_ERR_INVALID,
                                         "expected 'format <ascii|binary_little_endian> 1.0'");
            if (TOK_IS(1, "ascii"))
                h->format = PLY_ASCII;
            else if (TOK_IS(1, "binary_little_endian"))
                h->format = PLY_BINARY_LE;
            else if (TOK_IS(1, "binary_big_endian"))
                return ts_mesh_fail_line(
                    c, line, TS_ERR_UNSUPPORTED,
                    "binary_big_endian PLY is not supported (use ascii or binary_little_endian)");
            else
                return ts_mesh_fail_line(c, line, TS_ERR_INVALID,
                                         "unknown PLY format '" TS_MESH_TOKEN_FMT "'",
                                         TS_MESH_TOKEN_ARG(tok[1][0], tok[1][1]));
        } else if (TOK_IS(0, "element")) {
            int64_t count;
            if (nt != 3 || !ts_mesh_parse_int(tok[2][0], tok[2][1], &count) || count < 0 || *tok[2][0] == '-')
                return ts_mesh_fail_line(c, line, TS_ERR_INVALID, "expected 'element <name> <count>'");
            if (!ts_mesh_grow((void **)&h->elems, &h->cap_elems, h->n_elems + 1, sizeof *h->elems))
                return ts_mesh_nomem(c);
            ply_elem *el = &h->elems[h->n_elems++];
            ptrdiff_t len = tok[1][1] - tok[1][0];
            *el = (ply_elem){.name = tok[1][0],
                             .name_len = len > INT_MAX / 2 ? INT_MAX / 2 : (int)len,
                             .count = (uint64_t)count};
            if (ts_mesh_token_is(tok[1][0], tok[1][1], "vertex") ||
                ts_mesh_token_is(tok[1][0], tok[1][1], "face")) {
                ply_elem **slot = *tok[1][0] == 'v' ? &h->vertex : &h->face;
                if (*slot)
                    return ts_mesh_fail_line(c, line, TS_ERR_INVALID, "second '%.*s' element", el->name_len,
                                             el->name);
                *slot = el;
            }
        } else if (TOK_IS(0, "property")) {
            if (h->n_elems == 0)
                return ts_mesh_fail_line(c, line, TS_ERR_INVALID, "property before any element");
            ply_elem *el = &h->elems[h->n_elems - 1];
            ply_prop pr = {0};
            int name_tok;
            if (TOK_IS(1, "list")) {
                if (nt != 5 || !ply_parse_type(tok[2][0], tok[2][1], &pr.count_type) ||
                    !ply_parse_type(tok[3][0], tok[3][1], &pr.type))
                    return ts_mesh_fail_line(c, line, TS_ERR_INVALID,
                                             "expected 'property list <count type> <type> <name>'");
                if (!ply_is_int(pr.count_type))
                    return ts_mesh_fail_line(c, line, TS_ERR_INVALID,
                                             "a list count must have an integer type");
                pr.is_list = true;
                name_tok = 4;
            } else {
                if (nt != 3 || !ply_parse_type(tok[1][0], tok[1][1], &pr.type))
                    return ts_mesh_fail_line(c, line, TS_ERR_INVALID, "expected 'property <type> <name>'");
                name_tok = 2;
            }
            pr.name = tok[name_tok][0];
            pr.name_len = (int)(tok[name_tok][1] - tok[name_tok][0] > INT_MAX / 2
                                    ? INT_MAX / 2
                                    : tok[name_tok][1] - tok[name_tok][0]);
            if (!ts_mesh_grow((void **)&el->props, &el->cap_props, el->n_props + 1, sizeof *el->props))
                return ts_mesh_nomem(c);
            el->props[el->n_props++] = pr;
        } else {
            return ts_mesh_fail_line(c, line, TS_ERR_INVALID,
                                     "unexpected header line starting '" TS_MESH_TOKEN_FMT "'",
                                     TS_MESH_TOKEN_ARG(tok[0][0], tok[0][1]));
        }
#undef TOK_IS
    }
    h->data = p;
    h->data_line = line + 1;
    if (h->format == PLY_NONE) return ts_mesh_fail(c, TS_ERR_INVALID, "header has no 'format' line");
    return TS_OK;
}

/* Gives the vertex and face properties their roles and checks they are usable. */
static ts_status ply_assign_roles(const ts_mesh_reader *c, ply_header *h)
{
    if (!h->vertex) return ts_mesh_fail(c, TS_ERR_INVALID, "PLY header has no 'vertex' element");
    if (!h->face) return ts_mesh_fail(c, TS_ERR_INVALID, "PLY header has no 'face' element");
    static const char *const xyz[] = {"x", "y", "z", "nx", "ny", "nz"};
    for (int i = 0; i < 6; i++) {
        ply_prop *pr = ply_find(h->vertex, xyz[i]);
        if (!pr) {
            if (i < 3)
                return ts_mesh_fail(c, TS_ERR_INVALID, "element 'vertex' has no property '%s'", xyz[i]);
            continue;
        }
        if (pr->is_list) return ts_mesh_fail(c, TS_ERR_INVALID, "vertex property '%s' is a list", xyz[i]);
        pr->role = (ply_role)(ROLE_X + i);
    }
    bool nx = ply_find(h->vertex, "nx"), ny = ply_find(h->vertex, "ny"), nz = ply_find(h->vertex, "nz");
    if ((nx || ny || nz) && !(nx && ny && nz))
        return ts_mesh_fail(c, TS_ERR_INVALID, "element 'vertex' has some but not all of nx, ny, nz");
    h->has_normals = nx;
    static const char *const uv_names[][2] = {
        {"u", "v"}, {"s", "t"}, {"texture_u", "texture_v"}, {"texture_s", "texture_t"}};
    for (size_t i = 0; i < sizeof uv_names / sizeof uv_names[0] && !h->has_uv; i++) {
        ply_prop *u = ply_find(h->vertex, uv_names[i][0]), *v = ply_find(h->vertex, uv_names[i][1]);
        if (!u || !v) continue;
        if (u->is_list || v->is_list)
            return ts_mesh_fail(c, TS_ERR_INVALID, "vertex property '%s' is a list",
                                u->is_list ? uv_names[i][0] : uv_names[i][1]);
        u->role = ROLE_U;
        v->role = ROLE_V;
        h->has_uv = true;
    }
    ply_prop *ind = ply_find(h->face, "vertex_indices");
    if (!ind) ind = ply_find(h->face, "vertex_index");
    if (!ind) return ts_mesh_fail(c, TS_ERR_INVALID, "element 'face' has no property 'vertex_indices'");
    if (!ind->is_list || !ply_is_int(ind->type))
        return ts_mesh_fail(c, TS_ERR_INVALID, "face property 'vertex_indices' must be a list of integers");
    ind->role = ROLE_INDICES;
    return TS_OK;
}

/* Checks every element count against the limits and the bytes after the header. */
static ts_status ply_check_counts(const ts_mesh_reader *c, const ply_header *h, size_t data_bytes)
{
    if (ts_mesh_over(h->vertex->count, c->lim.max_vertices) || h->vertex->count >= UINT32_MAX)
        return ts_mesh_fail(c, TS_ERR_LIMIT, "file has %llu vertices, more than the limit of %llu",
                            (unsigned long long)h->vertex->count,
                            (unsigned long long)(c->lim.max_vertices ? c->lim.max_vertices : UINT32_MAX - 1));
    if (ts_mesh_over(h->face->count, c->lim.max_triangles) || h->face->count >= UINT32_MAX)
        return ts_mesh_fail(
            c, TS_ERR_LIMIT, "file has %llu faces, more than the limit of %llu triangles",
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
            return ts_mesh_fail(
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
            if (!ts_mesh_to_float(val[pr->role], &unused)) {
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
            if (!ts_mesh_normal_ok(m->n + 3 * i))
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
    const ts_mesh_reader *c = in->c;
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
            if (ts_mesh_over(tris, c->lim.max_triangles) || tris >= UINT32_MAX)
                return ply_fail(
                    in, TS_ERR_LIMIT, "more than the limit of %llu triangles",
                    (unsigned long long)(c->lim.max_triangles ? c->lim.max_triangles : UINT32_MAX - 1));
            if (!ts_mesh_grow((void **)&m->index, cap_tris, (size_t)tris * 3, sizeof *m->index))
                return ts_mesh_nomem(c);
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

static ts_status ply_parse(const ts_mesh_reader *c, const char *buf, size_t size, ts_mesh_data *out)
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
        !ts_mesh_grow((void **)&m.index, &cap_tris, (size_t)h.face->count * 3 + 3, sizeof *m.index)) {
        st = ts_mesh_nomem(c);
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
        st = ts_mesh_fail(c, TS_ERR_INVALID, "file has no faces");
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

ts_status ts_mesh_ply_parse(const ts_mesh_reader *r, const char *text, size_t size, ts_mesh_data *out)
{
    ts_mesh_data m = {0};
    ts_status st = ply_parse(r, text, size, &m);
    if (!st)
        *out = m;
    else
        ts_mesh_data_free(&m);
    return st;
}
