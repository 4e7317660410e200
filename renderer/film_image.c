/* film_image.c — film to image; see film_image.h. */
#include "film_image.h"

ts_status ts_film_to_image(const ts_film *f, ts_film_image_layout layout, ts_image *img, ts_error *err)
{
    static const char *const rgb[] = {"R", "G", "B"};
    static const char *const stats[] = {"R", "G", "B", "R.var", "G.var", "B.var", "count"};
    int nc = layout == TS_FILM_IMAGE_RGB ? 3 : 7;
    ts_status st = ts_image_init(img, f->width, f->height, nc, layout == TS_FILM_IMAGE_RGB ? rgb : stats, err);
    if (st) return st;
    for (int y = 0; y < f->height; y++)
        for (int x = 0; x < f->width; x++) {
            float *px = img->data + ((size_t)y * f->width + x) * nc;
            ts_rgb m = ts_film_pixel_rgb(f, f->x0 + x, f->y0 + y);
            px[0] = m.r, px[1] = m.g, px[2] = m.b;
            if (layout == TS_FILM_IMAGE_STATS) {
                ts_rgb v = ts_film_pixel_variance(f, f->x0 + x, f->y0 + y);
                px[3] = v.r, px[4] = v.g, px[5] = v.b;
                px[6] = (float)f->pixels[(size_t)y * f->width + x].count;
            }
        }
    return TS_OK;
}
