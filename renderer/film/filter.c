/* filter.c — box, triangle, gaussian and Mitchell filters with importance sampling; see
 * filter.h. Tables are built once in ts_filter_init (double precision, then stored as
 * float); sampling is a binary search over TS_FILTER_TABLE_CELLS + 1 CDF entries. */
#include "film/filter.h"

#include <math.h>

#define CELLS TS_FILTER_TABLE_CELLS
/* Midpoint-rule points per cell when averaging |f1| over a cell. The average only shapes
 * the density; E[weight] = ∫f holds whatever it is, so modest accuracy suffices. */
#define CELL_QUADRATURE 64

/* Mitchell–Netravali cubic with parameters B, C on t = |x| in [0, 2); integrates to 1 over
 * [-2, 2] (for any B, C with the cubic's normalisation). */
static double mitchell_1d(double b, double c, double t)
{
    t = fabs(t);
    if (t < 1) return ((12 - 9 * b - 6 * c) * t * t * t + (-18 + 12 * b + 6 * c) * t * t + (6 - 2 * b)) / 6;
    if (t < 2)
        return ((-b - 6 * c) * t * t * t + (6 * b + 30 * c) * t * t + (-12 * b - 48 * c) * t +
                (8 * b + 24 * c)) /
               6;
    return 0;
}

/* The normalised 1-D profile f1 of a tabulated filter (∫ f1 = 1 over [-r, r]). */
static float profile(const ts_filter *f, float x)
{
    if (!(fabsf(x) <= f->radius)) return 0;
    switch (f->type) {
    case TS_FILTER_GAUSSIAN:
        return f->profile_scale * fmaxf(0.0f, expf(-f->gaussian_alpha * x * x) - f->gaussian_floor);
    case TS_FILTER_MITCHELL:
        return f->profile_scale * (float)mitchell_1d(f->mitchell_b, f->mitchell_c, 2.0 * x / f->radius);
    case TS_FILTER_BOX:
        return 0.5f / f->radius;
    case TS_FILTER_TRIANGLE:
        return (f->radius - fabsf(x)) / (f->radius * f->radius);
    }
    return 0;
}

static double profile_d(const ts_filter *f, double x)
{
    double r = f->radius;
    if (fabs(x) > r) return 0;
    if (f->type == TS_FILTER_GAUSSIAN)
        return f->profile_scale * fmax(0.0, exp(-(double)f->gaussian_alpha * x * x) - f->gaussian_floor);
    return (2.0 / r) * mitchell_1d(f->mitchell_b, f->mitchell_c, 2.0 * x / r);
}

static void build_table(ts_filter *f)
{
    double r = f->radius, delta = 2 * r / CELLS, mass[CELLS], total = 0;
    for (int i = 0; i < CELLS; i++) {
        double sum = 0;
        for (int k = 0; k < CELL_QUADRATURE; k++)
            sum += fabs(profile_d(f, -r + (i + (k + 0.5) / CELL_QUADRATURE) * delta));
        mass[i] = sum / CELL_QUADRATURE * delta;
        total += mass[i];
    }
    double acc = 0;
    f->cdf[0] = 0;
    for (int i = 0; i < CELLS; i++) {
        acc += mass[i];
        f->cdf[i + 1] = (float)(acc / total);
    }
    f->cdf[CELLS] = 1;
    /* The density actually sampled is the float CDF's step over the cell. */
    for (int i = 0; i < CELLS; i++)
        f->cell_pdf[i] = (float)(((double)f->cdf[i + 1] - f->cdf[i]) / delta);
}

ts_status ts_filter_init(ts_filter *f, ts_filter_type type, float radius, ts_error *err)
{
    return ts_filter_init_params(f, type, radius, NULL, err);
}

ts_status ts_filter_init_params(ts_filter *f, ts_filter_type type, float radius, const ts_filter_params *params,
                                ts_error *err)
{
    if (!(radius > 0) || !isfinite(radius))
        return ts_error_set(err, TS_ERR_INVALID, "filter radius: expected a positive number, got %g",
                            (double)radius);
    static const ts_filter_params defaults = {0};
    if (!params) params = &defaults;
    if (!(params->gaussian_alpha >= 0) || !isfinite(params->gaussian_alpha))
        return ts_error_set(err, TS_ERR_INVALID, "filter alpha: expected a positive number, got %g",
                            (double)params->gaussian_alpha);
    if (params->mitchell_custom && !(isfinite(params->mitchell_b) && isfinite(params->mitchell_c)))
        return ts_error_set(err, TS_ERR_INVALID, "filter B and C: expected finite numbers");
    *f = (ts_filter){.type = type, .radius = radius, .mitchell_b = 1.0 / 3.0, .mitchell_c = 1.0 / 3.0};
    if (params->mitchell_custom) f->mitchell_b = params->mitchell_b, f->mitchell_c = params->mitchell_c;
    switch (type) {
    case TS_FILTER_BOX:
    case TS_FILTER_TRIANGLE:
        return TS_OK;
    case TS_FILTER_GAUSSIAN: {
        double r = radius, sigma = r / 3, alpha = 1 / (2 * sigma * sigma);
        if (params->gaussian_alpha > 0) alpha = params->gaussian_alpha, sigma = sqrt(1 / (2 * alpha));
        double floor_v = exp(-alpha * r * r);
        /* ∫_{-r}^{r} exp(−x²/2σ²) − floor dx, in closed form. */
        double integral = sigma * sqrt(2 * TS_PI_D) * erf(r / (sigma * sqrt(2.0))) - 2 * r * floor_v;
        f->gaussian_alpha = (float)alpha;
        f->gaussian_floor = (float)floor_v;
        f->profile_scale = (float)(1 / integral);
        build_table(f);
        return TS_OK;
    }
    case TS_FILTER_MITCHELL:
        f->profile_scale = 2 / radius;
        build_table(f);
        return TS_OK;
    }
    return ts_error_set(err, TS_ERR_INVALID, "filter type: unknown type %d", (int)type);
}

/* Inverts the tabulated CDF at u; *w = f1(x)/p(x) for the cell actually sampled. */
static float sample_table(const ts_filter *f, float u, float *w)
{
    int lo = 0, hi = CELLS - 1; /* largest i with cdf[i] <= u; then cdf[i+1] > u */
    while (lo < hi) {
        int mid = (lo + hi + 1) >> 1;
        if (f->cdf[mid] <= u)
            lo = mid;
        else
            hi = mid - 1;
    }
    float du = (u - f->cdf[lo]) / (f->cdf[lo + 1] - f->cdf[lo]);
    float r = f->radius, x = -r + ((float)lo + ts_clampf(du, 0, 1)) * (2 * r / CELLS);
    x = ts_clampf(x, -r, r);
    float pdf = f->cell_pdf[lo];
    *w = pdf > 0 ? profile(f, x) / pdf : 0;
    return x;
}

ts_vec2 ts_filter_sample(const ts_filter *f, ts_vec2 u, float *weight)
{
    float r = f->radius;
    switch (f->type) {
    case TS_FILTER_BOX:
        *weight = 1;
        return (ts_vec2){ts_clampf((2 * u.x - 1) * r, -r, r), ts_clampf((2 * u.y - 1) * r, -r, r)};
    case TS_FILTER_TRIANGLE: {
        /* Inverse CDF of the tent: F(x) = (1 + x/r)²/2 on [-r, 0], symmetric above. */
        float x = u.x < 0.5f ? r * (sqrtf(2 * u.x) - 1) : r * (1 - sqrtf(2 * (1 - u.x)));
        float y = u.y < 0.5f ? r * (sqrtf(2 * u.y) - 1) : r * (1 - sqrtf(2 * (1 - u.y)));
        *weight = 1;
        return (ts_vec2){ts_clampf(x, -r, r), ts_clampf(y, -r, r)};
    }
    case TS_FILTER_GAUSSIAN:
    case TS_FILTER_MITCHELL:
        break;
    }
    float wx, wy;
    float x = sample_table(f, u.x, &wx), y = sample_table(f, u.y, &wy);
    *weight = wx * wy;
    return (ts_vec2){x, y};
}

float ts_filter_eval(const ts_filter *f, ts_vec2 offset)
{
    return profile(f, offset.x) * profile(f, offset.y);
}

const char *ts_filter_type_name(ts_filter_type type)
{
    switch (type) {
    case TS_FILTER_BOX:
        return "box";
    case TS_FILTER_TRIANGLE:
        return "triangle";
    case TS_FILTER_GAUSSIAN:
        return "gaussian";
    case TS_FILTER_MITCHELL:
        return "mitchell";
    }
    return "unknown";
}
