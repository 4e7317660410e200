/* image.h — a float image with named channels and metadata: what encoders take and
 * decoders give.
 *
 * Design note: one container for every image that crosses a file or HTTP boundary (EXR,
 * PNG, shard merge, checkpoints). Pixels are interleaved float32,
 * data[(y*width + x)*n_channels + c], row 0 at the top. Channel names are free-form
 * ("R", "G", "B", "weight", "count", "R2", …); metadata is a small fixed array of typed
 * attributes so an image is one plain struct plus one malloc'd pixel block. Nothing here
 * keeps global state: every function is thread-safe on distinct images. */
#ifndef TS_IMAGE_H
#define TS_IMAGE_H

#include <stddef.h>
#include <stdint.h>

#include "core/error.h"

#define TS_IMAGE_MAX_CHANNELS 16
#define TS_IMAGE_MAX_ATTRS 32
/* Largest width x height accepted (16384², 1 GiB per channel). Guards against headers of
 * corrupt files asking for absurd allocations. */
#define TS_IMAGE_MAX_PIXELS ((int64_t)1 << 28)

typedef enum ts_attr_type { TS_ATTR_STRING, TS_ATTR_INT, TS_ATTR_DOUBLE } ts_attr_type;

/* One metadata entry. name: 1..63 bytes; s: the value when type == TS_ATTR_STRING
 * (0..255 bytes, NUL-terminated); i / d for the other types. */
typedef struct ts_image_attr {
    char name[64];
    ts_attr_type type;
    char s[256];
    int32_t i;
    double d;
} ts_image_attr;

typedef struct ts_image {
    int width, height, n_channels;
    char channel_names[TS_IMAGE_MAX_CHANNELS][32]; /* e.g. "R","G","B","weight","count",... */
    float *data; /* interleaved: data[(y*width + x)*n_channels + c], malloc-owned */
    int n_attrs;
    ts_image_attr attrs[TS_IMAGE_MAX_ATTRS];
} ts_image;

/* Initialises img with zeroed pixels. width, height ≥ 1 with width x height ≤
 * TS_IMAGE_MAX_PIXELS; 1 ≤ n_channels ≤ TS_IMAGE_MAX_CHANNELS; names: n_channels distinct
 * non-empty strings of at most 31 bytes. On failure img is left empty (safe to _fini) and
 * err says why (TS_ERR_INVALID, TS_ERR_LIMIT or TS_ERR_NOMEM). */
ts_status ts_image_init(ts_image *img, int width, int height, int n_channels,
                        const char *const *names, ts_error *err);

/* Frees the pixels and empties img. Safe on a zeroed or already finished image. */
void ts_image_fini(ts_image *img);

/* Sets an attribute, replacing one of the same name (whatever its type). Names are 1..63
 * bytes, string values at most 255 bytes; more than TS_IMAGE_MAX_ATTRS distinct names →
 * TS_ERR_LIMIT. */
ts_status ts_image_set_string(ts_image *img, const char *name, const char *value, ts_error *err);
ts_status ts_image_set_int(ts_image *img, const char *name, int32_t value, ts_error *err);
ts_status ts_image_set_double(ts_image *img, const char *name, double value, ts_error *err);

/* The attribute called name, or NULL if absent. */
const ts_image_attr *ts_image_attr_find(const ts_image *img, const char *name);

/* Index of the channel called name, or -1. */
int ts_image_channel(const ts_image *img, const char *name);

/* Writes len bytes to path atomically: to "<path>.tmp.<pid>.<serial>", fsync, then
 * rename(2) over path. On failure (TS_ERR_IO with a sentence naming path, never the
 * temporary name, so a repeated failure reads the same) the temporary file is removed and
 * an existing file at path is untouched. Shared by the EXR and PNG writers and the server's
 * checkpoints. Thread-safe: temporary names are unique per call. */
ts_status ts_image_write_file_atomic(const char *path, const void *bytes, size_t len,
                                     ts_error *err);

#endif
