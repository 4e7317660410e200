/* mesh_obj.c — Wavefront OBJ meshes; see mesh_obj.h for the accepted statements. */
#include "mesh/mesh_obj.h"

#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "core/hash.h"

#define NO_INDEX UINT32_MAX

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
        while (p < e && (ts_mesh_is_blank(*p) || *p == '\n'))
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
    while (p < e && !ts_mesh_is_blank(*p) && *p != '\n' &&
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
    const ts_mesh_reader *c;
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
        if (!ts_mesh_parse_double(ts, te, &d))
            return ts_mesh_fail_line(o->c, line, TS_ERR_INVALID,
                                     "%s: malformed number '" TS_MESH_TOKEN_FMT "'", what,
                                     TS_MESH_TOKEN_ARG(ts, te));
        float f;
        if (!ts_mesh_to_float(d, &f))
            return ts_mesh_fail_line(o->c, line, TS_ERR_INVALID,
                                     "%s: '" TS_MESH_TOKEN_FMT "' is not a finite number", what,
                                     TS_MESH_TOKEN_ARG(ts, te));
        if (k < want) dst[k] = f;
        k++;
        if (max_n && k > max_n)
            return ts_mesh_fail_line(o->c, line, TS_ERR_INVALID, "%s: too many values (at most %u)", what,
                                     max_n);
    }
    if (k < min_n)
        return ts_mesh_fail_line(o->c, line, TS_ERR_INVALID, "%s: expected %u numbers, found %u", what, min_n,
                                 k);
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
        return ts_mesh_fail_line(o->c, line, TS_ERR_INVALID, "%s index 0 is invalid (indices start at 1)",
                                 what);
    if (raw > 0)
        return ts_mesh_fail_line(o->c, line, TS_ERR_INVALID, "%s index %lld out of range (file has %llu %s)",
                                 what, (long long)raw, (unsigned long long)total, plural);
    return ts_mesh_fail_line(o->c, line, TS_ERR_INVALID,
                             "%s index %lld out of range (%llu %s defined before this line)", what,
                             (long long)raw, (unsigned long long)so_far, plural);
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
        if (!ts_mesh_parse_int(cut[i], part_end[i], &raw[i])) goto malformed;
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
    return ts_mesh_fail_line(o->c, line, TS_ERR_INVALID, "malformed face vertex '" TS_MESH_TOKEN_FMT "'",
                             TS_MESH_TOKEN_ARG(ts, te));
}

static ts_status obj_face(obj_state *o, unsigned long line, const char *s, const char *e)
{
    const char *ts, *te;
    size_t first = o->n_corners;
    uint32_t k = 0;
    while (obj_token(&s, e, &ts, &te)) {
        if (!ts_mesh_grow((void **)&o->corners, &o->cap_corners, o->n_corners + 1, sizeof *o->corners))
            return ts_mesh_nomem(o->c);
        obj_corner *cr = &o->corners[o->n_corners];
        ts_status st = obj_corner_parse(o, line, ts, te, cr);
        if (st) return st;
        if (cr->vt == NO_INDEX) o->all_vt = false;
        if (cr->vn == NO_INDEX) o->all_vn = false;
        o->n_corners++;
        if (++k == UINT32_MAX)
            return ts_mesh_fail_line(o->c, line, TS_ERR_LIMIT, "face has too many vertices");
    }
    if (k < 3) {
        o->n_corners = first;
        return ts_mesh_fail_line(o->c, line, TS_ERR_INVALID, "face has %u vertices (at least 3 needed)", k);
    }
    o->n_triangles += k - 2;
    if (ts_mesh_over(o->n_triangles, o->c->lim.max_triangles) || o->n_triangles > UINT32_MAX)
        return ts_mesh_fail_line(
            o->c, line, TS_ERR_LIMIT, "more than the limit of %llu triangles",
            (unsigned long long)(o->c->lim.max_triangles ? o->c->lim.max_triangles : UINT32_MAX));
    if (!ts_mesh_grow((void **)&o->face_size, &o->cap_faces, o->n_faces + 1, sizeof *o->face_size))
        return ts_mesh_nomem(o->c);
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
    const ts_mesh_reader *c = o->c;
    bool use_vt = o->all_vt, use_vn = o->all_vn;
    obj_slot *tab = NULL;
    size_t cap = 0;
    uint32_t n_out = 0;
    ts_status st = TS_OK;
    if (!obj_table_grow(&tab, &cap)) return ts_mesh_nomem(c);
    for (size_t i = 0; i < o->n_corners; i++) {
        obj_corner *cr = &o->corners[i];
        uint32_t vt = use_vt ? cr->vt : NO_INDEX, vn = use_vn ? cr->vn : NO_INDEX;
        size_t h = ts_hash4(cr->v, vt, vn, 0) & (cap - 1);
        while (tab[h].out != NO_INDEX && !(tab[h].v == cr->v && tab[h].vt == vt && tab[h].vn == vn))
            h = (h + 1) & (cap - 1);
        if (tab[h].out == NO_INDEX) {
            if (ts_mesh_over((uint64_t)n_out + 1, c->lim.max_vertices) || n_out == UINT32_MAX - 1) {
                st = ts_mesh_fail(
                    c, TS_ERR_LIMIT, "more than the limit of %llu vertices",
                    (unsigned long long)(c->lim.max_vertices ? c->lim.max_vertices : UINT32_MAX - 1));
                goto fail_tab;
            }
            tab[h] = (obj_slot){cr->v, vt, vn, n_out++};
            cr->v = tab[h].out;
            if ((size_t)n_out * 2 > cap && !obj_table_grow(&tab, &cap)) {
                st = ts_mesh_nomem(c);
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
        st = ts_mesh_nomem(c);
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

static ts_status obj_parse(const ts_mesh_reader *c, const char *buf, size_t size, ts_mesh_data *out)
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
        if (ts_mesh_token_is(ts, te, "v"))
            o.nv++;
        else if (ts_mesh_token_is(ts, te, "vt"))
            o.nvt++;
        else if (ts_mesh_token_is(ts, te, "vn"))
            o.nvn++;
    }
    if (ts_mesh_over(o.nv, c->lim.max_vertices))
        return ts_mesh_fail(c, TS_ERR_LIMIT, "file has %llu vertices, more than the limit of %llu",
                            (unsigned long long)o.nv, (unsigned long long)c->lim.max_vertices);
    if (o.nv >= UINT32_MAX || o.nvt >= UINT32_MAX || o.nvn >= UINT32_MAX)
        return ts_mesh_fail(c, TS_ERR_LIMIT, "more than %u vertex attributes of one kind", UINT32_MAX - 1);
    /* + 1: malloc(0) may return NULL. Each statement takes ≥ 8 bytes of file, so these
     * sizes are bounded by a few times the file size. */
    o.pos = malloc(((size_t)o.nv * 3 + 1) * sizeof(float));
    o.tex = malloc(((size_t)o.nvt * 2 + 1) * sizeof(float));
    o.nrm = malloc(((size_t)o.nvn * 3 + 1) * sizeof(float));
    if (!o.pos || !o.tex || !o.nrm) {
        st = ts_mesh_nomem(c);
        goto fail_arrays;
    }

    /* Pass 2: parse. */
    it = (obj_lines){buf, end, 1};
    while (obj_next_line(&it, &ls, &le, &line)) {
        const char *s = ls;
        if ((st = ts_mesh_poll(c, line))) goto fail_faces;
        if (!obj_token(&s, le, &ts, &te)) continue;
        if (ts_mesh_token_is(ts, te, "v")) {
            st = obj_numbers(&o, line, "vertex", s, le, 3, 0, o.pos + 3 * o.iv, 3);
            o.iv++;
        } else if (ts_mesh_token_is(ts, te, "vt")) {
            st = obj_numbers(&o, line, "texture coordinate", s, le, 1, 3, o.tex + 2 * o.ivt, 2);
            o.ivt++;
        } else if (ts_mesh_token_is(ts, te, "vn")) {
            st = obj_numbers(&o, line, "normal", s, le, 3, 3, o.nrm + 3 * o.ivn, 3);
            if (!st && !ts_mesh_normal_ok(o.nrm + 3 * o.ivn))
                st = ts_mesh_fail_line(c, line, TS_ERR_INVALID, "normal has zero length");
            o.ivn++;
        } else if (ts_mesh_token_is(ts, te, "f")) {
            st = obj_face(&o, line, s, le);
        } else {
            /* Any other statement is ignored, but a keyword must look like one: this
             * turns a binary file with an .obj name into an error, not an empty mesh. */
            for (const char *q = ts; q < te; q++) {
                char ch = *q;
                if (!((ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || (ch >= '0' && ch <= '9') ||
                      ch == '_')) {
                    st = ts_mesh_fail_line(c, line, TS_ERR_INVALID, "unexpected '" TS_MESH_TOKEN_FMT "'",
                                           TS_MESH_TOKEN_ARG(ts, te));
                    break;
                }
            }
        }
        if (st) goto fail_faces;
    }
    if (o.iv != o.nv || o.ivt != o.nvt || o.ivn != o.nvn) {
        st = ts_mesh_fail(c, TS_ERR_INTERNAL, "attribute count changed between passes");
        goto fail_faces;
    }
    if (o.n_faces == 0) {
        st = ts_mesh_fail(c, TS_ERR_INVALID, "file has no faces");
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

ts_status ts_mesh_obj_parse(const ts_mesh_reader *r, const char *text, size_t size, ts_mesh_data *out)
{
    ts_mesh_data m = {0};
    ts_status st = obj_parse(r, text, size, &m);
    if (!st)
        *out = m;
    else
        ts_mesh_data_free(&m);
    return st;
}
