/* pbrt_parser.c — pbrt-v3 directives and graphics state; see pbrt_parser.h.
 *
 * Structure: a stack of open files (each a streaming lexer) yields one current token;
 * the directive loop dispatches on it. Entities are collected in heap vectors while
 * parsing (their parameter values already in the scene's arena) and copied into the
 * arena, exactly sized, at the end. Scoped names (float and spectrum textures, named
 * materials) live in one hash table with an undo log: AttributeBegin remembers the log's
 * length and AttributeEnd rolls the table back to it, so scoping costs O(names defined
 * in the block), never a copy of the tables as pbrt-v3 makes. The CTM is interned: the
 * first entity that needs it after a change copies it into the arena and the following
 * ones share that copy. */
#ifndef _XOPEN_SOURCE
#define _XOPEN_SOURCE 700 /* realpath */
#endif

#include "pbrt3/pbrt_parser.h"

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <nettle/sha2.h>

#include "core/scene_path.h"

/* ---- growable heap vectors ---- */

typedef struct vec {
    void *data;
    size_t n, cap;
} vec;

typedef struct parser parser;

/* ---- the name table: (space, name) → int32, never shrinking; -1 = not defined ---- */

enum { NS_FLOAT_TEX, NS_SPECTRUM_TEX, NS_MATERIAL, NS_COORDSYS, NS_OBJECT };

typedef struct name_entry {
    const char *name; /* arena; NULL = empty slot */
    uint32_t hash;
    int32_t space;
    int32_t value;
} name_entry;

/* Slots move when the table grows, so the undo log keeps keys, not slots. */
typedef struct undo_entry {
    const char *name;
    int32_t space;
    int32_t previous;
} undo_entry;

enum { BLOCK_ATTRIBUTE, BLOCK_TRANSFORM, BLOCK_OBJECT };

typedef struct gstate {
    int32_t material; /* index, or -1 (default): Material or NamedMaterial, resolved where it is written */
    int32_t area_light;
    bool reverse_orientation;
    const char *inside_medium, *outside_medium;
} gstate;

typedef struct block {
    int kind;
    ts_pbrt_loc loc;
    const char *object_name; /* BLOCK_OBJECT */
    ts_mat4 ctm, ctm_end;
    const ts_mat4 *ctm_ptr, *ctm_end_ptr;
    unsigned active;
    gstate gs;
    size_t undo_mark;
} block;

typedef struct file_frame {
    ts_pbrt_lexer *lx;
    char *real_path;     /* malloc; NULL for text held in memory */
    const char *display; /* arena */
} file_frame;

enum { ACTIVE_START = 1, ACTIVE_END = 2, ACTIVE_ALL = 3 };

/* A named coordinate system: both CTMs, as pbrt-v3's TransformSet. */
typedef struct coordsys {
    ts_mat4 start, end;
} coordsys;

struct parser {
    ts_pbrt_scene *s;
    ts_error *err;
    ts_pbrt_limits lim;
    const char *root; /* base folder for file references, or NULL: none allowed */
    size_t heap_bytes;

    file_frame files[64];
    int nfiles;
    ts_pbrt_token tok;
    uint64_t n_tokens; /* read so far: every TS_PBRT_POLL-th polls lim.cancel */

    /* state */
    enum { PHASE_OPTIONS, PHASE_WORLD, PHASE_ENDED } phase;
    /* pbrt-v3's two CTMs (curTransform[0], [1]): at the start and the end time; the
     * transform directives change those ActiveTransform selects. */
    ts_mat4 ctm, ctm_end;
    const ts_mat4 *ctm_ptr, *ctm_end_ptr; /* arena copies, or NULL until one is needed */
    unsigned active;
    gstate gs;
    int32_t current_object;
    bool camera_given;

    name_entry *table;
    size_t table_cap, table_n;
    vec undo;   /* undo_entry */
    vec blocks; /* block */
    vec coordsys; /* coordsys */

    /* entities */
    vec textures, materials, area_lights, lights, shapes, objects, instances, media, warnings;

    /* parameter-list scratch */
    vec items;   /* ts_pbrt_param */
    vec floats;  /* float */
    vec ints;    /* int32_t */
    vec bools;   /* bool */
    vec strings; /* const char * */
    struct sha256_ctx digest; /* the scene digest over the files read (ts_pbrt_scene.digest) */
};

static ts_status perr(parser *p, ts_pbrt_loc loc, ts_status st, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static ts_status perr(parser *p, ts_pbrt_loc loc, ts_status st, const char *fmt, ...)
{
    char msg[TS_ERROR_MAX];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    ts_error_set(p->err, st, "%s:%u:%u: %s", loc.file ? loc.file : "?", loc.line, loc.column, msg);
    if (p->err) ts_pbrt_sanitize_utf8(p->err->message);
    return st;
}

static ts_status nomem(parser *p)
{
    if (p->lim.max_memory)
        return perr(p, p->tok.loc, TS_ERR_NOMEM, "out of memory (or past the scene's memory limit of %zu bytes)",
                    p->lim.max_memory);
    return perr(p, p->tok.loc, TS_ERR_NOMEM, "out of memory");
}

static bool vec_reserve(parser *p, vec *v, size_t elem, size_t want)
{
    if (want <= v->cap) return true;
    size_t ncap = v->cap ? v->cap : 16;
    while (ncap < want) {
        if (ncap > SIZE_MAX / 2 / elem) return false;
        ncap *= 2;
    }
    size_t grow = (ncap - v->cap) * elem;
    if (p->lim.max_memory && p->heap_bytes + grow > p->lim.max_memory) return false;
    void *d = realloc(v->data, ncap * elem);
    if (!d) return false;
    p->heap_bytes += grow;
    v->data = d;
    v->cap = ncap;
    return true;
}

/* Appends one zeroed element; returns it or NULL (out of memory, nothing changed). */
static void *vec_push(parser *p, vec *v, size_t elem)
{
    if (!vec_reserve(p, v, elem, v->n + 1)) return NULL;
    void *e = (char *)v->data + v->n * elem;
    memset(e, 0, elem);
    v->n++;
    return e;
}

static void vec_free(vec *v)
{
    free(v->data);
    v->data = NULL;
    v->n = v->cap = 0;
}

#define VEC_AT(v, T, i) (((T *)(v).data)[i])

static char *astrdup(parser *p, const char *s)
{
    return ts_arena_strdup(&p->s->arena, s);
}

static ts_status warn(parser *p, ts_pbrt_loc loc, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static ts_status warn(parser *p, ts_pbrt_loc loc, const char *fmt, ...)
{
    if (p->warnings.n >= p->lim.max_warnings) {
        p->s->warnings_dropped++;
        return TS_OK;
    }
    char buf[TS_ERROR_MAX];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    ts_pbrt_sanitize_utf8(buf);
    ts_pbrt_warning *w = vec_push(p, &p->warnings, sizeof *w);
    char *m = astrdup(p, buf);
    if (!w || !m) return nomem(p);
    w->loc = loc;
    w->message = m;
    return TS_OK;
}

/* ---- name table ---- */

static uint32_t hash_name(int32_t space, const char *s)
{
    uint32_t h = 2166136261u ^ (uint32_t)space;
    for (; *s; s++) h = (h ^ (unsigned char)*s) * 16777619u;
    return h;
}

static name_entry *table_find(parser *p, int32_t space, const char *name, uint32_t h)
{
    if (!p->table_cap) return NULL;
    size_t mask = p->table_cap - 1;
    for (size_t i = h & mask;; i = (i + 1) & mask) {
        name_entry *e = &p->table[i];
        if (!e->name) return e;
        if (e->hash == h && e->space == space && strcmp(e->name, name) == 0) return e;
    }
}

static int32_t name_lookup(parser *p, int32_t space, const char *name)
{
    name_entry *e = table_find(p, space, name, hash_name(space, name));
    return e && e->name ? e->value : -1;
}

static bool table_grow(parser *p)
{
    size_t ncap = p->table_cap ? p->table_cap * 2 : 256;
    size_t bytes = ncap * sizeof(name_entry);
    if (p->lim.max_memory && p->heap_bytes + bytes > p->lim.max_memory) return false;
    name_entry *nt = calloc(ncap, sizeof *nt);
    if (!nt) return false;
    for (size_t i = 0; i < p->table_cap; i++) {
        name_entry *e = &p->table[i];
        if (!e->name) continue;
        size_t j = e->hash & (ncap - 1);
        while (nt[j].name) j = (j + 1) & (ncap - 1);
        nt[j] = *e;
    }
    p->heap_bytes += bytes - p->table_cap * sizeof(name_entry);
    free(p->table);
    p->table = nt;
    p->table_cap = ncap;
    return true;
}

/* Sets (space, name) to value; with scoped, records the old value in the undo log.
 * *previous (if not NULL) gets the old value (-1: none). */
static ts_status name_define(parser *p, int32_t space, const char *name, int32_t value, bool scoped,
                             int32_t *previous)
{
    if ((p->table_n + 1) * 2 > p->table_cap && !table_grow(p)) return nomem(p);
    uint32_t h = hash_name(space, name);
    name_entry *e = table_find(p, space, name, h);
    int32_t old = -1;
    if (e->name) {
        old = e->value;
    } else {
        const char *key = astrdup(p, name);
        if (!key) return nomem(p);
        e->name = key;
        e->hash = h;
        e->space = space;
        p->table_n++;
    }
    if (scoped && p->blocks.n > 0) {
        undo_entry *u = vec_push(p, &p->undo, sizeof *u);
        if (!u) return nomem(p);
        u->name = e->name;
        u->space = space;
        u->previous = old;
    }
    e->value = value;
    if (previous) *previous = old;
    return TS_OK;
}

static void undo_to(parser *p, size_t mark)
{
    while (p->undo.n > mark) {
        undo_entry *u = &VEC_AT(p->undo, undo_entry, p->undo.n - 1);
        name_entry *e = table_find(p, u->space, u->name, hash_name(u->space, u->name));
        if (e && e->name) e->value = u->previous;
        p->undo.n--;
    }
}

/* ---- tokens across the file stack ---- */

/* Adds one file read to the scene digest: its name as written, its size and its SHA-256. */
static void digest_file(parser *p, ts_pbrt_lexer *lx, const char *display)
{
    uint8_t h[32], size[8];
    uint64_t n = ts_pbrt_lexer_bytes(lx);
    ts_pbrt_lexer_digest(lx, h);
    for (int i = 0; i < 8; i++) size[i] = (uint8_t)(n >> (8 * i));
    sha256_update(&p->digest, strlen(display) + 1, (const uint8_t *)display);
    sha256_update(&p->digest, sizeof size, size);
    sha256_update(&p->digest, sizeof h, h);
}

static void pop_file(parser *p)
{
    file_frame *f = &p->files[--p->nfiles];
    /* The top-level file counts without its name: the same scene at another path (a farm
     * node's copy) has the same digest. */
    digest_file(p, f->lx, p->nfiles == 0 || !f->display ? "" : f->display);
    p->s->bytes_parsed += ts_pbrt_lexer_bytes(f->lx);
    ts_pbrt_lexer_destroy(f->lx);
    free(f->real_path);
    f->lx = NULL;
    f->real_path = NULL;
}

/* Moves to the next token; the end of an included file continues in the includer. */
#define TS_PBRT_POLL 16384u

static ts_status advance(parser *p)
{
    if (++p->n_tokens % TS_PBRT_POLL == 0) {
        ts_status polled = ts_cancel_check(p->lim.cancel, p->err);
        if (polled) return polled;
    }
    for (;;) {
        ts_status st = ts_pbrt_lexer_next(p->files[p->nfiles - 1].lx, &p->tok, p->err);
        if (st) return st;
        if (p->tok.kind != TS_PBRT_TOKEN_EOF || p->nfiles == 1) return TS_OK;
        pop_file(p);
    }
}

static const char *describe(parser *p, char *buf, size_t n) { return ts_pbrt_token_describe(&p->tok, buf, n); }

static ts_status expect_numbers(parser *p, const char *directive, double *v, int n)
{
    for (int i = 0; i < n; i++) {
        if (p->tok.kind != TS_PBRT_TOKEN_NUMBER) {
            char d[96];
            return perr(p, p->tok.loc, TS_ERR_INVALID, "%s expects %d numbers, got %s after %d", directive, n,
                        describe(p, d, sizeof d), i);
        }
        v[i] = p->tok.number;
        ts_status st = advance(p);
        if (st) return st;
    }
    return TS_OK;
}

/* The current token as a quoted string copied into the arena (then advances). */
static ts_status expect_string(parser *p, const char *directive, const char *what, const char **out,
                               ts_pbrt_loc *loc)
{
    *out = NULL;
    if (p->tok.kind != TS_PBRT_TOKEN_STRING) {
        char d[96];
        return perr(p, p->tok.loc, TS_ERR_INVALID, "%s: expected %s in quotes, got %s", directive, what,
                    describe(p, d, sizeof d));
    }
    if (loc) *loc = p->tok.loc;
    *out = astrdup(p, p->tok.text);
    if (!*out) return nomem(p);
    return advance(p);
}

/* ---- parameter lists ---- */

static ts_status param_fail(parser *p, ts_pbrt_loc loc, const ts_pbrt_params *ps, const char *decl, ts_status st,
                            const char *fmt, ...) __attribute__((format(printf, 6, 7)));
static ts_status param_fail(parser *p, ts_pbrt_loc loc, const ts_pbrt_params *ps, const char *decl, ts_status st,
                            const char *fmt, ...)
{
    char msg[TS_ERROR_MAX];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return perr(p, loc, st, "%s \"%.100s\": \"%.80s\" %s", ps->directive, ps->directive_arg, decl, msg);
}

/* Reads a .spd file (wavelength-value pairs, # comments) into p->floats. */
static ts_status read_spd(parser *p, const ts_pbrt_params *ps, const char *decl, ts_pbrt_loc loc, const char *file)
{
    char *text = NULL;
    size_t len = 0;
    ts_status st = ts_scene_path_read(p->root, file, "spectrum file", p->lim.max_file_bytes, &text, &len, p->err);
    if (st) return param_fail(p, loc, ps, decl, st, "%s", p->err->message);
    ts_pbrt_lexer *lx = NULL;
    char *display = astrdup(p, file);
    if (!display) {
        st = nomem(p);
        goto fail_text;
    }
    st = ts_pbrt_lexer_from_memory(text, len, display, &lx, p->err);
    if (st) goto fail_text;
    p->floats.n = 0;
    for (;;) {
        ts_pbrt_token t;
        st = ts_pbrt_lexer_next(lx, &t, p->err);
        if (st) {
            char inner[TS_ERROR_MAX];
            memcpy(inner, p->err->message, sizeof inner);
            st = param_fail(p, loc, ps, decl, st, "%s", inner);
            goto fail_lexer;
        }
        if (t.kind == TS_PBRT_TOKEN_EOF) break;
        if (t.kind != TS_PBRT_TOKEN_NUMBER || fabs(t.number) > FLT_MAX) {
            char d[96];
            st = param_fail(p, loc, ps, decl, TS_ERR_INVALID, "%s:%u:%u: expected a number, got %s", display,
                            t.loc.line, t.loc.column, ts_pbrt_token_describe(&t, d, sizeof d));
            goto fail_lexer;
        }
        float *f = vec_push(p, &p->floats, sizeof(float));
        if (!f) {
            st = nomem(p);
            goto fail_lexer;
        }
        *f = (float)t.number;
    }
    if (p->floats.n < 2 || p->floats.n % 2)
        st = param_fail(p, loc, ps, decl, TS_ERR_INVALID,
                        "spectrum file '%s' holds %zu numbers; it needs (wavelength, value) pairs", file, p->floats.n);
    if (!st) digest_file(p, lx, display);
fail_lexer:
    ts_pbrt_lexer_destroy(lx);
fail_text:
    free(text);
    return st;
}

/* Copies n elements of scratch into the arena. */
static void *arena_copy(parser *p, const void *src, size_t n, size_t elem)
{
    void *d = ts_arena_calloc(&p->s->arena, n ? n : 1, elem);
    if (d && n) memcpy(d, src, n * elem);
    return d;
}

static bool is_numeric_type(ts_pbrt_param_type t)
{
    return t != TS_PBRT_PARAM_BOOL && t != TS_PBRT_PARAM_STRING && t != TS_PBRT_PARAM_TEXTURE &&
           t != TS_PBRT_PARAM_SPECTRUM;
}

/* Adds the current token (a value) to the scratch arrays for a parameter of type t. */
static ts_status add_value(parser *p, ts_pbrt_param_type t, const ts_pbrt_params *ps, const char *decl,
                           bool *numbers, bool *strings)
{
    ts_pbrt_token *k = &p->tok;
    char d[96];
    if (t == TS_PBRT_PARAM_BOOL) {
        const char *w = NULL;
        if (k->kind == TS_PBRT_TOKEN_STRING || k->kind == TS_PBRT_TOKEN_WORD) w = k->text;
        if (!w || (strcmp(w, "true") != 0 && strcmp(w, "false") != 0))
            return param_fail(p, k->loc, ps, decl, TS_ERR_INVALID, "expects true or false, got %s",
                              describe(p, d, sizeof d));
        bool *b = vec_push(p, &p->bools, sizeof(bool));
        if (!b) return nomem(p);
        *b = w[0] == 't';
        return TS_OK;
    }
    if (k->kind == TS_PBRT_TOKEN_NUMBER) {
        if (t == TS_PBRT_PARAM_STRING || t == TS_PBRT_PARAM_TEXTURE)
            return param_fail(p, k->loc, ps, decl, TS_ERR_INVALID, "expects a quoted string, got %s",
                              describe(p, d, sizeof d));
        if (*strings)
            return param_fail(p, k->loc, ps, decl, TS_ERR_INVALID, "mixes strings and numbers");
        *numbers = true;
        double v = k->number;
        if (t == TS_PBRT_PARAM_INTEGER) {
            if (v != floor(v) || v < INT32_MIN || v > INT32_MAX)
                return param_fail(p, k->loc, ps, decl, TS_ERR_INVALID, "expects integers, got %.17g", v);
            int32_t *i = vec_push(p, &p->ints, sizeof(int32_t));
            if (!i) return nomem(p);
            *i = (int32_t)v;
            return TS_OK;
        }
        if (fabs(v) > FLT_MAX)
            return param_fail(p, k->loc, ps, decl, TS_ERR_INVALID, "value %.9g is out of range for a float",
                              v);
        if (!vec_reserve(p, &p->floats, sizeof(float), p->floats.n + 1)) return nomem(p);
        VEC_AT(p->floats, float, p->floats.n++) = (float)v;
        return TS_OK;
    }
    if (k->kind == TS_PBRT_TOKEN_STRING) {
        if (is_numeric_type(t))
            return param_fail(p, k->loc, ps, decl, TS_ERR_INVALID, "expects numbers, got %s",
                              describe(p, d, sizeof d));
        if (*numbers) return param_fail(p, k->loc, ps, decl, TS_ERR_INVALID, "mixes strings and numbers");
        *strings = true;
        const char **s = vec_push(p, &p->strings, sizeof(char *));
        if (!s) return nomem(p);
        *s = astrdup(p, k->text);
        if (!*s) return nomem(p);
        return TS_OK;
    }
    return param_fail(p, k->loc, ps, decl, TS_ERR_INVALID, "expects a value, got %s", describe(p, d, sizeof d));
}

/* Splits "type name" into its two words (copied into the arena). */
static ts_status split_decl(parser *p, const ts_pbrt_params *ps, const char *decl, ts_pbrt_loc loc, ts_pbrt_param *par)
{
    const char *s = decl;
    while (*s == ' ' || *s == '\t') s++;
    const char *te = s;
    while (*te && *te != ' ' && *te != '\t') te++;
    const char *n = te;
    while (*n == ' ' || *n == '\t') n++;
    const char *ne = n;
    while (*ne && *ne != ' ' && *ne != '\t') ne++;
    const char *rest = ne;
    while (*rest == ' ' || *rest == '\t') rest++;
    if (te == s || ne == n || *rest)
        return param_fail(p, loc, ps, decl, TS_ERR_INVALID,
                          "is not a parameter declaration (expected \"type name\")");
    char type[32];
    if ((size_t)(te - s) >= sizeof type)
        return param_fail(p, loc, ps, decl, TS_ERR_INVALID, "has an unknown parameter type");
    memcpy(type, s, (size_t)(te - s));
    type[te - s] = '\0';
    if (!ts_pbrt_param_type_from_name(type, &par->type, &par->type_name))
        return param_fail(p, loc, ps, decl, TS_ERR_INVALID, "has an unknown parameter type \"%s\"", type);
    char *nm = ts_arena_alloc(&p->s->arena, (size_t)(ne - n) + 1, 1);
    if (!nm) return nomem(p);
    memcpy(nm, n, (size_t)(ne - n));
    par->name = nm;
    par->loc = loc;
    return TS_OK;
}

/* Resolves a texture parameter's name in the scope in force. */
static ts_status resolve_texture(parser *p, const ts_pbrt_params *ps, const char *decl, ts_pbrt_param *par)
{
    par->texture_float = name_lookup(p, NS_FLOAT_TEX, par->strings[0]);
    par->texture_spectrum = name_lookup(p, NS_SPECTRUM_TEX, par->strings[0]);
    if (par->texture_float < 0 && par->texture_spectrum < 0)
        return param_fail(p, par->loc, ps, decl, TS_ERR_INVALID, "names texture \"%s\", which is not defined here",
                          par->strings[0]);
    return TS_OK;
}

/* Reads the parameter list that follows a directive (every "type name" value pair up to
 * the next token that is not a quoted string) into *out. */
static ts_status read_params(parser *p, const char *directive, const char *directive_arg, ts_pbrt_params *ps)
{
    ts_status st;
    p->items.n = 0;
    ps->directive = directive;
    ps->directive_arg = directive_arg;
    while (p->tok.kind == TS_PBRT_TOKEN_STRING) {
        ts_pbrt_param par;
        memset(&par, 0, sizeof par);
        par.texture_float = par.texture_spectrum = -1;
        char decl[128]; /* as written, for messages */
        size_t dl = p->tok.len < sizeof decl - 1 ? p->tok.len : sizeof decl - 1;
        memcpy(decl, p->tok.text, dl);
        decl[dl] = '\0';
        if ((st = split_decl(p, ps, p->tok.text, p->tok.loc, &par))) return st;
        if ((st = advance(p))) return st;
        p->floats.n = p->ints.n = p->bools.n = p->strings.n = 0;
        bool numbers = false, strings = false;
        size_t values = 0;
        if (p->tok.kind == TS_PBRT_TOKEN_LBRACKET) {
            ts_pbrt_loc open = p->tok.loc;
            if ((st = advance(p))) return st;
            while (p->tok.kind != TS_PBRT_TOKEN_RBRACKET) {
                if (p->tok.kind == TS_PBRT_TOKEN_EOF)
                    return param_fail(p, open, ps, decl, TS_ERR_INVALID,
                                      "has a '[' that is never closed (the file ends first)");
                if (p->tok.kind == TS_PBRT_TOKEN_LBRACKET ||
                    (p->tok.kind == TS_PBRT_TOKEN_WORD && par.type != TS_PBRT_PARAM_BOOL)) {
                    char d[96];
                    return param_fail(p, open, ps, decl, TS_ERR_INVALID,
                                      "has a '[' that is never closed (found %s at %u:%u)", describe(p, d, sizeof d),
                                      p->tok.loc.line, p->tok.loc.column);
                }
                /* The hot loop of big meshes: numbers straight into the float scratch. */
                if (p->tok.kind == TS_PBRT_TOKEN_NUMBER && is_numeric_type(par.type) &&
                    par.type != TS_PBRT_PARAM_INTEGER && fabs(p->tok.number) <= FLT_MAX) {
                    if (p->floats.n == p->floats.cap && !vec_reserve(p, &p->floats, sizeof(float), p->floats.n + 1))
                        return nomem(p);
                    VEC_AT(p->floats, float, p->floats.n++) = (float)p->tok.number;
                    numbers = true;
                } else if (p->tok.kind == TS_PBRT_TOKEN_NUMBER && par.type == TS_PBRT_PARAM_INTEGER &&
                           p->tok.number == floor(p->tok.number) && p->tok.number >= INT32_MIN &&
                           p->tok.number <= INT32_MAX) {
                    if (p->ints.n == p->ints.cap && !vec_reserve(p, &p->ints, sizeof(int32_t), p->ints.n + 1))
                        return nomem(p);
                    VEC_AT(p->ints, int32_t, p->ints.n++) = (int32_t)p->tok.number;
                    numbers = true;
                } else if ((st = add_value(p, par.type, ps, decl, &numbers, &strings))) {
                    return st;
                }
                values++;
                if ((st = advance(p))) return st;
            }
            if ((st = advance(p))) return st;
        } else {
            if (p->tok.kind == TS_PBRT_TOKEN_EOF || p->tok.kind == TS_PBRT_TOKEN_RBRACKET ||
                (p->tok.kind == TS_PBRT_TOKEN_WORD && par.type != TS_PBRT_PARAM_BOOL)) {
                char d[96];
                return param_fail(p, par.loc, ps, decl, TS_ERR_INVALID, "has no value (found %s)",
                                  describe(p, d, sizeof d));
            }
            if ((st = add_value(p, par.type, ps, decl, &numbers, &strings))) return st;
            values = 1;
            if ((st = advance(p))) return st;
        }
        if (values == 0) return param_fail(p, par.loc, ps, decl, TS_ERR_INVALID, "has no values");
        /* Counts per type, then the values into the arena. */
        size_t arity = ts_pbrt_param_arity(par.type);
        switch (par.type) {
        case TS_PBRT_PARAM_INTEGER:
            par.n = p->ints.n;
            par.ints = arena_copy(p, p->ints.data, p->ints.n, sizeof(int32_t));
            if (!par.ints) return nomem(p);
            break;
        case TS_PBRT_PARAM_BOOL:
            par.n = p->bools.n;
            par.bools = arena_copy(p, p->bools.data, p->bools.n, sizeof(bool));
            if (!par.bools) return nomem(p);
            break;
        case TS_PBRT_PARAM_STRING:
        case TS_PBRT_PARAM_TEXTURE:
            if (par.type == TS_PBRT_PARAM_TEXTURE && p->strings.n != 1)
                return param_fail(p, par.loc, ps, decl, TS_ERR_INVALID, "expects 1 texture name, got %zu",
                                  p->strings.n);
            par.n = p->strings.n;
            par.strings = arena_copy(p, p->strings.data, p->strings.n, sizeof(char *));
            if (!par.strings) return nomem(p);
            if (par.type == TS_PBRT_PARAM_TEXTURE && (st = resolve_texture(p, ps, decl, &par))) return st;
            break;
        case TS_PBRT_PARAM_SPECTRUM:
            if (strings) {
                if (p->strings.n != 1)
                    return param_fail(p, par.loc, ps, decl, TS_ERR_INVALID,
                                      "expects 1 spectrum file name, got %zu", p->strings.n);
                par.strings = arena_copy(p, p->strings.data, 1, sizeof(char *));
                if (!par.strings) return nomem(p);
                if ((st = read_spd(p, ps, decl, par.loc, par.strings[0]))) return st;
            } else if (p->floats.n % 2) {
                return param_fail(p, par.loc, ps, decl, TS_ERR_INVALID,
                                  "expects (wavelength, value) pairs, got %zu values", p->floats.n);
            }
            par.n = p->floats.n;
            par.floats = arena_copy(p, p->floats.data, p->floats.n, sizeof(float));
            if (!par.floats) return nomem(p);
            break;
        case TS_PBRT_PARAM_BLACKBODY:
            if (p->floats.n != 1 && p->floats.n != 2)
                return param_fail(p, par.loc, ps, decl, TS_ERR_INVALID,
                                  "expects 1 or 2 values (temperature [scale]), got %zu", p->floats.n);
            /* fall through */
        default:
            if (p->floats.n % arity)
                return param_fail(p, par.loc, ps, decl, TS_ERR_INVALID,
                                  "expects a multiple of %zu values, got %zu", arity, p->floats.n);
            par.n = p->floats.n;
            par.floats = arena_copy(p, p->floats.data, p->floats.n, sizeof(float));
            if (!par.floats) return nomem(p);
            break;
        }
        /* A name given twice: the last one counts (pbrt-v3). */
        bool replaced = false;
        for (size_t i = 0; i < p->items.n; i++) {
            ts_pbrt_param *old = &VEC_AT(p->items, ts_pbrt_param, i);
            if (strcmp(old->name, par.name) == 0) {
                if ((st = warn(p, par.loc, "%s \"%s\": parameter \"%s\" is given twice; the last one counts",
                               ps->directive, ps->directive_arg, par.name)))
                    return st;
                *old = par;
                replaced = true;
                break;
            }
        }
        if (!replaced) {
            ts_pbrt_param *slot = vec_push(p, &p->items, sizeof par);
            if (!slot) return nomem(p);
            *slot = par;
        }
    }
    ps->count = p->items.n;
    ps->items = arena_copy(p, p->items.data, p->items.n, sizeof(ts_pbrt_param));
    if (!ps->items) return nomem(p);
    return TS_OK;
}

/* ---- transforms ---- */

static const ts_mat4 *ctm_ptr(parser *p)
{
    if (!p->ctm_ptr) {
        ts_mat4 *m = ts_arena_alloc(&p->s->arena, sizeof *m, 16);
        if (!m) return NULL;
        *m = p->ctm;
        p->ctm_ptr = m;
    }
    return p->ctm_ptr;
}

/* Whether the two CTMs differ (pbrt-v3's IsAnimated of the CTM pair). */
static bool ctm_animated(const parser *p) { return memcmp(&p->ctm, &p->ctm_end, sizeof p->ctm) != 0; }

/* The end CTM's arena copy when it differs from the start one; *out NULL when not. */
static ts_status ctm_end_ptr(parser *p, const ts_mat4 **out)
{
    *out = NULL;
    if (!ctm_animated(p)) return TS_OK;
    if (!p->ctm_end_ptr) {
        ts_mat4 *m = ts_arena_alloc(&p->s->arena, sizeof *m, 16);
        if (!m) return nomem(p);
        *m = p->ctm_end;
        p->ctm_end_ptr = m;
    }
    *out = p->ctm_end_ptr;
    return TS_OK;
}

/* Sets the active CTMs to m (ActiveTransform's selection, as pbrt-v3's transform directives). */
static void ctm_set(parser *p, const ts_mat4 *m)
{
    if (p->active & ACTIVE_START) {
        p->ctm = *m;
        p->ctm_ptr = NULL;
    }
    if (p->active & ACTIVE_END) {
        p->ctm_end = *m;
        p->ctm_end_ptr = NULL;
    }
}

/* Sets both CTMs whatever is active (CoordSysTransform, as pbrt-v3's). */
static void ctm_set_both(parser *p, const ts_mat4 *start, const ts_mat4 *end)
{
    p->ctm = *start;
    p->ctm_end = *end;
    p->ctm_ptr = p->ctm_end_ptr = NULL;
}

/* Post-multiplies the active CTMs by m. */
static void ctm_concat(parser *p, const ts_mat4 *m)
{
    if (p->active & ACTIVE_START) {
        p->ctm = ts_mat4_mul(&p->ctm, m);
        p->ctm_ptr = NULL;
    }
    if (p->active & ACTIVE_END) {
        p->ctm_end = ts_mat4_mul(&p->ctm_end, m);
        p->ctm_end_ptr = NULL;
    }
}

/* pbrt-v3's LookAt: the world-to-camera matrix of a camera at eye looking at look. */
static bool look_at(const double v[9], ts_mat4 *out)
{
    ts_dvec3 eye = {v[0], v[1], v[2]}, look = {v[3], v[4], v[5]}, up = {v[6], v[7], v[8]};
    ts_dvec3 d = {look.x - eye.x, look.y - eye.y, look.z - eye.z};
    double dl = sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    double ul = sqrt(up.x * up.x + up.y * up.y + up.z * up.z);
    if (!(dl > 0) || !(ul > 0) || !isfinite(dl) || !isfinite(ul)) return false;
    d = (ts_dvec3){d.x / dl, d.y / dl, d.z / dl};
    up = (ts_dvec3){up.x / ul, up.y / ul, up.z / ul};
    ts_dvec3 r = {up.y * d.z - up.z * d.y, up.z * d.x - up.x * d.z, up.x * d.y - up.y * d.x};
    double rl = sqrt(r.x * r.x + r.y * r.y + r.z * r.z);
    if (!(rl > 0)) return false;
    r = (ts_dvec3){r.x / rl, r.y / rl, r.z / rl};
    ts_dvec3 u = {d.y * r.z - d.z * r.y, d.z * r.x - d.x * r.z, d.x * r.y - d.y * r.x};
    /* camera-to-world has columns right, up, dir, eye; its inverse is [Rᵀ | −Rᵀ·eye]. */
    ts_mat4 m = ts_mat4_identity();
    const ts_dvec3 rows[3] = {r, u, d};
    for (int i = 0; i < 3; i++) {
        m.m[i][0] = rows[i].x;
        m.m[i][1] = rows[i].y;
        m.m[i][2] = rows[i].z;
        m.m[i][3] = -(rows[i].x * eye.x + rows[i].y * eye.y + rows[i].z * eye.z);
    }
    *out = m;
    return true;
}

static ts_status read_matrix(parser *p, const char *directive, ts_mat4 *out)
{
    char d[96];
    if (p->tok.kind != TS_PBRT_TOKEN_LBRACKET)
        return perr(p, p->tok.loc, TS_ERR_INVALID, "%s expects [ 16 numbers ], got %s", directive,
                    describe(p, d, sizeof d));
    ts_pbrt_loc open = p->tok.loc;
    ts_status st = advance(p);
    if (st) return st;
    double v[16];
    int n = 0;
    while (p->tok.kind == TS_PBRT_TOKEN_NUMBER) {
        if (n == 16)
            return perr(p, open, TS_ERR_INVALID, "%s expects [ 16 numbers ], got more", directive);
        v[n++] = p->tok.number;
        if ((st = advance(p))) return st;
    }
    if (p->tok.kind != TS_PBRT_TOKEN_RBRACKET || n != 16)
        return perr(p, open, TS_ERR_INVALID, "%s expects [ 16 numbers ], got %d and then %s", directive, n,
                    describe(p, d, sizeof d));
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) out->m[i][j] = v[4 * j + i];
    return advance(p);
}

/* ---- blocks ---- */

static ts_status push_block(parser *p, int kind, ts_pbrt_loc loc, const char *object_name)
{
    block *b = vec_push(p, &p->blocks, sizeof *b);
    if (!b) return nomem(p);
    b->kind = kind;
    b->loc = loc;
    b->object_name = object_name;
    b->ctm = p->ctm;
    b->ctm_end = p->ctm_end;
    b->ctm_ptr = p->ctm_ptr;
    b->ctm_end_ptr = p->ctm_end_ptr;
    b->active = p->active;
    b->gs = p->gs;
    b->undo_mark = p->undo.n;
    return TS_OK;
}

static const char *block_name(int kind)
{
    return kind == BLOCK_ATTRIBUTE ? "AttributeBegin" : kind == BLOCK_TRANSFORM ? "TransformBegin" : "ObjectBegin";
}

static const char *block_end_name(int kind)
{
    return kind == BLOCK_ATTRIBUTE ? "AttributeEnd" : kind == BLOCK_TRANSFORM ? "TransformEnd" : "ObjectEnd";
}

/* Closes the innermost block, which must be of kind (the directive at loc closes it). */
static ts_status pop_block(parser *p, int kind, ts_pbrt_loc loc)
{
    if (p->blocks.n == 0)
        return perr(p, loc, TS_ERR_INVALID, "%s without a matching %s", block_end_name(kind), block_name(kind));
    block *b = &VEC_AT(p->blocks, block, p->blocks.n - 1);
    if (b->kind != kind)
        return perr(p, loc, TS_ERR_INVALID, "%s, but the innermost open block is the %s at %s:%u:%u", block_end_name(kind),
                    block_name(b->kind), b->loc.file, b->loc.line, b->loc.column);
    p->ctm = b->ctm;
    p->ctm_end = b->ctm_end;
    p->ctm_ptr = b->ctm_ptr;
    p->ctm_end_ptr = b->ctm_end_ptr;
    p->active = b->active;
    if (kind != BLOCK_TRANSFORM) {
        p->gs = b->gs;
        undo_to(p, b->undo_mark);
    }
    p->blocks.n--;
    return TS_OK;
}

/* ---- Include ---- */

static ts_status push_file(parser *p, const char *rel, ts_pbrt_loc loc)
{
    if (p->nfiles >= p->lim.max_include_depth || p->nfiles >= (int)(sizeof p->files / sizeof p->files[0]))
        return perr(p, loc, TS_ERR_LIMIT, "Include \"%s\": includes nest more than %d files deep", rel,
                    p->nfiles);
    char *real = malloc(PATH_MAX);
    if (!real) return nomem(p);
    ts_status st = ts_scene_path_resolve(p->root, rel, real, PATH_MAX, p->err);
    if (st) {
        char inner[TS_ERROR_MAX];
        memcpy(inner, p->err->message, sizeof inner);
        free(real);
        return perr(p, loc, st, "Include: %s", inner);
    }
    for (int i = 0; i < p->nfiles; i++)
        if (p->files[i].real_path && strcmp(p->files[i].real_path, real) == 0) {
            char chain[TS_ERROR_MAX] = "";
            size_t used = 0;
            for (int j = i; j < p->nfiles && used < sizeof chain; j++)
                used += (size_t)snprintf(chain + used, sizeof chain - used, "%s -> ", p->files[j].display);
            if (used < sizeof chain) snprintf(chain + used, sizeof chain - used, "%s", rel);
            free(real);
            return perr(p, loc, TS_ERR_INVALID, "Include \"%s\": include cycle (%s)", rel, chain);
        }
    char *display = astrdup(p, rel);
    if (!display) {
        free(real);
        return nomem(p);
    }
    ts_pbrt_lexer *lx;
    st = ts_pbrt_lexer_open(real, true, display, p->lim.max_file_bytes, &lx, p->err);
    if (st) {
        char inner[TS_ERROR_MAX];
        memcpy(inner, p->err->message, sizeof inner);
        free(real);
        return perr(p, loc, st, "Include: %s", inner);
    }
    p->files[p->nfiles].lx = lx;
    p->files[p->nfiles].real_path = real;
    p->files[p->nfiles].display = display;
    p->nfiles++;
    return TS_OK;
}

/* ---- directives ---- */

typedef enum { D_ANY, D_OPTIONS, D_WORLD } dir_block;

typedef enum {
    DIR_UNKNOWN,
    DIR_ACCELERATOR, DIR_ACTIVE_TRANSFORM, DIR_AREA_LIGHT, DIR_ATTRIBUTE_BEGIN, DIR_ATTRIBUTE_END, DIR_CAMERA,
    DIR_CONCAT_TRANSFORM, DIR_COORDINATE_SYSTEM, DIR_COORD_SYS_TRANSFORM, DIR_FILM, DIR_IDENTITY, DIR_INCLUDE,
    DIR_INTEGRATOR, DIR_LIGHT, DIR_LOOK_AT, DIR_MAKE_NAMED_MATERIAL, DIR_MAKE_NAMED_MEDIUM, DIR_MATERIAL,
    DIR_MEDIUM_INTERFACE, DIR_NAMED_MATERIAL, DIR_OBJECT_BEGIN, DIR_OBJECT_END, DIR_OBJECT_INSTANCE,
    DIR_PIXEL_FILTER, DIR_REVERSE_ORIENTATION, DIR_ROTATE, DIR_SAMPLER, DIR_SCALE, DIR_SHAPE, DIR_TEXTURE,
    DIR_TRANSFORM, DIR_TRANSFORM_BEGIN, DIR_TRANSFORM_END, DIR_TRANSFORM_TIMES, DIR_TRANSLATE, DIR_WORLD_BEGIN,
    DIR_WORLD_END,
} dir_id;

static const struct {
    const char *name;
    dir_id id;
    dir_block where;
} directives[] = {
    {"Accelerator", DIR_ACCELERATOR, D_OPTIONS},
    {"ActiveTransform", DIR_ACTIVE_TRANSFORM, D_ANY},
    {"AreaLightSource", DIR_AREA_LIGHT, D_WORLD},
    {"AttributeBegin", DIR_ATTRIBUTE_BEGIN, D_WORLD},
    {"AttributeEnd", DIR_ATTRIBUTE_END, D_WORLD},
    {"Camera", DIR_CAMERA, D_OPTIONS},
    {"ConcatTransform", DIR_CONCAT_TRANSFORM, D_ANY},
    {"CoordinateSystem", DIR_COORDINATE_SYSTEM, D_ANY},
    {"CoordSysTransform", DIR_COORD_SYS_TRANSFORM, D_ANY},
    {"Film", DIR_FILM, D_OPTIONS},
    {"Identity", DIR_IDENTITY, D_ANY},
    {"Include", DIR_INCLUDE, D_ANY},
    {"Integrator", DIR_INTEGRATOR, D_OPTIONS},
    {"LightSource", DIR_LIGHT, D_WORLD},
    {"LookAt", DIR_LOOK_AT, D_ANY},
    {"MakeNamedMaterial", DIR_MAKE_NAMED_MATERIAL, D_WORLD},
    {"MakeNamedMedium", DIR_MAKE_NAMED_MEDIUM, D_ANY},
    {"Material", DIR_MATERIAL, D_WORLD},
    {"MediumInterface", DIR_MEDIUM_INTERFACE, D_ANY},
    {"NamedMaterial", DIR_NAMED_MATERIAL, D_WORLD},
    {"ObjectBegin", DIR_OBJECT_BEGIN, D_WORLD},
    {"ObjectEnd", DIR_OBJECT_END, D_WORLD},
    {"ObjectInstance", DIR_OBJECT_INSTANCE, D_WORLD},
    {"PixelFilter", DIR_PIXEL_FILTER, D_OPTIONS},
    {"ReverseOrientation", DIR_REVERSE_ORIENTATION, D_WORLD},
    {"Rotate", DIR_ROTATE, D_ANY},
    {"Sampler", DIR_SAMPLER, D_OPTIONS},
    {"Scale", DIR_SCALE, D_ANY},
    {"Shape", DIR_SHAPE, D_WORLD},
    {"Texture", DIR_TEXTURE, D_WORLD},
    {"Transform", DIR_TRANSFORM, D_ANY},
    {"TransformBegin", DIR_TRANSFORM_BEGIN, D_WORLD},
    {"TransformEnd", DIR_TRANSFORM_END, D_WORLD},
    {"TransformTimes", DIR_TRANSFORM_TIMES, D_OPTIONS},
    {"Translate", DIR_TRANSLATE, D_ANY},
    {"WorldBegin", DIR_WORLD_BEGIN, D_OPTIONS},
    {"WorldEnd", DIR_WORLD_END, D_WORLD},
};

/* Directives of the form  Name "type" params  into an option slot. */
static ts_status option_directive(parser *p, const char *name, ts_pbrt_loc loc, ts_pbrt_option *opt)
{
    const char *type = NULL;
    ts_status st = expect_string(p, name, "a type", &type, NULL);
    if (st) return st;
    ts_pbrt_option o = {.type = type, .loc = loc};
    if ((st = read_params(p, name, type, &o.params))) return st;
    *opt = o;
    return TS_OK;
}

static ts_status add_material(parser *p, const char *name, const char *type, ts_pbrt_params *params,
                              ts_pbrt_loc loc, int32_t *index)
{
    ts_pbrt_material m = {.name = name, .type = type, .params = *params, .mix = {-1, -1}, .loc = loc};
    if (strcmp(type, "mix") == 0) {
        static const char *keys[2] = {"namedmaterial1", "namedmaterial2"};
        for (int i = 0; i < 2; i++) {
            const char *ref = NULL;
            ts_status st = ts_pbrt_find_string(params, keys[i], NULL, &ref, p->err);
            if (st) return st;
            if (!ref)
                return perr(p, loc, TS_ERR_INVALID, "%s \"%s\": a mix material needs \"string %s\"", params->directive,
                            params->directive_arg, keys[i]);
            m.mix[i] = name_lookup(p, NS_MATERIAL, ref);
            if (m.mix[i] < 0) {
                ts_pbrt_param *par = ts_pbrt_params_get(params, keys[i]);
                return ts_pbrt_param_error(params, par, p->err, TS_ERR_INVALID,
                                           "names material \"%s\", which is not defined here", ref);
            }
        }
    }
    if (p->materials.n >= INT32_MAX) return nomem(p);
    ts_pbrt_material *slot = vec_push(p, &p->materials, sizeof m);
    if (!slot) return nomem(p);
    *slot = m;
    *index = (int32_t)(p->materials.n - 1);
    return TS_OK;
}

static ts_status directive(parser *p)
{
    char d[96];
    ts_status st;
    if (p->tok.kind != TS_PBRT_TOKEN_WORD)
        return perr(p, p->tok.loc, TS_ERR_INVALID, "expected a directive, got %s", describe(p, d, sizeof d));
    ts_pbrt_loc loc = p->tok.loc;
    dir_id id = DIR_UNKNOWN;
    dir_block where = D_ANY;
    const char *name = NULL;
    for (size_t i = 0; i < sizeof directives / sizeof directives[0]; i++)
        if (directives[i].name[0] == p->tok.text[0] && strcmp(p->tok.text, directives[i].name) == 0) {
            id = directives[i].id;
            where = directives[i].where;
            name = directives[i].name;
            break;
        }
    if (id == DIR_UNKNOWN) {
        if (strcmp(p->tok.text, "true") == 0 || strcmp(p->tok.text, "false") == 0)
            return perr(p, loc, TS_ERR_INVALID, "expected a directive, got %s (a value outside a parameter list)", p->tok.text);
        return perr(p, loc, TS_ERR_INVALID, "unknown directive '%.60s'", p->tok.text);
    }
    if (p->phase == PHASE_ENDED)
        return perr(p, loc, TS_ERR_INVALID, "%s after WorldEnd (a file holds one scene; nothing may follow WorldEnd)", name);
    if (where == D_OPTIONS && p->phase == PHASE_WORLD)
        return perr(p, loc, TS_ERR_INVALID, "%s is an option and must come before WorldBegin", name);
    if (where == D_WORLD && p->phase == PHASE_OPTIONS)
        return perr(p, loc, TS_ERR_INVALID, "%s must come after WorldBegin", name);
    if ((st = advance(p))) return st;

    switch (id) {
    case DIR_UNKNOWN: break;
    /* --- transforms --- */
    case DIR_IDENTITY: {
        ts_mat4 i = ts_mat4_identity();
        ctm_set(p, &i);
        return TS_OK;
    }
    case DIR_TRANSLATE: {
        double v[3] = {0};
        if ((st = expect_numbers(p, name, v, 3))) return st;
        ts_xform t = ts_xform_translate((ts_dvec3){v[0], v[1], v[2]});
        ctm_concat(p, &t.m);
        return TS_OK;
    }
    case DIR_SCALE: {
        double v[3] = {0};
        if ((st = expect_numbers(p, name, v, 3))) return st;
        ts_mat4 m = ts_mat4_identity();
        m.m[0][0] = v[0], m.m[1][1] = v[1], m.m[2][2] = v[2];
        ctm_concat(p, &m);
        return TS_OK;
    }
    case DIR_ROTATE: {
        double v[4] = {0};
        if ((st = expect_numbers(p, name, v, 4))) return st;
        double len = sqrt(v[1] * v[1] + v[2] * v[2] + v[3] * v[3]);
        if (!(len > 0) || !isfinite(len)) return perr(p, loc, TS_ERR_INVALID, "Rotate: the axis (%g, %g, %g) has no direction", v[1], v[2], v[3]);
        ts_xform t = ts_xform_rotate(v[0], (ts_dvec3){v[1], v[2], v[3]});
        ctm_concat(p, &t.m);
        return TS_OK;
    }
    case DIR_LOOK_AT: {
        double v[9] = {0};
        if ((st = expect_numbers(p, name, v, 9))) return st;
        ts_mat4 m;
        if (!look_at(v, &m))
            return warn(p, loc, "LookAt: the up vector is parallel to the viewing direction (or zero); "
                                "the transform is left unchanged, as pbrt-v3 does");
        ctm_concat(p, &m);
        return TS_OK;
    }
    case DIR_TRANSFORM:
    case DIR_CONCAT_TRANSFORM: {
        ts_mat4 m;
        if ((st = read_matrix(p, name, &m))) return st;
        if (id == DIR_TRANSFORM)
            ctm_set(p, &m);
        else
            ctm_concat(p, &m);
        return TS_OK;
    }
    case DIR_COORDINATE_SYSTEM:
    case DIR_COORD_SYS_TRANSFORM: {
        const char *cs = NULL;
        if ((st = expect_string(p, name, "a coordinate system name", &cs, NULL))) return st;
        int32_t idx = name_lookup(p, NS_COORDSYS, cs);
        if (id == DIR_COORDINATE_SYSTEM) {
            if (idx < 0) {
                coordsys *m = vec_push(p, &p->coordsys, sizeof *m);
                if (!m) return nomem(p);
                idx = (int32_t)(p->coordsys.n - 1);
                if ((st = name_define(p, NS_COORDSYS, cs, idx, false, NULL))) return st;
            }
            VEC_AT(p->coordsys, coordsys, idx) = (coordsys){p->ctm, p->ctm_end};
            return TS_OK;
        }
        if (idx < 0)
            return warn(p, loc, "CoordSysTransform: no coordinate system is named \"%s\"%s; the transform is left "
                                "unchanged, as pbrt-v3 does",
                        cs, strcmp(cs, "camera") == 0 ? " (\"camera\" is named by Camera)" : "");
        coordsys c = VEC_AT(p->coordsys, coordsys, idx);
        ctm_set_both(p, &c.start, &c.end);
        return TS_OK;
    }
    case DIR_ACTIVE_TRANSFORM: {
        if (p->tok.kind != TS_PBRT_TOKEN_WORD ||
            (strcmp(p->tok.text, "All") && strcmp(p->tok.text, "StartTime") && strcmp(p->tok.text, "EndTime")))
            return perr(p, p->tok.loc, TS_ERR_INVALID, "ActiveTransform expects All, StartTime or EndTime, got %s",
                        describe(p, d, sizeof d));
        char which = p->tok.text[0];
        p->active = which == 'A' ? ACTIVE_ALL : which == 'S' ? ACTIVE_START : ACTIVE_END;
        return advance(p);
    }
    case DIR_TRANSFORM_TIMES: {
        double v[2] = {0};
        if ((st = expect_numbers(p, name, v, 2))) return st;
        /* pbrt-v3 takes any pair; an end before the start makes its AnimatedTransform a jump
         * from the start to the end transform at the start time — refused here. */
        if (v[1] < v[0])
            return perr(p, loc, TS_ERR_INVALID, "TransformTimes: the end time %g is before the start time %g", v[1],
                        v[0]);
        p->s->transform_start_time = v[0];
        p->s->transform_end_time = v[1];
        p->s->transform_times_loc = loc;
        return TS_OK;
    }
    /* --- options --- */
    case DIR_CAMERA: {
        ts_mat4 inv, inv_end;
        if (!ts_mat4_invert(&p->ctm, &inv))
            return perr(p, loc, TS_ERR_INVALID, "Camera: the current transformation is singular (it has no inverse)");
        if (!ts_mat4_invert(&p->ctm_end, &inv_end))
            return perr(p, loc, TS_ERR_INVALID,
                        "Camera: the current transformation at the end time (ActiveTransform EndTime) is singular");
        if ((st = option_directive(p, name, loc, &p->s->camera))) return st;
        p->s->world_to_camera = p->ctm;
        p->s->camera_to_world = inv;
        p->s->world_to_camera_end = p->ctm_end;
        p->s->camera_to_world_end = inv_end;
        p->s->camera_animated = ctm_animated(p);
        p->s->camera_medium = p->gs.outside_medium;
        p->camera_given = true;
        int32_t idx = name_lookup(p, NS_COORDSYS, "camera");
        if (idx < 0) {
            if (!vec_push(p, &p->coordsys, sizeof(coordsys))) return nomem(p);
            idx = (int32_t)(p->coordsys.n - 1);
            if ((st = name_define(p, NS_COORDSYS, "camera", idx, false, NULL))) return st;
        }
        VEC_AT(p->coordsys, coordsys, idx) = (coordsys){inv, inv_end};
        return TS_OK;
    }
    case DIR_FILM: return option_directive(p, name, loc, &p->s->film);
    case DIR_SAMPLER: return option_directive(p, name, loc, &p->s->sampler);
    case DIR_PIXEL_FILTER: return option_directive(p, name, loc, &p->s->filter);
    case DIR_INTEGRATOR: return option_directive(p, name, loc, &p->s->integrator);
    case DIR_ACCELERATOR: return option_directive(p, name, loc, &p->s->accelerator);
    case DIR_WORLD_BEGIN: {
        p->phase = PHASE_WORLD;
        ts_mat4 i = ts_mat4_identity();
        ctm_set_both(p, &i, &i);
        p->active = ACTIVE_ALL;
        int32_t idx = name_lookup(p, NS_COORDSYS, "world");
        if (idx < 0) {
            if (!vec_push(p, &p->coordsys, sizeof(coordsys))) return nomem(p);
            idx = (int32_t)(p->coordsys.n - 1);
            if ((st = name_define(p, NS_COORDSYS, "world", idx, false, NULL))) return st;
        }
        VEC_AT(p->coordsys, coordsys, idx) = (coordsys){i, i};
        return TS_OK;
    }
    case DIR_WORLD_END: {
        if (p->blocks.n) {
            block *b = &VEC_AT(p->blocks, block, p->blocks.n - 1);
            return perr(p, loc, TS_ERR_INVALID, "WorldEnd, but the %s at %s:%u:%u has no %s", block_name(b->kind),
                        b->loc.file, b->loc.line, b->loc.column, block_end_name(b->kind));
        }
        p->phase = PHASE_ENDED;
        return TS_OK;
    }
    /* --- blocks --- */
    case DIR_ATTRIBUTE_BEGIN: return push_block(p, BLOCK_ATTRIBUTE, loc, NULL);
    case DIR_ATTRIBUTE_END: return pop_block(p, BLOCK_ATTRIBUTE, loc);
    case DIR_TRANSFORM_BEGIN: return push_block(p, BLOCK_TRANSFORM, loc, NULL);
    case DIR_TRANSFORM_END: return pop_block(p, BLOCK_TRANSFORM, loc);
    case DIR_OBJECT_BEGIN: {
        const char *on = NULL;
        if ((st = expect_string(p, name, "an object name", &on, NULL))) return st;
        if (p->current_object >= 0) {
            const ts_pbrt_object *o = &VEC_AT(p->objects, ts_pbrt_object, p->current_object);
            return perr(p, loc, TS_ERR_INVALID, "ObjectBegin \"%s\" inside the definition of object \"%s\" (%s:%u:%u)", on,
                        o->name, o->loc.file, o->loc.line, o->loc.column);
        }
        int32_t prev = name_lookup(p, NS_OBJECT, on);
        if (prev >= 0) {
            const ts_pbrt_object *o = &VEC_AT(p->objects, ts_pbrt_object, prev);
            return perr(p, loc, TS_ERR_INVALID, "ObjectBegin \"%s\": an object of that name is already defined at %s:%u:%u",
                        on, o->loc.file, o->loc.line, o->loc.column);
        }
        if ((st = push_block(p, BLOCK_OBJECT, loc, on))) return st;
        ts_pbrt_object *o = vec_push(p, &p->objects, sizeof *o);
        if (!o) return nomem(p);
        o->name = on;
        o->first_shape = p->shapes.n;
        o->loc = loc;
        p->current_object = (int32_t)(p->objects.n - 1);
        return name_define(p, NS_OBJECT, on, p->current_object, false, NULL);
    }
    case DIR_OBJECT_END: {
        if (p->current_object < 0) return perr(p, loc, TS_ERR_INVALID, "ObjectEnd without a matching ObjectBegin");
        if ((st = pop_block(p, BLOCK_OBJECT, loc))) return st;
        ts_pbrt_object *o = &VEC_AT(p->objects, ts_pbrt_object, p->current_object);
        o->shape_count = p->shapes.n - o->first_shape;
        p->current_object = -1;
        return TS_OK;
    }
    case DIR_OBJECT_INSTANCE: {
        const char *on = NULL;
        if ((st = expect_string(p, name, "an object name", &on, NULL))) return st;
        if (p->current_object >= 0)
            return perr(p, loc, TS_ERR_INVALID, "ObjectInstance \"%s\" inside the definition of object \"%s\"", on,
                        VEC_AT(p->objects, ts_pbrt_object, p->current_object).name);
        int32_t idx = name_lookup(p, NS_OBJECT, on);
        if (idx < 0) return perr(p, loc, TS_ERR_INVALID, "ObjectInstance \"%s\": no object of that name is defined", on);
        const ts_mat4 *m = ctm_ptr(p), *m_end;
        if ((st = ctm_end_ptr(p, &m_end))) return st;
        ts_pbrt_instance *in = vec_push(p, &p->instances, sizeof *in);
        if (!m || !in) return nomem(p);
        in->object = idx;
        in->instance_to_world = m;
        in->instance_to_world_end = m_end;
        in->loc = loc;
        VEC_AT(p->objects, ts_pbrt_object, idx).instance_count++;
        return TS_OK;
    }
    /* --- attributes --- */
    case DIR_REVERSE_ORIENTATION: p->gs.reverse_orientation = !p->gs.reverse_orientation; return TS_OK;
    case DIR_MATERIAL: {
        const char *type = NULL;
        if ((st = expect_string(p, name, "a material type", &type, NULL))) return st;
        ts_pbrt_params ps;
        if ((st = read_params(p, name, type, &ps))) return st;
        int32_t idx;
        if ((st = add_material(p, NULL, type, &ps, loc, &idx))) return st;
        p->gs.material = idx;
        return TS_OK;
    }
    case DIR_MAKE_NAMED_MATERIAL: {
        const char *mn = NULL;
        if ((st = expect_string(p, name, "a material name", &mn, NULL))) return st;
        ts_pbrt_params ps;
        if ((st = read_params(p, name, mn, &ps))) return st;
        const char *type = NULL;
        if ((st = ts_pbrt_find_string(&ps, "type", NULL, &type, p->err))) return st;
        if (!type) return perr(p, loc, TS_ERR_INVALID, "%s \"%s\" has no \"string type\" parameter", name, mn);
        int32_t idx, prev;
        if ((st = add_material(p, mn, type, &ps, loc, &idx))) return st;
        if ((st = name_define(p, NS_MATERIAL, mn, idx, true, &prev))) return st;
        if (prev >= 0) return warn(p, loc, "%s \"%s\" redefines the named material \"%s\"", name, mn, mn);
        return TS_OK;
    }
    case DIR_NAMED_MATERIAL: {
        const char *mn = NULL;
        if ((st = expect_string(p, name, "a material name", &mn, NULL))) return st;
        /* pbrt-v3's pbrtNamedMaterial: the named material defined here and now becomes the
         * current one; an unknown name is an error it reports and goes on from, keeping the
         * material in force. */
        int32_t idx = name_lookup(p, NS_MATERIAL, mn);
        if (idx < 0)
            return warn(p, loc,
                        "NamedMaterial \"%s\": no material of that name is defined here; the material in force "
                        "stays (pbrt-v3 reports an error and goes on the same way)",
                        mn);
        p->gs.material = idx;
        return TS_OK;
    }
    case DIR_TEXTURE: {
        const char *tn = NULL, *ttype = NULL, *tclass = NULL;
        ts_pbrt_loc type_loc;
        if ((st = expect_string(p, name, "a texture name", &tn, NULL))) return st;
        if ((st = expect_string(p, name, "a texture type (\"float\", \"color\" or \"spectrum\")", &ttype, &type_loc)))
            return st;
        bool is_float = strcmp(ttype, "float") == 0;
        if (!is_float && strcmp(ttype, "color") != 0 && strcmp(ttype, "spectrum") != 0)
            return perr(p, type_loc, TS_ERR_INVALID, "Texture \"%s\": the type must be \"float\", \"color\" or \"spectrum\", got \"%s\"",
                        tn, ttype);
        if ((st = expect_string(p, name, "a texture class", &tclass, NULL))) return st;
        ts_pbrt_texture t = {.name = tn, .is_float = is_float, .class_name = tclass, .loc = loc};
        if ((st = read_params(p, name, tn, &t.params))) return st;
        t.texture_to_world = ctm_ptr(p);
        if (!t.texture_to_world || p->textures.n >= INT32_MAX) return nomem(p);
        ts_pbrt_texture *slot = vec_push(p, &p->textures, sizeof t);
        if (!slot) return nomem(p);
        *slot = t;
        int32_t prev;
        if ((st = name_define(p, is_float ? NS_FLOAT_TEX : NS_SPECTRUM_TEX, tn, (int32_t)(p->textures.n - 1), true, &prev)))
            return st;
        if (prev >= 0)
            return warn(p, loc, "Texture \"%s\" redefines the %s texture \"%s\"", tn, is_float ? "float" : "spectrum", tn);
        return TS_OK;
    }
    case DIR_AREA_LIGHT: {
        ts_pbrt_area_light a = {.loc = loc};
        if ((st = expect_string(p, name, "an area light type", &a.type, NULL))) return st;
        if ((st = read_params(p, name, a.type, &a.params))) return st;
        ts_pbrt_area_light *slot = vec_push(p, &p->area_lights, sizeof a);
        if (!slot || p->area_lights.n > INT32_MAX) return nomem(p);
        *slot = a;
        p->gs.area_light = (int32_t)(p->area_lights.n - 1);
        return TS_OK;
    }
    case DIR_LIGHT: {
        ts_pbrt_light l = {.loc = loc};
        if ((st = expect_string(p, name, "a light type", &l.type, NULL))) return st;
        if ((st = read_params(p, name, l.type, &l.params))) return st;
        l.light_to_world = ctm_ptr(p);
        l.inside_medium = p->gs.inside_medium;
        l.outside_medium = p->gs.outside_medium;
        ts_pbrt_light *slot = vec_push(p, &p->lights, sizeof l);
        if (!slot || !l.light_to_world) return nomem(p);
        *slot = l;
        return TS_OK;
    }
    case DIR_SHAPE: {
        ts_pbrt_shape sh = {.loc = loc, .area_light = -1, .object = p->current_object};
        if ((st = expect_string(p, name, "a shape type", &sh.type, NULL))) return st;
        if ((st = read_params(p, name, sh.type, &sh.params))) return st;
        sh.object_to_world = ctm_ptr(p);
        if (!sh.object_to_world) return nomem(p);
        if ((st = ctm_end_ptr(p, &sh.object_to_world_end))) return st;
        sh.reverse_orientation = p->gs.reverse_orientation;
        sh.material = p->gs.material;
        if (p->gs.area_light >= 0) {
            if (p->current_object >= 0) {
                if ((st = warn(p, loc, "Shape \"%s\": area lights are not supported inside object definitions; the "
                                       "shape is not emissive (as in pbrt-v3)",
                               sh.type)))
                    return st;
            } else {
                sh.area_light = p->gs.area_light;
            }
        }
        sh.inside_medium = p->gs.inside_medium;
        sh.outside_medium = p->gs.outside_medium;
        ts_pbrt_shape *slot = vec_push(p, &p->shapes, sizeof sh);
        if (!slot) return nomem(p);
        *slot = sh;
        return TS_OK;
    }
    /* --- media (mapped by the importer) --- */
    case DIR_MAKE_NAMED_MEDIUM: {
        ts_pbrt_medium m = {.loc = loc};
        if ((st = expect_string(p, name, "a medium name", &m.name, NULL))) return st;
        if ((st = read_params(p, name, m.name, &m.params))) return st;
        if ((st = ts_pbrt_find_string(&m.params, "type", NULL, &m.type, p->err))) return st;
        if (!m.type) return perr(p, loc, TS_ERR_INVALID, "MakeNamedMedium \"%s\" has no \"string type\" parameter", m.name);
        m.medium_to_world = ctm_ptr(p);
        ts_pbrt_medium *slot = vec_push(p, &p->media, sizeof m);
        if (!slot || !m.medium_to_world) return nomem(p);
        *slot = m;
        return TS_OK;
    }
    case DIR_MEDIUM_INTERFACE: {
        const char *in = NULL, *out = NULL;
        if ((st = expect_string(p, name, "a medium name", &in, NULL))) return st;
        out = in;
        if (p->tok.kind == TS_PBRT_TOKEN_STRING && (st = expect_string(p, name, "a medium name", &out, NULL))) return st;
        p->gs.inside_medium = in;
        p->gs.outside_medium = out;
        return TS_OK;
    }
    case DIR_INCLUDE: {
        const char *rel = NULL;
        ts_pbrt_loc rloc;
        if (p->tok.kind != TS_PBRT_TOKEN_STRING)
            return perr(p, p->tok.loc, TS_ERR_INVALID, "Include: expected a file name in quotes, got %s",
                        describe(p, d, sizeof d));
        rloc = p->tok.loc;
        rel = astrdup(p, p->tok.text);
        if (!rel) return nomem(p);
        /* Open the file before moving on, so the next token comes from it. */
        if ((st = push_file(p, rel, rloc))) return st;
        /* The string token is consumed; what follows is the new file's first token. */
        return advance(p);
    }
    }
    return TS_OK;
}

/* ---- driver ---- */

void ts_pbrt_limits_default(ts_pbrt_limits *lim)
{
    lim->max_file_bytes = 0;
    lim->max_memory = 0;
    lim->max_include_depth = 32;
    lim->max_warnings = 1000;
    lim->cancel = NULL;
}

static void option_default(ts_pbrt_option *o, const char *type)
{
    memset(o, 0, sizeof *o);
    o->type = type;
}

/* Copies a heap vector into the arena. */
static ts_status finish_vec(parser *p, vec *v, size_t elem, void **out, size_t *n)
{
    *n = v->n;
    *out = arena_copy(p, v->data, v->n, elem);
    if (!*out) return nomem(p);
    return TS_OK;
}

static ts_status finish(parser *p)
{
    ts_pbrt_scene *s = p->s;
    ts_status st;
    if ((st = finish_vec(p, &p->textures, sizeof(ts_pbrt_texture), (void **)&s->textures, &s->texture_count))) return st;
    if ((st = finish_vec(p, &p->materials, sizeof(ts_pbrt_material), (void **)&s->materials, &s->material_count)))
        return st;
    if ((st = finish_vec(p, &p->area_lights, sizeof(ts_pbrt_area_light), (void **)&s->area_lights,
                         &s->area_light_count)))
        return st;
    if ((st = finish_vec(p, &p->lights, sizeof(ts_pbrt_light), (void **)&s->lights, &s->light_count))) return st;
    if ((st = finish_vec(p, &p->shapes, sizeof(ts_pbrt_shape), (void **)&s->shapes, &s->shape_count))) return st;
    if ((st = finish_vec(p, &p->objects, sizeof(ts_pbrt_object), (void **)&s->objects, &s->object_count))) return st;
    if ((st = finish_vec(p, &p->instances, sizeof(ts_pbrt_instance), (void **)&s->instances, &s->instance_count)))
        return st;
    if ((st = finish_vec(p, &p->media, sizeof(ts_pbrt_medium), (void **)&s->media, &s->medium_count))) return st;
    if ((st = finish_vec(p, &p->warnings, sizeof(ts_pbrt_warning), (void **)&s->warnings, &s->warning_count)))
        return st;
    /* Per object, its instances' transforms. */
    for (size_t i = 0; i < s->object_count; i++) {
        ts_pbrt_object *o = &s->objects[i];
        const ts_mat4 **list = ts_arena_calloc(&s->arena, o->instance_count ? o->instance_count : 1, sizeof *list);
        if (!list) return nomem(p);
        o->instance_to_world = list;
        o->instance_count = 0;
    }
    for (size_t i = 0; i < s->instance_count; i++) {
        ts_pbrt_object *o = &s->objects[s->instances[i].object];
        ((const ts_mat4 **)o->instance_to_world)[o->instance_count++] = s->instances[i].instance_to_world;
    }
    return TS_OK;
}

static ts_status run(parser *p)
{
    ts_status st = advance(p);
    while (!st && p->tok.kind != TS_PBRT_TOKEN_EOF) st = directive(p);
    if (st) return st;
    ts_pbrt_loc end = p->tok.loc;
    if (p->phase == PHASE_OPTIONS) return perr(p, end, TS_ERR_INVALID, "the file ends without WorldBegin");
    if (p->phase == PHASE_WORLD) {
        if (p->blocks.n) {
            block *b = &VEC_AT(p->blocks, block, p->blocks.n - 1);
            return perr(p, end, TS_ERR_INVALID, "the file ends inside the %s at %s:%u:%u (no %s, no WorldEnd)",
                        block_name(b->kind), b->loc.file, b->loc.line, b->loc.column, block_end_name(b->kind));
        }
        return perr(p, end, TS_ERR_INVALID, "the file ends without WorldEnd");
    }
    return finish(p);
}

static ts_status parse(const char *path, const char *text, size_t len, const char *name, const char *base_dir,
                       const ts_pbrt_limits *lim, ts_pbrt_scene **out, ts_error *err)
{
    *out = NULL;
    ts_error local = {0};
    if (!err) err = &local;
    parser *p = calloc(1, sizeof *p);
    ts_pbrt_scene *s = calloc(1, sizeof *s);
    ts_status st = TS_OK;
    if (!p || !s) {
        free(p);
        free(s);
        return ts_error_set(err, TS_ERR_NOMEM, "%s: out of memory", name);
    }
    p->s = s;
    p->err = err;
    sha256_init(&p->digest);
    static const char domain[] = "tessera pbrt-v3 scene digest 1";
    sha256_update(&p->digest, sizeof domain, (const uint8_t *)domain);
    if (lim)
        p->lim = *lim;
    else
        ts_pbrt_limits_default(&p->lim);
    if (p->lim.max_include_depth < 1) p->lim.max_include_depth = 1;
    ts_arena_init(&s->arena, p->lim.max_memory);
    p->ctm = p->ctm_end = ts_mat4_identity();
    p->active = ACTIVE_ALL;
    p->gs.material = -1;
    p->gs.area_light = -1;
    p->gs.inside_medium = p->gs.outside_medium = "";
    p->current_object = -1;
    option_default(&s->camera, "perspective");
    option_default(&s->film, "image");
    option_default(&s->sampler, "halton");
    option_default(&s->filter, "box");
    option_default(&s->integrator, "path");
    option_default(&s->accelerator, "bvh");
    s->world_to_camera = s->camera_to_world = ts_mat4_identity();
    s->camera_medium = "";
    s->transform_end_time = 1;

    char dir[4096], stem[256];
    const char *display = ts_arena_strdup(&s->arena, name);
    if (!display) {
        st = ts_error_set(err, TS_ERR_NOMEM, "%s: out of memory", name);
        goto fail;
    }
    if (path) {
        p->files[0].real_path = realpath(path, NULL); /* NULL if missing: the open says why */
        if (!base_dir) { /* the folder of the file itself, symbolic links followed (pbrt-v3) */
            ts_scene_path_split(p->files[0].real_path ? p->files[0].real_path : path, dir, sizeof dir, stem,
                                sizeof stem);
            base_dir = dir;
        }
        st = ts_pbrt_lexer_open(path, false, display, p->lim.max_file_bytes, &p->files[0].lx, err);
    } else {
        st = ts_pbrt_lexer_from_memory(text, len, display, &p->files[0].lx, err);
    }
    if (st) {
        free(p->files[0].real_path);
        goto fail;
    }
    p->files[0].display = display;
    p->nfiles = 1;
    if (base_dir) {
        p->root = ts_arena_strdup(&s->arena, base_dir);
        if (!p->root) {
            st = ts_error_set(err, TS_ERR_NOMEM, "%s: out of memory", name);
            goto fail;
        }
    }
    s->base_dir = p->root;
    st = run(p);
fail:
    while (p->nfiles > 0) pop_file(p);
    if (!st) sha256_digest(&p->digest, sizeof s->digest, s->digest);
    vec *vecs[] = {&p->undo,      &p->blocks, &p->coordsys, &p->textures,  &p->materials, &p->area_lights,
                   &p->lights,    &p->shapes, &p->objects,  &p->instances, &p->media,     &p->warnings,
                   &p->items,     &p->floats, &p->ints,     &p->bools,     &p->strings};
    for (size_t i = 0; i < sizeof vecs / sizeof vecs[0]; i++) vec_free(vecs[i]);
    free(p->table);
    free(p);
    if (st) {
        ts_arena_fini(&s->arena);
        free(s);
        return st;
    }
    *out = s;
    return TS_OK;
}

ts_status ts_pbrt_parse_file(const char *path, const char *base_dir, const ts_pbrt_limits *lim,
                             ts_pbrt_scene **out, ts_error *err)
{
    return parse(path, NULL, 0, path, base_dir, lim, out, err);
}

ts_status ts_pbrt_parse_text(const char *text, size_t len, const char *name, const char *base_dir,
                             const ts_pbrt_limits *lim, ts_pbrt_scene **out, ts_error *err)
{
    return parse(NULL, text, len, name ? name : "scene", base_dir, lim, out, err);
}

void ts_pbrt_scene_destroy(ts_pbrt_scene *scene)
{
    if (!scene) return;
    ts_arena_fini(&scene->arena);
    free(scene);
}
