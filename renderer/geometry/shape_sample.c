/* shape_sample.c — area and solid-angle sampling of shapes (see shape_sample.h).
 *
 * Geometry is done in double and rounded to float once at the end, like shape.c: the
 * sampled world point is within a few ulps of the exact surface and p_error bounds it.
 * Analytic shapes are sampled uniformly in object space; the world density is the object
 * density divided by the area Jacobian of to_world at that point, |det M|·|M^{-T} n_obj|
 * (Nanson's formula), which is exact for any non-singular affine transform. */
#include "geometry/shape_sample.h"

#include <string.h>

#include "sampling/sampling.h"

/* Cone sampling switches to the small-angle series for 1 − cos θ_max below this sin²θ_max
 * (next series term relative size sin⁴/8 < 2e-7). */
#define SMALL_SIN2 1e-3
/* Spherical-triangle sampling limits (sr): pbrt-v4's range for AUTO; forced spherical
 * sampling accepts smaller triangles because it runs in double here. */
#define SPHERICAL_MIN_AUTO 3e-4
#define SPHERICAL_MIN_FORCED 1e-8
#define SPHERICAL_MAX 6.22
/* AUTO samples a triangle by area, with no spherical set-up at all, where it is small as
 * seen from the reference point: area A over the squared distance to its nearest vertex
 * below this (sr; an estimate of the solid angle that errs high). There 1/r² and the
 * emitter's cosine vary little across the triangle, so spherical sampling's lower variance
 * does not pay for its trigonometry (TS_SPHERICAL_AUTO_MIN_ESTIMATE). */
#ifndef TS_SPHERICAL_AUTO_MIN_ESTIMATE
#define TS_SPHERICAL_AUTO_MIN_ESTIMATE 0.1
#endif

/* ---- small double helpers ---- */

static ts_dvec3 dv(ts_vec3 a) { return ts_dvec3_from(a); }
static ts_dvec3 dabs(ts_dvec3 a) { return (ts_dvec3){fabs(a.x), fabs(a.y), fabs(a.z)}; }
static double dmax3(ts_dvec3 a) { return fmax(a.x, fmax(a.y, a.z)); }

static void dcoordinate_system(ts_dvec3 n, ts_dvec3 *s, ts_dvec3 *t)
{
    double sign = copysign(1.0, n.z);
    double a = -1.0 / (sign + n.z);
    double b = n.x * n.y * a;
    *s = (ts_dvec3){1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x};
    *t = (ts_dvec3){b, sign + n.y * n.y * a, -n.y};
}

/* Angle between unit vectors, accurate near 0 and π. */
static double dangle_between(ts_dvec3 u, ts_dvec3 v)
{
    if (ts_dvec3_dot(u, v) < 0) return TS_PI_D - 2.0 * asin(fmin(1.0, ts_dvec3_length(ts_dvec3_add(u, v)) / 2));
    return 2.0 * asin(fmin(1.0, ts_dvec3_length(ts_dvec3_sub(v, u)) / 2));
}

static void tri_vertices(const ts_shape *s, uint32_t prim, ts_dvec3 v[3])
{
    const uint32_t *ix = s->mesh.index + 3 * (size_t)prim;
    for (int k = 0; k < 3; k++) {
        const float *p = s->mesh.p + 3 * (size_t)ix[k];
        v[k] = (ts_dvec3){p[0], p[1], p[2]};
    }
}

static double det3(const ts_mat4 *a)
{
    const double(*m)[4] = a->m;
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

/* dA_world / dA_object at a point whose unit object-space normal is n_obj. */
static double area_jacobian(const ts_shape *s, const ts_shape_sample_info *info, ts_dvec3 n_obj)
{
    return info->det_abs * ts_dvec3_length(ts_xform_normal(&s->to_world, n_obj));
}

static double object_area(const ts_shape *s) { return ts_shape_object_area(s); }

/* Unit object-space normal of an analytic shape at object point p_obj. */
static ts_dvec3 object_normal(const ts_shape *s, ts_dvec3 p_obj)
{
    switch (s->type) {
    case TS_SHAPE_SPHERE: return ts_dvec3_normalize(p_obj);
    case TS_SHAPE_CYLINDER: return ts_dvec3_normalize((ts_dvec3){p_obj.x, p_obj.y, 0});
    default: return (ts_dvec3){0, 0, 1};
    }
}

/* Conservative error bound of a point computed in double and rounded to float. */
static ts_vec3 rounding_error(ts_dvec3 p)
{
    ts_dvec3 a = dabs(p);
    float g = ts_gamma(3);
    return (ts_vec3){(float)a.x * g, (float)a.y * g, (float)a.z * g};
}

ts_status ts_shape_sample_info_init(const ts_shape *s, uint32_t prim, ts_triangle_sampling triangle_mode,
                                    ts_shape_sample_info *info, ts_error *err)
{
    memset(info, 0, sizeof *info);
    info->triangle_mode = triangle_mode;
    if (s->type == TS_SHAPE_MESH) {
        if (prim >= s->mesh.n_triangles)
            return ts_error_set(err, TS_ERR_INVALID, "triangle %u out of range (mesh has %u)", prim,
                                s->mesh.n_triangles);
        ts_dvec3 *v = info->tri_p;
        tri_vertices(s, prim, v);
        ts_dvec3 N = ts_dvec3_cross(ts_dvec3_sub(v[1], v[0]), ts_dvec3_sub(v[2], v[0]));
        info->area = 0.5 * ts_dvec3_length(N);
        info->tri_n = ts_dvec3_normalize(N);
        info->tri_pdf_area = (float)(1.0 / info->area);
        info->similarity = true;
        info->det_abs = 1;
        return TS_OK;
    }
    const ts_mat4 *m = &s->to_world.m;
    info->det_abs = fabs(det3(m));
    /* Similarity: the columns of the linear part are orthogonal and of equal length. */
    ts_dvec3 c[3];
    for (int j = 0; j < 3; j++) c[j] = (ts_dvec3){m->m[0][j], m->m[1][j], m->m[2][j]};
    double l0 = ts_dvec3_length(c[0]), l1 = ts_dvec3_length(c[1]), l2 = ts_dvec3_length(c[2]);
    double tol = 1e-9 * l0 * l0;
    info->similarity = fabs(l0 - l1) <= 1e-9 * l0 && fabs(l0 - l2) <= 1e-9 * l0 &&
                       fabs(ts_dvec3_dot(c[0], c[1])) <= tol && fabs(ts_dvec3_dot(c[0], c[2])) <= tol &&
                       fabs(ts_dvec3_dot(c[1], c[2])) <= tol;
    double a_obj = object_area(s);
    if (s->partial) {
        /* pbrt-v3's partial quadrics: shape.c's area (exact under a similarity). */
        if (s->type == TS_SHAPE_SPHERE) {
            info->center = ts_xform_point(&s->to_world, (ts_dvec3){0, 0, 0});
            info->radius = s->sphere.radius * l0;
        }
        info->area = ts_shape_area(s, 0);
        if (!isfinite(info->area)) info->area = 0;
        return TS_OK;
    }
    switch (s->type) {
    case TS_SHAPE_SPHERE: {
        info->center = ts_xform_point(&s->to_world, (ts_dvec3){0, 0, 0});
        info->radius = s->sphere.radius * l0;
        if (info->similarity) {
            info->area = a_obj * l0 * l0;
        } else {
            /* ∫∫ J(n(θ,φ)) r² sinθ dθ dφ by the midpoint rule (smooth, periodic in φ). */
            const int nt = 512, np = 1024;
            double sum = 0, r = s->sphere.radius;
            for (int i = 0; i < nt; i++) {
                double th = (i + 0.5) * TS_PI_D / nt, st = sin(th), ct = cos(th);
                for (int k = 0; k < np; k++) {
                    double ph = (k + 0.5) * 2 * TS_PI_D / np;
                    sum += area_jacobian(s, info, (ts_dvec3){st * cos(ph), st * sin(ph), ct}) * st;
                }
            }
            info->area = sum * r * r * (TS_PI_D / nt) * (2 * TS_PI_D / np);
        }
        break;
    }
    case TS_SHAPE_DISK: info->area = a_obj * area_jacobian(s, info, (ts_dvec3){0, 0, 1}); break;
    case TS_SHAPE_CYLINDER: {
        const int np = 1024;
        double sum = 0;
        for (int k = 0; k < np; k++) {
            double ph = (k + 0.5) * 2 * TS_PI_D / np;
            sum += area_jacobian(s, info, (ts_dvec3){cos(ph), sin(ph), 0});
        }
        info->area = a_obj * sum / np;
        break;
    }
    case TS_SHAPE_MESH:
    case TS_SHAPE_CURVE: break; /* curves never emit (pbrt-v3 cannot sample them) */
    }
    if (!isfinite(info->area)) info->area = 0;
    return TS_OK;
}

/* ---- rectangles of two triangles ---- */

/* The vertices of triangles a and b split as ts_shape_triangles_rectangle describes: o_a,
 * the shared s0, s1 (in a's order after o_a) and o_b. False unless exactly two positions
 * are shared. */
static bool rect_vertices(const ts_shape *s, uint32_t a, uint32_t b, ts_dvec3 *o_a, ts_dvec3 *s0, ts_dvec3 *s1,
                          ts_dvec3 *o_b)
{
    if (s->type != TS_SHAPE_MESH || a >= s->mesh.n_triangles || b >= s->mesh.n_triangles || a == b) return false;
    ts_dvec3 va[3], vb[3];
    tri_vertices(s, a, va);
    tri_vertices(s, b, vb);
    bool shared_a[3] = {false, false, false}, shared_b[3] = {false, false, false};
    int shared = 0;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            if (!shared_b[j] && va[i].x == vb[j].x && va[i].y == vb[j].y && va[i].z == vb[j].z) {
                shared_a[i] = shared_b[j] = true;
                shared++;
                break;
            }
    if (shared != 2) return false;
    int ia = !shared_a[0] ? 0 : !shared_a[1] ? 1 : 2, jb = !shared_b[0] ? 0 : !shared_b[1] ? 1 : 2;
    *o_a = va[ia];
    *s0 = va[(ia + 1) % 3];
    *s1 = va[(ia + 2) % 3];
    *o_b = vb[jb];
    return true;
}

static double dabsmax(ts_dvec3 a) { return dmax3(dabs(a)); }

bool ts_shape_triangles_rectangle(const ts_shape *s, uint32_t a, uint32_t b)
{
    ts_dvec3 o_a, s0, s1, o_b, va[3], vb[3];
    if (!rect_vertices(s, a, b, &o_a, &s0, &s1, &o_b)) return false;
    tri_vertices(s, a, va);
    tri_vertices(s, b, vb);
    ts_dvec3 na = ts_dvec3_cross(ts_dvec3_sub(va[1], va[0]), ts_dvec3_sub(va[2], va[0]));
    ts_dvec3 nb = ts_dvec3_cross(ts_dvec3_sub(vb[1], vb[0]), ts_dvec3_sub(vb[2], vb[0]));
    if (!(ts_dvec3_length(na) > 0 && ts_dvec3_length(nb) > 0) || !(ts_dvec3_dot(na, nb) > 0)) return false;
    ts_dvec3 ex = ts_dvec3_sub(s0, o_a), ey = ts_dvec3_sub(s1, o_a);
    double lx = ts_dvec3_length(ex), ly = ts_dvec3_length(ey);
    if (!(lx > 0 && ly > 0) || !isfinite(lx) || !isfinite(ly)) return false;
    ts_dvec3 D = ts_dvec3_sub(ts_dvec3_add(o_a, o_b), ts_dvec3_add(s0, s1));
    double M = fmax(fmax(dabsmax(o_a), dabsmax(o_b)), fmax(dabsmax(s0), dabsmax(s1)));
    if (!(dabsmax(D) <= 0x1p-21 * M)) return false;
    if (!(ts_dvec3_length(D) <= 0x1p-16 * fmin(lx, ly))) return false;
    return fabs(ts_dvec3_dot(ex, ey)) <= 0x1p-20 * lx * ly;
}

ts_status ts_shape_sample_info_init_rect(const ts_shape *s, uint32_t a, uint32_t b,
                                         ts_triangle_sampling triangle_mode, ts_shape_sample_info *info,
                                         ts_error *err)
{
    memset(info, 0, sizeof *info);
    info->triangle_mode = triangle_mode;
    ts_dvec3 o_a, s0, s1, o_b;
    if (!ts_shape_triangles_rectangle(s, a, b) || !rect_vertices(s, a, b, &o_a, &s0, &s1, &o_b))
        return ts_error_set(err, TS_ERR_INVALID, "triangles %u and %u do not form a rectangle", a, b);
    ts_dvec3 v[3];
    tri_vertices(s, a, v);
    info->tri_n = ts_dvec3_normalize(ts_dvec3_cross(ts_dvec3_sub(v[1], v[0]), ts_dvec3_sub(v[2], v[0])));
    ts_dvec3 ex = ts_dvec3_sub(s0, o_a), ey = ts_dvec3_sub(s1, o_a);
    info->rect_w = ts_dvec3_length(ex);
    info->rect_x = ts_dvec3_scale(ex, 1 / info->rect_w);
    ts_dvec3 ey_perp = ts_dvec3_sub(ey, ts_dvec3_scale(info->rect_x, ts_dvec3_dot(ey, info->rect_x)));
    info->rect_h = ts_dvec3_length(ey_perp);
    info->rect_y = ts_dvec3_scale(ey_perp, 1 / info->rect_h);
    info->tri_p[0] = o_a;
    info->tri_p[1] = s0;
    info->tri_p[2] = s1;
    ts_dvec3 far = ts_dvec3_add(o_a, ts_dvec3_add(ts_dvec3_scale(info->rect_x, info->rect_w),
                                                  ts_dvec3_scale(info->rect_y, info->rect_h)));
    info->rect_defect = ts_dvec3_to_vec3(dabs(ts_dvec3_sub(o_b, far)));
    info->rect = true;
    info->rect_prim[0] = a;
    info->rect_prim[1] = b;
    info->area = info->rect_w * info->rect_h;
    info->tri_pdf_area = (float)(1.0 / info->area);
    info->similarity = true;
    info->det_abs = 1;
    if (!(info->area > 0) || !isfinite(info->area)) info->area = 0;
    return TS_OK;
}

/* The point c + sx·x + sy·y of a rectangle (sx ∈ [0, w], sy ∈ [0, h]) with its error bound:
 * a triangle's bound for the sum of three terms, plus the rectangle's defect. */
static void rect_point(const ts_shape_sample_info *info, double sx, double sy, ts_shape_point *out)
{
    ts_dvec3 tx = ts_dvec3_scale(info->rect_x, sx), ty = ts_dvec3_scale(info->rect_y, sy);
    ts_dvec3 p = ts_dvec3_add(info->tri_p[0], ts_dvec3_add(tx, ty));
    ts_dvec3 e = ts_dvec3_add(dabs(info->tri_p[0]), ts_dvec3_add(dabs(tx), dabs(ty)));
    out->p = ts_dvec3_to_vec3(p);
    out->p_error = ts_vec3_add(ts_vec3_scale(ts_dvec3_to_vec3(e), ts_gamma(6)), info->rect_defect);
    out->n = ts_dvec3_to_vec3(info->tri_n);
}

/* ---- area sampling ---- */

bool ts_shape_sample_area(const ts_shape *s, uint32_t prim, const ts_shape_sample_info *info, ts_vec2 u,
                          ts_shape_point *out)
{
    (void)prim; /* a triangle's vertices and normal are in info */
    if (!(info->area > 0)) return false;
    if (s->type == TS_SHAPE_MESH && info->rect) {
        rect_point(info, (double)u.x * info->rect_w, (double)u.y * info->rect_h, out);
        out->pdf = info->tri_pdf_area;
        return isfinite(out->pdf) && out->pdf > 0;
    }
    if (s->type == TS_SHAPE_MESH) {
        const ts_dvec3 *v = info->tri_p;
        ts_vec2 b = ts_sample_uniform_triangle(u);
        double b0 = b.x, b1 = b.y, b2 = 1.0 - b0 - b1;
        ts_dvec3 p = ts_dvec3_add(ts_dvec3_add(ts_dvec3_scale(v[0], b0), ts_dvec3_scale(v[1], b1)),
                                  ts_dvec3_scale(v[2], b2));
        ts_dvec3 n = info->tri_n;
        ts_dvec3 e = ts_dvec3_add(ts_dvec3_add(dabs(ts_dvec3_scale(v[0], b0)), dabs(ts_dvec3_scale(v[1], b1))),
                                  dabs(ts_dvec3_scale(v[2], b2)));
        out->p = ts_dvec3_to_vec3(p);
        out->p_error = ts_vec3_scale(ts_dvec3_to_vec3(e), ts_gamma(6));
        out->n = ts_dvec3_to_vec3(n);
        out->pdf = info->tri_pdf_area;
        return isfinite(out->pdf) && out->pdf > 0;
    }
    ts_dvec3 p_obj, n_obj;
    if (s->partial) {
        /* Uniform over the partial surface in object space (pbrt-v3's own Sample ignores
         * the cut: docs/design.md §4). Sphere: z uniform in [z_min, z_max] (Archimedes)
         * and φ in [0, φ_max]; disk: r² uniform in [r_i², r²]; tube: z and φ uniform. */
        double phi = (double)u.y * s->phi_max, cp = cos(phi), sp = sin(phi);
        switch (s->type) {
        case TS_SHAPE_SPHERE: {
            double r = s->sphere.radius, z = s->sphere.z_min + (double)u.x * (s->sphere.z_max - s->sphere.z_min);
            double ct = fmax(-1.0, fmin(1.0, z / r)), st = sqrt(fmax(0.0, 1 - ct * ct));
            n_obj = (ts_dvec3){st * cp, st * sp, ct};
            p_obj = ts_dvec3_scale(n_obj, r);
            break;
        }
        case TS_SHAPE_DISK: {
            double ri = s->disk.inner_radius, ro = s->disk.radius;
            double rho = sqrt(ri * ri + (double)u.x * (ro * ro - ri * ri));
            p_obj = (ts_dvec3){rho * cp, rho * sp, 0};
            n_obj = (ts_dvec3){0, 0, 1};
            break;
        }
        case TS_SHAPE_CYLINDER: {
            double r = s->cylinder.radius;
            n_obj = (ts_dvec3){cp, sp, 0};
            p_obj = (ts_dvec3){r * cp, r * sp, (double)u.x * s->cylinder.height};
            break;
        }
        default: return false;
        }
    } else switch (s->type) {
    case TS_SHAPE_SPHERE:
        n_obj = ts_dvec3_normalize(ts_dvec3_from(ts_sample_uniform_sphere(u)));
        p_obj = ts_dvec3_scale(n_obj, s->sphere.radius);
        break;
    case TS_SHAPE_DISK: {
        /* Concentric point on the unit disk; its r² is uniform, so mapping r² linearly onto
         * [ri², R²] keeps the density uniform on the annulus. */
        ts_vec2 c = ts_sample_concentric_disk(u);
        double r2 = (double)c.x * c.x + (double)c.y * c.y;
        double ri = s->disk.inner_radius, ro = s->disk.radius;
        double rho = sqrt(ri * ri + r2 * (ro * ro - ri * ri));
        if (r2 > 0) p_obj = (ts_dvec3){c.x * rho / sqrt(r2), c.y * rho / sqrt(r2), 0};
        else p_obj = (ts_dvec3){rho, 0, 0};
        n_obj = (ts_dvec3){0, 0, 1};
        break;
    }
    case TS_SHAPE_CYLINDER: {
        double phi = 2 * TS_PI_D * u.y, r = s->cylinder.radius;
        n_obj = (ts_dvec3){cos(phi), sin(phi), 0};
        p_obj = (ts_dvec3){r * n_obj.x, r * n_obj.y, (double)u.x * s->cylinder.height};
        break;
    }
    default: return false;
    }
    double j = area_jacobian(s, info, n_obj);
    double pdf = 1.0 / (object_area(s) * j);
    if (!(pdf > 0) || !isfinite(pdf)) return false;
    ts_dvec3 p = ts_xform_point(&s->to_world, p_obj);
    out->p = ts_dvec3_to_vec3(p);
    out->p_error = rounding_error(p);
    ts_dvec3 n_w = ts_dvec3_normalize(ts_xform_normal(&s->to_world, n_obj));
    if (s->reverse_orientation) n_w = ts_dvec3_scale(n_w, -1);
    out->n = ts_dvec3_to_vec3(n_w);
    out->pdf = (float)pdf;
    return out->pdf > 0 && isfinite(out->pdf);
}

float ts_shape_pdf_area(const ts_shape *s, uint32_t prim, const ts_shape_sample_info *info, ts_vec3 p)
{
    (void)prim;
    if (!(info->area > 0)) return 0;
    if (s->type == TS_SHAPE_MESH) return info->tri_pdf_area;
    ts_dvec3 n_obj = object_normal(s, ts_xform_point_inv(&s->to_world, dv(p)));
    double pdf = 1.0 / (object_area(s) * area_jacobian(s, info, n_obj));
    return isfinite(pdf) ? (float)pdf : 0.0f;
}

/* World-space unit front normal at world point p of the shape. */
static ts_dvec3 normal_at(const ts_shape *s, const ts_shape_sample_info *info, ts_dvec3 p)
{
    if (s->type == TS_SHAPE_MESH) return info->tri_n;
    ts_dvec3 n_obj = object_normal(s, ts_xform_point_inv(&s->to_world, p));
    ts_dvec3 n_w = ts_dvec3_normalize(ts_xform_normal(&s->to_world, n_obj));
    return s->reverse_orientation ? ts_dvec3_scale(n_w, -1) : n_w;
}

/* ---- intersection: shape.c's exact, conservative routines ---- */

/* Nearest hit of (o, d) in (0, tmax): one triangle of a mesh, or the analytic shape. */
static bool first_hit(const ts_shape *s, uint32_t prim, const ts_ray *ray, float tmax, float *t)
{
    if (s->type == TS_SHAPE_MESH) return ts_shape_triangle_intersect(s, prim, ray, tmax, t);
    return ts_shape_intersect(s, ray, tmax, t);
}

bool ts_shape_sample_intersect(const ts_shape *s, uint32_t prim, ts_vec3 o, ts_vec3 d, double tmin, double tmax,
                               double *t_out, ts_vec3 *n_out)
{
    if (s->type == TS_SHAPE_MESH && prim >= s->mesh.n_triangles) return false;
    float tmax_f = (float)tmax, t;
    ts_ray ray = ts_ray_make(o, d, tmax_f);
    if (!first_hit(s, prim, &ray, tmax_f, &t)) return false;
    double t_hit = t;
    if (!(t_hit > tmin)) {
        /* A root at or before tmin (the surface o lies on): the next one is found from a
         * ray starting just past both; spheres and tubes have at most one more. */
        float t_skip = ts_next_float_up(fmaxf(t, (float)tmin));
        ray.o = ts_ray_at(&ray, t_skip);
        if (!first_hit(s, prim, &ray, tmax_f - t_skip, &t)) return false;
        t_hit = (double)t_skip + t;
        ray.o = o;
        if (!(t_hit > tmin && t_hit < tmax)) return false;
    }
    *t_out = t_hit;
    if (n_out) {
        ts_interaction si;
        ts_shape_interaction(s, 0, s->type == TS_SHAPE_MESH ? prim : 0, &ray, (float)t_hit, &si);
        *n_out = si.n;
    }
    return true;
}

/* ---- solid angle ---- */

/* Plane of a disk or triangle: unit normal and a point. False for other shapes. */
static bool shape_plane(const ts_shape *s, const ts_shape_sample_info *info, ts_dvec3 *n, ts_dvec3 *p0)
{
    if (s->type == TS_SHAPE_MESH) {
        *n = info->tri_n;
        *p0 = info->tri_p[0];
        return true;
    }
    if (s->type == TS_SHAPE_DISK) {
        *n = ts_dvec3_normalize(ts_xform_normal(&s->to_world, (ts_dvec3){0, 0, 1}));
        *p0 = ts_xform_point(&s->to_world, (ts_dvec3){0, 0, 0});
        return true;
    }
    return false;
}

/* True if ref lies on the plane of a planar shape within its error bound (plus one float
 * ulp of the coordinates): it sees the shape edge-on, solid angle 0. */
static bool edge_on(const ts_shape *s, const ts_shape_sample_info *info, const ts_interaction *ref)
{
    ts_dvec3 n, p0;
    if (!shape_plane(s, info, &n, &p0)) return false;
    ts_dvec3 p = dv(ref->p), an = dabs(n);
    double dist = ts_dvec3_dot(n, ts_dvec3_sub(p, p0));
    double tol = ts_dvec3_dot(an, dv(ref->p_error)) +
                 FLT_EPSILON * ts_dvec3_dot(an, ts_dvec3_add(dabs(p), dabs(p0)));
    return fabs(dist) <= tol;
}

/* Sphere seen from outside: the cone of directions it subtends. A reference point on the
 * surface within its error bound (plus a few ulps) counts as inside, as pbrt-v3's offset
 * origin does: from there the cone degenerates to the point itself. */
static bool sphere_cone(const ts_shape *s, const ts_shape_sample_info *info, const ts_interaction *ref)
{
    /* Not for a partial sphere: the cone covers the whole sphere's silhouette. */
    if (s->type != TS_SHAPE_SPHERE || !info->similarity || s->partial) return false;
    ts_dvec3 p_ref = dv(ref->p);
    ts_dvec3 dc = ts_dvec3_sub(info->center, p_ref);
    double slack = ts_dvec3_length(dv(ref->p_error)) + 4 * FLT_EPSILON * dmax3(dabs(p_ref));
    double r = info->radius + slack;
    return ts_dvec3_dot(dc, dc) > r * r;
}

/* 1 − cos θ_max of the cone, with the small-angle series for tiny spheres. */
static double sphere_one_minus_cos(const ts_shape_sample_info *info, ts_dvec3 p_ref)
{
    ts_dvec3 dc = ts_dvec3_sub(info->center, p_ref);
    double sin2 = info->radius * info->radius / ts_dvec3_dot(dc, dc);
    if (sin2 < SMALL_SIN2) return 0.5 * sin2 * (1 + 0.25 * sin2);
    return 1 - sqrt(fmax(0.0, 1 - sin2));
}

/* Unit vectors from p to the triangle's vertices and the solid angle; false if p is at a
 * vertex. */
static bool spherical_setup(const ts_shape_sample_info *info, ts_dvec3 p, ts_dvec3 w[3], double *omega)
{
    const ts_dvec3 *v = info->tri_p;
    for (int k = 0; k < 3; k++) {
        w[k] = ts_dvec3_sub(v[k], p);
        double len = ts_dvec3_length(w[k]);
        if (!(len > 0)) return false;
        w[k] = ts_dvec3_scale(w[k], 1 / len);
    }
    double num = fabs(ts_dvec3_dot(w[0], ts_dvec3_cross(w[1], w[2])));
    double den = 1 + ts_dvec3_dot(w[0], w[1]) + ts_dvec3_dot(w[0], w[2]) + ts_dvec3_dot(w[1], w[2]);
    *omega = 2 * atan2(num, den);
    return true;
}

double ts_spherical_triangle_area(ts_dvec3 a, ts_dvec3 b, ts_dvec3 c, ts_dvec3 p)
{
    ts_dvec3 w[3] = {ts_dvec3_normalize(ts_dvec3_sub(a, p)), ts_dvec3_normalize(ts_dvec3_sub(b, p)),
                     ts_dvec3_normalize(ts_dvec3_sub(c, p))};
    double num = fabs(ts_dvec3_dot(w[0], ts_dvec3_cross(w[1], w[2])));
    double den = 1 + ts_dvec3_dot(w[0], w[1]) + ts_dvec3_dot(w[0], w[2]) + ts_dvec3_dot(w[1], w[2]);
    return 2 * atan2(num, den);
}

/* Ureña, Fajardo and King (2013), "An Area-Preserving Parametrization for Spherical
 * Rectangles": in the rectangle's frame (x, y along its edges, z = x × y turned so that the
 * rectangle lies at z0 < 0 from p) the rectangle is [x0, x1] × [y0, y1] × {z0}. The planes
 * through p and its four edges have unit normals n0…n3 (edges y = y0, x = x1, y = y1,
 * x = x0); the spherical rectangle's interior angles are g_i = ∠(n_i, −n_{i+1}) and its
 * area S = Σg_i − 2π. u.x picks the sub-rectangle [x0, xu] of area u.x·S in closed form
 * (through k = 2π − g2 − g3, b0 = n0.z, b1 = n2.z), u.y the height by the uniform
 * distribution of h = y/√(xu² + z0² + y²) between its values at y0 and y1. */
typedef struct rect_view {
    double x0, x1, y0, y1, z0; /* the rectangle in p's frame */
    ts_dvec3 z;                /* the frame's third axis (x, y are the rectangle's) */
    double b0, b1, k, S;
} rect_view;

static bool rect_setup(const ts_shape_sample_info *info, ts_dvec3 p, rect_view *r)
{
    ts_dvec3 d = ts_dvec3_sub(info->tri_p[0], p);
    r->z = ts_dvec3_cross(info->rect_x, info->rect_y);
    r->x0 = ts_dvec3_dot(d, info->rect_x);
    r->y0 = ts_dvec3_dot(d, info->rect_y);
    r->z0 = ts_dvec3_dot(d, r->z);
    if (r->z0 > 0) {
        r->z0 = -r->z0;
        r->z = ts_dvec3_scale(r->z, -1);
    }
    if (!(r->z0 < 0)) return false; /* on the plane (or NaN) */
    double x0 = r->x0, y0 = r->y0, z0 = r->z0, x1 = x0 + info->rect_w, y1 = y0 + info->rect_h;
    r->x1 = x1;
    r->y1 = y1;
    /* n0 = (0, z0, −y0)/L0, n1 = (−z0, 0, x1)/L1, n2 = (0, −z0, y1)/L2, n3 = (z0, 0, −x0)/L3, so
     * the cosines −n_i·n_{i+1} are products of the coordinates. acos from a cosine of a few
     * ulps' error is within ~1e-16/sin g of g: near 0 and π (edge-on views) that is still
     * 1e-12 at g = 1e-4, far below the 3e-4 sr where AUTO stops sampling spherically. */
    double L0 = sqrt(z0 * z0 + y0 * y0), L1 = sqrt(z0 * z0 + x1 * x1), L2 = sqrt(z0 * z0 + y1 * y1),
           L3 = sqrt(z0 * z0 + x0 * x0);
    if (!(L0 > 0 && L1 > 0 && L2 > 0 && L3 > 0) || !isfinite(L0 * L1 * L2 * L3)) return false;
    double c[4] = {y0 * x1 / (L0 * L1), -x1 * y1 / (L1 * L2), x0 * y1 / (L2 * L3), -x0 * y0 / (L3 * L0)};
    double g[4];
    for (int i = 0; i < 4; i++)
        g[i] = acos(fmin(1.0, fmax(-1.0, c[i])));
    r->b0 = -y0 / L0;
    r->b1 = y1 / L2;
    r->k = 2 * TS_PI_D - g[2] - g[3];
    r->S = g[0] + g[1] - r->k;
    return r->S > 0 && isfinite(r->S);
}

double ts_spherical_rectangle_area(const ts_shape_sample_info *info, ts_dvec3 p)
{
    rect_view r;
    return info->rect && rect_setup(info, p, &r) ? r.S : 0;
}

/* The sample of u from a set-up view: offsets (sx, sy) from the corner, within [0, w] × [0, h]. */
static bool rect_map(const ts_shape_sample_info *info, const rect_view *r, ts_vec2 u, double *sx, double *sy)
{
    double au = u.x * r->S + r->k;
    double sa = sin(au), num = cos(au) * r->b0 - r->b1;
    /* cu = sign(fu)/√(fu² + b0²) with fu = num/sin(au), written without the division:
     * sin(au) vanishes inside the range when the sub-rectangle passes a half-turn. */
    double den = sqrt(num * num + r->b0 * r->b0 * sa * sa);
    if (!(den > 0) || !isfinite(den)) return false;
    double cu = fmin(1.0, fmax(-1.0, copysign(1.0, num) * sa / den));
    double one_c2 = 1 - cu * cu, xu;
    if (one_c2 > 0) xu = -(cu * r->z0) / sqrt(one_c2);
    else xu = cu > 0 ? r->x1 : r->x0;
    xu = fmin(r->x1, fmax(r->x0, xu));
    double dd = sqrt(xu * xu + r->z0 * r->z0);
    double h0 = r->y0 / sqrt(dd * dd + r->y0 * r->y0), h1 = r->y1 / sqrt(dd * dd + r->y1 * r->y1);
    double hv = h0 + u.y * (h1 - h0), hv2 = hv * hv, yv;
    if (hv2 < 1 - 1e-12) yv = hv * dd / sqrt(1 - hv2);
    else yv = hv > 0 ? r->y1 : r->y0;
    yv = fmin(r->y1, fmax(r->y0, yv));
    *sx = fmin(info->rect_w, fmax(0.0, xu - r->x0));
    *sy = fmin(info->rect_h, fmax(0.0, yv - r->y0));
    return isfinite(*sx) && isfinite(*sy);
}

bool ts_spherical_rectangle_sample(const ts_shape_sample_info *info, ts_dvec3 p, ts_vec2 u, ts_dvec3 *p_rect,
                                   double *omega)
{
    rect_view r;
    double sx, sy;
    if (!info->rect || !rect_setup(info, p, &r) || !rect_map(info, &r, u, &sx, &sy)) return false;
    *p_rect = ts_dvec3_add(info->tri_p[0],
                           ts_dvec3_add(ts_dvec3_scale(info->rect_x, sx), ts_dvec3_scale(info->rect_y, sy)));
    *omega = r.S;
    return true;
}

/* AUTO's cheap test: the triangle looks small from p (see TS_SPHERICAL_AUTO_MIN_ESTIMATE).
 * A rectangle is judged by half its area (one of its triangles): the same distances as
 * its two triangles had. Judged by its whole area (twice as far out), the Cornell box cost
 * 2.9% more instructions a sample for 0.2% less variance (docs/performance.md, third round). */
static bool auto_small(const ts_shape_sample_info *info, ts_dvec3 p)
{
    if (info->triangle_mode != TS_TRIANGLE_SAMPLING_AUTO) return false;
    const ts_dvec3 *v = info->tri_p;
    double d2 = INFINITY;
    for (int k = 0; k < 3; k++) {
        ts_dvec3 w = ts_dvec3_sub(v[k], p);
        d2 = fmin(d2, ts_dvec3_dot(w, w));
    }
    if (info->rect) { /* the fourth corner */
        ts_dvec3 w = ts_dvec3_sub(ts_dvec3_sub(ts_dvec3_add(v[1], v[2]), v[0]), p);
        d2 = fmin(d2, ts_dvec3_dot(w, w));
    }
    return (info->rect ? 0.5 : 1) * info->area < TS_SPHERICAL_AUTO_MIN_ESTIMATE * d2;
}

static bool use_spherical(const ts_shape_sample_info *info, double omega)
{
    switch (info->triangle_mode) {
    case TS_TRIANGLE_SAMPLING_AREA: return false;
    case TS_TRIANGLE_SAMPLING_SPHERICAL: return omega >= SPHERICAL_MIN_FORCED && omega <= SPHERICAL_MAX;
    case TS_TRIANGLE_SAMPLING_AUTO: break;
    }
    return omega >= SPHERICAL_MIN_AUTO && omega <= SPHERICAL_MAX;
}

/* Arvo's uniform sampling of the spherical triangle (a, b, c) (unit vectors), pbrt-v4
 * §6.5.4: choose the sub-triangle of area u0·A by its third vertex c' on arc ac, then a
 * point on arc b c' with the right cosine distribution. */
static bool sample_spherical_triangle(const ts_dvec3 w[3], ts_vec2 u, ts_dvec3 *dir)
{
    ts_dvec3 a = w[0], b = w[1], c = w[2];
    ts_dvec3 n_ab = ts_dvec3_cross(a, b), n_bc = ts_dvec3_cross(b, c), n_ca = ts_dvec3_cross(c, a);
    double l_ab = ts_dvec3_length(n_ab), l_bc = ts_dvec3_length(n_bc), l_ca = ts_dvec3_length(n_ca);
    if (!(l_ab > 0 && l_bc > 0 && l_ca > 0)) return false;
    n_ab = ts_dvec3_scale(n_ab, 1 / l_ab);
    n_bc = ts_dvec3_scale(n_bc, 1 / l_bc);
    n_ca = ts_dvec3_scale(n_ca, 1 / l_ca);
    /* Interior angles at a, b, c from the normals of the great circles through them. */
    double alpha = dangle_between(n_ab, ts_dvec3_scale(n_ca, -1));
    double beta = dangle_between(n_bc, ts_dvec3_scale(n_ab, -1));
    double gamma = dangle_between(n_ca, ts_dvec3_scale(n_bc, -1));
    double ap_pi = TS_PI_D + u.x * (alpha + beta + gamma - TS_PI_D); /* A' + π */
    double ca = cos(alpha), sa = sin(alpha);
    double sin_phi = sin(ap_pi) * ca - cos(ap_pi) * sa;
    double cos_phi = cos(ap_pi) * ca + sin(ap_pi) * sa;
    double k1 = cos_phi + ca;
    double k2 = sin_phi - sa * ts_dvec3_dot(a, b);
    double den = (k2 * sin_phi + k1 * cos_phi) * sa;
    if (den == 0) return false;
    double cos_bp = (k2 + (k2 * cos_phi - k1 * sin_phi) * ca) / den;
    cos_bp = fmin(1.0, fmax(-1.0, cos_bp));
    double sin_bp = sqrt(fmax(0.0, 1 - cos_bp * cos_bp));
    ts_dvec3 c_perp = ts_dvec3_normalize(ts_dvec3_sub(c, ts_dvec3_scale(a, ts_dvec3_dot(c, a))));
    ts_dvec3 cp = ts_dvec3_add(ts_dvec3_scale(a, cos_bp), ts_dvec3_scale(c_perp, sin_bp));
    double cos_t = 1 - u.y * (1 - ts_dvec3_dot(cp, b));
    double sin_t = sqrt(fmax(0.0, 1 - cos_t * cos_t));
    ts_dvec3 cp_perp = ts_dvec3_sub(cp, ts_dvec3_scale(b, ts_dvec3_dot(cp, b)));
    double lp = ts_dvec3_length(cp_perp);
    if (!(lp > 0)) {
        *dir = b;
        return true;
    }
    *dir = ts_dvec3_add(ts_dvec3_scale(b, cos_t), ts_dvec3_scale(cp_perp, sin_t / lp));
    return isfinite(dir->x) && isfinite(dir->y) && isfinite(dir->z);
}

/* tmin for a ray leaving ref: past ref's error bound and a few ulps of its coordinates. */
static double ray_tmin(const ts_interaction *ref, ts_dvec3 d)
{
    double len = ts_dvec3_length(d);
    double dist = 4 * dmax3(dv(ref->p_error)) + 4 * FLT_EPSILON * dmax3(dabs(dv(ref->p)));
    return len > 0 ? dist / len : INFINITY;
}

/* Converts an area-density point to solid angle as seen from p_ref; false if degenerate. */
static bool area_to_solid_angle(ts_dvec3 p_ref, ts_shape_point *pt)
{
    ts_dvec3 w = ts_dvec3_sub(dv(pt->p), p_ref);
    double d2 = ts_dvec3_dot(w, w);
    if (!(d2 > 0)) return false;
    double cos_o = fabs(ts_dvec3_dot(dv(pt->n), w)) / sqrt(d2);
    if (!(cos_o > 0)) return false;
    double pdf = pt->pdf * d2 / cos_o;
    if (!(pdf > 0) || !(pdf < FLT_MAX)) return false;
    pt->pdf = (float)pdf;
    return true;
}

bool ts_shape_sample_solid_angle(const ts_shape *s, uint32_t prim, const ts_shape_sample_info *info,
                                 const ts_interaction *ref, ts_vec2 u, ts_shape_point *out)
{
    if (!(info->area > 0) || edge_on(s, info, ref)) return false;
    ts_dvec3 p_ref = dv(ref->p);
    if (sphere_cone(s, info, ref)) {
        ts_dvec3 dc = ts_dvec3_sub(info->center, p_ref);
        double d2 = ts_dvec3_dot(dc, dc), d = sqrt(d2), r = info->radius;
        double sin2_max = r * r / d2;
        double omc = sphere_one_minus_cos(info, p_ref);
        if (!(omc > 0)) return false;
        /* Direction at angle θ from the axis, uniform in the cone. */
        double eps = u.x * omc;
        double cos_t = 1 - eps, sin2_t = eps * (2 - eps);
        double phi = 2 * TS_PI_D * u.y;
        /* Angle α at the centre between −axis and the point where that direction first
         * meets the sphere. */
        double cos_a = sin2_t / sqrt(sin2_max) + cos_t * sqrt(fmax(0.0, 1 - sin2_t / sin2_max));
        cos_a = fmin(1.0, fmax(-1.0, cos_a));
        double sin_a = sqrt(fmax(0.0, 1 - cos_a * cos_a));
        ts_dvec3 wc = ts_dvec3_scale(dc, 1 / d), wx, wy;
        dcoordinate_system(wc, &wx, &wy);
        ts_dvec3 n = ts_dvec3_add(ts_dvec3_add(ts_dvec3_scale(wx, -sin_a * cos(phi)), ts_dvec3_scale(wy, -sin_a * sin(phi))),
                                  ts_dvec3_scale(wc, -cos_a));
        ts_dvec3 p = ts_dvec3_add(info->center, ts_dvec3_scale(n, r));
        if (s->reverse_orientation) n = ts_dvec3_scale(n, -1);
        out->p = ts_dvec3_to_vec3(p);
        out->p_error = rounding_error(p);
        out->n = ts_dvec3_to_vec3(n);
        out->pdf = (float)(1 / (2 * TS_PI_D * omc));
        return isfinite(out->pdf) && ts_vec3_distance_sq(out->p, ref->p) > 0;
    }
    if (s->type == TS_SHAPE_MESH && info->rect && !auto_small(info, p_ref)) {
        rect_view r;
        double sx, sy;
        if (!rect_setup(info, p_ref, &r)) return false;
        if (use_spherical(info, r.S)) {
            if (!rect_map(info, &r, u, &sx, &sy)) return false;
            rect_point(info, sx, sy, out);
            out->pdf = (float)(1 / r.S);
            return isfinite(out->pdf) && out->pdf > 0 && ts_vec3_distance_sq(out->p, ref->p) > 0;
        }
    } else if (s->type == TS_SHAPE_MESH && !auto_small(info, p_ref)) {
        const ts_dvec3 *v = info->tri_p;
        ts_dvec3 w[3], dir;
        double omega;
        if (!spherical_setup(info, p_ref, w, &omega)) return false;
        if (use_spherical(info, omega)) {
            if (!sample_spherical_triangle(w, u, &dir)) return false;
            ts_dvec3 n = info->tri_n;
            double dn = ts_dvec3_dot(n, dir);
            if (dn == 0) return false;
            double t = ts_dvec3_dot(n, ts_dvec3_sub(v[0], p_ref)) / dn;
            if (!(t > 0)) return false;
            ts_dvec3 p = ts_dvec3_add(p_ref, ts_dvec3_scale(dir, t));
            /* Barycentrics of p (clamped into the triangle against rounding). */
            ts_dvec3 e1 = ts_dvec3_sub(v[1], v[0]), e2 = ts_dvec3_sub(v[2], v[0]), ep = ts_dvec3_sub(p, v[0]);
            double d11 = ts_dvec3_dot(e1, e1), d12 = ts_dvec3_dot(e1, e2), d22 = ts_dvec3_dot(e2, e2);
            double dp1 = ts_dvec3_dot(ep, e1), dp2 = ts_dvec3_dot(ep, e2);
            double den = d11 * d22 - d12 * d12;
            if (!(den > 0)) return false;
            double b1 = fmax(0.0, (d22 * dp1 - d12 * dp2) / den), b2 = fmax(0.0, (d11 * dp2 - d12 * dp1) / den);
            double b0 = fmax(0.0, 1 - b1 - b2), sum = b0 + b1 + b2;
            b0 /= sum, b1 /= sum, b2 /= sum;
            p = ts_dvec3_add(ts_dvec3_add(ts_dvec3_scale(v[0], b0), ts_dvec3_scale(v[1], b1)), ts_dvec3_scale(v[2], b2));
            ts_dvec3 e = ts_dvec3_add(ts_dvec3_add(dabs(ts_dvec3_scale(v[0], b0)), dabs(ts_dvec3_scale(v[1], b1))),
                                      dabs(ts_dvec3_scale(v[2], b2)));
            out->p = ts_dvec3_to_vec3(p);
            out->p_error = ts_vec3_scale(ts_dvec3_to_vec3(e), ts_gamma(6));
            out->n = ts_dvec3_to_vec3(n);
            out->pdf = (float)(1 / omega);
            return isfinite(out->pdf) && ts_vec3_distance_sq(out->p, ref->p) > 0;
        }
    }
    if (!ts_shape_sample_area(s, prim, info, u, out)) return false;
    return area_to_solid_angle(p_ref, out);
}

float ts_shape_pdf_solid_angle_at(const ts_shape *s, uint32_t prim, const ts_shape_sample_info *info,
                                  const ts_interaction *ref, ts_vec3 p_hit)
{
    if (!(info->area > 0) || edge_on(s, info, ref)) return 0;
    ts_dvec3 p_ref = dv(ref->p);
    if (sphere_cone(s, info, ref)) return (float)(1 / (2 * TS_PI_D * sphere_one_minus_cos(info, p_ref)));
    if (s->type == TS_SHAPE_MESH && info->rect && !auto_small(info, p_ref)) {
        rect_view r;
        if (!rect_setup(info, p_ref, &r)) return 0;
        if (use_spherical(info, r.S)) return (float)(1 / r.S);
    } else if (s->type == TS_SHAPE_MESH && !auto_small(info, p_ref)) {
        ts_dvec3 w[3];
        double omega;
        if (!spherical_setup(info, p_ref, w, &omega)) return 0;
        if (use_spherical(info, omega)) return (float)(1 / omega);
    }
    ts_shape_point pt = {p_hit, {0, 0, 0}, ts_dvec3_to_vec3(normal_at(s, info, dv(p_hit))),
                         ts_shape_pdf_area(s, prim, info, p_hit)};
    if (!(pt.pdf > 0) || !area_to_solid_angle(p_ref, &pt)) return 0;
    return pt.pdf;
}

float ts_shape_pdf_solid_angle(const ts_shape *s, uint32_t prim, const ts_shape_sample_info *info,
                               const ts_interaction *ref, ts_vec3 wi)
{
    if (!(info->area > 0) || edge_on(s, info, ref)) return 0;
    ts_dvec3 p_ref = dv(ref->p), d = ts_dvec3_normalize(dv(wi));
    if (!(ts_dvec3_length(d) > 0)) return 0;
    if (sphere_cone(s, info, ref)) {
        /* Inside the cone iff the line's distance to the centre is at most r (ahead of
         * ref). Slack of a few float ulps of the distance, so directions rounded from
         * silhouette samples still count: outside the true cone such a direction misses
         * the sphere and never asks for this pdf. */
        ts_dvec3 dc = ts_dvec3_sub(info->center, p_ref);
        if (!(ts_dvec3_dot(dc, d) > 0)) return 0;
        ts_dvec3 x = ts_dvec3_cross(dc, d);
        double r = info->radius * (1 + 1e-5) + 1e-6 * ts_dvec3_length(dc);
        if (ts_dvec3_dot(x, x) > r * r) return 0;
        return (float)(1 / (2 * TS_PI_D * sphere_one_minus_cos(info, p_ref)));
    }
    double t, t_b;
    ts_vec3 wf = ts_dvec3_to_vec3(d);
    bool hit = ts_shape_sample_intersect(s, info->rect ? info->rect_prim[0] : prim, ref->p, wf, ray_tmin(ref, d),
                                         INFINITY, &t, NULL);
    if (info->rect && ts_shape_sample_intersect(s, info->rect_prim[1], ref->p, wf, ray_tmin(ref, d), INFINITY, &t_b,
                                                NULL) && (!hit || t_b < t)) {
        t = t_b;
        hit = true;
    }
    if (!hit) return 0;
    ts_dvec3 p_hit = ts_dvec3_add(p_ref, ts_dvec3_scale(dv(wf), t));
    return ts_shape_pdf_solid_angle_at(s, prim, info, ref, ts_dvec3_to_vec3(p_hit));
}
