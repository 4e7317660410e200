/* exr_compare.c — are two EXR images the same pixels, bit for bit?
 *
 *   bench_exr_compare A.exr B.exr
 *
 * Compares every channel of every pixel as raw float bits (so -0 ≠ +0 and NaN payloads
 * count), ignoring metadata (render time and rates differ between runs). Prints one line:
 * "identical: N values" or the number of differing values, the first difference and the
 * largest relative difference. Exit status 0 when identical, 1 when not, 2 on bad input.
 * Used by bench/run's bit-identity check of optimisations (bench/README.md). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "image/exr.h"

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: %s A.exr B.exr\n", argv[0]);
        return 2;
    }
    ts_image a = {0}, b = {0};
    ts_error err = {0};
    if (ts_exr_read(argv[1], &a, &err) != TS_OK || ts_exr_read(argv[2], &b, &err) != TS_OK) {
        fprintf(stderr, "exr_compare: %s\n", err.message);
        ts_image_fini(&a);
        ts_image_fini(&b);
        return 2;
    }
    int status = 0;
    if (a.width != b.width || a.height != b.height || a.n_channels != b.n_channels) {
        printf("different layouts: %dx%d×%d vs %dx%d×%d\n", a.width, a.height, a.n_channels, b.width,
               b.height, b.n_channels);
        status = 1;
        goto done;
    }
    for (int c = 0; c < a.n_channels; c++)
        if (strcmp(a.channel_names[c], b.channel_names[c]) != 0) {
            printf("different channels: %s vs %s\n", a.channel_names[c], b.channel_names[c]);
            status = 1;
            goto done;
        }
    size_t n = (size_t)a.width * a.height * a.n_channels, n_diff = 0, first = 0;
    double max_rel = 0;
    for (size_t i = 0; i < n; i++) {
        if (memcmp(&a.data[i], &b.data[i], sizeof(float)) == 0) continue;
        if (n_diff++ == 0) first = i;
        double x = a.data[i], y = b.data[i], m = fmax(fabs(x), fabs(y));
        double rel = m > 0 ? fabs(x - y) / m : 1;
        if (!(rel <= max_rel)) max_rel = rel;
    }
    if (n_diff == 0) {
        printf("identical: %zu values\n", n);
    } else {
        size_t px = first / (size_t)a.n_channels;
        int c = (int)(first % (size_t)a.n_channels);
        printf(
            "DIFFERENT: %zu of %zu values; first at pixel (%zu, %zu) channel %s: %.9g vs %.9g; max relative "
            "difference %.3g\n",
            n_diff, n, px % (size_t)a.width, px / (size_t)a.width, a.channel_names[c], a.data[first],
            b.data[first], max_rel);
        status = 1;
    }
done:
    ts_image_fini(&a);
    ts_image_fini(&b);
    return status;
}
