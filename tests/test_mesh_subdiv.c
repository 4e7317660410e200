/* test_mesh_subdiv.c — pbrt-v3's Loop subdivision (mesh/mesh_subdiv.h): closed-form limit
 * positions, counts, watertightness, limit normals, boundaries, refusals, JSON v1.
 *
 * Closed forms. A limit position does not depend on the level it is computed from (the
 * limit surface is the same surface), so the limit of an original vertex after L levels
 * equals the limit mask applied to the control mesh: for the regular octahedron (±e_i,
 * valence 4, β = 3/32, γ = 1/8) that is e_i/2, for the regular tetrahedron (valence 3,
 * β = 3/16, γ = 1/5, ring sum −v) v/5, for a boundary vertex of a planar fan
 * (⅔·v + ⅙·neighbours) likewise. All of these are deterministic: the bounds are float
 * rounding (a few 1e-7 relative).
 *
 * Normals are pbrt-v3's S × T, unnormalised (their lengths weight the triangles'
 * interpolation), so the tests compare directions after normalising, and lengths as ratios
 * (test_pbrt3_rules derives both by hand for an irregular mesh). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mesh/mesh_subdiv.h"
#include "json/scene_json.h"

static const float oct_p[] = {1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1};
/* Counter-clockwise seen from outside. */
static const uint32_t oct_i[] = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
static const float tet_p[] = {1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1};
static const uint32_t tet_i[] = {0, 1, 2, 0, 2, 3, 0, 3, 1, 1, 3, 2};

static ts_mesh_data subdivide(const float *p, uint32_t nv, const uint32_t *ix, uint32_t nt, uint32_t levels)
{
    ts_mesh_data m;
    ts_error err = {0};
    if (ts_mesh_loop_subdivide(p, nv, ix, nt, levels, 0, NULL, &m, &err)) fail_msg("%s", err.message);
    return m;
}

/* The unit vector along m's normal i. */
static void unit_normal(const ts_mesh_data *m, uint32_t i, double u[3])
{
    const float *n = m->n + 3 * (size_t)i;
    double len = sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]);
    for (int k = 0; k < 3; k++) u[k] = n[k] / len;
}

static double dlen(const double v[3]) { return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

static double vdist(const float *a, const double b[3])
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

/* Every edge in exactly two triangles, traversed once each way (closed and consistently
 * wound), and the signed volume positive (facing outwards). */
typedef struct edge_rec {
    uint32_t a, b;
} edge_rec;
static int edge_cmp(const void *x, const void *y)
{
    const edge_rec *p = x, *q = y;
    if (p->a != q->a) return p->a < q->a ? -1 : 1;
    return p->b < q->b ? -1 : (p->b > q->b);
}

static void check_closed(const ts_mesh_data *m)
{
    size_t n = 3 * (size_t)m->n_triangles;
    edge_rec *e = malloc(n * sizeof *e);
    double vol = 0;
    for (uint32_t t = 0; t < m->n_triangles; t++) {
        const uint32_t *v = m->index + 3 * (size_t)t;
        for (int k = 0; k < 3; k++) e[3 * t + k] = (edge_rec){v[k], v[(k + 1) % 3]};
        const float *a = m->p + 3 * v[0], *b = m->p + 3 * v[1], *c = m->p + 3 * v[2];
        vol += (a[0] * ((double)b[1] * c[2] - (double)b[2] * c[1]) - a[1] * ((double)b[0] * c[2] - (double)b[2] * c[0]) +
                a[2] * ((double)b[0] * c[1] - (double)b[1] * c[0])) / 6;
    }
    qsort(e, n, sizeof *e, edge_cmp);
    for (size_t i = 0; i < n; i++) {
        if (i + 1 < n && e[i].a == e[i + 1].a && e[i].b == e[i + 1].b) fail_msg("edge %u→%u used twice the same way", e[i].a, e[i].b);
        edge_rec r = {e[i].b, e[i].a};
        if (!bsearch(&r, e, n, sizeof *e, edge_cmp)) fail_msg("edge %u→%u has no opposite: a hole", e[i].a, e[i].b);
    }
    free(e);
    assert_true(vol > 0);
}

/* The angles (radians) between the vertices' normals and the area-weighted normals of
 * their triangles (the finite-difference normals of the refined polyhedron): the median and
 * the largest. */
static int dcmp(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return a < b ? -1 : (a > b);
}

static void normal_error(const ts_mesh_data *m, double *median, double *worst)
{
    double *acc = calloc(3 * (size_t)m->n_vertices, sizeof *acc), *e = malloc(m->n_vertices * sizeof *e);
    for (uint32_t t = 0; t < m->n_triangles; t++) {
        const uint32_t *v = m->index + 3 * (size_t)t;
        const float *a = m->p + 3 * v[0], *b = m->p + 3 * v[1], *c = m->p + 3 * v[2];
        double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        for (int k = 0; k < 3; k++)
            for (int j = 0; j < 3; j++) acc[3 * v[k] + j] += n[j];
    }
    for (uint32_t i = 0; i < m->n_vertices; i++) {
        double *a = acc + 3 * i, len = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        double n[3];
        unit_normal(m, i, n);
        e[i] = acos(fmin(1.0, (a[0] * n[0] + a[1] * n[1] + a[2] * n[2]) / len));
    }
    qsort(e, m->n_vertices, sizeof *e, dcmp);
    *median = e[m->n_vertices / 2];
    *worst = e[m->n_vertices - 1];
    free(acc), free(e);
}

static void test_octahedron(void **state)
{
    (void)state;
    double prev_med = INFINITY, prev_worst = INFINITY;
    for (uint32_t L = 0; L <= 5; L++) {
        ts_mesh_data m = subdivide(oct_p, 6, oct_i, 8, L);
        /* 4^L × 8 triangles; a closed genus-0 mesh has V = F/2 + 2 (Euler). */
        assert_int_equal(m.n_triangles, 8u << (2 * L));
        assert_int_equal(m.n_vertices, m.n_triangles / 2 + 2);
        for (int i = 0; i < 6; i++) {
            double want[3] = {oct_p[3 * i] / 2, oct_p[3 * i + 1] / 2, oct_p[3 * i + 2] / 2};
            if (!(vdist(m.p + 3 * i, want) <= 3e-7))
                fail_msg("level %u: vertex %d at (%g %g %g), limit e/2", L, i, m.p[3 * i], m.p[3 * i + 1], m.p[3 * i + 2]);
            /* By symmetry its normal is ±e_i, outwards. */
            double nw[3] = {oct_p[3 * i], oct_p[3 * i + 1], oct_p[3 * i + 2]}, u[3];
            unit_normal(&m, (uint32_t)i, u);
            float uf[3] = {(float)u[0], (float)u[1], (float)u[2]};
            if (!(vdist(uf, nw) <= 1e-6)) fail_msg("level %u: normal %d off e_i", L, i);
        }
        for (uint32_t i = 0; i < m.n_vertices; i++) {
            double r = sqrt((double)m.p[3 * i] * m.p[3 * i] + (double)m.p[3 * i + 1] * m.p[3 * i + 1] +
                            (double)m.p[3 * i + 2] * m.p[3 * i + 2]);
            /* Inside the octahedron's |x|+|y|+|z| ≤ 1, outside the limit vertices' inner sphere. */
            assert_true(r <= 1 && r >= 0.4);
        }
        check_closed(&m);
        /* Limit normals against the refined polyhedron, which converges to them. pbrt-v3
         * takes the tangent masks over the pushed ring (test_pbrt3_rules), which is off
         * the true limit tangents by O(h) relative, so the first levels converge slowly
         * (level 3: median ×0.53, largest ×0.86); from level 4 on the median falls ×0.18
         * to ×0.32 a level and the largest, near the valence-4 vertices, ×0.67 to ×0.75
         * (measured to level 7). Bounds: from level 4 the median at least halves and the
         * largest falls by ×0.8; at level 5 they are below 1e-3 and 0.012 rad (measured
         * 1.1e-4 and 0.0100). */
        double med, worst;
        normal_error(&m, &med, &worst);
        if (L >= 4 && !(med < 0.5 * prev_med && worst < 0.8 * prev_worst))
            fail_msg("level %u: normal errors %g (median), %g (largest) did not shrink from %g, %g", L, med, worst,
                     prev_med, prev_worst);
        if (L == 5 && !(med < 1e-3 && worst < 0.012)) fail_msg("level 5: normal errors %g, %g rad", med, worst);
        print_message("octahedron level %u: %u triangles, normal error median %.3g, largest %.3g rad\n", L,
                      m.n_triangles, med, worst);
        prev_med = med, prev_worst = worst;
        ts_mesh_data_free(&m);
    }
}

static void test_tetrahedron(void **state)
{
    (void)state;
    for (uint32_t L = 0; L <= 4; L++) {
        ts_mesh_data m = subdivide(tet_p, 4, tet_i, 4, L);
        assert_int_equal(m.n_triangles, 4u << (2 * L));
        for (int i = 0; i < 4; i++) {
            double want[3] = {tet_p[3 * i] / 5, tet_p[3 * i + 1] / 5, tet_p[3 * i + 2] / 5};
            if (!(vdist(m.p + 3 * i, want) <= 3e-7)) fail_msg("level %u: tetrahedron vertex %d not at v/5", L, i);
        }
        check_closed(&m);
        ts_mesh_data_free(&m);
    }
}

/* A planar open fan: stays in its plane with normals +z (its winding), and a boundary
 * vertex's limit is the same from every level (⅔·v + ⅙·neighbours on the control mesh). */
static void test_boundary(void **state)
{
    (void)state;
    /* Centre 0 and five rim vertices, four triangles: an open fan (rim 1 and 5 are ends). */
    const float p[] = {0, 0, 0, 2, 0, 0, 1.2f, 1.5f, 0, -0.5f, 2, 0, -1.8f, 0.4f, 0, -1, -1.5f, 0};
    const uint32_t ix[] = {0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 4, 5};
    for (uint32_t L = 0; L <= 4; L++) {
        ts_mesh_data m = subdivide(p, 6, ix, 4, L);
        for (uint32_t i = 0; i < m.n_vertices; i++) {
            assert_true(m.p[3 * i + 2] == 0);
            assert_true(m.n[3 * i] == 0 && m.n[3 * i + 1] == 0 && m.n[3 * i + 2] > 0);
        }
        /* Rim vertex 2's boundary neighbours are 1 and 3. */
        double want[3];
        for (int j = 0; j < 3; j++) want[j] = (4 * (double)p[6 + j] + p[3 + j] + p[9 + j]) / 6;
        if (!(vdist(m.p + 6, want) <= 4e-7))
            fail_msg("level %u: boundary vertex at (%.9g %.9g), limit (%.9g %.9g)", L, m.p[6], m.p[7], want[0], want[1]);
        ts_mesh_data_free(&m);
    }
}

/* pbrt-v3's limit normals, derived by hand from shapes/loopsubdiv.cpp for a pentagonal
 * bipyramid: an irregular pentagon e_0 … e_4 in z = 0 (counter-clockwise) and apexes
 * a = (0, 0, 1), b = −a; levels 0, so the control mesh itself is pushed to the limit.
 *  - Valence 4 at e_i (γ = 1/8), 5 at the apexes (β = 3/40, γ = 1/10). With a + b = 0:
 *    lim e_i = ½·e_i + ⅛·(e_i−1 + e_i+1), lim a = ½·a + (1/10)·Σe.
 *  - pbrt-v3 takes the tangent masks over these pushed positions. At e_i (ring e_i+1, a,
 *    e_i−1, b; weights cos(πj/2), sin(πj/2)): S = lim e_i+1 − lim e_i−1 = ½·(e_i+1 − e_i−1)
 *    + ⅛·(e_i+2 − e_i−2) and T = lim a − lim b = ½·(a − b). Over the unpushed ring it
 *    would be S = e_i+1 − e_i−1, T = a − b: a normal ⊥ (e_i+1 − e_i−1), which for this
 *    pentagon is 3.0° off at e_0 (e_2 − e_3 is not parallel to e_1 − e_4).
 *  - At a: every pushed e_j is ½·e_j + ⅛·(e_j−1 + e_j+1), and the sums Σ cos(2πj/5)·(…)
 *    pick up 2·cos(2π/5) from the neighbours, so S and T are (½ + cos(2π/5)/4) times the
 *    control ring's and |S × T| is that squared times the control ring's |S × T|.
 *  - The normals are left unnormalised: |n_a| / |n_e_i| is the ratio of those two cross
 *    products, 4.00 at e_0 (3.57 from the unpushed rings, 1 if normalised).
 * Bounds: float rounding of values of size 1 to 10 (1e-6 relative). */
static void test_pbrt3_rules(void **state)
{
    (void)state;
    static const float p[] = {2, 0, 0, 1, 2, 0, -2, 1, 0, -1, -2, 0, 1, -2, 0, 0, 0, 1, 0, 0, -1};
    uint32_t ix[30];
    for (uint32_t i = 0; i < 5; i++) {
        uint32_t j = (i + 1) % 5;
        uint32_t up[3] = {i, j, 5}, down[3] = {j, i, 6};
        memcpy(ix + 6 * i, up, sizeof up), memcpy(ix + 6 * i + 3, down, sizeof down);
    }
    ts_mesh_data m = subdivide(p, 7, ix, 10, 0);
    check_closed(&m);
    const double *e[5];
    double ed[5][3], a[3] = {0, 0, 1}, b[3] = {0, 0, -1};
    for (int i = 0; i < 5; i++) {
        for (int k = 0; k < 3; k++) ed[i][k] = p[3 * i + k];
        e[i] = ed[i];
    }
    /* Limit positions. */
    double sum[3] = {0, 0, 0};
    for (int i = 0; i < 5; i++)
        for (int k = 0; k < 3; k++) sum[k] += e[i][k];
    for (int i = 0; i < 5; i++) {
        double want[3];
        for (int k = 0; k < 3; k++) want[k] = 0.5 * e[i][k] + (e[(i + 4) % 5][k] + e[(i + 1) % 5][k]) / 8;
        if (!(vdist(m.p + 3 * i, want) <= 1e-6)) fail_msg("lim e_%d at (%g %g %g)", i, m.p[3 * i], m.p[3 * i + 1], m.p[3 * i + 2]);
    }
    double want_a[3] = {sum[0] / 10, sum[1] / 10, 0.5 + sum[2] / 10};
    assert_true(vdist(m.p + 15, want_a) <= 1e-6);
    /* Normals at e_i: S × T with T = ½(a − b) = ẑ, oriented outwards (the winding). */
    double len_e[5];
    for (int i = 0; i < 5; i++) {
        double S[3], n[3], u[3];
        for (int k = 0; k < 3; k++)
            S[k] = 0.5 * (e[(i + 1) % 5][k] - e[(i + 4) % 5][k]) + (e[(i + 2) % 5][k] - e[(i + 3) % 5][k]) / 8;
        double T[3] = {0.5 * (a[0] - b[0]), 0.5 * (a[1] - b[1]), 0.5 * (a[2] - b[2])};
        n[0] = S[1] * T[2] - S[2] * T[1], n[1] = S[2] * T[0] - S[0] * T[2], n[2] = S[0] * T[1] - S[1] * T[0];
        if (n[0] * e[i][0] + n[1] * e[i][1] < 0)
            for (int k = 0; k < 3; k++) n[k] = -n[k];
        len_e[i] = dlen(n);
        for (int k = 0; k < 3; k++) n[k] /= len_e[i];
        unit_normal(&m, (uint32_t)i, u);
        float uf[3] = {(float)u[0], (float)u[1], (float)u[2]};
        if (!(vdist(uf, n) <= 1e-6))
            fail_msg("normal at e_%d: (%.7f %.7f %.7f), pbrt-v3's (%.7f %.7f %.7f)", i, u[0], u[1], u[2], n[0], n[1], n[2]);
    }
    /* At e_0 the hand-derived normal is (19, 1, 0)/√362. */
    double u0[3];
    unit_normal(&m, 0, u0);
    assert_true(fabs(u0[0] - 19 / sqrt(362.0)) < 1e-6 && fabs(u0[1] - 1 / sqrt(362.0)) < 1e-6);
    /* The apex: along +z, its length the control ring's |S × T|·(½ + cos(2π/5)/4)². */
    double S[3] = {0, 0, 0}, T[3] = {0, 0, 0};
    for (int j = 0; j < 5; j++)
        for (int k = 0; k < 3; k++) {
            S[k] += cos(2 * M_PI * j / 5) * e[j][k];
            T[k] += sin(2 * M_PI * j / 5) * e[j][k];
        }
    double f = 0.5 + cos(2 * M_PI / 5) / 4, len_a = fabs(S[0] * T[1] - S[1] * T[0]) * f * f;
    double ua[3];
    unit_normal(&m, 5, ua);
    assert_true(ua[2] > 1 - 1e-6);
    for (int i = 0; i < 5; i++) {
        double na = dlen((double[3]){m.n[15], m.n[16], m.n[17]}),
               ni = dlen((double[3]){m.n[3 * i], m.n[3 * i + 1], m.n[3 * i + 2]});
        if (!(fabs(na / ni - len_a / len_e[i]) <= 1e-6 * (len_a / len_e[i])))
            fail_msg("|n_a| / |n_e_%d| = %.7f, pbrt-v3's %.7f", i, na / ni, len_a / len_e[i]);
    }
    print_message("pentagonal bipyramid: |n_a| / |n_e_0| = %.4f\n", len_a / len_e[0]);
    ts_mesh_data_free(&m);
}

static void refused(const float *p, uint32_t nv, const uint32_t *ix, uint32_t nt, uint32_t levels, uint64_t max_t,
                    const char *msg)
{
    ts_mesh_data m;
    ts_error err = {0};
    assert_int_not_equal(ts_mesh_loop_subdivide(p, nv, ix, nt, levels, max_t, NULL, &m, &err), TS_OK);
    if (!strstr(err.message, msg)) fail_msg("got '%s', expected '%s'", err.message, msg);
    assert_null(m.p);
}

static void test_refusals(void **state)
{
    (void)state;
    const float p[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
    const uint32_t three[] = {0, 1, 2, 1, 0, 3, 0, 1, 4};
    refused(p, 5, three, 3, 1, 0, "the edge between vertices 0 and 1 is shared by 3 triangles (at most 2)");
    const uint32_t same[] = {0, 1, 2, 0, 1, 3};
    refused(p, 5, same, 2, 1, 0, "triangles 0 and 1 run the same way along their shared edge (vertices 0 and 1)");
    const uint32_t bowtie[] = {0, 1, 2, 0, 3, 4};
    refused(p, 5, bowtie, 2, 1, 0, "vertex 0 is not manifold");
    const uint32_t rep[] = {0, 1, 1};
    refused(p, 5, rep, 1, 1, 0, "triangle 0 repeats a vertex (0, 1, 1)");
    refused(oct_p, 6, oct_i, 8, 3, 511, "3 levels make 512 triangles, more than the limit of 511");
    refused(oct_p, 6, oct_i, 8, 13, 0, "levels: expected 0 to 12, got 13");
    const uint32_t out_of_range[] = {0, 1, 7};
    refused(p, 5, out_of_range, 1, 1, 0, "indices[2]: 7 is not a vertex index (5 vertices)");
}

/* JSON v1: a loopsubdiv shape loads as its limit mesh; a bad one names its path. */
static void test_json(void **state)
{
    (void)state;
    const char *doc =
        "{\"tessera\": 1, \"camera\": {\"from\": [0, 0, 5], \"to\": [0, 0, 0]}, \"materials\": {\"m\": {\"type\": "
        "\"diffuse\"}}, \"shapes\": [{\"type\": \"loopsubdiv\", \"levels\": 2, \"material\": \"m\", \"positions\": "
        "[1,0,0, -1,0,0, 0,1,0, 0,-1,0, 0,0,1, 0,0,-1], \"indices\": [0,2,4, 2,1,4, 1,3,4, 3,0,4, 2,0,5, 1,2,5, "
        "3,1,5, 0,3,5]}]}";
    ts_scene *s = NULL;
    ts_error err = {0};
    if (ts_scene_load_text(doc, strlen(doc), NULL, NULL, NULL, &s, &err)) fail_msg("%s", err.message);
    assert_int_equal(s->n_shapes, 1);
    assert_int_equal(s->shapes[0].mesh.n_triangles, 128);
    assert_non_null(s->shapes[0].mesh.n);
    ts_scene_destroy(s);
    const char *bad =
        "{\"tessera\": 1, \"camera\": {\"from\": [0, 0, 5], \"to\": [0, 0, 0]}, \"materials\": {\"m\": {\"type\": "
        "\"diffuse\"}}, \"shapes\": [{\"type\": \"loopsubdiv\", \"material\": \"m\", \"positions\": [0,0,0, 1,0,0, "
        "0,1,0, 0,0,1], \"indices\": [0,1,2, 0,1,3]}]}";
    assert_int_not_equal(ts_scene_load_text(bad, strlen(bad), NULL, NULL, NULL, &s, &err), TS_OK);
    assert_string_equal(err.message, "shapes[0]: triangles 0 and 1 run the same way along their shared edge (vertices 0 "
                                     "and 1): the winding is inconsistent");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_octahedron), cmocka_unit_test(test_tetrahedron), cmocka_unit_test(test_boundary),
        cmocka_unit_test(test_pbrt3_rules), cmocka_unit_test(test_refusals), cmocka_unit_test(test_json),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
