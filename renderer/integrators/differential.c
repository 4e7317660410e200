/* differential.c — ray differentials; see differential.h. The specular rules are
 * pbrt-v3's, in its order of operations, with its ∂n/∂x = ∂n/∂u·∂u/∂x + ∂n/∂v·∂v/∂x. */
#include "integrators/differential.h"

#include <math.h>

#include "materials/material.h"

/* The shading normal's change per pixel in x (*dndx) and y: pbrt-v3's from the
 * interaction's ∂n/∂u, ∂n/∂v and the footprint's ∂u/∂x, …. */
static void normal_footprint(const ts_interaction *si, const ts_texture_context *c, ts_vec3 *dndx, ts_vec3 *dndy)
{
    *dndx = ts_vec3_add(ts_vec3_scale(si->dndu, c->dudx), ts_vec3_scale(si->dndv, c->dvdx));
    *dndy = ts_vec3_add(ts_vec3_scale(si->dndu, c->dudy), ts_vec3_scale(si->dndv, c->dvdy));
}

static ts_vec3 lerp_towards(ts_vec3 main, ts_vec3 offset, float s)
{
    return ts_vec3_add(main, ts_vec3_scale(ts_vec3_sub(offset, main), s));
}

void ts_ray_differential_camera(const ts_camera *cam, ts_vec2 p_raster, ts_vec2 u_lens, const ts_ray *ray,
                                float scale, ts_ray_differential *out)
{
    /* The rays through the raster points one pixel over, with the same lens point: pbrt-v3
     * offsets the camera-space film point by one pixel's dxCamera, dyCamera. */
    ts_ray rx = ts_camera_ray(cam, (ts_vec2){p_raster.x + 1, p_raster.y}, u_lens);
    ts_ray ry = ts_camera_ray(cam, (ts_vec2){p_raster.x, p_raster.y + 1}, u_lens);
    out->has = true;
    out->rx_o = lerp_towards(ray->o, rx.o, scale);
    out->rx_d = lerp_towards(ray->d, rx.d, scale);
    out->ry_o = lerp_towards(ray->o, ry.o, scale);
    out->ry_d = lerp_towards(ray->d, ry.d, scale);
}

void ts_ray_differential_context(const ts_interaction *si, const ts_ray_differential *rd,
                                 ts_texture_context *c)
{
    ts_material_texture_context(si, c);
    if (rd && rd->has) ts_texture_context_set_differentials(c, si->n, rd->rx_o, rd->rx_d, rd->ry_o, rd->ry_d);
}

void ts_ray_differential_reflect(const ts_ray_differential *rd, const ts_interaction *si,
                                 const ts_texture_context *c, ts_vec3 wi, ts_ray_differential *out)
{
    const ts_vec3 wo = si->wo, ns = si->ns;
    ts_vec3 dndx, dndy;
    normal_footprint(si, c, &dndx, &dndy);
    out->has = true;
    out->rx_o = ts_vec3_add(si->p, c->dpdx);
    out->ry_o = ts_vec3_add(si->p, c->dpdy);
    ts_vec3 dwodx = ts_vec3_sub(ts_vec3_neg(rd->rx_d), wo), dwody = ts_vec3_sub(ts_vec3_neg(rd->ry_d), wo);
    float ddndx = ts_vec3_dot(dwodx, ns) + ts_vec3_dot(wo, dndx);
    float ddndy = ts_vec3_dot(dwody, ns) + ts_vec3_dot(wo, dndy);
    float won = ts_vec3_dot(wo, ns);
    out->rx_d =
        ts_vec3_add(ts_vec3_sub(wi, dwodx),
                    ts_vec3_scale(ts_vec3_add(ts_vec3_scale(dndx, won), ts_vec3_scale(ns, ddndx)), 2.f));
    out->ry_d =
        ts_vec3_add(ts_vec3_sub(wi, dwody),
                    ts_vec3_scale(ts_vec3_add(ts_vec3_scale(dndy, won), ts_vec3_scale(ns, ddndy)), 2.f));
}

void ts_ray_differential_transmit(const ts_ray_differential *rd, const ts_interaction *si,
                                  const ts_texture_context *c, ts_vec3 wi, float bsdf_eta,
                                  ts_ray_differential *out)
{
    const ts_vec3 wo = si->wo;
    ts_vec3 ns = si->ns, dndx, dndy;
    normal_footprint(si, c, &dndx, &dndy);
    out->has = true;
    out->rx_o = ts_vec3_add(si->p, c->dpdx);
    out->ry_o = ts_vec3_add(si->p, c->dpdy);
    /* The relative index from wo's side to wi's, entering first; leaving, the inverse and
     * the normal (and its derivatives) turned to wo's side. */
    float eta = 1 / bsdf_eta;
    if (ts_vec3_dot(wo, ns) < 0) {
        eta = 1 / eta;
        ns = ts_vec3_neg(ns);
        dndx = ts_vec3_neg(dndx);
        dndy = ts_vec3_neg(dndy);
    }
    ts_vec3 dwodx = ts_vec3_sub(ts_vec3_neg(rd->rx_d), wo), dwody = ts_vec3_sub(ts_vec3_neg(rd->ry_d), wo);
    float ddndx = ts_vec3_dot(dwodx, ns) + ts_vec3_dot(wo, dndx);
    float ddndy = ts_vec3_dot(dwody, ns) + ts_vec3_dot(wo, dndy);
    float won = ts_vec3_dot(wo, ns), win = fabsf(ts_vec3_dot(wi, ns));
    float mu = eta * won - win;
    float dmu = win > 0 ? eta - (eta * eta * won) / win : 0; /* ∂μ/∂(wo·n); wi in the plane: none */
    float dmudx = dmu * ddndx, dmudy = dmu * ddndy;
    out->rx_d = ts_vec3_add(ts_vec3_sub(wi, ts_vec3_scale(dwodx, eta)),
                            ts_vec3_add(ts_vec3_scale(dndx, mu), ts_vec3_scale(ns, dmudx)));
    out->ry_d = ts_vec3_add(ts_vec3_sub(wi, ts_vec3_scale(dwody, eta)),
                            ts_vec3_add(ts_vec3_scale(dndy, mu), ts_vec3_scale(ns, dmudy)));
}
