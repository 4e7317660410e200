/* image_error.c — error of an image against a reference, and how two images' levels agree.
 *
 *   bench_image_error IMAGE.exr REF.exr [REF_B.exr]
 *
 * Reads the R, G, B channels of each EXR (any extra channels are ignored; tessera's and
 * Blender's files both have them by those names) and prints one line of key=value pairs:
 *
 *   rmse       sqrt(mean over pixels and channels of (x − r)²), with r the reference; when
 *              REF_B is given, r = (REF + REF_B)/2 and the reference's own noise,
 *              estimated as mean (REF − REF_B)²/4 (two independent halves), is subtracted
 *              from the mean square first (not below 0)
 *   rmse_raw   the same without the subtraction
 *   ref_rmse   the reference's own RMSE estimate (0 without REF_B)
 *   relmse     mean (x − r)² / (r² + 0.01), raw (as bench_accuracy's relMSE)
 *   mean_x_R…  per-channel means of IMAGE, mean_r_R… of the reference
 *   ratio_R…   mean_x / mean_r − 1 per channel (level agreement of two converged images)
 *   mean_abs_rel  mean |x − r| / (r + 0.01) over pixels and channels
 *   render_time_s IMAGE's tessera_render_time_s attribute (tessera's own render time:
 *              the sampling passes, not loading the scene nor writing files), when present
 *
 * Exit status 0, or 2 on bad input (missing channels, different sizes). Used by
 * bench/cycles/run.sh (bench/README.md, "Against Blender Cycles"). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "image/exr.h"

static const char *const k_rgb[3] = {"R", "G", "B"};

/* Loads path and finds its R, G, B channels; returns 0 or prints why and returns 2. */
static int load_rgb(const char *path, ts_image *img, int idx[3])
{
    ts_error err = {0};
    if (ts_exr_read(path, img, &err) != TS_OK) {
        fprintf(stderr, "image_error: %s\n", err.message);
        return 2;
    }
    for (int c = 0; c < 3; c++) {
        idx[c] = ts_image_channel(img, k_rgb[c]);
        if (idx[c] < 0) {
            fprintf(stderr, "image_error: %s has no %s channel\n", path, k_rgb[c]);
            return 2;
        }
    }
    return 0;
}

int main(int argc, char **argv)
{
    if (argc != 3 && argc != 4) {
        fprintf(stderr, "usage: %s IMAGE.exr REF.exr [REF_B.exr]\n", argv[0]);
        return 2;
    }
    ts_image img[3] = {{0}, {0}, {0}};
    int idx[3][3], n_img = argc - 1, status = 0;
    for (int i = 0; i < n_img && !status; i++)
        status = load_rgb(argv[i + 1], &img[i], idx[i]);
    for (int i = 1; i < n_img && !status; i++)
        if (img[i].width != img[0].width || img[i].height != img[0].height) {
            fprintf(stderr, "image_error: %s is %dx%d, %s is %dx%d\n", argv[i + 1], img[i].width,
                    img[i].height, argv[1], img[0].width, img[0].height);
            status = 2;
        }
    if (status) goto done;

    size_t n_px = (size_t)img[0].width * (size_t)img[0].height;
    double sum_sq = 0, sum_rel = 0, sum_abs_rel = 0, sum_ref_sq = 0;
    double sum_x[3] = {0}, sum_r[3] = {0};
    for (size_t p = 0; p < n_px; p++)
        for (int c = 0; c < 3; c++) {
            double x = img[0].data[p * (size_t)img[0].n_channels + (size_t)idx[0][c]];
            double r = img[1].data[p * (size_t)img[1].n_channels + (size_t)idx[1][c]];
            if (n_img == 3) {
                double r_b = img[2].data[p * (size_t)img[2].n_channels + (size_t)idx[2][c]];
                sum_ref_sq += (r - r_b) * (r - r_b) / 4;
                r = (r + r_b) / 2;
            }
            double d = x - r;
            sum_sq += d * d;
            sum_rel += d * d / (r * r + 0.01);
            sum_abs_rel += fabs(d) / (fabs(r) + 0.01);
            sum_x[c] += x;
            sum_r[c] += r;
        }
    double n = 3.0 * (double)n_px;
    double mse_raw = sum_sq / n, ref_mse = sum_ref_sq / n;
    double mse = mse_raw > ref_mse ? mse_raw - ref_mse : 0;
    printf("rmse=%.9g rmse_raw=%.9g ref_rmse=%.9g relmse=%.9g mean_abs_rel=%.6g", sqrt(mse), sqrt(mse_raw),
           sqrt(ref_mse), sum_rel / n, sum_abs_rel / n);
    for (int c = 0; c < 3; c++)
        printf(" mean_x_%s=%.7g", k_rgb[c], sum_x[c] / (double)n_px);
    for (int c = 0; c < 3; c++)
        printf(" mean_r_%s=%.7g", k_rgb[c], sum_r[c] / (double)n_px);
    for (int c = 0; c < 3; c++)
        printf(" ratio_%s=%.5f", k_rgb[c], sum_r[c] != 0 ? sum_x[c] / sum_r[c] - 1 : 0.0);
    const ts_image_attr *t = ts_image_attr_find(&img[0], "tessera_render_time_s");
    if (t && t->type == TS_ATTR_DOUBLE) printf(" render_time_s=%.6f", t->d);
    printf("\n");
done:
    for (int i = 0; i < 3; i++)
        ts_image_fini(&img[i]);
    return status;
}
