/* film_image.h — a film's accumulated state as an image for the encoders, and back.
 *
 * Design note: the CLI, the server and the farm nodes all turn films into EXR/PNG, so the
 * channel layout lives here, once. TS_FILM_IMAGE_RGB gives the resolved colour (Σw·L/Σw);
 * TS_FILM_IMAGE_STATS adds what a user computing with the image wants: per-pixel variance
 * of the mean ("R.var", "G.var", "B.var") and sample count ("count"). Pixels are the
 * film's crop window. Metadata is the caller's. Thread-safety: reads the film without
 * locking; the caller guarantees no worker writes it meanwhile (or uses a snapshot). */
#ifndef TS_FILM_IMAGE_H
#define TS_FILM_IMAGE_H

#include "error.h"
#include "film.h"
#include "image.h"

typedef enum ts_film_image_layout {
    TS_FILM_IMAGE_RGB,   /* R, G, B */
    TS_FILM_IMAGE_STATS, /* R, G, B, R.var, G.var, B.var, count */
} ts_film_image_layout;

/* Fills img (initialised here; the caller finis it). */
ts_status ts_film_to_image(const ts_film *f, ts_film_image_layout layout, ts_image *img, ts_error *err);

#endif
