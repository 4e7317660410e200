/* accuracy.c — error against time for every integrator configuration (docs/design.md §8;
 * how to run it and read it: bench/README.md, results: docs/accuracy.md).
 *
 *   bench_accuracy [--width W] [--max-spp N] [--ref-spp N] [--threads T] [--cache DIR]
 *                  [--configs LIST] [--summary FILE] [--header] SCENE.json...
 *   bench_accuracy --summarise ACCURACY.csv      (the summary again from the CSV)
 *
 * For every scene it renders each configuration of the list below (those that apply to
 * the scene) progressively at 1, 2, 4, … N samples per pixel (default 128) on a film W
 * pixels wide (default 96; the height keeps the scene's aspect), and after each doubling
 * measures the error of the image against a reference:
 *
 *   relMSE = mean over pixels and channels of (x − r)² / (r² + 0.01)
 *   RMSE   = sqrt(mean over pixels and channels of (x − r)²)
 *
 * Wall time is measured side by side: at each sample count every configuration renders its
 * next pass before any renders the one after, in an order rotated per pass, so a change in
 * the machine's load hits all configurations alike. Times are cumulative seconds of
 * ts_render over the passes (loading and error computation excluded).
 *
 * References: the scene's own settings at that film size (path for path scenes, `direct
 * all` for the direct configurations), --ref-spp samples (default 1024) as two independent
 * halves (seeds 1000 and 1001), cached in DIR (default: none, always rendered) under a
 * name holding the scene's digest. The reference is the mean of the halves; its own error
 * is estimated from them (E[(h₁−h₂)²] = 4·Var[mean]) and subtracted from the measured
 * relMSE and MSE (the raw values are in the CSV too), so that the reference's noise does
 * not flatten the curves at high sample counts. The measured images use seed 0.
 *
 * Output (stdout): CSV rows
 *   scene, config, integrator, spp, seconds, relmse, rmse, relmse_raw, rmse_raw,
 *   ref_relmse, ref_rmse, ref_spp, relmse_trim
 * (relmse_trim: relMSE without the 0.1% largest per-pixel-channel terms, i.e. without the
 * few fireflies that dominate relMSE in caustic and environment scenes; raw, not corrected)
 * and on --summary FILE one row per (scene, config):
 *   scene, config, integrator, slope_spp, slope_time, final_spp, final_seconds, final_relmse,
 *   t_1pct, how_1pct, t_01pct, how_01pct, ratio_1pct, ratio_01pct, slope_mse_spp, final_rmse,
 *   slope_trim_spp, final_relmse_trim, seconds_per_spp
 * slope_spp / slope_time: least-squares slope of log relMSE against log spp / log seconds
 * (slope_mse_spp: of log MSE = RMSE² against log spp) over the
 * counts ≥ 4 spp. t_X: seconds to relMSE X = the spp that reaches X, `interpolated`
 * (log-log between the two measured counts that bracket it) or `extrapolated` (from the
 * last count along the fitted spp slope, when that slope is below −0.3), × seconds per
 * spp; ratio_X = t_X ÷ the same scene's `base` t_X. seconds_per_spp: after the series,
 * R rounds (--reps, default 7) each render N/4 (≥ 4) more samples of every configuration
 * side by side, order rotated per round; the fastest round per configuration. It is printed in
 * the CSV as a row with spp 0 (seconds = seconds per spp).
 *
 * Configurations (--configs, comma-separated; default all):
 *   base           the scene's integrator as in its file (path: MIS, Sobol, power, RR)
 *   direct-all     direct, UniformSampleAllLights (path scenes only)
 *   direct-one     direct, UniformSampleOneLight
 *   light, bsdf    "sampling": light only / BSDF only instead of MIS
 *   independent    the independent sampler instead of Sobol
 *   uniform        "light_sampling": uniform instead of power (path)
 *   rr-off         rr_depth 65535: no Russian roulette (path)
 *   generic        ts_render_request.generic: effect specialisation off
 *   tri-area, tri-spherical  triangle lights forced to area / spherical sampling
 *                  (ts_lights_set_triangle_sampling; scenes with triangle emitters only)
 *
 * Exit status 0, 1 when a scene fails to load or render, 2 on usage errors. */
#include <cjson/cJSON.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "film/film.h"
#include "lights/light.h"
#include "render/render.h"
#include "scene/scene.h"
#include "json/scene_json.h"
#include "../bench_util.h"

#define MAX_LEVELS  24
#define MAX_CONFIGS 16
#define REL_EPS     0.01

typedef struct options {
    int width, threads, header, reps;
    uint32_t max_spp, ref_spp;
    const char *cache, *configs, *summary, *summarise;
} options;

typedef enum ref_kind { REF_PATH, REF_DIRECT } ref_kind;

typedef struct config {
    const char *name;
    int needs_path;      /* applies to path scenes only */
    int needs_tri;       /* applies to scenes with triangle emitters only */
} config;

static const config CONFIGS[] = {
    {"base", 0, 0},     {"direct-all", 1, 0}, {"direct-one", 0, 0}, {"light", 0, 0},
    {"bsdf", 0, 0},     {"independent", 0, 0}, {"uniform", 1, 0},   {"rr-off", 1, 0},
    {"generic", 0, 0},  {"tri-area", 0, 1},   {"tri-spherical", 0, 1},
};
#define N_CONFIGS (sizeof CONFIGS / sizeof CONFIGS[0])

typedef struct reference {
    int w, h;
    float *mean, *h1, *h2;
    double relmse_floor, mse_floor; /* estimated error of the mean itself */
} reference;

typedef struct run {
    char name[32], integ[16]; /* configuration, integrator */
    const config *cfg;
    ts_scene *scene;
    ts_film *film;
    int generic;
    ref_kind kind;
    int n;
    double per_spp; /* median seconds per spp of the timing rounds (0: use the series') */
    uint32_t spp[MAX_LEVELS];
    double seconds[MAX_LEVELS], relmse[MAX_LEVELS], rmse[MAX_LEVELS], trim[MAX_LEVELS];
} run;

/* ---------------------------------------------------------------- files and JSON */

static char *read_text(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *s = n >= 0 ? malloc((size_t)n + 1) : NULL;
    if (s && fread(s, 1, (size_t)n, f) != (size_t)n) {
        free(s);
        s = NULL;
    }
    fclose(f);
    if (s) s[n] = 0, *len = (size_t)n;
    return s;
}

static void set_num(cJSON *o, const char *k, double v)
{
    cJSON_DeleteItemFromObjectCaseSensitive(o, k);
    cJSON_AddNumberToObject(o, k, v);
}

static void set_str(cJSON *o, const char *k, const char *v)
{
    cJSON_DeleteItemFromObjectCaseSensitive(o, k);
    cJSON_AddStringToObject(o, k, v);
}

static int json_int(const cJSON *o, const char *k, int dflt)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, k);
    return cJSON_IsNumber(v) ? v->valueint : dflt;
}

/* The scene document for a configuration (NULL: the configuration does not apply). */
static char *config_document(const cJSON *orig, const char *cfg, int width, uint32_t spp, uint32_t seed)
{
    cJSON *d = cJSON_Duplicate(orig, 1);
    cJSON *film = cJSON_GetObjectItemCaseSensitive(d, "film");
    if (!film) film = cJSON_AddObjectToObject(d, "film");
    int w0 = json_int(film, "width", 512), h0 = json_int(film, "height", 512);
    int h = (int)lround((double)width * h0 / w0);
    set_num(film, "width", width);
    set_num(film, "height", h < 1 ? 1 : h);
    cJSON_DeleteItemFromObjectCaseSensitive(film, "crop");
    cJSON *smp = cJSON_GetObjectItemCaseSensitive(d, "sampler");
    if (!smp) smp = cJSON_AddObjectToObject(d, "sampler");
    set_num(smp, "spp", spp);
    set_num(smp, "seed", seed);
    cJSON *in = cJSON_GetObjectItemCaseSensitive(d, "integrator");
    const cJSON *ty = cJSON_GetObjectItemCaseSensitive(in, "type");
    int is_path = cJSON_IsString(ty) && strcmp(ty->valuestring, "path") == 0;
    int max_depth = json_int(in, "max_depth", 5);
    if (!strcmp(cfg, "direct-all") || (!strcmp(cfg, "direct-one") && is_path)) {
        cJSON_DeleteItemFromObjectCaseSensitive(d, "integrator");
        in = cJSON_AddObjectToObject(d, "integrator");
        cJSON_AddStringToObject(in, "type", "direct");
        cJSON_AddNumberToObject(in, "max_depth", max_depth > 1000 ? 1000 : max_depth);
        cJSON_AddStringToObject(in, "strategy", strcmp(cfg, "direct-all") ? "one" : "all");
    } else if (!strcmp(cfg, "direct-one")) {
        set_str(in, "strategy", "one");
    } else if (!strcmp(cfg, "light") || !strcmp(cfg, "bsdf")) {
        set_str(in, "sampling", cfg);
    } else if (!strcmp(cfg, "independent")) {
        set_str(smp, "type", "independent");
    } else if (!strcmp(cfg, "uniform")) {
        set_str(in, "light_sampling", "uniform");
    } else if (!strcmp(cfg, "rr-off")) {
        set_num(in, "rr_depth", 65535);
    }
    char *text = cJSON_PrintUnformatted(d);
    cJSON_Delete(d);
    return text;
}

static int has_triangle_emitters(const ts_scene *s)
{
    for (uint32_t i = 0; i < s->n_lights; i++)
        if (s->lights[i].type == TS_LIGHT_AREA && s->shapes[s->lights[i].shape].type == TS_SHAPE_MESH) return 1;
    return 0;
}

static ts_scene *load_doc(const char *text, const char *base_dir, const char *name)
{
    ts_scene_limits lim;
    ts_scene_limits_default(&lim);
    ts_scene *s = NULL;
    ts_error err = {0};
    if (ts_scene_load_text(text, strlen(text), base_dir, name, &lim, &s, &err)) {
        fprintf(stderr, "bench_accuracy: %s: %s\n", name, err.message);
        return NULL;
    }
    return s;
}

/* ---------------------------------------------------------------- rendering and error */

static ts_film *new_film(const ts_scene *s)
{
    ts_error err = {0};
    ts_film *f = ts_film_create(s->width, s->height, s->crop_x0, s->crop_y0, s->crop_x1 - s->crop_x0,
                                s->crop_y1 - s->crop_y0, &err);
    if (!f) fprintf(stderr, "bench_accuracy: film: %s\n", err.message);
    return f;
}

/* Renders [b, e) into f; returns the wall seconds, or −1 on failure. */
static double render_pass(const ts_scene *s, ts_film *f, uint32_t b, uint32_t e, int threads, int generic)
{
    ts_render_request req = {.scene = s, .integrator = s->integrator.type, .film = f, .sample_begin = b,
                             .sample_end = e, .threads = threads, .generic = generic};
    ts_render_stats st = {0};
    ts_error err = {0};
    double t0 = ts_now_seconds();
    if (ts_render(&req, &st, &err)) {
        fprintf(stderr, "bench_accuracy: render: %s\n", err.message);
        return -1;
    }
    return ts_now_seconds() - t0;
}

/* relMSE, MSE, and relMSE without the 0.1% largest per-value terms (fireflies), each
 * against the reference mean. scratch: 3·w·h doubles. */
static void errors(const float *x, const reference *r, double *scratch, double *relmse, double *mse, double *trim)
{
    size_t n = (size_t)3 * r->w * r->h;
    double a = 0, b = 0;
    for (size_t i = 0; i < n; i++) {
        double d = (double)x[i] - r->mean[i];
        scratch[i] = d * d / ((double)r->mean[i] * r->mean[i] + REL_EPS);
        a += scratch[i];
        b += d * d;
    }
    *relmse = a / n, *mse = b / n;
    qsort(scratch, n, sizeof *scratch, cmp_double);
    size_t keep = n - n / 1000;
    double t = 0;
    for (size_t i = 0; i < keep; i++) t += scratch[i];
    *trim = t / keep;
}

static int mkdirs(const char *dir)
{
    char buf[4096];
    snprintf(buf, sizeof buf, "%s", dir);
    for (char *p = buf + 1; *p; p++)
        if (*p == '/') {
            *p = 0;
            if (mkdir(buf, 0755) && errno != EEXIST) return -1;
            *p = '/';
        }
    return mkdir(buf, 0755) && errno != EEXIST ? -1 : 0;
}

/* The reference of (scene document, kind): from the cache or rendered (and cached). */
static int get_reference(const cJSON *orig, const char *scene_name, const char *base_dir, ref_kind kind,
                         const options *o, reference *ref)
{
    const char *cfg = kind == REF_DIRECT ? "direct-all" : "base";
    char *doc0 = config_document(orig, cfg, o->width, o->ref_spp, 0);
    ts_scene *s0 = load_doc(doc0, base_dir, scene_name);
    free(doc0);
    if (!s0) return -1;
    ref->w = s0->crop_x1 - s0->crop_x0, ref->h = s0->crop_y1 - s0->crop_y0;
    size_t n = (size_t)3 * ref->w * ref->h;
    ref->mean = malloc(n * sizeof(float));
    ref->h1 = malloc(n * sizeof(float));
    ref->h2 = malloc(n * sizeof(float));
    char path[4096] = "";
    if (o->cache)
        snprintf(path, sizeof path, "%s/%s-%s-%.16s-%dx%d-%uspp.f32", o->cache, scene_name,
                 kind == REF_DIRECT ? "direct" : "path", s0->digest, ref->w, ref->h, o->ref_spp);
    ts_scene_destroy(s0);
    FILE *f = path[0] ? fopen(path, "rb") : NULL;
    int ok = 0;
    if (f) {
        ok = fread(ref->h1, sizeof(float), n, f) == n && fread(ref->h2, sizeof(float), n, f) == n;
        fclose(f);
        if (ok) fprintf(stderr, "bench_accuracy: %s: %s reference from %s\n", scene_name, cfg, path);
    }
    if (!ok) {
        uint32_t half = o->ref_spp / 2;
        double t = 0;
        for (int k = 0; k < 2; k++) {
            char *doc = config_document(orig, cfg, o->width, o->ref_spp, 1000 + k);
            ts_scene *s = load_doc(doc, base_dir, scene_name);
            free(doc);
            if (!s) return -1;
            ts_film *film = new_film(s);
            if (!film) return -1;
            for (uint32_t b = 0; b < half; b += 256) {
                uint32_t e = b + 256 < half ? b + 256 : half;
                double dt = render_pass(s, film, b, e, o->threads, 0);
                if (dt < 0) return -1;
                t += dt;
                fprintf(stderr, "\rbench_accuracy: %s: %s reference %u/%u spp, %.0f s ", scene_name, cfg,
                        k * half + e, 2 * half, t);
            }
            ts_film_resolve(film, k ? ref->h2 : ref->h1);
            ts_film_destroy(film);
            ts_scene_destroy(s);
        }
        fprintf(stderr, "\n");
        if (path[0] && mkdirs(o->cache) == 0) {
            char tmp[4200];
            snprintf(tmp, sizeof tmp, "%s.tmp", path);
            FILE *w = fopen(tmp, "wb");
            if (w && fwrite(ref->h1, sizeof(float), n, w) == n && fwrite(ref->h2, sizeof(float), n, w) == n &&
                fclose(w) == 0) {
                rename(tmp, path);
                snprintf(tmp, sizeof tmp, "%s.txt", path);
                FILE *m = fopen(tmp, "w");
                if (m) {
                    fprintf(m, "scene %s\nintegrator %s\nspp %u (two halves of %u, seeds 1000 and 1001)\n"
                               "size %dx%d\nrender seconds %.1f at %d threads\nformat: two float32 RGB images, row-major\n",
                            scene_name, cfg, o->ref_spp, half, ref->w, ref->h, t, o->threads);
                    fclose(m);
                }
            } else if (w) {
                fclose(w);
            }
        }
    }
    double a = 0, b = 0;
    for (size_t i = 0; i < n; i++) {
        ref->mean[i] = 0.5f * (ref->h1[i] + ref->h2[i]);
        double d = (double)ref->h1[i] - ref->h2[i];
        a += d * d / ((double)ref->mean[i] * ref->mean[i] + REL_EPS);
        b += d * d;
    }
    ref->relmse_floor = a / n / 4, ref->mse_floor = b / n / 4;
    return 0;
}

/* ---------------------------------------------------------------- fitting */

static double fit_slope(const double *x, const double *y, const uint32_t *spp, int n)
{
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    int m = 0;
    for (int i = 0; i < n; i++) {
        if (spp[i] < 4 || !(x[i] > 0) || !(y[i] > 0)) continue;
        double lx = log(x[i]), ly = log(y[i]);
        sx += lx, sy += ly, sxx += lx * lx, sxy += lx * ly, m++;
    }
    if (m < 2) return NAN;
    double den = m * sxx - sx * sx;
    return den > 0 ? (m * sxy - sx * sy) / den : NAN;
}

/* Seconds to reach relMSE `target`: the sample count that reaches it, `interpolated`
 * (log-log between the two measured counts that bracket it) or `extrapolated` (from the
 * last count along the fitted spp slope), times the configuration's measured seconds per
 * sample over the whole series (cost per sample is constant; the per-pass times of a busy
 * machine are not, so this is steadier than fitting against time). *how "-": no estimate. */
static double time_to(const run *r, double slope_spp, double target, const char **how)
{
    int l = r->n - 1;
    if (l < 0) {
        *how = "-";
        return NAN;
    }
    double per_spp = r->per_spp > 0 ? r->per_spp : r->seconds[l] / r->spp[l];
    for (int i = 0; i < r->n; i++) {
        if (r->relmse[i] > target) continue;
        *how = "interpolated";
        if (i == 0 || !(r->relmse[i] > 0)) return r->spp[i] * per_spp;
        double e0 = log(r->relmse[i - 1]), e1 = log(r->relmse[i]);
        double f = (log(target) - e0) / (e1 - e0);
        return exp(log(r->spp[i - 1]) + f * (log(r->spp[i]) - log(r->spp[i - 1]))) * per_spp;
    }
    if (!(slope_spp < -0.3) || !(r->relmse[l] > 0)) { /* not converging in the measured range */
        *how = "-";
        return NAN;
    }
    *how = "extrapolated";
    return r->spp[l] * pow(target / r->relmse[l], 1 / slope_spp) * per_spp;
}

/* Summary rows of one scene: slopes and times to 1% and 0.1% relMSE, ratios to `base`. */
static void write_summary(FILE *out, const char *scene, const run *runs, int nr)
{
    double t1_base = NAN, t01_base = NAN;
    double t1[MAX_CONFIGS], t01[MAX_CONFIGS], ss[MAX_CONFIGS], st[MAX_CONFIGS], sm[MAX_CONFIGS], sr[MAX_CONFIGS];
    const char *h1[MAX_CONFIGS], *h01[MAX_CONFIGS];
    for (int i = 0; i < nr; i++) {
        const run *r = &runs[i];
        double x[MAX_LEVELS], mse[MAX_LEVELS];
        for (int k = 0; k < r->n; k++) x[k] = r->spp[k], mse[k] = r->rmse[k] * r->rmse[k];
        ss[i] = fit_slope(x, r->relmse, r->spp, r->n);
        sm[i] = fit_slope(x, mse, r->spp, r->n);
        sr[i] = fit_slope(x, r->trim, r->spp, r->n);
        st[i] = fit_slope(r->seconds, r->relmse, r->spp, r->n);
        t1[i] = time_to(r, ss[i], 0.01, &h1[i]);
        t01[i] = time_to(r, ss[i], 0.001, &h01[i]);
        if (!strcmp(r->name, "base")) t1_base = t1[i], t01_base = t01[i];
    }
    for (int i = 0; i < nr; i++) {
        const run *r = &runs[i];
        int l = r->n - 1;
        if (l < 0) continue;
        fprintf(out, "%s,%s,%s,%.3f,%.3f,%u,%.4f,%.6g,%.4g,%s,%.4g,%s,%.3g,%.3g,%.3f,%.4g,%.3f,%.4g,%.6g\n", scene, r->name,
                r->integ, ss[i], st[i], r->spp[l], r->seconds[l], r->relmse[l], t1[i], h1[i], t01[i], h01[i],
                t1[i] / t1_base, t01[i] / t01_base, sm[i], r->rmse[l], sr[i], r->trim[l],
                r->per_spp > 0 ? r->per_spp : r->seconds[l] / r->spp[l]);
    }
    fflush(out);
}

/* --summarise CSV: the summary again from bench_accuracy's CSV (e.g. after changing it). */
static int summarise(const char *csv, FILE *out)
{
    FILE *f = fopen(csv, "r");
    if (!f) {
        fprintf(stderr, "bench_accuracy: cannot read %s\n", csv);
        return 1;
    }
    static run runs[MAX_CONFIGS];
    char line[1024], scene[256] = "", sc[256], cf[64], in[64];
    int nr = 0;
    while (fgets(line, sizeof line, f)) {
        unsigned spp, rs;
        double sec, rel, rmse, d[4], tr = NAN;
        int k = sscanf(line, "%255[^,],%63[^,],%63[^,],%u,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%u,%lf", sc, cf, in, &spp, &sec,
                       &rel, &rmse, &d[0], &d[1], &d[2], &d[3], &rs, &tr);
        if (k < 5 || (k < 7 && spp != 0)) continue;
        if (strcmp(sc, scene)) {
            if (nr) write_summary(out, scene, runs, nr);
            snprintf(scene, sizeof scene, "%s", sc);
            nr = 0;
        }
        int i = 0;
        while (i < nr && strcmp(runs[i].name, cf)) i++;
        if (i == nr) {
            if (nr == MAX_CONFIGS) continue;
            memset(&runs[nr], 0, sizeof runs[nr]);
            snprintf(runs[nr].name, sizeof runs[nr].name, "%s", cf);
            snprintf(runs[nr].integ, sizeof runs[nr].integ, "%s", in);
            nr++;
        }
        run *r = &runs[i];
        if (spp == 0) { /* the timing rounds' seconds per spp */
            r->per_spp = sec;
            continue;
        }
        if (r->n == MAX_LEVELS) continue;
        r->spp[r->n] = spp, r->seconds[r->n] = sec, r->relmse[r->n] = rel, r->rmse[r->n] = rmse, r->trim[r->n] = tr;
        r->n++;
    }
    if (nr) write_summary(out, scene, runs, nr);
    fclose(f);
    return 0;
}

/* ---------------------------------------------------------------- one scene */

static int wanted(const options *o, const char *name)
{
    if (!o->configs) return 1;
    size_t n = strlen(name);
    for (const char *p = o->configs; *p;) {
        const char *e = strchr(p, ',');
        size_t l = e ? (size_t)(e - p) : strlen(p);
        if (l == n && !strncmp(p, name, n)) return 1;
        if (!e) break;
        p = e + 1;
    }
    return 0;
}

static int bench_scene(const char *path, const options *o, FILE *summary)
{
    size_t len = 0;
    char *text = read_text(path, &len);
    if (!text) {
        fprintf(stderr, "bench_accuracy: cannot read %s\n", path);
        return -1;
    }
    cJSON *orig = cJSON_ParseWithLength(text, len);
    free(text);
    if (!orig) {
        fprintf(stderr, "bench_accuracy: %s: not JSON\n", path);
        return -1;
    }
    char base_dir[4096], name[256];
    snprintf(base_dir, sizeof base_dir, "%s", path);
    char *slash = strrchr(base_dir, '/');
    if (slash) *slash = 0;
    else snprintf(base_dir, sizeof base_dir, ".");
    const char *fn = strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
    snprintf(name, sizeof name, "%s", fn);
    char *dot = strrchr(name, '.');
    if (dot) *dot = 0;

    const cJSON *ty = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(orig, "integrator"), "type");
    int is_path = cJSON_IsString(ty) && !strcmp(ty->valuestring, "path");
    int is_direct = cJSON_IsString(ty) && !strcmp(ty->valuestring, "direct");
    if (!is_path && !is_direct) {
        fprintf(stderr, "bench_accuracy: %s: integrator is neither path nor direct; skipped\n", name);
        cJSON_Delete(orig);
        return 0;
    }

    run runs[MAX_CONFIGS];
    int nr = 0, rc = 0;
    int need[2] = {0, 0};
    for (size_t c = 0; c < N_CONFIGS; c++) {
        const config *cf = &CONFIGS[c];
        if (!wanted(o, cf->name) || (cf->needs_path && !is_path)) continue;
        char *doc = config_document(orig, cf->name, o->width, o->max_spp, 0);
        ts_scene *s = load_doc(doc, base_dir, name);
        free(doc);
        if (!s) {
            rc = -1;
            goto done;
        }
        if (cf->needs_tri) {
            if (!has_triangle_emitters(s)) {
                ts_scene_destroy(s);
                continue;
            }
            ts_lights_set_triangle_sampling(s->lights, s->n_lights, s->shapes,
                                            !strcmp(cf->name, "tri-area") ? TS_TRIANGLE_SAMPLING_AREA
                                                                          : TS_TRIANGLE_SAMPLING_SPHERICAL);
        }
        run *r = &runs[nr++];
        memset(r, 0, sizeof *r);
        r->cfg = cf, r->scene = s, r->generic = !strcmp(cf->name, "generic");
        snprintf(r->name, sizeof r->name, "%s", cf->name);
        snprintf(r->integ, sizeof r->integ, "%s", ts_integrator_name(s->integrator.type));
        r->kind = s->integrator.type == TS_INTEGRATOR_DIRECT ? REF_DIRECT : REF_PATH;
        need[r->kind] = 1;
        if (!(r->film = new_film(s))) {
            rc = -1;
            goto done;
        }
    }
    reference refs[2];
    memset(refs, 0, sizeof refs);
    for (int k = 0; k < 2; k++)
        if (need[k] && get_reference(orig, name, base_dir, (ref_kind)k, o, &refs[k])) {
            rc = -1;
            goto done_refs;
        }

    /* Warm-up: one sample per configuration into a scratch film (caches, page faults). */
    for (int i = 0; i < nr; i++) {
        ts_film *f = new_film(runs[i].scene);
        if (!f || render_pass(runs[i].scene, f, 0, 1, o->threads, runs[i].generic) < 0) rc = -1;
        ts_film_destroy(f);
        if (rc) goto done_refs;
    }
    size_t npx = (size_t)3 * refs[need[0] ? 0 : 1].w * refs[need[0] ? 0 : 1].h;
    float *img = malloc(npx * sizeof(float));
    double *scratch = malloc(npx * sizeof(double));
    double total = 0;
    int level = 0;
    for (uint32_t e = 1, b = 0; e <= o->max_spp && level < MAX_LEVELS; b = e, e *= 2, level++) {
        for (int j = 0; j < nr; j++) {
            run *r = &runs[(j + level) % nr];
            double dt = render_pass(r->scene, r->film, b, e, o->threads, r->generic);
            if (dt < 0) {
                rc = -1;
                break;
            }
            total += dt;
            const reference *ref = &refs[r->kind];
            ts_film_resolve(r->film, img);
            double rel, mse, trim;
            errors(img, ref, scratch, &rel, &mse, &trim);
            int i = r->n++;
            r->spp[i] = e;
            r->seconds[i] = (i ? r->seconds[i - 1] : 0) + dt;
            r->relmse[i] = rel - ref->relmse_floor;
            r->rmse[i] = sqrt(fmax(mse - ref->mse_floor, 0));
            r->trim[i] = trim;
            printf("%s,%s,%s,%u,%.6f,%.6g,%.6g,%.6g,%.6g,%.3g,%.3g,%u,%.6g\n", name, r->cfg->name,
                   ts_integrator_name(r->scene->integrator.type), e, r->seconds[i], r->relmse[i], r->rmse[i], rel,
                   sqrt(mse), ref->relmse_floor, sqrt(ref->mse_floor), o->ref_spp, trim);
        }
        fflush(stdout);
        if (rc) break;
        fprintf(stderr, "\rbench_accuracy: %s: %u spp, %d configurations, %.0f s ", name, e, nr, total);
    }
    fprintf(stderr, "\n");

    /* Timing rounds: the cost per sample, side by side. Each round renders K more samples
     * of every configuration (rotated order) into a scratch film; the fastest round's
     * seconds per spp is what the times to 1% and 0.1% use (on a shared machine the
     * other jobs only ever add time, so the minimum is the steadiest estimate of the cost;
     * medians of 5 still moved by ±30% between identical configurations). */
    uint32_t K = o->max_spp / 4 < 4 ? 4 : o->max_spp / 4;
    double per[MAX_CONFIGS][32];
    int reps = o->reps > 32 ? 32 : o->reps;
    for (int k = 0; k < reps && !rc; k++)
        for (int j = 0; j < nr && !rc; j++) {
            int i = (j + k) % nr;
            ts_film *f = new_film(runs[i].scene);
            double dt = f ? render_pass(runs[i].scene, f, o->max_spp, o->max_spp + K, o->threads, runs[i].generic) : -1;
            ts_film_destroy(f);
            if (dt < 0) rc = -1;
            else per[i][k] = dt / K;
        }
    for (int i = 0; i < nr && !rc && reps > 0; i++) {
        qsort(per[i], (size_t)reps, sizeof(double), cmp_double);
        runs[i].per_spp = per[i][0];
        fprintf(stderr, "bench_accuracy: %s: %s: %.3g ms/spp (fastest of %d rounds of %u spp)\n", name,
                runs[i].name, 1e3 * runs[i].per_spp, reps, K);
        /* A CSV row with spp 0 carries it, for --summarise. */
        printf("%s,%s,%s,0,%.6f,,,,,,,,\n", name, runs[i].name, runs[i].integ, runs[i].per_spp);
    }
    fflush(stdout);
    free(img);
    free(scratch);

    if (summary && !rc) write_summary(summary, name, runs, nr);
done_refs:
    for (int k = 0; k < 2; k++) free(refs[k].mean), free(refs[k].h1), free(refs[k].h2);
done:
    for (int i = 0; i < nr; i++) ts_film_destroy(runs[i].film), ts_scene_destroy(runs[i].scene);
    cJSON_Delete(orig);
    return rc;
}

/* ---------------------------------------------------------------- main */

static int usage(void)
{
    fprintf(stderr, "usage: bench_accuracy [--width W] [--max-spp N] [--ref-spp N] [--threads T] [--reps R] [--cache DIR]\n"
                    "                      [--configs LIST] [--summary FILE] [--header] SCENE.json...\n"
                    "       bench_accuracy --summarise ACCURACY.csv   (the summary again, to stdout)\n");
    return 2;
}

int main(int argc, char **argv)
{
    options o = {.reps = 7, .width = 96, .threads = (int)sysconf(_SC_NPROCESSORS_ONLN), .max_spp = 128, .ref_spp = 1024};
    if (o.threads < 1) o.threads = 1;
    int i = 1;
    for (; i < argc && argv[i][0] == '-'; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--header")) {
            o.header = 1;
            continue;
        }
        if (!v) return usage();
        i++;
        if (!strcmp(a, "--width")) o.width = atoi(v);
        else if (!strcmp(a, "--max-spp")) o.max_spp = (uint32_t)strtoul(v, NULL, 10);
        else if (!strcmp(a, "--ref-spp")) o.ref_spp = (uint32_t)strtoul(v, NULL, 10);
        else if (!strcmp(a, "--threads")) o.threads = atoi(v);
        else if (!strcmp(a, "--reps")) o.reps = atoi(v);
        else if (!strcmp(a, "--cache")) o.cache = v;
        else if (!strcmp(a, "--configs")) o.configs = v;
        else if (!strcmp(a, "--summary")) o.summary = v;
        else if (!strcmp(a, "--summarise")) o.summarise = v;
        else return usage();
    }
    if (o.summarise && i == argc) {
        printf("scene,config,integrator,slope_spp,slope_time,final_spp,final_seconds,final_relmse,"
               "t_1pct,how_1pct,t_01pct,how_01pct,ratio_1pct,ratio_01pct,slope_mse_spp,final_rmse,"
                         "slope_trim_spp,final_relmse_trim,seconds_per_spp\n");
        return summarise(o.summarise, stdout);
    }
    if (i >= argc || o.width < 8 || o.max_spp < 1 || o.ref_spp < 2 || o.threads < 1) return usage();
    FILE *summary = NULL;
    if (o.summary) {
        summary = fopen(o.summary, "w");
        if (!summary) {
            fprintf(stderr, "bench_accuracy: cannot write %s\n", o.summary);
            return 1;
        }
        fprintf(summary, "scene,config,integrator,slope_spp,slope_time,final_spp,final_seconds,final_relmse,"
                         "t_1pct,how_1pct,t_01pct,how_01pct,ratio_1pct,ratio_01pct,slope_mse_spp,final_rmse,"
                         "slope_trim_spp,final_relmse_trim,seconds_per_spp\n");
    }
    if (o.header)
        printf("scene,config,integrator,spp,seconds,relmse,rmse,relmse_raw,rmse_raw,ref_relmse,ref_rmse,ref_spp,"
               "relmse_trim\n");
    int rc = 0;
    for (; i < argc; i++)
        if (bench_scene(argv[i], &o, summary)) rc = 1;
    if (summary) fclose(summary);
    return rc;
}
