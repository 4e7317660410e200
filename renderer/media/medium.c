/* medium.c — homogeneous and grid media, Henyey–Greenstein; see medium.h. */
#include "media/medium.h"

#include <float.h>
#include <math.h>
#include <string.h>

/* ---------------------------------------------------------------- Henyey–Greenstein */

float ts_hg_phase(float cos_theta, float g)
{
    float denom = 1 + g * g - 2 * g * cos_theta;
    if (!(denom > 0)) denom = FLT_MIN; /* g = ±1 exactly is refused by the builder; keep it finite anyway */
    return TS_INV_4PI * (1 - g * g) / (denom * sqrtf(denom));
}

ts_vec3 ts_hg_sample(ts_vec3 d_in, float g, ts_vec2 u, float *pdf)
{
    /* Invert the cdf of cos θ (θ measured from d_in): for g → 0 the uniform sphere. */
    float cos_theta;
    if (fabsf(g) < 1e-3f) {
        cos_theta = 1 - 2 * u.x;
    } else {
        float q = (1 - g * g) / (1 + g - 2 * g * u.x);
        cos_theta = (1 + g * g - q * q) / (2 * g);
    }
    cos_theta = ts_clampf(cos_theta, -1, 1);
    float sin_theta = sqrtf(ts_maxf(0, 1 - cos_theta * cos_theta));
    float phi = 2 * TS_PI * u.y;
    ts_vec3 a, b;
    ts_coordinate_system(d_in, &a, &b);
    ts_vec3 w = ts_vec3_add(ts_vec3_add(ts_vec3_scale(a, sin_theta * cosf(phi)), ts_vec3_scale(b, sin_theta * sinf(phi))),
                            ts_vec3_scale(d_in, cos_theta));
    w = ts_vec3_normalize(w);
    *pdf = ts_hg_phase(ts_vec3_dot(d_in, w), g); /* of the direction returned, as every caller evaluates it */
    return w;
}

/* ---------------------------------------------------------------- walks */

void ts_medium_walk_init(ts_medium_walk *w, uint32_t seed, uint32_t px, uint32_t py, uint32_t index,
                         const atomic_bool *stop)
{
    uint64_t s = ((uint64_t)ts_hash4(seed, px, py, index) << 32) | ts_hash4(index, py, px, seed ^ 0x6d656469u);
    ts_pcg32_seed(&w->rng, s, 0x6d65646961ull); /* "media" */
    w->steps = 0;
    w->truncated = 0;
    w->stop = stop;
}

/* One more tracking step: false when the walk must end now (bound or stop). */
static inline bool walk_step(ts_medium_walk *w, uint32_t *n)
{
    w->steps++;
    if (++*n >= TS_MEDIUM_MAX_STEPS ||
        ((*n & 1023u) == 0 && w->stop && atomic_load_explicit(w->stop, memory_order_relaxed))) {
        w->truncated++;
        return false;
    }
    return true;
}

/* exp(−σ·d) with σ ≥ 0, d ≥ 0 (d may be ∞): 1 where σ is 0, never 0·∞. */
static inline float tr_channel(float sigma, float d) { return sigma > 0 ? expf(-sigma * d) : 1; }

static inline ts_rgb tr_homogeneous(ts_rgb sigma_t, float d)
{
    return (ts_rgb){tr_channel(sigma_t.r, d), tr_channel(sigma_t.g, d), tr_channel(sigma_t.b, d)};
}

static inline float rgb_channel(ts_rgb c, int i) { return i == 0 ? c.r : i == 1 ? c.g : c.b; }

/* ---------------------------------------------------------------- grid */

static inline float grid_at(const ts_medium *m, int x, int y, int z)
{
    if (x < 0 || y < 0 || z < 0 || x >= (int)m->nx || y >= (int)m->ny || z >= (int)m->nz) return 0;
    return m->density[((size_t)z * m->ny + (size_t)y) * m->nx + (size_t)x];
}

static inline float lerpf(float t, float a, float b) { return (1 - t) * a + t * b; }

/* Trilinear interpolation of the samples at cell centres; p in the unit cube's space. */
static float grid_density(const ts_medium *m, ts_vec3 p)
{
    float sx = p.x * (float)m->nx - 0.5f, sy = p.y * (float)m->ny - 0.5f, sz = p.z * (float)m->nz - 0.5f;
    if (!(sx > -2 && sy > -2 && sz > -2 && sx < (float)m->nx + 1 && sy < (float)m->ny + 1 && sz < (float)m->nz + 1))
        return 0; /* also NaN */
    float fx = floorf(sx), fy = floorf(sy), fz = floorf(sz);
    int x = (int)fx, y = (int)fy, z = (int)fz;
    float dx = sx - fx, dy = sy - fy, dz = sz - fz;
    /* The eight samples: inside the grid straight from one base index (the common case, and
     * the tracking loops' hot spot), else one by one with 0 outside; the same values. */
    float v000, v100, v010, v110, v001, v101, v011, v111;
    if (x >= 0 && y >= 0 && z >= 0 && x + 1 < (int)m->nx && y + 1 < (int)m->ny && z + 1 < (int)m->nz) {
        const size_t row = m->nx, slab = (size_t)m->nx * m->ny;
        const float *d = m->density + ((size_t)z * m->ny + (size_t)y) * row + (size_t)x;
        v000 = d[0], v100 = d[1], v010 = d[row], v110 = d[row + 1];
        v001 = d[slab], v101 = d[slab + 1], v011 = d[slab + row], v111 = d[slab + row + 1];
    } else {
        v000 = grid_at(m, x, y, z), v100 = grid_at(m, x + 1, y, z);
        v010 = grid_at(m, x, y + 1, z), v110 = grid_at(m, x + 1, y + 1, z);
        v001 = grid_at(m, x, y, z + 1), v101 = grid_at(m, x + 1, y, z + 1);
        v011 = grid_at(m, x, y + 1, z + 1), v111 = grid_at(m, x + 1, y + 1, z + 1);
    }
    float d00 = lerpf(dx, v000, v100);
    float d10 = lerpf(dx, v010, v110);
    float d01 = lerpf(dx, v001, v101);
    float d11 = lerpf(dx, v011, v111);
    return lerpf(dz, lerpf(dy, d00, d10), lerpf(dy, d01, d11));
}

float ts_medium_density(const ts_medium *m, ts_vec3 p_world)
{
    if (m->type == TS_MEDIUM_HOMOGENEOUS) return 1;
    ts_dvec3 q = ts_xform_point_inv(&m->to_unit, (ts_dvec3){p_world.x, p_world.y, p_world.z});
    if (!(q.x >= 0 && q.x <= 1 && q.y >= 0 && q.y <= 1 && q.z >= 0 && q.z <= 1)) return 0; /* the trackers' box */
    return grid_density(m, (ts_vec3){(float)q.x, (float)q.y, (float)q.z});
}

/* The ray in the unit cube's space with a unit-length world direction: origin o, direction
 * dd per unit of world distance, and the world-distance interval [*t0, *t1) inside the cube
 * and within [0, tmax·|d|). False if the segment misses the cube. *len: |d|. */
static bool grid_segment(const ts_medium *m, const ts_ray *ray, float tmax, ts_vec3 *o, ts_vec3 *dd, float *t0,
                         float *t1, float *len)
{
    *len = ts_vec3_length(ray->d);
    if (!(*len > 0)) return false;
    ts_dvec3 ou = ts_xform_point_inv(&m->to_unit, (ts_dvec3){ray->o.x, ray->o.y, ray->o.z});
    double il = 1.0 / *len;
    ts_dvec3 du = ts_xform_vector_inv(&m->to_unit, (ts_dvec3){ray->d.x * il, ray->d.y * il, ray->d.z * il});
    double lo = 0, hi = (double)tmax * *len;
    const double oo[3] = {ou.x, ou.y, ou.z}, dv[3] = {du.x, du.y, du.z};
    for (int a = 0; a < 3; a++) {
        if (dv[a] == 0) {
            if (oo[a] < 0 || oo[a] > 1) return false;
            continue;
        }
        double ta = (0 - oo[a]) / dv[a], tb = (1 - oo[a]) / dv[a];
        if (ta > tb) {
            double t = ta;
            ta = tb;
            tb = t;
        }
        if (ta > lo) lo = ta;
        if (tb < hi) hi = tb;
        if (!(lo <= hi)) return false;
    }
    *o = (ts_vec3){(float)ou.x, (float)ou.y, (float)ou.z};
    *dd = (ts_vec3){(float)du.x, (float)du.y, (float)du.z};
    *t0 = (float)lo;
    *t1 = (float)hi;
    return *t1 > *t0;
}

/* An exponential step of rate `rate` (> 0): a division, as a denormal rate has no finite
 * inverse. */
static inline float exp_step(ts_medium_walk *w, float rate) { return -logf(1 - ts_pcg32_float(&w->rng)) / rate; }

void ts_medium_majorant_grid(const ts_medium *m, uint32_t *mx, uint32_t *my, uint32_t *mz, float *cells)
{
    const uint32_t n[3] = {m->nx, m->ny, m->nz}, c = TS_MEDIUM_MAJORANT_CELL;
    uint32_t k[3];
    for (int a = 0; a < 3; a++) k[a] = (n[a] + c - 1) / c;
    *mx = k[0], *my = k[1], *mz = k[2];
    if (!cells) return;
    /* Cell i of an axis spans unit coordinates [i/k, (i+1)/k], where the interpolation reads
     * samples ⌊u·n − ½⌋ and the one after: from ⌊i·n/k − ½⌋ to ⌊(i+1)·n/k − ½⌋ + 1, one more
     * each side, clamped (samples outside the grid are 0 and raise no bound). */
    int lo[3][2]; /* per axis, scratch for one cell */
    for (uint32_t z = 0; z < k[2]; z++)
        for (uint32_t y = 0; y < k[1]; y++)
            for (uint32_t x = 0; x < k[0]; x++) {
                const uint32_t i[3] = {x, y, z};
                for (int a = 0; a < 3; a++) {
                    double u0 = (double)i[a] / k[a], u1 = (double)(i[a] + 1) / k[a];
                    int s0 = (int)floor(u0 * n[a] - 0.5) - 1, s1 = (int)floor(u1 * n[a] - 0.5) + 2;
                    lo[a][0] = s0 < 0 ? 0 : s0;
                    lo[a][1] = s1 > (int)n[a] - 1 ? (int)n[a] - 1 : s1;
                }
                float b = 0;
                for (int sz = lo[2][0]; sz <= lo[2][1]; sz++)
                    for (int sy = lo[1][0]; sy <= lo[1][1]; sy++)
                        for (int sx = lo[0][0]; sx <= lo[0][1]; sx++) b = ts_maxf(b, grid_at(m, sx, sy, sz));
                cells[((size_t)z * k[1] + y) * k[0] + x] = b;
            }
}

/* A walk through the majorant grid's cells along the ray o + dd·t (unit-cube space, t in
 * world distance) over [t, t_end): the cell holding the current point, and the t where the
 * ray leaves it. */
typedef struct cell_walk {
    int c[3], step[3], n[3];
    float t_next[3], t_delta[3];
    float t_end;
} cell_walk;

static void cell_walk_init(const ts_medium *m, ts_vec3 o, ts_vec3 dd, float t, float t_end, cell_walk *cw)
{
    const float oo[3] = {o.x, o.y, o.z}, dv[3] = {dd.x, dd.y, dd.z};
    cw->n[0] = (int)m->mx, cw->n[1] = (int)m->my, cw->n[2] = (int)m->mz;
    cw->t_end = t_end;
    for (int a = 0; a < 3; a++) {
        float u = oo[a] + dv[a] * t, k = (float)cw->n[a];
        int c = (int)floorf(u * k);
        if (!(c >= 0)) c = 0; /* also NaN */
        if (c > cw->n[a] - 1) c = cw->n[a] - 1;
        cw->c[a] = c;
        if (dv[a] > 0) {
            cw->step[a] = 1;
            cw->t_next[a] = ((float)(c + 1) / k - oo[a]) / dv[a];
            cw->t_delta[a] = 1 / (k * dv[a]);
        } else if (dv[a] < 0) {
            cw->step[a] = -1;
            cw->t_next[a] = ((float)c / k - oo[a]) / dv[a];
            cw->t_delta[a] = -1 / (k * dv[a]);
        } else {
            cw->step[a] = 0;
            cw->t_next[a] = INFINITY;
            cw->t_delta[a] = INFINITY;
        }
    }
}

/* The end of the current cell's stretch of the ray (at most t_end). */
static inline float cell_exit(const cell_walk *cw)
{
    float t = ts_minf(cw->t_next[0], ts_minf(cw->t_next[1], cw->t_next[2]));
    return ts_minf(t, cw->t_end);
}

/* On to the next cell: false when the ray leaves the grid (or reaches t_end). */
static inline bool cell_advance(cell_walk *cw)
{
    int a = cw->t_next[0] <= cw->t_next[1] ? (cw->t_next[0] <= cw->t_next[2] ? 0 : 2)
                                           : (cw->t_next[1] <= cw->t_next[2] ? 1 : 2);
    if (!(cw->t_next[a] < cw->t_end)) return false;
    cw->c[a] += cw->step[a];
    if (cw->c[a] < 0 || cw->c[a] >= cw->n[a]) return false;
    cw->t_next[a] += cw->t_delta[a];
    return true;
}

static inline float cell_bound(const ts_medium *m, const cell_walk *cw)
{
    return m->majorant[((size_t)cw->c[2] * m->my + (size_t)cw->c[1]) * m->mx + (size_t)cw->c[0]];
}

/* Delta tracking: in each cell, tentative collisions at the cell's rate σt·bound, the first
 * accepted with probability density/bound. */
static ts_rgb grid_sample(const ts_medium *m, const ts_ray *ray, float tmax, ts_medium_walk *w, bool *scattered,
                          float *t_out)
{
    ts_vec3 o, dd;
    float t0, t1, len;
    if (!(m->max_density > 0) || !grid_segment(m, ray, tmax, &o, &dd, &t0, &t1, &len)) return ts_rgb_gray(1);
    cell_walk cw;
    cell_walk_init(m, o, dd, t0, t1, &cw);
    float t = t0;
    for (uint32_t n = 0;;) {
        float bound = cell_bound(m, &cw), t_exit = cell_exit(&cw);
        float rate = m->sigma_t.r * bound;
        if (rate > 0)
            for (;;) {
                float tn = t + exp_step(w, rate);
                if (!(tn < t_exit)) break;
                t = tn;
                if (!walk_step(w, &n)) return ts_rgb_gray(0);
                float d = grid_density(m, ts_vec3_add(o, ts_vec3_scale(dd, t)));
                if (d / bound > ts_pcg32_float(&w->rng)) {
                    *scattered = true;
                    *t_out = t / len;
                    return ts_rgb_scale(m->sigma_s, 1 / m->sigma_t.r);
                }
            }
        if (t_exit > t) t = t_exit; /* never back: the cell's exit may round below its entry */
        if (!(t < t1) || !cell_advance(&cw)) return ts_rgb_gray(1);
    }
}

/* Ratio tracking: the product of (1 − density/bound) over the tentative collisions, each
 * cell at its own rate σt·bound. */
static ts_rgb grid_tr(const ts_medium *m, const ts_ray *ray, float tmax, ts_medium_walk *w)
{
    ts_vec3 o, dd;
    float t0, t1, len;
    if (!(m->max_density > 0) || !grid_segment(m, ray, tmax, &o, &dd, &t0, &t1, &len)) return ts_rgb_gray(1);
    cell_walk cw;
    cell_walk_init(m, o, dd, t0, t1, &cw);
    float t = t0, tr = 1;
    for (uint32_t n = 0;;) {
        float bound = cell_bound(m, &cw), t_exit = cell_exit(&cw);
        float rate = m->sigma_t.r * bound;
        if (rate > 0)
            for (;;) {
                float tn = t + exp_step(w, rate);
                if (!(tn < t_exit)) break;
                t = tn;
                if (!walk_step(w, &n)) return ts_rgb_gray(0);
                float d = grid_density(m, ts_vec3_add(o, ts_vec3_scale(dd, t)));
                tr *= 1 - ts_maxf(0, d / bound);
                if (!(tr > 0)) return ts_rgb_gray(0);
            }
        if (t_exit > t) t = t_exit; /* never back: the cell's exit may round below its entry */
        if (!(t < t1) || !cell_advance(&cw)) return ts_rgb_gray(tr);
    }
}

/* ---------------------------------------------------------------- dispatch */

ts_rgb ts_medium_tr(const ts_medium *m, const ts_ray *ray, float tmax, ts_medium_walk *w)
{
    if (m->type == TS_MEDIUM_GRID) return grid_tr(m, ray, tmax, w);
    float d = tmax * ts_vec3_length(ray->d);
    return tr_homogeneous(m->sigma_t, d);
}

ts_rgb ts_medium_sample(const ts_medium *m, const ts_ray *ray, float tmax, ts_vec2 u, ts_medium_walk *w,
                        bool *scattered, float *t)
{
    *scattered = false;
    *t = tmax;
    if (m->type == TS_MEDIUM_GRID) return grid_sample(m, ray, tmax, w, scattered, t);
    /* One channel picked uniformly, its exponential distance, weighted by the average of
     * the three channels' densities (the one-sample MIS estimator, pbrt-v3 §15.2.1). */
    int ch = (int)(u.x * 3);
    if (ch > 2) ch = 2;
    float len = ts_vec3_length(ray->d);
    float sc = rgb_channel(m->sigma_t, ch);
    float dist = sc > 0 ? -logf(1 - u.y) / sc : INFINITY;
    float tt = len > 0 ? dist / len : INFINITY;
    bool sampled = tt < tmax;
    if (!sampled) tt = tmax;
    ts_rgb tr = tr_homogeneous(m->sigma_t, sampled ? dist : tmax * len);
    ts_rgb density = sampled ? ts_rgb_mul(m->sigma_t, tr) : tr;
    float pdf = ts_rgb_average(density);
    if (!(pdf > 0)) return ts_rgb_gray(0);
    *scattered = sampled;
    *t = tt;
    return ts_rgb_scale(sampled ? ts_rgb_mul(tr, m->sigma_s) : tr, 1 / pdf);
}

/* ---------------------------------------------------------------- presets */

/* pbrt-v3's table of measured media (σ's mm⁻¹; its σ′s taken as σs, g 0):
 * Jensen, Marschner, Levoy, Hanrahan, "A Practical Model for Subsurface Light Transport",
 * SIGGRAPH 2001, and Narasimhan, Gupta, Donner, Ramamoorthi, Nayar, Jensen, "Acquiring
 * Scattering Properties of Participating Media by Dilution", SIGGRAPH 2006. */
static const struct {
    const char *name;
    float sigma_s[3], sigma_a[3];
} presets[] = {
    {"Apple", {2.29f, 2.39f, 1.97f}, {0.0030f, 0.0034f, 0.046f}},
    {"Chicken1", {0.15f, 0.21f, 0.38f}, {0.015f, 0.077f, 0.19f}},
    {"Chicken2", {0.19f, 0.25f, 0.32f}, {0.018f, 0.088f, 0.20f}},
    {"Cream", {7.38f, 5.47f, 3.15f}, {0.0002f, 0.0028f, 0.0163f}},
    {"Ketchup", {0.18f, 0.07f, 0.03f}, {0.061f, 0.97f, 1.45f}},
    {"Marble", {2.19f, 2.62f, 3.00f}, {0.0021f, 0.0041f, 0.0071f}},
    {"Potato", {0.68f, 0.70f, 0.55f}, {0.0024f, 0.0090f, 0.12f}},
    {"Skimmilk", {0.70f, 1.22f, 1.90f}, {0.0014f, 0.0025f, 0.0142f}},
    {"Skin1", {0.74f, 0.88f, 1.01f}, {0.032f, 0.17f, 0.48f}},
    {"Skin2", {1.09f, 1.59f, 1.79f}, {0.013f, 0.070f, 0.145f}},
    {"Spectralon", {11.6f, 20.4f, 14.9f}, {0.00f, 0.00f, 0.00f}},
    {"Wholemilk", {2.55f, 3.21f, 3.77f}, {0.0011f, 0.0024f, 0.014f}},
    {"Lowfat Milk", {0.89187f, 1.5136f, 2.532f}, {0.002875f, 0.00575f, 0.0115f}},
    {"Reduced Milk", {2.4858f, 3.1669f, 4.5214f}, {0.0025556f, 0.0051111f, 0.012778f}},
    {"Regular Milk", {4.5513f, 5.8294f, 7.136f}, {0.0015333f, 0.0046f, 0.019933f}},
    {"Espresso", {0.72378f, 0.84557f, 1.0247f}, {4.7984f, 6.5751f, 8.8493f}},
    {"Mint Mocha Coffee", {0.31602f, 0.38538f, 0.48131f}, {3.772f, 5.8228f, 7.82f}},
    {"Lowfat Soy Milk", {0.30576f, 0.34233f, 0.61664f}, {0.0014375f, 0.0071875f, 0.035937f}},
    {"Regular Soy Milk", {0.59223f, 0.73866f, 1.4693f}, {0.0019167f, 0.0095833f, 0.065167f}},
    {"Lowfat Chocolate Milk", {0.64925f, 0.83916f, 1.1057f}, {0.0115f, 0.0368f, 0.1564f}},
    {"Regular Chocolate Milk", {1.4585f, 2.1289f, 2.9527f}, {0.010063f, 0.043125f, 0.14375f}},
    {"Coke", {8.9053e-05f, 8.372e-05f, 0}, {0.10014f, 0.16503f, 0.2468f}},
    {"Pepsi", {6.1697e-05f, 4.2564e-05f, 0}, {0.091641f, 0.14158f, 0.20729f}},
    {"Sprite", {6.0306e-06f, 6.4139e-06f, 6.5504e-06f}, {0.001886f, 0.0018308f, 0.0020025f}},
    {"Gatorade", {0.0024574f, 0.003007f, 0.0037325f}, {0.024794f, 0.019289f, 0.008878f}},
    {"Chardonnay", {1.7982e-05f, 1.3758e-05f, 1.2023e-05f}, {0.010782f, 0.011855f, 0.023997f}},
    {"White Zinfandel", {1.7501e-05f, 1.9069e-05f, 1.288e-05f}, {0.012072f, 0.016184f, 0.019843f}},
    {"Merlot", {2.1129e-05f, 0, 0}, {0.11632f, 0.25191f, 0.29434f}},
    {"Budweiser Beer", {2.4356e-05f, 2.4079e-05f, 1.0564e-05f}, {0.011492f, 0.024911f, 0.057786f}},
    {"Coors Light Beer", {5.0922e-05f, 4.301e-05f, 0}, {0.006164f, 0.013984f, 0.034983f}},
    {"Clorox", {0.0024035f, 0.0031373f, 0.003991f}, {0.0033542f, 0.014892f, 0.026297f}},
    {"Apple Juice", {0.00013612f, 0.00015836f, 0.000227f}, {0.012957f, 0.023741f, 0.052184f}},
    {"Cranberry Juice", {0.00010402f, 0.00011646f, 7.8139e-05f}, {0.039437f, 0.094223f, 0.12426f}},
    {"Grape Juice", {5.382e-05f, 0, 0}, {0.10404f, 0.23958f, 0.29325f}},
    {"Ruby Grapefruit Juice", {0.011002f, 0.010927f, 0.011036f}, {0.085867f, 0.18314f, 0.25262f}},
    {"White Grapefruit Juice", {0.22826f, 0.23998f, 0.32748f}, {0.0138f, 0.018831f, 0.056781f}},
    {"Shampoo", {0.0007176f, 0.0008303f, 0.0009016f}, {0.014107f, 0.045693f, 0.061717f}},
    {"Strawberry Shampoo", {0.00015671f, 0.00015947f, 1.518e-05f}, {0.01449f, 0.05796f, 0.075823f}},
    {"Head & Shoulders Shampoo", {0.023805f, 0.028804f, 0.034306f}, {0.084621f, 0.15688f, 0.20365f}},
    {"Lemon Tea Powder", {0.040224f, 0.045264f, 0.051081f}, {2.4288f, 4.5757f, 7.2127f}},
    {"Orange Powder", {0.00015617f, 0.00017482f, 0.0001762f}, {0.001449f, 0.003441f, 0.007863f}},
    {"Pink Lemonade Powder", {0.00012103f, 0.00013073f, 0.00012528f}, {0.001165f, 0.002366f, 0.003195f}},
    {"Cappuccino Powder", {1.8436f, 2.5851f, 2.1662f}, {35.844f, 49.547f, 61.084f}},
    {"Salt Powder", {0.027333f, 0.032451f, 0.031979f}, {0.28415f, 0.3257f, 0.34148f}},
    {"Sugar Powder", {0.00022272f, 0.00025513f, 0.000271f}, {0.012638f, 0.031051f, 0.050124f}},
    {"Suisse Mocha Powder", {2.7979f, 3.5452f, 4.3365f}, {17.502f, 27.004f, 35.433f}},
    {"Pacific Ocean Surface Water", {0.0001764f, 0.00032095f, 0.00019617f}, {0.031845f, 0.031324f, 0.030147f}},
};

bool ts_medium_preset(const char *name, ts_rgb *sigma_a, ts_rgb *sigma_s)
{
    for (size_t i = 0; i < sizeof presets / sizeof *presets; i++)
        if (strcmp(presets[i].name, name) == 0) {
            *sigma_a = (ts_rgb){presets[i].sigma_a[0], presets[i].sigma_a[1], presets[i].sigma_a[2]};
            *sigma_s = (ts_rgb){presets[i].sigma_s[0], presets[i].sigma_s[1], presets[i].sigma_s[2]};
            return true;
        }
    return false;
}

const char *ts_medium_preset_name(uint32_t i)
{
    return i < sizeof presets / sizeof *presets ? presets[i].name : NULL;
}
