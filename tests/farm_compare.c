/* farm_compare.c — test helper for the farm scripts: compares a merged shard EXR with a
 * single render (both in the shard layout) and prints the differences.
 *   farm_compare MERGED.exr REFERENCE.exr
 * Exit 0 when every pixel's mean agrees to 1e-12 relative and the image mean to 1e-13
 * (see test_farm_merge.c for why these bounds), the sample counts are equal and the
 * merge holds every sample [0, S); 1 otherwise. */
#include <math.h>
#include <stdio.h>

#include "render/shard.h"

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: farm_compare MERGED.exr REFERENCE.exr\n");
        return 2;
    }
    ts_shard_info ia, ib;
    ts_film *a, *b;
    ts_error err = {0};
    if (ts_shard_read(argv[1], &ia, &a, &err) || ts_shard_read(argv[2], &ib, &b, &err)) {
        fprintf(stderr, "farm_compare: %s\n", err.message);
        return 1;
    }
    int rc = 0;
    if (a->width != b->width || a->height != b->height || a->x0 != b->x0 || a->y0 != b->y0) {
        fprintf(stderr, "farm_compare: the images cover different windows\n");
        return 1;
    }
    if (ia.n_ranges != 1 || ia.ranges[0].begin != 0 || ia.ranges[0].end != ia.spp_total) {
        fprintf(stderr, "farm_compare: %s does not hold every sample [0,%u)\n", argv[1], ia.spp_total);
        rc = 1;
    }
    double worst = 0, sa = 0, sb = 0;
    for (int i = 0; i < a->width * a->height; i++) {
        const ts_film_pixel *p = &a->pixels[i], *q = &b->pixels[i];
        if (p->count != q->count) rc = 1;
        for (int c = 0; c < 3; c++) {
            double ma = p->weight ? p->sum[c] / p->weight : 0, mb = q->weight ? q->sum[c] / q->weight : 0;
            double scale = fmax(fabs(ma), fabs(mb));
            double d = scale > 0 ? fabs(ma - mb) / scale : 0;
            if (d > worst) worst = d;
            sa += ma, sb += mb;
        }
    }
    double mean = sb != 0 ? fabs(sa - sb) / fabs(sb) : fabs(sa);
    printf("farm_compare: %d×%d, %u spp: largest pixel difference %.3g relative, image mean %.3g relative\n",
           a->width, a->height, ia.spp_total, worst, mean);
    if (!(worst <= 1e-12 && mean <= 1e-13)) rc = 1;
    ts_film_destroy(a);
    ts_film_destroy(b);
    return rc;
}
