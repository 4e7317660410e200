/* texture_mapping.c — the shading context's footprint and pbrt-v3's texture mappings
 * (see texture_mapping.h). Operation order follows pbrt-v3 where it decides rounding
 * (a difference quotient is multiplied by 1/δ, as pbrt-v3's Vector2f / Float does). */
#include "textures/texture_mapping.h"

#include <math.h>

static ts_vec3 xform_point(const ts_mat4 *m, ts_vec3 p)
{
    double x = m->m[0][0] * p.x + m->m[0][1] * p.y + m->m[0][2] * p.z + m->m[0][3];
    double y = m->m[1][0] * p.x + m->m[1][1] * p.y + m->m[1][2] * p.z + m->m[1][3];
    double z = m->m[2][0] * p.x + m->m[2][1] * p.y + m->m[2][2] * p.z + m->m[2][3];
    double w = m->m[3][0] * p.x + m->m[3][1] * p.y + m->m[3][2] * p.z + m->m[3][3];
    if (w != 1) x /= w, y /= w, z /= w;
    return (ts_vec3){(float)x, (float)y, (float)z};
}

static ts_vec3 xform_vector(const ts_mat4 *m, ts_vec3 v)
{
    return (ts_vec3){(float)(m->m[0][0] * v.x + m->m[0][1] * v.y + m->m[0][2] * v.z),
                     (float)(m->m[1][0] * v.x + m->m[1][1] * v.y + m->m[1][2] * v.z),
                     (float)(m->m[2][0] * v.x + m->m[2][1] * v.y + m->m[2][2] * v.z)};
}

void ts_texture_context_clear_differentials(ts_texture_context *c)
{
    c->dpdx = c->dpdy = (ts_vec3){0, 0, 0};
    c->dudx = c->dvdx = c->dudy = c->dvdy = 0;
}

/* pbrt-v3's SolveLinearSystem2x2: false for |det| < 1e-10 or a NaN solution. */
static bool solve2x2(const float a[2][2], const float b[2], float *x0, float *x1)
{
    float det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
    if (fabsf(det) < 1e-10f) return false;
    *x0 = (a[1][1] * b[0] - a[0][1] * b[1]) / det;
    *x1 = (a[0][0] * b[1] - a[1][0] * b[0]) / det;
    return !(isnan(*x0) || isnan(*x1));
}

void ts_texture_context_set_differentials(ts_texture_context *c, ts_vec3 n, ts_vec3 rx_o, ts_vec3 rx_d,
                                          ts_vec3 ry_o, ts_vec3 ry_d)
{
    float d = ts_vec3_dot(n, c->p);
    float tx = -(ts_vec3_dot(n, rx_o) - d) / ts_vec3_dot(n, rx_d);
    float ty = -(ts_vec3_dot(n, ry_o) - d) / ts_vec3_dot(n, ry_d);
    if (!isfinite(tx) || !isfinite(ty)) {
        ts_texture_context_clear_differentials(c);
        return;
    }
    ts_vec3 px = ts_vec3_add(rx_o, ts_vec3_scale(rx_d, tx));
    ts_vec3 py = ts_vec3_add(ry_o, ts_vec3_scale(ry_d, ty));
    c->dpdx = ts_vec3_sub(px, c->p);
    c->dpdy = ts_vec3_sub(py, c->p);

    /* The two coordinates in which the plane's projection is best conditioned. */
    int d0, d1;
    if (fabsf(n.x) > fabsf(n.y) && fabsf(n.x) > fabsf(n.z))
        d0 = 1, d1 = 2;
    else if (fabsf(n.y) > fabsf(n.z))
        d0 = 0, d1 = 2;
    else
        d0 = 0, d1 = 1;
    const float a[2][2] = {{ts_vec3_get(c->dpdu, d0), ts_vec3_get(c->dpdv, d0)},
                           {ts_vec3_get(c->dpdu, d1), ts_vec3_get(c->dpdv, d1)}};
    const float bx[2] = {ts_vec3_get(px, d0) - ts_vec3_get(c->p, d0),
                         ts_vec3_get(px, d1) - ts_vec3_get(c->p, d1)};
    const float by[2] = {ts_vec3_get(py, d0) - ts_vec3_get(c->p, d0),
                         ts_vec3_get(py, d1) - ts_vec3_get(c->p, d1)};
    if (!solve2x2(a, bx, &c->dudx, &c->dvdx)) c->dudx = c->dvdx = 0;
    if (!solve2x2(a, by, &c->dudy, &c->dvdy)) c->dudy = c->dvdy = 0;
}

ts_texture_mapping2d ts_texture_mapping2d_uv(float su, float sv, float du, float dv)
{
    return (ts_texture_mapping2d){.type = TS_TEXTURE_MAPPING_UV,
                                  .su = su,
                                  .sv = sv,
                                  .du = du,
                                  .dv = dv,
                                  .world_to_texture = ts_mat4_identity()};
}

ts_texture_mapping2d ts_texture_mapping2d_spherical(const ts_mat4 *world_to_texture)
{
    return (ts_texture_mapping2d){
        .type = TS_TEXTURE_MAPPING_SPHERICAL, .su = 1, .sv = 1, .world_to_texture = *world_to_texture};
}

ts_texture_mapping2d ts_texture_mapping2d_cylindrical(const ts_mat4 *world_to_texture)
{
    return (ts_texture_mapping2d){
        .type = TS_TEXTURE_MAPPING_CYLINDRICAL, .su = 1, .sv = 1, .world_to_texture = *world_to_texture};
}

ts_texture_mapping2d ts_texture_mapping2d_planar(ts_vec3 vs, ts_vec3 vt, float du, float dv)
{
    return (ts_texture_mapping2d){.type = TS_TEXTURE_MAPPING_PLANAR,
                                  .su = 1,
                                  .sv = 1,
                                  .du = du,
                                  .dv = dv,
                                  .vs = vs,
                                  .vt = vt,
                                  .world_to_texture = ts_mat4_identity()};
}

static ts_vec2 sphere_st(const ts_mat4 *m, ts_vec3 p)
{
    ts_vec3 v = ts_vec3_normalize(xform_point(m, p));
    float theta = ts_safe_acosf(v.z);
    float phi = atan2f(v.y, v.x);
    if (phi < 0) phi += 2 * TS_PI;
    return (ts_vec2){theta * TS_INV_PI, phi * TS_INV_2PI};
}

static ts_vec2 cylinder_st(const ts_mat4 *m, ts_vec3 p)
{
    ts_vec3 v = ts_vec3_normalize(xform_point(m, p));
    return (ts_vec2){(TS_PI + atan2f(v.y, v.x)) * TS_INV_2PI, v.z};
}

/* (st(p + δ·dp) − st(p)) / δ, then pbrt-v3's wrap correction of its second component. */
static ts_vec2 wrapped_difference(ts_vec2 st_delta, ts_vec2 st, float inv_delta)
{
    ts_vec2 d = {(st_delta.x - st.x) * inv_delta, (st_delta.y - st.y) * inv_delta};
    if (d.y > 0.5f)
        d.y = 1 - d.y;
    else if (d.y < -0.5f)
        d.y = -(d.y + 1);
    return d;
}

ts_vec2 ts_texture_mapping2d_map(const ts_texture_mapping2d *m, const ts_texture_context *c, ts_vec2 *dstdx,
                                 ts_vec2 *dstdy)
{
    switch (m->type) {
    case TS_TEXTURE_MAPPING_UV:
        *dstdx = (ts_vec2){m->su * c->dudx, m->sv * c->dvdx};
        *dstdy = (ts_vec2){m->su * c->dudy, m->sv * c->dvdy};
        return (ts_vec2){m->su * c->uv.x + m->du, m->sv * c->uv.y + m->dv};
    case TS_TEXTURE_MAPPING_SPHERICAL:
    case TS_TEXTURE_MAPPING_CYLINDRICAL: {
        bool sphere = m->type == TS_TEXTURE_MAPPING_SPHERICAL;
        const float delta = sphere ? 0.1f : 0.01f;
        ts_vec3 px = ts_vec3_add(c->p, ts_vec3_scale(c->dpdx, delta));
        ts_vec3 py = ts_vec3_add(c->p, ts_vec3_scale(c->dpdy, delta));
        ts_vec2 st = sphere ? sphere_st(&m->world_to_texture, c->p) : cylinder_st(&m->world_to_texture, c->p);
        ts_vec2 sx = sphere ? sphere_st(&m->world_to_texture, px) : cylinder_st(&m->world_to_texture, px);
        ts_vec2 sy = sphere ? sphere_st(&m->world_to_texture, py) : cylinder_st(&m->world_to_texture, py);
        *dstdx = wrapped_difference(sx, st, 1.0f / delta);
        *dstdy = wrapped_difference(sy, st, 1.0f / delta);
        return st;
    }
    case TS_TEXTURE_MAPPING_PLANAR:
        *dstdx = (ts_vec2){ts_vec3_dot(c->dpdx, m->vs), ts_vec3_dot(c->dpdx, m->vt)};
        *dstdy = (ts_vec2){ts_vec3_dot(c->dpdy, m->vs), ts_vec3_dot(c->dpdy, m->vt)};
        return (ts_vec2){m->du + ts_vec3_dot(c->p, m->vs), m->dv + ts_vec3_dot(c->p, m->vt)};
    }
    *dstdx = *dstdy = (ts_vec2){0, 0};
    return (ts_vec2){0, 0};
}

ts_vec3 ts_texture_mapping3d_map(const ts_texture_mapping3d *m, const ts_texture_context *c, ts_vec3 *dpdx,
                                 ts_vec3 *dpdy)
{
    *dpdx = xform_vector(&m->world_to_texture, c->dpdx);
    *dpdy = xform_vector(&m->world_to_texture, c->dpdy);
    return xform_point(&m->world_to_texture, c->p);
}
