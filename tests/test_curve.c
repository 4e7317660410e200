/* test_curve.c — pbrt-v3's curve shape (geometry/curve.h, docs/design.md §4): what rays see
 * of a curve through the accelerator, the interaction pbrt-v3's formulas give, both front
 * ends and their refusals.
 *
 * Most checks cast rays straight at the accelerator (ts_accel_intersect) on a regular grid,
 * so coverage is counted, not estimated: a straight flat curve along x with evenly spaced
 * control points (u = (x + 1)/2) seen along −z covers exactly |y| < w(u)/2 and x within
 * its ends, and grid points are kept ≥ 7e-4 away from every edge, four orders of magnitude
 * beyond Embree's float edge error (measured: an edge found by bisection lies within 3e-7
 * of the analytic one), so each count must equal the analytic count exactly. Edge
 * positions found by bisection are compared to 1e-5. The one statistical check (the
 * rendered cylinder shading) uses a fixed seed; its tolerance is explained beside it.
 *
 * pbrt-v3's intersection (its Curve::recursiveIntersect, re-implemented here in double as
 * the reference, with its refinement depth rule and splitdepth 3) is compared with
 * Embree's on a strongly bent curve: the figures are printed and bounded (the departure
 * docs/design.md records). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
// clang-format off
#include <cmocka.h>
// clang-format on

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "build/scene_builder.h"
#include "film/film.h"
#include "geometry/accel.h"
#include "geometry/curve.h"
#include "json/scene_json.h"
#include "load/scene_load.h"
#include "render/render.h"
#include "scene_support.h"
#include "tmp_folder.h"
#include "scene/scene.h"

/* ---------------------------------------------------------------- helpers */

/* An orthographic view down −z of 2 × 2 units, 16 × 16 pixels, box filter. */
#define VIEW                                                                                                   \
    "{\"tessera\":1,\"camera\":{\"type\":\"orthographic\",\"from\":[0,0,5],\"to\":[0,0,0],\"height\":2},"      \
    "\"film\":{\"width\":16,\"height\":16,\"filter\":{\"type\":\"box\"}},\"sampler\":{\"spp\":4},"             \
    "\"materials\":{\"m\":{\"type\":\"diffuse\",\"reflectance\":0.5}},"

/* A scene of one curve shape with keys CURVE (the part after "type":"curve",). */
static ts_scene *curve_scene(const char *curve)
{
    char doc[8192];
    snprintf(doc, sizeof doc, VIEW "\"shapes\":[{\"type\":\"curve\",\"material\":\"m\",%s}]}", curve);
    return ts_test_load_json(doc);
}

/* The straight curve from (−1, 0, 0) to (1, 0, 0), control points evenly spaced. */
#define STRAIGHT "\"points\":[-1,0,0, -0.3333333333,0,0, 0.3333333333,0,0, 1,0,0]"

static ts_ray down_ray(double x, double y)
{
    return ts_ray_make((ts_vec3){(float)x, (float)y, 5}, (ts_vec3){0, 0, -1}, INFINITY);
}

static bool hit_at(const ts_scene *s, double x, double y, ts_interaction *si)
{
    ts_interaction tmp;
    ts_ray r = down_ray(x, y);
    return ts_accel_intersect(s->accel, &r, si ? si : &tmp);
}

/* The y > 0 edge of the strip above x, by bisection between y_in (hit) and y_out (miss). */
static double edge_y(const ts_scene *s, double x, double y_in, double y_out)
{
    assert_true(hit_at(s, x, y_in, NULL));
    assert_false(hit_at(s, x, y_out, NULL));
    for (int k = 0; k < 40; k++) {
        double m = 0.5 * (y_in + y_out);
        if (hit_at(s, x, m, NULL))
            y_in = m;
        else
            y_out = m;
    }
    return 0.5 * (y_in + y_out);
}

/* ---------------------------------------------------------------- coverage */

/* A straight flat curve of width 0.25 covers exactly |y| < 0.125 for x in [−1, 1]: pixels of
 * 0.1 × 0.1 sampled by 64 × 64 grid points each; the edge pixels' counts are the analytic
 * coverage (y: 16 of 64 rows in [0.1, 0.2); x: 32 of 64 columns in [0.95, 1.05)). */
static void flat_strip_coverage(void **state)
{
    (void)state;
    ts_scene *s = curve_scene(STRAIGHT ",\"width\":0.25");
    const int G = 64;
    for (int py = -3; py < 3; py++)
        for (int px = -12; px < 12; px++) {
            double x0 = px * 0.1 + 0.05, y0 = py * 0.1; /* x pixels straddle ±1 at their middle */
            int hits = 0;
            for (int j = 0; j < G; j++)
                for (int i = 0; i < G; i++)
                    hits += hit_at(s, x0 + (i + 0.5) * 0.1 / G, y0 + (j + 0.5) * 0.1 / G, NULL);
            /* analytic: rows with |y| < 0.125, columns with |x| < 1 */
            int rows = 0, cols = 0;
            for (int j = 0; j < G; j++) rows += fabs(y0 + (j + 0.5) * 0.1 / G) < 0.125;
            for (int i = 0; i < G; i++) cols += fabs(x0 + (i + 0.5) * 0.1 / G) < 1;
            if (hits != rows * cols) fail_msg("pixel (%d, %d): %d grid hits, want %d", px, py, hits, rows * cols);
        }
    /* and the edge pixels are the fractional ones the analytic strip predicts */
    int rows = 0;
    for (int j = 0; j < G; j++) rows += 0.1 + (j + 0.5) * 0.1 / G < 0.125;
    assert_int_equal(rows, 16);
    ts_scene_destroy(s);
}

/* width0 → width1 is linear along the curve (pbrt-v3's Lerp(u, w0, w1)): the strip's edge
 * above x is at w(u)/2, u = (x + 1)/2; a uniform scale of 2 doubles it; over two segments the
 * width is pbrt-v3's per-segment lerp of the whole curve's. */
static void width_interpolation(void **state)
{
    (void)state;
    ts_scene *s = curve_scene(STRAIGHT ",\"width0\":0.1,\"width1\":0.3");
    for (double x = -0.95; x < 1; x += 0.1) {
        double u = (x + 1) / 2, w = 0.1 + 0.2 * u;
        double e = edge_y(s, x, 0, 0.5);
        if (fabs(e - w / 2) > 1e-5) fail_msg("x %g: edge at %.7f, want %.7f", x, e, w / 2);
    }
    ts_scene_destroy(s);
    s = curve_scene(STRAIGHT ",\"width0\":0.1,\"width1\":0.3,\"transform\":[{\"scale\":[2,2,2]}]");
    for (double x = -1.9; x < 2; x += 0.2) {
        double u = (x / 2 + 1) / 2, w = 2 * (0.1 + 0.2 * u);
        double e = edge_y(s, x, 0, 1);
        if (fabs(e - w / 2) > 1e-5) fail_msg("scaled, x %g: edge at %.7f, want %.7f", x, e, w / 2);
    }
    ts_scene_destroy(s);
    /* two segments from x = −1 to 1: widths 0.1 → 0.2 → 0.3 at x = −1, 0, 1 */
    s = curve_scene("\"points\":[-1,0,0, -0.6666666667,0,0, -0.3333333333,0,0, 0,0,0, 0.3333333333,0,0, "
                    "0.6666666667,0,0, 1,0,0],\"width0\":0.1,\"width1\":0.3");
    for (double x = -0.95; x < 1; x += 0.1) {
        double w = 0.2 + 0.1 * x;
        double e = edge_y(s, x, 0, 0.5);
        if (fabs(e - w / 2) > 1e-5) fail_msg("two segments, x %g: edge at %.7f, want %.7f", x, e, w / 2);
    }
    ts_scene_destroy(s);
}

/* ---------------------------------------------------------------- interaction */

/* The hit quantities of pbrt-v3's formulas on the straight curve seen along −z (curve.h):
 * u = (x + 1)/2, v = 1/2 − y/w, ∂p/∂u = (2, 0, 0); flat: ∂p/∂v = w·(d × ∂p/∂u)/|…| =
 * (0, −w, 0), n = −z (away from the ray); cylinder: θ = 180°(v − 1/2) = −180°·y/w and
 * n = (0, sin(πy/w), −cos(πy/w)); reverse_orientation negates n. */
static void interaction_flat_and_cylinder(void **state)
{
    (void)state;
    const double w = 0.25;
    for (int kind = 0; kind < 3; kind++) {
        ts_scene *s = curve_scene(kind == 0   ? STRAIGHT ",\"width\":0.25"
                                  : kind == 1 ? STRAIGHT ",\"width\":0.25,\"curve_type\":\"cylinder\""
                                              : STRAIGHT ",\"width\":0.25,\"curve_type\":\"cylinder\","
                                                         "\"reverse_orientation\":true");
        for (double x = -0.9; x < 1; x += 0.3)
            for (double y = -0.12; y <= 0.12; y += 0.02) {
                ts_interaction si;
                if (!hit_at(s, x, y, &si)) fail_msg("kind %d: no hit at (%g, %g)", kind, x, y);
                double u = (x + 1) / 2, v = 0.5 - y / w;
                ts_vec3 n = {0, 0, -1};
                if (kind) n = (ts_vec3){0, (float)sin(TS_PI_D * y / w), (float)-cos(TS_PI_D * y / w)};
                if (kind == 2) n = ts_vec3_neg(n);
                if (fabs(si.uv.x - u) > 1e-5 || fabs(si.uv.y - v) > 1e-5)
                    fail_msg("kind %d at (%g, %g): uv (%g, %g), want (%g, %g)", kind, x, y, si.uv.x, si.uv.y, u, v);
                if (fabs(si.n.x - n.x) > 1e-4 || fabs(si.n.y - n.y) > 1e-4 || fabs(si.n.z - n.z) > 1e-4)
                    fail_msg("kind %d at (%g, %g): n (%g, %g, %g), want (%g, %g, %g)", kind, x, y, si.n.x, si.n.y,
                             si.n.z, n.x, n.y, n.z);
                assert_true(si.ns.x == si.n.x && si.ns.y == si.n.y && si.ns.z == si.n.z);
                assert_float_equal(si.dpdu.x, 2, 1e-5);
                assert_float_equal(si.dpdu.y, 0, 1e-6);
                assert_float_equal(si.t, 5, 1e-5);
                assert_float_equal(si.p.x, x, 1e-6);
                assert_float_equal(si.p.y, y, 1e-6);
                assert_float_equal(si.p_error.x, 2 * w, 1e-5); /* pbrt-v3's 2·hitWidth */
                if (kind == 0) assert_float_equal(si.dpdv.y, -w, 1e-6);
            }
        ts_scene_destroy(s);
    }
}

/* A diffuse (R = 0.5) cylinder curve of width 1 under a distant light of irradiance π along
 * −z shades as pbrt-v3's bent normal says: L = R/π·E·|n·z| = 0.5·|cos(πy/w)|, averaged over
 * each pixel's rows (box filter). Rendered at 64 spp with the fixed seed; the per-pixel
 * function varies smoothly (|f'| ≤ π/2 over a pixel of 1/8): the Sobol estimate's error on
 * such a pixel is below 1e-3, measured 2e-4 at most, and a wrong normal (a sin for the cos,
 * or θ over [−45°, 45°]) moves the edge pixels by more than 0.05. Tolerance 3e-3. */
static void cylinder_shading(void **state)
{
    (void)state;
    const char *doc =
        "{\"tessera\":1,\"camera\":{\"type\":\"orthographic\",\"from\":[0,0,5],\"to\":[0,0,0],\"height\":2},"
        "\"film\":{\"width\":16,\"height\":16,\"filter\":{\"type\":\"box\"}},\"sampler\":{\"spp\":64},"
        "\"integrator\":{\"type\":\"direct\"},"
        "\"materials\":{\"m\":{\"type\":\"diffuse\",\"reflectance\":0.5}},"
        "\"lights\":[{\"type\":\"distant\",\"from\":[0,0,1],\"to\":[0,0,0],\"irradiance\":3.14159265358979}],"
        "\"shapes\":[{\"type\":\"curve\",\"material\":\"m\",\"curve_type\":\"cylinder\",\"width\":1,"
        "\"points\":[-2,0,0, -0.6666666667,0,0, 0.6666666667,0,0, 2,0,0]}]}";
    ts_scene *s = ts_test_load_json(doc);
    ts_film *f = ts_test_render(s, 2);
    double worst = 0;
    for (int py = 0; py < 16; py++) {
        double y0 = 1 - (py + 1) / 8.0, y1 = 1 - py / 8.0, sum = 0; /* the pixel's rows */
        const int M = 4096;
        for (int k = 0; k < M; k++) {
            double y = y0 + (k + 0.5) * (y1 - y0) / M;
            sum += fabs(y) < 0.5 ? 0.5 * fabs(cos(TS_PI_D * y)) : 0;
        }
        double want = sum / M;
        for (int px = 0; px < 16; px++) {
            ts_rgb got = ts_film_pixel_rgb(f, px, py);
            worst = fmax(worst, fabs(got.r - want));
            if (fabs(got.r - want) > 3e-3) fail_msg("pixel (%d, %d): %.5f, want %.5f", px, py, got.r, want);
        }
    }
    print_message("cylinder shading: worst pixel error %.2g\n", worst);
    ts_film_destroy(f);
    ts_scene_destroy(s);
}

/* ---------------------------------------------------------------- ribbons */

/* A ribbon's width seen along d is w·|n_u·d| (pbrt-v3): a constant normal tilted by β from
 * z gives w·cos β; end normals z → y (90°) give w·cos(90°·u); past 90° pbrt-v3 clamps the
 * angle used by its slerp to 90° (dot clamped at 0), its nHit then not unit. */
static void ribbon_width(void **state)
{
    (void)state;
    const double w = 0.2, beta = 0.6;
    char keys[512];
    snprintf(keys, sizeof keys, STRAIGHT ",\"width\":0.2,\"curve_type\":\"ribbon\",\"normals\":[0,%.17g,%.17g, 0,%.17g,%.17g]",
             sin(beta), cos(beta), sin(beta), cos(beta));
    ts_scene *s = curve_scene(keys);
    for (double x = -0.9; x < 1; x += 0.2) {
        double e = edge_y(s, x, 0, 0.5);
        if (fabs(e - w * cos(beta) / 2) > 1e-5) fail_msg("tilted, x %g: edge %.7f, want %.7f", x, e, w * cos(beta) / 2);
    }
    ts_scene_destroy(s);
    s = curve_scene(STRAIGHT ",\"width\":0.2,\"curve_type\":\"ribbon\",\"normals\":[0,0,1, 0,1,0]");
    for (double x = -0.9; x < 0.9; x += 0.2) {
        double u = (x + 1) / 2, want = w * cos(u * TS_PI_D / 2) / 2;
        double e = edge_y(s, x, 0, 0.5);
        if (fabs(e - want) > 1e-5) fail_msg("turning, x %g: edge %.7f, want %.7f", x, e, want);
    }
    ts_scene_destroy(s);
    /* 135° apart: pbrt-v3 slerps as if 90°: n = sin((1 − u)π/2)·z + sin(uπ/2)·(0, −1, −1)/√2 */
    s = curve_scene(STRAIGHT ",\"width\":0.2,\"curve_type\":\"ribbon\",\"normals\":[0,0,1, 0,-1,-1]");
    for (double x = -0.9; x < 0.9; x += 0.2) {
        double u = (x + 1) / 2;
        double nz = sin((1 - u) * TS_PI_D / 2) - sin(u * TS_PI_D / 2) / sqrt(2.0);
        double want = w * fabs(nz) / 2;
        if (want < 2e-3) continue; /* the strip vanishes near there */
        double e = edge_y(s, x, 0, 0.5);
        if (fabs(e - want) > 1e-5) fail_msg("clamped, x %g: edge %.7f, want %.7f", x, e, want);
    }
    ts_scene_destroy(s);
}

/* ---------------------------------------------------------------- bases and degrees */

/* Hits of two scenes on a grid: the same set, t and uv within float rounding. */
static void same_hits(const char *what, const ts_scene *a, const ts_scene *b, double y_lo, double y_hi)
{
    int n = 0, both = 0;
    for (double y = y_lo; y < y_hi; y += 0.0123)
        for (double x = -1.3; x < 1.3; x += 0.0117) {
            ts_interaction sa, sb;
            bool ha = hit_at(a, x, y, &sa), hb = hit_at(b, x, y, &sb);
            n++;
            if (ha != hb) fail_msg("%s: at (%g, %g) one hits and the other does not", what, x, y);
            if (!ha) continue;
            both++;
            if (fabs(sa.t - sb.t) > 1e-5 || fabs(sa.uv.x - sb.uv.x) > 1e-4 || fabs(sa.uv.y - sb.uv.y) > 1e-4)
                fail_msg("%s: at (%g, %g) t %g / %g, uv (%g, %g) / (%g, %g)", what, x, y, sa.t, sb.t, sa.uv.x, sa.uv.y,
                         sb.uv.x, sb.uv.y);
            /* Embree's v carries pbrt-v3's edge-function sign: the interaction from the nearest
             * curve point (curve.h, ts_curve_interaction_at) agrees to Embree's chordal error,
             * TS_CURVE_FLATNESS of the width, i.e. 1/200 in v (a wrong sign is off by up to 1) */
            ts_interaction r;
            ts_ray ray = down_ray(x, y);
            ts_shape_interaction(&a->shapes[0], 0, sa.prim, &ray, sa.t, &r);
            if (fabs(r.uv.y - sa.uv.y) > 1e-2 || fabs(r.uv.x - sa.uv.x) > 1e-2)
                fail_msg("%s: at (%g, %g) uv (%g, %g), from the nearest point (%g, %g)", what, x, y, sa.uv.x, sa.uv.y,
                         r.uv.x, r.uv.y);
        }
    assert_true(both > n / 50); /* the curve is in view */
}

/* B-spline points → the Bézier points of each segment by the uniform cubic B-spline's
 * basis change (each Bézier point a fixed combination of four B-spline points: (1,4,1)/6,
 * (4,2)/6… written out independently of curve.c's blossoms), and a quadratic Bézier
 * elevated by the textbook rule (P0, (P0 + 2P1)/3, (2P1 + P2)/3, P2): the same hits. */
static void bspline_and_degree2_equivalence(void **state)
{
    (void)state;
    const double B[5][3] = {{-1.2, -0.5, 0}, {-0.6, 0.6, 0.1}, {0, -0.4, -0.2}, {0.6, 0.5, 0}, {1.2, -0.3, 0.3}};
    char pts_b[1024] = "", pts_z[2048] = "";
    for (int i = 0; i < 5; i++)
        snprintf(pts_b + strlen(pts_b), sizeof pts_b - strlen(pts_b), "%s%.17g,%.17g,%.17g", i ? "," : "", B[i][0],
                 B[i][1], B[i][2]);
    int nz = 0;
    for (int seg = 0; seg < 2; seg++) {
        const double(*p)[3] = B + seg;
        double Z[4][3];
        for (int k = 0; k < 3; k++) {
            Z[0][k] = (p[0][k] + 4 * p[1][k] + p[2][k]) / 6;
            Z[1][k] = (4 * p[1][k] + 2 * p[2][k]) / 6;
            Z[2][k] = (2 * p[1][k] + 4 * p[2][k]) / 6;
            Z[3][k] = (p[1][k] + 4 * p[2][k] + p[3][k]) / 6;
        }
        for (int i = seg ? 1 : 0; i < 4; i++, nz++)
            snprintf(pts_z + strlen(pts_z), sizeof pts_z - strlen(pts_z), "%s%.9g,%.9g,%.9g", nz ? "," : "", Z[i][0],
                     Z[i][1], Z[i][2]);
    }
    char keys[4096];
    snprintf(keys, sizeof keys, "\"basis\":\"bspline\",\"width\":0.1,\"points\":[%s]", pts_b);
    ts_scene *a = curve_scene(keys);
    snprintf(keys, sizeof keys, "\"width\":0.1,\"points\":[%s]", pts_z);
    ts_scene *b = curve_scene(keys);
    assert_int_equal(a->shapes[0].curve.n_segments, 2);
    same_hits("bspline vs bezier", a, b, -0.7, 0.7);
    ts_scene_destroy(a);
    ts_scene_destroy(b);

    /* degree 2: two quadratic segments (5 points) against their elevation (7 points) */
    const double Q[5][3] = {{-1.2, -0.5, 0}, {-0.6, 0.7, 0}, {0, 0, 0.2}, {0.6, -0.7, 0}, {1.2, 0.4, 0}};
    char pts_q[1024] = "", pts_e[2048] = "";
    for (int i = 0; i < 5; i++)
        snprintf(pts_q + strlen(pts_q), sizeof pts_q - strlen(pts_q), "%s%.17g,%.17g,%.17g", i ? "," : "", Q[i][0],
                 Q[i][1], Q[i][2]);
    int ne = 0;
    for (int seg = 0; seg < 2; seg++) {
        const double(*p)[3] = Q + 2 * seg;
        double E[4][3];
        for (int k = 0; k < 3; k++) {
            E[0][k] = p[0][k];
            E[1][k] = (p[0][k] + 2 * p[1][k]) / 3;
            E[2][k] = (2 * p[1][k] + p[2][k]) / 3;
            E[3][k] = p[2][k];
        }
        for (int i = seg ? 1 : 0; i < 4; i++, ne++)
            snprintf(pts_e + strlen(pts_e), sizeof pts_e - strlen(pts_e), "%s%.9g,%.9g,%.9g", ne ? "," : "", E[i][0],
                     E[i][1], E[i][2]);
    }
    snprintf(keys, sizeof keys, "\"degree\":2,\"width\":0.1,\"points\":[%s]", pts_q);
    a = curve_scene(keys);
    snprintf(keys, sizeof keys, "\"width\":0.1,\"points\":[%s]", pts_e);
    b = curve_scene(keys);
    same_hits("degree 2 vs elevated", a, b, -0.8, 0.8);
    ts_scene_destroy(a);
    ts_scene_destroy(b);

    /* and the elevated cubic is the quadratic: at 101 u, to float rounding */
    float P[9] = {-1.2f, -0.5f, 0, -0.6f, 0.7f, 0, 0, 0, 0.2f}, cp[4][3];
    ts_curve_bezier_segment(TS_CURVE_BEZIER, 2, P, 0, cp);
    for (int k = 0; k <= 100; k++) {
        double u = k / 100.0, b0 = (1 - u) * (1 - u) * (1 - u), b1 = 3 * u * (1 - u) * (1 - u), b2 = 3 * u * u * (1 - u),
               b3 = u * u * u;
        for (int c = 0; c < 3; c++) {
            double cubic = b0 * cp[0][c] + b1 * cp[1][c] + b2 * cp[2][c] + b3 * cp[3][c];
            double quad = (1 - u) * (1 - u) * P[c] + 2 * u * (1 - u) * P[3 + c] + u * u * P[6 + c];
            if (fabs(cubic - quad) > 1e-6) fail_msg("u %g axis %d: cubic %g, quadratic %g", u, c, cubic, quad);
        }
    }
}

/* ---------------------------------------------------------------- pbrt-v3's intersection */

/* pbrt-v3's Curve::Intersect for a flat curve seen along −z from above (the ray space is
 * then the world's x, y up to a rotation, which changes nothing the test reads): hit or
 * miss of the ray through (x, y), in double. cp: one segment's Bézier points, width w0 → w1
 * over it, pieces 2^splitdepth. */
typedef struct { double x, y; } p2;
static p2 bez2(const p2 c[4], double u)
{
    p2 a[3], b[2];
    for (int i = 0; i < 3; i++) a[i] = (p2){(1 - u) * c[i].x + u * c[i + 1].x, (1 - u) * c[i].y + u * c[i + 1].y};
    for (int i = 0; i < 2; i++) b[i] = (p2){(1 - u) * a[i].x + u * a[i + 1].x, (1 - u) * a[i].y + u * a[i + 1].y};
    return (p2){(1 - u) * b[0].x + u * b[1].x, (1 - u) * b[0].y + u * b[1].y};
}
static bool pbrt_recursive(const p2 cp[4], double u0, double u1, int depth, double w0, double w1)
{
    if (depth > 0) {
        p2 s[7] = {cp[0],
                   {(cp[0].x + cp[1].x) / 2, (cp[0].y + cp[1].y) / 2},
                   {(cp[0].x + 2 * cp[1].x + cp[2].x) / 4, (cp[0].y + 2 * cp[1].y + cp[2].y) / 4},
                   {(cp[0].x + 3 * cp[1].x + 3 * cp[2].x + cp[3].x) / 8, (cp[0].y + 3 * cp[1].y + 3 * cp[2].y + cp[3].y) / 8},
                   {(cp[1].x + 2 * cp[2].x + cp[3].x) / 4, (cp[1].y + 2 * cp[2].y + cp[3].y) / 4},
                   {(cp[2].x + cp[3].x) / 2, (cp[2].y + cp[3].y) / 2},
                   cp[3]};
        double u[3] = {u0, (u0 + u1) / 2, u1};
        for (int sg = 0; sg < 2; sg++) {
            const p2 *c = s + 3 * sg;
            double mw = fmax((1 - u[sg]) * w0 + u[sg] * w1, (1 - u[sg + 1]) * w0 + u[sg + 1] * w1);
            double lx = fmin(fmin(c[0].x, c[1].x), fmin(c[2].x, c[3].x)), hx = fmax(fmax(c[0].x, c[1].x), fmax(c[2].x, c[3].x));
            double ly = fmin(fmin(c[0].y, c[1].y), fmin(c[2].y, c[3].y)), hy = fmax(fmax(c[0].y, c[1].y), fmax(c[2].y, c[3].y));
            if (hy + 0.5 * mw < 0 || ly - 0.5 * mw > 0 || hx + 0.5 * mw < 0 || lx - 0.5 * mw > 0) continue;
            if (pbrt_recursive(c, u[sg], u[sg + 1], depth - 1, w0, w1)) return true;
        }
        return false;
    }
    if ((cp[1].y - cp[0].y) * -cp[0].y + cp[0].x * (cp[0].x - cp[1].x) < 0) return false;
    if ((cp[2].y - cp[3].y) * -cp[3].y + cp[3].x * (cp[3].x - cp[2].x) < 0) return false;
    double sx = cp[3].x - cp[0].x, sy = cp[3].y - cp[0].y, den = sx * sx + sy * sy;
    if (den == 0) return false;
    double wpar = (-cp[0].x * sx - cp[0].y * sy) / den;
    double u = fmin(fmax((1 - wpar) * u0 + wpar * u1, u0), u1);
    double hw = (1 - u) * w0 + u * w1;
    p2 pc = bez2(cp, fmin(fmax(wpar, 0), 1));
    return pc.x * pc.x + pc.y * pc.y <= hw * hw * 0.25;
}
static bool pbrt_flat_hit(const p2 seg[4], double w, double x, double y)
{
    p2 c[4];
    for (int i = 0; i < 4; i++) c[i] = (p2){seg[i].x - x, seg[i].y - y};
    double eps = w * 0.05;
    for (int k = 0; k < 8; k++) { /* splitdepth 3: the curve's 8 pieces, each blossomed */
        double a = k / 8.0, b = (k + 1) / 8.0;
        p2 q[4];
        double us[4][3] = {{a, a, a}, {a, a, b}, {a, b, b}, {b, b, b}};
        for (int i = 0; i < 4; i++) {
            /* blossom of c at (u0, u1, u2) */
            p2 l1[3], l2[2];
            for (int j = 0; j < 3; j++)
                l1[j] = (p2){(1 - us[i][0]) * c[j].x + us[i][0] * c[j + 1].x, (1 - us[i][0]) * c[j].y + us[i][0] * c[j + 1].y};
            for (int j = 0; j < 2; j++)
                l2[j] = (p2){(1 - us[i][1]) * l1[j].x + us[i][1] * l1[j + 1].x, (1 - us[i][1]) * l1[j].y + us[i][1] * l1[j + 1].y};
            q[i] = (p2){(1 - us[i][2]) * l2[0].x + us[i][2] * l2[1].x, (1 - us[i][2]) * l2[0].y + us[i][2] * l2[1].y};
        }
        double L = 0;
        for (int i = 0; i < 2; i++)
            L = fmax(L, fmax(fabs(q[i].x - 2 * q[i + 1].x + q[i + 2].x), fabs(q[i].y - 2 * q[i + 1].y + q[i + 2].y)));
        double vv = 1.41421356237 * 6 * L / (8 * eps);
        int e2;
        double m2 = 2 * frexp(vv, &e2); /* pbrt-v3's Log2: the exponent, rounded up from a mantissa of 1.5 */
        int rr = vv < 1 ? 0 : (e2 - 1 + (m2 >= 1.5)) / 2, dd = rr > 10 ? 10 : rr;
        if (pbrt_recursive(q, a, b, dd, w, w)) return true;
    }
    return false;
}

/* A strongly bent flat curve (a U: control polygon (−1, 0), (−1, 2), (1, 2), (1, 0)) of
 * width 0.05 and 0.2: Embree's hit set against pbrt-v3's on a 400 × 400 grid. Embree tests
 * 16 straight pieces here (TS_CURVE_MAX_TESSELLATION; pbrt-v3 8·2^depth): the points where
 * the two disagree lie within the chordal error of those pieces of the edges, measured below
 * 0.3% of the hits (docs/design.md, Decisions); the bound here is 1%. A straight curve agrees
 * everywhere. */
static void against_pbrt_intersection(void **state)
{
    (void)state;
    const p2 U[4] = {{-1, 0}, {-1, 2}, {1, 2}, {1, 0}};
    const double widths[2] = {0.05, 0.2};
    for (int k = 0; k < 2; k++) {
        char keys[512];
        snprintf(keys, sizeof keys, "\"points\":[-1,0,0, -1,2,0, 1,2,0, 1,0,0],\"width\":%g", widths[k]);
        ts_scene *s = curve_scene(keys);
        assert_int_equal(s->shapes[0].curve.tessellation, TS_CURVE_MAX_TESSELLATION);
        long hits = 0, differ = 0;
        const int G = 400;
        for (int j = 0; j < G; j++)
            for (int i = 0; i < G; i++) {
                double x = -1.2 + 2.4 * (i + 0.5) / G, y = -0.2 + 1.8 * (j + 0.5) / G;
                bool e = hit_at(s, x, y, NULL), p = pbrt_flat_hit(U, widths[k], x, y);
                hits += p;
                differ += e != p;
            }
        print_message("bent curve, width %g: %ld of %ld pbrt-v3 hits differ (%.3f%%)\n", widths[k], differ, hits,
                      100.0 * differ / hits);
        assert_true(hits > 1000);
        assert_true(differ <= hits / 100);
        ts_scene_destroy(s);
    }
}

/* ---------------------------------------------------------------- instances, threads */

/* A curve inside an object, placed by an instance, has the hits of the same curve placed
 * directly under the composed transform. */
static void instanced_curve(void **state)
{
    (void)state;
    const char *curve = "{\"type\":\"curve\",\"material\":\"m\",\"curve_type\":\"cylinder\",\"width\":0.2,"
                        "\"points\":[-0.8,-0.3,0, -0.3,0.6,0.2, 0.3,-0.6,0, 0.8,0.3,0.1]";
    char doc[4096];
    snprintf(doc, sizeof doc,
             VIEW "\"objects\":{\"o\":{\"shapes\":[%s}]}},\"instances\":[{\"object\":\"o\",\"transform\":"
                  "[{\"rotate\":{\"angle\":30,\"axis\":[0,0,1]}},{\"translate\":[0.1,0.05,0]}]}]}",
             curve);
    ts_scene *a = ts_test_load_json(doc);
    snprintf(doc, sizeof doc,
             VIEW "\"shapes\":[%s,\"transform\":[{\"rotate\":{\"angle\":30,\"axis\":[0,0,1]}},{\"translate\":[0.1,0.05,"
                  "0]}]}]}",
             curve);
    ts_scene *b = ts_test_load_json(doc);
    int both = 0;
    for (double y = -0.9; y < 0.9; y += 0.0131)
        for (double x = -0.9; x < 0.9; x += 0.0127) {
            ts_interaction sa, sb;
            bool ha = hit_at(a, x, y, &sa), hb = hit_at(b, x, y, &sb);
            if (ha != hb) {
                /* a grid point on an edge within float rounding of the two transforms */
                ts_interaction t0;
                bool near = hit_at(a, x + 1e-4, y, &t0) != hit_at(a, x - 1e-4, y, &t0) ||
                            hit_at(a, x, y + 1e-4, &t0) != hit_at(a, x, y - 1e-4, &t0);
                if (!near) fail_msg("at (%g, %g) instance %d, direct %d", x, y, ha, hb);
                continue;
            }
            if (!ha) continue;
            both++;
            assert_int_equal(sa.inst, 1);
            if (fabs(sa.t - sb.t) > 1e-4 || fabs(sa.n.x - sb.n.x) > 1e-3 || fabs(sa.n.y - sb.n.y) > 1e-3 ||
                fabs(sa.n.z - sb.n.z) > 1e-3 || fabs(sa.uv.x - sb.uv.x) > 1e-4)
                fail_msg("at (%g, %g): t %g / %g, n (%g %g %g) / (%g %g %g)", x, y, sa.t, sb.t, sa.n.x, sa.n.y, sa.n.z,
                         sb.n.x, sb.n.y, sb.n.z);
        }
    assert_true(both > 100);
    ts_scene_destroy(a);
    ts_scene_destroy(b);
}

/* A moving curve (JSON "motion", pbrt-v3's animated transform: an object of its own under
 * a moving instance) is where its transform at the ray's time puts it: the strip of width
 * 0.25 translated by 0.2·t in y. */
static void moving_curve(void **state)
{
    (void)state;
    ts_scene *s = curve_scene(STRAIGHT ",\"width\":0.25,\"motion\":{\"transform\":[{\"translate\":[0,0.2,0]}]}");
    const double times[3] = {0, 0.5, 1};
    for (int k = 0; k < 3; k++)
        for (double x = -0.9; x < 1; x += 0.3) {
            double c = 0.2 * times[k];
            ts_interaction si;
            ts_ray in = down_ray(x, c + 0.12), out = down_ray(x, c + 0.13), below = down_ray(x, c - 0.13);
            in.time = out.time = below.time = (float)times[k];
            if (!ts_accel_intersect(s->accel, &in, &si)) fail_msg("time %g: no hit at (%g, %g)", times[k], x, c + 0.12);
            assert_true(ts_accel_intersect(s->accel, &out, &si) == false);
            assert_true(ts_accel_intersect(s->accel, &below, &si) == false);
            assert_true(ts_accel_intersect(s->accel, &in, &si));
            assert_float_equal(si.uv.y, 0.5 - 0.12 / 0.25, 1e-4);
            assert_float_equal(si.n.z, -1, 1e-5);
            assert_float_equal(si.time, times[k], 0); /* rays spawned here keep it */
        }
    ts_scene_destroy(s);
}

/* Textures on curves take the hit's (u, v) and ray differentials from its ∂p/∂u, ∂p/∂v as on
 * any shape (pbrt-v3's): a checkerboard (closed-form antialiasing, which reads the
 * footprint) and a bump map on each kind, under the path integrator, give finite pixels,
 * both checks' colours, and the same image on 1 and 2 threads. */
static void textured_curves(void **state)
{
    (void)state;
    const char *doc =
        "{\"tessera\":1,\"camera\":{\"from\":[0,0,4],\"to\":[0,0,0],\"fov\":40},"
        "\"film\":{\"width\":64,\"height\":48},\"sampler\":{\"spp\":4},\"integrator\":{\"type\":\"path\"},"
        "\"textures\":{\"checks\":{\"type\":\"checkerboard\",\"mapping\":{\"type\":\"uv\",\"uscale\":8,"
        "\"vscale\":2},\"tex1\":[0.9,0.1,0.1],\"tex2\":[0.1,0.1,0.9]},"
        "\"bumps\":{\"type\":\"fbm\",\"kind\":\"float\",\"octaves\":4,\"transform\":[{\"scale\":0.1}]}},"
        "\"materials\":{\"m\":{\"type\":\"diffuse\",\"reflectance\":\"checks\",\"bumpmap\":\"bumps\"}},"
        "\"lights\":[{\"type\":\"distant\",\"from\":[1,1,3],\"to\":[0,0,0],\"irradiance\":3}],"
        "\"shapes\":["
        "{\"type\":\"curve\",\"material\":\"m\",\"width\":0.3,\"points\":[-1.5,0.6,0, -0.5,1.2,0.3, 0.5,0,0, 1.5,0.8,0]},"
        "{\"type\":\"curve\",\"material\":\"m\",\"width\":0.3,\"curve_type\":\"cylinder\","
        "\"points\":[-1.5,0,0, -0.5,0.6,0.3, 0.5,-0.6,0, 1.5,0.2,0]},"
        "{\"type\":\"curve\",\"material\":\"m\",\"width\":0.3,\"curve_type\":\"ribbon\","
        "\"normals\":[0,0,1, 0,0.6,0.8],\"points\":[-1.5,-0.7,0, -0.5,-0.1,0.3, 0.5,-1.3,0, 1.5,-0.6,0]}]}";
    ts_scene *s = ts_test_load_json(doc);
    ts_film *f[2] = {ts_test_render(s, 1), ts_test_render(s, 2)};
    int red = 0, blue = 0;
    for (int y = 0; y < s->height; y++)
        for (int x = 0; x < s->width; x++) {
            ts_rgb a = ts_film_pixel_rgb(f[0], x, y), b = ts_film_pixel_rgb(f[1], x, y);
            assert_true(isfinite(a.r) && isfinite(a.g) && isfinite(a.b));
            assert_true(a.r == b.r && a.g == b.g && a.b == b.b);
            red += a.r > 4 * a.b && a.r > 0.05;
            blue += a.b > 4 * a.r && a.b > 0.05;
        }
    print_message("textured curves: %d red pixels, %d blue\n", red, blue);
    assert_true(red > 10 && blue > 10);
    ts_film_destroy(f[0]);
    ts_film_destroy(f[1]);
    ts_scene_destroy(s);
}

/* ---------------------------------------------------------------- front ends */

#define PBRT_HEAD                                                                                              \
    "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"orthographic\"\nFilm \"image\" \"integer xresolution\" 8 "           \
    "\"integer yresolution\" 8\nWorldBegin\n"

/* pbrt-v3's checks at file:line:column, its warnings where it goes on; convert's document
 * renders as the .pbrt does. */
static void pbrt_curve_params(void **state)
{
    (void)state;
    ts_test_pbrt_refused(PBRT_HEAD "Shape \"curve\" \"point P\" [0 0 0 1 0 0 2 0 0]\nWorldEnd\n",
                 "t.pbrt:5:15: Shape \"curve\": \"point P\" has 3 control points: for the degree 3 Bézier basis 4 + "
                 "n * 3 are required, for n >= 0 (as pbrt-v3)");
    ts_test_pbrt_refused(PBRT_HEAD "Shape \"curve\" \"string basis\" \"bspline\" \"point P\" [0 0 0 1 0 0 2 0 0]\nWorldEnd\n",
                 "t.pbrt:5:40: Shape \"curve\": \"point P\" has 3 control points: the degree 3 b-spline basis needs "
                 "at least 4 (as pbrt-v3)");
    ts_test_pbrt_refused(PBRT_HEAD "Shape \"curve\" \"integer degree\" 4 \"point P\" [0 0 0 1 0 0 2 0 0 3 0 0]\nWorldEnd\n",
                 "t.pbrt:5:15: Shape \"curve\": \"integer degree\" is 4: only degree 2 and 3 curves are supported (as "
                 "pbrt-v3)");
    ts_test_pbrt_refused(PBRT_HEAD "Shape \"curve\" \"string basis\" \"hermite\" \"point P\" [0 0 0 1 0 0 2 0 0 3 0 0]\nWorldEnd\n",
                 "t.pbrt:5:15: Shape \"curve\": \"string basis\" is \"hermite\": only \"bezier\" and \"bspline\" are "
                 "supported (as pbrt-v3)");
    ts_test_pbrt_refused(PBRT_HEAD "Shape \"curve\" \"string type\" \"ribbon\" \"point P\" [0 0 0 1 0 0 2 0 0 3 0 0]\nWorldEnd\n",
                 "t.pbrt:5:1: Shape \"curve\": a \"ribbon\" curve needs normals \"normal N\" at its segment ends (as "
                 "pbrt-v3)");
    ts_test_pbrt_refused(PBRT_HEAD "Shape \"curve\" \"string type\" \"ribbon\" \"point P\" [0 0 0 1 0 0 2 0 0 3 0 0] "
                           "\"normal N\" [0 0 1]\nWorldEnd\n",
                 "t.pbrt:5:74: Shape \"curve\": \"normal N\" has 1 normals: a ribbon curve of 1 segments needs 2 (as "
                 "pbrt-v3)");
    ts_test_pbrt_refused(PBRT_HEAD "Shape \"curve\" \"float width\" 0 \"point P\" [0 0 0 1 0 0 2 0 0 3 0 0]\nWorldEnd\n",
                 "t.pbrt:5:15: Shape \"curve\": \"float width\" must be a positive finite number, got 0 (pbrt-v3 "
                 "draws nothing or misbounds the curve)");
    ts_test_pbrt_refused(PBRT_HEAD "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\n"
                           "Shape \"curve\" \"point P\" [0 0 0 1 0 0 2 0 0 3 0 0]\nAttributeEnd\nWorldEnd\n",
                 "t.pbrt:6:1: AreaLightSource \"diffuse\" is refused on a \"curve\": pbrt-v3 cannot sample curves (its "
                 "Curve::Sample is not implemented and stops the render at the first light sample)");
    ts_test_warnings w = {0};
    ts_scene *s = ts_test_load_pbrt(PBRT_HEAD "Shape \"curve\" \"normal N\" [0 0 1 0 0 1] \"point P\" [0 0 0 1 0 0 2 0 0 3 0 0]\n"
                                      "WorldEnd\n",
                            &w);
    assert_string_equal(w.last, "t.pbrt:5:15: Shape \"curve\": \"normal N\" is ignored: curve normals are only used "
                                "with \"ribbon\" curves (as pbrt-v3)");
    assert_int_equal(s->shapes[0].type, TS_SHAPE_CURVE);
    assert_int_equal(s->shapes[0].curve.type, TS_CURVE_FLAT);
    ts_scene_destroy(s);
    w = (ts_test_warnings){0};
    s = ts_test_load_pbrt(PBRT_HEAD "Shape \"curve\" \"string type\" \"tube\" \"point P\" [0 0 0 1 0 0 2 0 0 3 0 0]\nWorldEnd\n",
                  &w);
    assert_string_equal(w.last, "t.pbrt:5:15: Shape \"curve\": \"string type\" is \"tube\", not a curve type (flat, "
                                "ribbon, cylinder): a \"cylinder\" curve, as pbrt-v3 makes it");
    assert_int_equal(s->shapes[0].curve.type, TS_CURVE_CYLINDER);
    ts_scene_destroy(s);
    /* an animated curve: pbrt-v3's TransformedPrimitive, an object of its own and a moving
     * instance (as the JSON's, tested by moving_curve) */
    w = (ts_test_warnings){0};
    s = ts_test_load_pbrt("LookAt 0 0 5  0 0 0  0 1 0\nCamera \"orthographic\" \"float shutteropen\" 0 \"float shutterclose\" 1\n"
                  "Film \"image\" \"integer xresolution\" 8 \"integer yresolution\" 8\nWorldBegin\n"
                  "ActiveTransform EndTime\nTranslate 0 0.2 0\nActiveTransform All\n"
                  "Shape \"curve\" \"point P\" [-1 0 0 -0.3333333333 0 0 0.3333333333 0 0 1 0 0] \"float width\" 0.25\n"
                  "WorldEnd\n",
                  &w);
    assert_int_equal(s->n_instances, 1);
    assert_true(s->shapes[0].type == TS_SHAPE_CURVE && s->shapes[0].in_object);
    ts_interaction si;
    ts_ray r = down_ray(0.3, 0.1 + 0.12);
    r.time = 0.5f;
    assert_true(ts_accel_intersect(s->accel, &r, &si));
    r.time = 0;
    assert_false(ts_accel_intersect(s->accel, &r, &si));
    ts_scene_destroy(s);
    /* splitdepth is taken (int or float, as pbrt-v3 reads it) and warned about nothing */
    w = (ts_test_warnings){0};
    s = ts_test_load_pbrt(PBRT_HEAD "Shape \"curve\" \"float splitdepth\" 5 \"point P\" [0 0 0 1 0 0 2 0 0 3 0 0 4 0 0 5 0 0 6 0 0]\n"
                            "WorldEnd\n",
                  &w);
    assert_int_equal(w.n, 0);
    assert_int_equal(s->shapes[0].curve.n_segments, 2);
    ts_scene_destroy(s);
}

/* `tessera convert` writes every curve parameter: the document renders the .pbrt's pixels
 * bit for bit (a flat, a ribbon, a bspline of degree 2, a reversed cylinder under a mirror
 * and an animated curve). */
static void pbrt_convert_same_pixels(void **state)
{
    (void)state;
    const char *text =
        "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 40 \"float shutterclose\" 1\n"
        "Film \"image\" \"integer xresolution\" 32 \"integer yresolution\" 24\n"
        "Sampler \"sobol\" \"integer pixelsamples\" 4\nIntegrator \"path\"\nWorldBegin\n"
        "LightSource \"distant\" \"point from\" [1 1 5] \"point to\" [0 0 0] \"rgb L\" [3 3 3]\n"
        "Material \"matte\" \"rgb Kd\" [0.8 0.3 0.2]\n"
        "Shape \"curve\" \"point P\" [-1.5 -1 0 -0.5 1 0 0.5 -1 0 1.5 1 0] \"float width0\" 0.2 \"float width1\" 0.05\n"
        "Shape \"curve\" \"point P\" [-1.5 0.5 0 -0.5 1.5 0 0.5 0.5 0 1.5 1.5 0 2 1 0 2 0 0 1.5 -1 0] "
        "\"float width\" 0.1 \"string type\" \"ribbon\" \"normal N\" [0 0 1 0 1 1 1 0 0]\n"
        "Shape \"curve\" \"point P\" [-1.5 -1.2 0 -0.5 -0.5 0 0.5 -1.5 0 1.5 -1.2 0] \"float width\" 0.1 "
        "\"string basis\" \"bspline\" \"integer degree\" 2\n"
        "AttributeBegin\nScale -1 1 1\nReverseOrientation\nShape \"curve\" \"point P\" [-1 -0.5 0.5 0 0.5 0 1 -0.5 0.5 "
        "1.5 0 0] \"float width\" 0.15 \"string type\" \"cylinder\"\nAttributeEnd\n"
        "AttributeBegin\nActiveTransform EndTime\nTranslate 0 0.3 0\nActiveTransform All\n"
        "Shape \"curve\" \"point P\" [-1 0 1 0 0.4 1 1 0 1 1.2 0.2 1] \"float width\" 0.08\nAttributeEnd\nWorldEnd\n";
    char path[512];
    ts_tmp_write("curves.pbrt", text, strlen(text), path, sizeof path);
    ts_scene *a = NULL, *b = NULL;
    ts_error err = {0};
    if (ts_scene_load_path(path, NULL, NULL, NULL, &a, &err)) fail_msg("%s", err.message);
    char *json = NULL;
    size_t len = 0;
    if (ts_scene_convert_pbrt_path(path, NULL, NULL, NULL, &json, &len, &err)) fail_msg("%s", err.message);
    if (ts_scene_load_text(json, len, ts_tmp_dir, "curves", NULL, &b, &err)) fail_msg("%s", err.message);
    free(json);
    assert_int_equal(a->n_shapes, b->n_shapes);
    ts_film *fa = ts_test_render(a, 2), *fb = ts_test_render(b, 2);
    int lit = 0;
    for (int y = 0; y < a->height; y++)
        for (int x = 0; x < a->width; x++) {
            ts_rgb p = ts_film_pixel_rgb(fa, x, y), q = ts_film_pixel_rgb(fb, x, y);
            if (p.r != q.r || p.g != q.g || p.b != q.b)
                fail_msg("pixel (%d, %d): .pbrt (%g %g %g), converted (%g %g %g)", x, y, p.r, p.g, p.b, q.r, q.g, q.b);
            lit += p.r > 0;
        }
    assert_true(lit > 50);
    ts_film_destroy(fa);
    ts_film_destroy(fb);
    ts_scene_destroy(a);
    ts_scene_destroy(b);
}

static void json_curve_keys(void **state)
{
    (void)state;
    char doc[2048];
#define CURVE_DOC(keys) (snprintf(doc, sizeof doc, VIEW "\"shapes\":[{\"type\":\"curve\",\"material\":\"m\"," keys "}]}"), doc)
    ts_test_json_refused(CURVE_DOC("\"points\":[0,0,0, 1,0,0, 2,0,0]"),
                 "shapes[0]: points: 3 control points do not make degree-3 Bézier segments (4 + n·3 are needed, n ≥ 0)");
    ts_test_json_refused(CURVE_DOC("\"points\":[0,0,0, 1,0,0, 2,0,0, 3,0,0],\"curve_type\":\"ribbon\""),
                 "shapes[0]: normals: a ribbon curve of 1 segments needs 2 normals (one at each segment end), got 0");
    ts_test_json_refused(CURVE_DOC("\"points\":[0,0,0, 1,0,0, 2,0,0, 3,0,0],\"normals\":[0,0,1, 0,0,1]"),
                 "shapes[0]: normals: only ribbon curves take normals");
    ts_test_json_refused(CURVE_DOC("\"points\":[0,0,0, 1,0,0, 2,0,0, 3,0,0],\"emission\":1"),
                 "shapes[0]: emission: a curve cannot be an area light (pbrt-v3 cannot sample curves: its "
                 "Curve::Sample is not implemented and its render stops there)");
    ts_test_json_refused(CURVE_DOC("\"points\":[0,0,0, 1,0,0, 2,0,0, 3,0,0],\"degree\":4"),
                 "shapes[0].degree: expected an integer in [2, 3], got 4");
    ts_test_json_refused(CURVE_DOC("\"points\":[0,0,0, 1,0,0, 2,0,0, 3,0,0],\"width0\":-1"),
                 "shapes[0].width0: expected a positive number, got -1");
    ts_test_json_refused(CURVE_DOC("\"points\":[0,0,0, 1,0,0, 2,0,0, 3,0,0],\"curve_type\":\"tube\""),
                 "shapes[0].curve_type: expected one of \"flat\", \"ribbon\", \"cylinder\", got \"tube\"");
    ts_test_json_refused(CURVE_DOC("\"points\":[0,0,0, 1,0,0, 2,0,0, 3,0,0],\"radius\":1"),
                 "shapes[0].radius: unknown key (allowed here: type, material, transform, motion, emission, two_sided, "
                 "light_samples, reverse_orientation, medium, points, basis, degree, curve_type, normals, width, "
                 "width0, width1)");
#undef CURVE_DOC
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(flat_strip_coverage),
        cmocka_unit_test(width_interpolation),
        cmocka_unit_test(interaction_flat_and_cylinder),
        cmocka_unit_test(cylinder_shading),
        cmocka_unit_test(ribbon_width),
        cmocka_unit_test(bspline_and_degree2_equivalence),
        cmocka_unit_test(against_pbrt_intersection),
        cmocka_unit_test(instanced_curve),
        cmocka_unit_test(textured_curves),
        cmocka_unit_test(moving_curve),
        cmocka_unit_test(pbrt_curve_params),
        cmocka_unit_test(pbrt_convert_same_pixels),
        cmocka_unit_test(json_curve_keys),
    };
    return cmocka_run_group_tests(tests, ts_tmp_group_setup, ts_tmp_group_teardown);
}
