/* mesh_subdiv.c — Loop subdivision (pbrt-v3's loopsubdiv); see mesh_subdiv.h.
 *
 * Each level is an indexed triangle list with its edge adjacency rebuilt from scratch
 * (sorting the 3·n half-edges by their vertex pair), which also checks the control mesh's
 * topology. The vertex and triangle order of every level is pbrt-v3's: the old vertices
 * first, then one new vertex per edge in the order the triangles first reach it; the four
 * children of a triangle (a, b, c) with edge vertices e0 (ab), e1 (bc), e2 (ca) are
 * (a, e0, e2), (e0, b, e1), (e2, e1, c), (e0, e1, e2). */
#include "mesh/mesh_subdiv.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/vecmath.h"

#define NONE UINT32_MAX
#define NEXT(k) (((k) + 1) % 3)
#define PREV(k) (((k) + 2) % 3)

typedef struct level {
    uint32_t nv, nf;
    ts_dvec3 *p;       /* nv */
    uint32_t *v;       /* 3·nf vertex ids */
    uint32_t *nb;      /* 3·nf: the triangle across edge k (v[k] → v[k+1]), or NONE */
    uint32_t *nb_k;    /* 3·nf: that edge's number in the neighbour */
    uint32_t *start;   /* nv: a triangle using the vertex (for a boundary vertex: the last one
                          reached by nextFace), or NONE */
    uint32_t *count;   /* nv: triangles using the vertex */
    unsigned char *boundary;
} level;

static void level_free(level *L)
{
    free(L->p), free(L->v), free(L->nb), free(L->nb_k), free(L->start), free(L->count), free(L->boundary);
    memset(L, 0, sizeof *L);
}

static ts_status nomem(ts_error *err) { return ts_error_set(err, TS_ERR_NOMEM, "out of memory subdividing the mesh"); }

typedef struct half {
    uint32_t lo, hi, f, k;
} half;

static int half_cmp(const void *a, const void *b)
{
    const half *x = a, *y = b;
    if (x->lo != y->lo) return x->lo < y->lo ? -1 : 1;
    if (x->hi != y->hi) return x->hi < y->hi ? -1 : 1;
    if (x->f != y->f) return x->f < y->f ? -1 : 1;
    return x->k < y->k ? -1 : (x->k > y->k);
}

static inline uint32_t vnum(const level *L, uint32_t f, uint32_t vert)
{
    const uint32_t *v = L->v + 3 * (size_t)f;
    return v[0] == vert ? 0 : v[1] == vert ? 1 : 2;
}
static inline uint32_t next_face(const level *L, uint32_t f, uint32_t vert) { return L->nb[3 * (size_t)f + vnum(L, f, vert)]; }
static inline uint32_t prev_face(const level *L, uint32_t f, uint32_t vert)
{
    return L->nb[3 * (size_t)f + PREV(vnum(L, f, vert))];
}
static inline uint32_t next_vert(const level *L, uint32_t f, uint32_t vert)
{
    return L->v[3 * (size_t)f + NEXT(vnum(L, f, vert))];
}
static inline uint32_t prev_vert(const level *L, uint32_t f, uint32_t vert)
{
    return L->v[3 * (size_t)f + PREV(vnum(L, f, vert))];
}

/* Sorts the half-edges h[0, n) of one bucket (one lo) by half_cmp: insertion for the
 * usual few, qsort for a vertex of high valence (no quadratic case). */
static void sort_bucket(half *h, size_t n)
{
    if (n > 16) {
        qsort(h, n, sizeof *h, half_cmp);
        return;
    }
    for (size_t i = 1; i < n; i++) {
        half x = h[i];
        size_t j = i;
        while (j > 0 && half_cmp(&h[j - 1], &x) > 0) h[j] = h[j - 1], j--;
        h[j] = x;
    }
}

#define SUBDIV_POLL 65536u

/* Adjacency, boundary flags and start triangles of L (v and p set), checking the topology
 * (only the control mesh can fail). The half-edges are sorted by (lo, hi, f, k) in linear
 * time — placed into buckets by lo in face order, each bucket sorted by hi — polling cancel
 * as it goes (the last level of a large surface has millions). */
static ts_status adjacency(level *L, ts_cancel *cancel, ts_error *err)
{
    size_t nh = 3 * (size_t)L->nf;
    L->nb = malloc(nh * sizeof *L->nb);
    L->nb_k = malloc(nh * sizeof *L->nb_k);
    L->start = malloc((size_t)L->nv * sizeof *L->start);
    L->count = calloc((size_t)L->nv + 1, sizeof *L->count);
    L->boundary = calloc((size_t)L->nv + 1, 1);
    half *h = malloc((nh + 1) * sizeof *h);
    size_t *first = calloc((size_t)L->nv + 2, sizeof *first); /* bucket lo starts at first[lo] */
    if (!L->nb || !L->nb_k || !L->start || !L->count || !L->boundary || !h || !first) {
        free(h), free(first);
        return nomem(err);
    }
    ts_status polled = TS_OK;
    for (uint32_t f = 0; f < L->nf; f++)
        for (uint32_t k = 0; k < 3; k++) {
            uint32_t a = L->v[3 * f + k], b = L->v[3 * f + NEXT(k)];
            first[(a < b ? a : b) + 1]++;
            L->nb[3 * (size_t)f + k] = NONE;
            L->count[a]++;
        }
    for (size_t i = 1; i <= (size_t)L->nv + 1; i++) first[i] += first[i - 1];
    for (uint32_t f = 0; f < L->nf && !polled; f++) {
        if (f % SUBDIV_POLL == 0 && (polled = ts_cancel_check(cancel, err))) break;
        for (uint32_t k = 0; k < 3; k++) {
            uint32_t a = L->v[3 * f + k], b = L->v[3 * f + NEXT(k)], lo = a < b ? a : b;
            h[first[lo]++] = (half){lo, a < b ? b : a, f, k};
        }
    }
    /* first[lo] is now the end of bucket lo, the start of lo + 1. */
    for (uint32_t v = 0; v < L->nv && !polled; v++) {
        if (v % SUBDIV_POLL == 0 && (polled = ts_cancel_check(cancel, err))) break;
        size_t b0 = v ? first[v - 1] : 0;
        sort_bucket(h + b0, first[v] - b0);
    }
    free(first);
    if (polled) {
        free(h);
        return polled;
    }
    for (size_t i = 0; i < nh;) {
        size_t j = i + 1;
        while (j < nh && h[j].lo == h[i].lo && h[j].hi == h[i].hi) j++;
        if (j - i > 2) {
            ts_status st = ts_error_set(err, TS_ERR_INVALID, "the edge between vertices %u and %u is shared by %zu triangles (at most 2)",
                                        h[i].lo, h[i].hi, j - i);
            free(h);
            return st;
        }
        if (j - i == 2) {
            half a = h[i], b = h[i + 1];
            if (L->v[3 * (size_t)a.f + a.k] == L->v[3 * (size_t)b.f + b.k]) {
                ts_status st = ts_error_set(err, TS_ERR_INVALID,
                                            "triangles %u and %u run the same way along their shared edge (vertices %u "
                                            "and %u): the winding is inconsistent",
                                            a.f, b.f, h[i].lo, h[i].hi);
                free(h);
                return st;
            }
            L->nb[3 * (size_t)a.f + a.k] = b.f, L->nb_k[3 * (size_t)a.f + a.k] = b.k;
            L->nb[3 * (size_t)b.f + b.k] = a.f, L->nb_k[3 * (size_t)b.f + b.k] = a.k;
        }
        i = j;
    }
    free(h);
    for (uint32_t i = 0; i < L->nv; i++) L->start[i] = NONE;
    for (uint32_t f = 0; f < L->nf; f++)
        for (uint32_t k = 0; k < 3; k++) L->start[L->v[3 * f + k]] = f;
    /* pbrt-v3's walks round each vertex; they must meet every triangle using it. */
    for (uint32_t i = 0; i < L->nv; i++) {
        uint32_t s = L->start[i];
        if (s == NONE) continue;
        uint32_t n = 1, f = s, last = s, limit = L->count[i] + 1;
        while ((f = next_face(L, f, i)) != NONE && f != s && n <= limit) n++, last = f;
        if (f == NONE) {
            L->boundary[i] = 1;
            for (f = s; (f = prev_face(L, f, i)) != NONE && n <= limit;) n++;
            L->start[i] = last;
        }
        if (n != L->count[i])
            return ts_error_set(err, TS_ERR_INVALID,
                                "vertex %u is not manifold: its %u triangles do not form one fan around it", i,
                                L->count[i]);
    }
    return TS_OK;
}

/* The ring of vertex i in pbrt-v3's order into ring (room for count + 1); its valence. */
static uint32_t one_ring(const level *L, uint32_t i, uint32_t *ring)
{
    uint32_t s = L->start[i], n = 0, f = s;
    if (!L->boundary[i]) {
        do {
            ring[n++] = next_vert(L, f, i);
            f = next_face(L, f, i);
        } while (f != s);
    } else {
        ring[n++] = next_vert(L, f, i);
        do {
            ring[n++] = prev_vert(L, f, i);
            f = prev_face(L, f, i);
        } while (f != NONE);
    }
    return n;
}

/* The boundary limit mask (1, 4, 1)/6: the left eigenvector of the boundary curve's
 * refinement (⅛, ¾, ⅛ even, ½, ½ odd: the cubic B-spline's), so a boundary vertex's limit
 * is the same whichever level it is taken from. pbrt-v3 weights 1/5 (3/5 in the middle),
 * which moves boundary limits off the limit curve (docs/design.md §4). */
#define BOUNDARY_LIMIT (1.0 / 6)

static inline double beta(uint32_t valence) { return valence == 3 ? 3.0 / 16 : 3.0 / (8.0 * valence); }
static inline double loop_gamma(uint32_t valence) { return 1 / (valence + 3 / (8 * beta(valence))); }

static ts_dvec3 weight_one_ring(const level *L, uint32_t i, const uint32_t *ring, uint32_t k, double b)
{
    ts_dvec3 p = ts_dvec3_scale(L->p[i], 1 - k * b);
    for (uint32_t j = 0; j < k; j++) p = ts_dvec3_add(p, ts_dvec3_scale(L->p[ring[j]], b));
    return p;
}

static ts_dvec3 weight_boundary(const level *L, uint32_t i, const uint32_t *ring, uint32_t k, double b)
{
    ts_dvec3 p = ts_dvec3_scale(L->p[i], 1 - 2 * b);
    p = ts_dvec3_add(p, ts_dvec3_scale(L->p[ring[0]], b));
    return ts_dvec3_add(p, ts_dvec3_scale(L->p[ring[k - 1]], b));
}

static uint32_t max_count(const level *L)
{
    uint32_t m = 0;
    for (uint32_t i = 0; i < L->nv; i++) m = L->count[i] > m ? L->count[i] : m;
    return m;
}

/* One refinement of L (with adjacency) into N (positions and triangles only). */
static ts_status refine(const level *L, level *N, ts_error *err)
{
    uint32_t *ring = malloc(((size_t)max_count(L) + 2) * sizeof *ring);
    uint32_t *edge = malloc(3 * (size_t)L->nf * sizeof *edge);
    uint64_t ne = 0;
    for (size_t h = 0; h < 3 * (size_t)L->nf; h++) ne += L->nb[h] == NONE || L->nb[h] > h / 3;
    if (!ring || !edge || (uint64_t)L->nv + ne > UINT32_MAX - 1 || 4ull * L->nf > UINT32_MAX) {
        free(ring), free(edge);
        return (uint64_t)L->nv + ne > UINT32_MAX - 1 || 4ull * L->nf > UINT32_MAX
                   ? ts_error_set(err, TS_ERR_LIMIT, "the subdivided mesh has more than 2^32 vertices or triangles")
                   : nomem(err);
    }
    N->nv = L->nv + (uint32_t)ne;
    N->nf = 4 * L->nf;
    N->p = malloc((size_t)N->nv * sizeof *N->p);
    N->v = malloc(3 * (size_t)N->nf * sizeof *N->v);
    if (!N->p || !N->v) {
        free(ring), free(edge);
        return nomem(err);
    }
    /* Even vertices. */
    for (uint32_t i = 0; i < L->nv; i++) {
        if (L->start[i] == NONE) {
            N->p[i] = L->p[i];
            continue;
        }
        uint32_t k = one_ring(L, i, ring);
        if (L->boundary[i]) N->p[i] = weight_boundary(L, i, ring, k, 1.0 / 8);
        else N->p[i] = weight_one_ring(L, i, ring, k, k == 6 ? 1.0 / 16 : beta(k));
    }
    /* Odd vertices, in the order the triangles first reach their edges. */
    uint32_t next = L->nv;
    for (uint32_t f = 0; f < L->nf; f++)
        for (uint32_t k = 0; k < 3; k++) {
            size_t h = 3 * (size_t)f + k;
            uint32_t g = L->nb[h];
            if (g != NONE && g < f) {
                edge[h] = edge[3 * (size_t)g + L->nb_k[h]];
                continue;
            }
            uint32_t a = L->v[h], b = L->v[3 * (size_t)f + NEXT(k)];
            ts_dvec3 p;
            if (g == NONE) {
                p = ts_dvec3_add(ts_dvec3_scale(L->p[a], 0.5), ts_dvec3_scale(L->p[b], 0.5));
            } else {
                uint32_t c = L->v[3 * (size_t)f + PREV(k)], d = L->v[3 * (size_t)g + PREV(L->nb_k[h])];
                p = ts_dvec3_add(ts_dvec3_scale(L->p[a], 3.0 / 8), ts_dvec3_scale(L->p[b], 3.0 / 8));
                p = ts_dvec3_add(p, ts_dvec3_scale(L->p[c], 1.0 / 8));
                p = ts_dvec3_add(p, ts_dvec3_scale(L->p[d], 1.0 / 8));
            }
            N->p[next] = p;
            edge[h] = next++;
        }
    /* Four children per triangle, windings kept. */
    for (uint32_t f = 0; f < L->nf; f++) {
        const uint32_t *v = L->v + 3 * (size_t)f, *e = edge + 3 * (size_t)f;
        uint32_t *c = N->v + 12 * (size_t)f;
        uint32_t kids[12] = {v[0], e[0], e[2], e[0], v[1], e[1], e[2], e[1], v[2], e[0], e[1], e[2]};
        memcpy(c, kids, sizeof kids);
    }
    free(ring), free(edge);
    return TS_OK;
}

ts_status ts_mesh_loop_subdivide(const float *p, uint32_t n_vertices, const uint32_t *index, uint32_t n_triangles,
                                 uint32_t levels, uint64_t max_triangles, ts_cancel *cancel, ts_mesh_data *out,
                                 ts_error *err)
{
    memset(out, 0, sizeof *out);
    if (levels > TS_SUBDIV_MAX_LEVELS)
        return ts_error_set(err, TS_ERR_INVALID, "levels: expected 0 to %d, got %u", TS_SUBDIV_MAX_LEVELS, levels);
    if (n_vertices == 0 || n_triangles == 0)
        return ts_error_set(err, TS_ERR_INVALID, "a subdivision surface needs at least one triangle");
    uint64_t nt = (uint64_t)n_triangles << (2 * levels);
    if (nt > UINT32_MAX || (max_triangles && nt > max_triangles))
        return ts_error_set(err, TS_ERR_LIMIT, "%u levels make %llu triangles, more than the limit of %llu", levels,
                            (unsigned long long)nt, (unsigned long long)(max_triangles ? max_triangles : UINT32_MAX));
    for (uint64_t k = 0; k < 3ull * n_triangles; k++)
        if (index[k] >= n_vertices)
            return ts_error_set(err, TS_ERR_INVALID, "indices[%llu]: %u is not a vertex index (%u vertices)",
                                (unsigned long long)k, index[k], n_vertices);
    for (uint32_t f = 0; f < n_triangles; f++) {
        const uint32_t *v = index + 3 * (size_t)f;
        if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2])
            return ts_error_set(err, TS_ERR_INVALID, "triangle %u repeats a vertex (%u, %u, %u)", f, v[0], v[1], v[2]);
    }
    for (uint64_t k = 0; k < 3ull * n_vertices; k++)
        if (!isfinite(p[k])) return ts_error_set(err, TS_ERR_INVALID, "P[%llu]: expected a finite number", (unsigned long long)k);

    level L = {0}, N = {0};
    ts_status st = TS_OK;
    L.nv = n_vertices, L.nf = n_triangles;
    L.p = malloc((size_t)n_vertices * sizeof *L.p);
    L.v = malloc(3 * (size_t)n_triangles * sizeof *L.v);
    if (!L.p || !L.v) {
        st = nomem(err);
        goto done;
    }
    for (uint32_t i = 0; i < n_vertices; i++) L.p[i] = (ts_dvec3){p[3 * i], p[3 * i + 1], p[3 * i + 2]};
    memcpy(L.v, index, 3 * (size_t)n_triangles * sizeof *L.v);
    if ((st = adjacency(&L, cancel, err))) goto done;
    for (uint32_t l = 0; l < levels; l++) {
        if ((st = ts_cancel_check(cancel, err))) goto done;
        if ((st = refine(&L, &N, err))) goto done;
        level_free(&L);
        L = N;
        memset(&N, 0, sizeof N);
        if ((st = ts_cancel_check(cancel, err)) || (st = adjacency(&L, cancel, err))) goto done;
    }
    if ((st = ts_cancel_check(cancel, err))) goto done;

    /* The limit surface: positions and normals from the last level. */
    out->p = malloc(3 * (size_t)L.nv * sizeof *out->p);
    out->n = malloc(3 * (size_t)L.nv * sizeof *out->n);
    out->index = malloc(3 * (size_t)L.nf * sizeof *out->index);
    uint32_t *ring = malloc(((size_t)max_count(&L) + 2) * sizeof *ring);
    ts_dvec3 *wind = calloc((size_t)L.nv, sizeof *wind), *lim = malloc((size_t)L.nv * sizeof *lim),
             *nrm = malloc((size_t)L.nv * sizeof *nrm);
    if (!out->p || !out->n || !out->index || !ring || !wind || !lim || !nrm) {
        free(ring), free(wind), free(lim), free(nrm);
        st = nomem(err);
        goto done;
    }
    /* The winding's side at each vertex: the sum of its triangles' area vectors. */
    for (uint32_t f = 0; f < L.nf; f++) {
        const uint32_t *v = L.v + 3 * (size_t)f;
        ts_dvec3 a = ts_dvec3_cross(ts_dvec3_sub(L.p[v[1]], L.p[v[0]]), ts_dvec3_sub(L.p[v[2]], L.p[v[0]]));
        for (int k = 0; k < 3; k++) wind[v[k]] = ts_dvec3_add(wind[v[k]], a);
    }
    /* Every vertex to its limit position first: pbrt-v3 then takes the tangent masks over
     * the pushed positions (its one-ring reads them), not over the last level's. */
    for (uint32_t i = 0; i < L.nv; i++) {
        lim[i] = L.p[i];
        if (L.start[i] == NONE) continue;
        uint32_t k = one_ring(&L, i, ring);
        lim[i] = L.boundary[i] ? weight_boundary(&L, i, ring, k, BOUNDARY_LIMIT)
                               : weight_one_ring(&L, i, ring, k, loop_gamma(k));
    }
    free(L.p);
    L.p = lim;
    /* Normals S × T as pbrt-v3 leaves them, unnormalised: its triangles interpolate them
     * with their lengths (a high-valence vertex, whose tangent sums are long, weighs more)
     * and take ∂n/∂u from their differences, so the lengths are kept — the whole mesh scaled
     * by one power of two only where the longest is outside [2^-8, 2^64]. */
    double n_max = 0;
    for (uint32_t i = 0; i < L.nv; i++) {
        ts_dvec3 n = wind[i];
        if (L.start[i] != NONE) {
            uint32_t k = one_ring(&L, i, ring);
            ts_dvec3 S = {0, 0, 0}, T = {0, 0, 0};
            if (L.boundary[i]) {
                S = ts_dvec3_sub(L.p[ring[k - 1]], L.p[ring[0]]);
                if (k == 2) {
                    T = ts_dvec3_sub(ts_dvec3_add(L.p[ring[0]], L.p[ring[1]]), ts_dvec3_scale(L.p[i], 2));
                } else if (k == 3) {
                    T = ts_dvec3_sub(L.p[ring[1]], L.p[i]);
                } else if (k == 4) {
                    T = ts_dvec3_add(ts_dvec3_scale(L.p[ring[0]], -1), ts_dvec3_scale(L.p[ring[1]], 2));
                    T = ts_dvec3_add(T, ts_dvec3_scale(L.p[ring[2]], 2));
                    T = ts_dvec3_sub(T, L.p[ring[3]]);
                    T = ts_dvec3_sub(T, ts_dvec3_scale(L.p[i], 2));
                } else {
                    double th = TS_PI_D / (k - 1);
                    T = ts_dvec3_scale(ts_dvec3_add(L.p[ring[0]], L.p[ring[k - 1]]), sin(th));
                    for (uint32_t j = 1; j < k - 1; j++)
                        T = ts_dvec3_add(T, ts_dvec3_scale(L.p[ring[j]], (2 * cos(th) - 2) * sin(j * th)));
                    T = ts_dvec3_scale(T, -1);
                }
            } else {
                for (uint32_t j = 0; j < k; j++) {
                    S = ts_dvec3_add(S, ts_dvec3_scale(L.p[ring[j]], cos(2 * TS_PI_D * j / k)));
                    T = ts_dvec3_add(T, ts_dvec3_scale(L.p[ring[j]], sin(2 * TS_PI_D * j / k)));
                }
            }
            ts_dvec3 c = ts_dvec3_cross(S, T);
            double len = ts_dvec3_length(c);
            /* A degenerate ring: the winding's area vector (a length² as S × T is). */
            if (len > 0 && isfinite(len)) n = c;
            if (ts_dvec3_dot(n, wind[i]) < 0) n = ts_dvec3_scale(n, -1);
        }
        double len = ts_dvec3_length(n);
        if (!(len > 0 && isfinite(len))) n = (ts_dvec3){0, 0, 1}, len = 1;
        nrm[i] = n;
        n_max = fmax(n_max, len);
    }
    int e = 0;
    if (n_max > 0x1p64 || n_max < 0x1p-8) frexp(n_max, &e);
    for (uint32_t i = 0; i < L.nv; i++) {
        ts_dvec3 q = L.p[i], n = ts_dvec3_scale(nrm[i], ldexp(1, -e));
        /* One over 2^60 times shorter than the longest is lengthened to that (its weight was
         * nil): every normal's squared length stays non-zero in float. */
        double len = ts_dvec3_length(n), floor_len = ldexp(n_max, -e - 60);
        if (len < floor_len) n = ts_dvec3_scale(n, floor_len / len);
        out->p[3 * i] = (float)q.x, out->p[3 * i + 1] = (float)q.y, out->p[3 * i + 2] = (float)q.z;
        out->n[3 * i] = (float)n.x, out->n[3 * i + 1] = (float)n.y, out->n[3 * i + 2] = (float)n.z;
        if (!(isfinite(out->p[3 * i]) && isfinite(out->p[3 * i + 1]) && isfinite(out->p[3 * i + 2]))) {
            free(ring), free(wind), free(nrm);
            st = ts_error_set(err, TS_ERR_INVALID, "a subdivided vertex is not a finite float");
            goto done;
        }
    }
    free(ring), free(wind), free(nrm);
    memcpy(out->index, L.v, 3 * (size_t)L.nf * sizeof *out->index);
    out->n_vertices = L.nv;
    out->n_triangles = L.nf;

done:
    level_free(&L);
    level_free(&N);
    if (st) ts_mesh_data_free(out);
    return st;
}
