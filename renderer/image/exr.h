/* exr.h — OpenEXR read/write of ts_image through OpenEXR's core C API.
 *
 * Design note: writing always goes to memory first (one encoder, so the file and the
 * HTTP body are the same bytes), then a file is replaced atomically. Output is fixed:
 * single-part scanline, FLOAT channels, ZIP compression, increasing Y, data window =
 * display window = (0,0)-(w-1,h-1); same image ⇒ bit-identical bytes. Reading accepts
 * any single-part scanline or tiled (level 0 of mip/rip maps) file with UINT, HALF or
 * FLOAT channels and converts them to float; the image is the data window. Deep and
 * multi-part files are refused (TS_ERR_UNSUPPORTED). Reading goes through our own
 * bounded read callback with chunk-table reconstruction disabled, so truncated or
 * corrupt input fails cleanly with a sentence instead of reading partial data.
 * All functions are thread-safe (no shared state); the library's messages go into err,
 * never to stderr. */
#ifndef TS_EXR_H
#define TS_EXR_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "core/error.h"
#include "image/image.h"

/* Atomic: writes "<path>.tmp.<pid>" then rename(2); on failure nothing is left behind.
 * FLOAT channels, ZIP compression, scanline; metadata as EXR attributes of the matching
 * type (string, int, double). Channels may be given in any order (the file lists them
 * sorted, as EXR requires). Attribute names that are standard header attributes
 * ("channels", "compression", "dataWindow", …) are refused with TS_ERR_INVALID. */
ts_status ts_exr_write(const char *path, const ts_image *img, ts_error *err);

/* Same bytes as ts_exr_write, in a malloc'd buffer the caller frees (for HTTP). On failure
 * *buf is NULL and *len 0. */
ts_status ts_exr_write_memory(const ts_image *img, unsigned char **buf, size_t *len, ts_error *err);

/* Reads a single-part scanline or tiled EXR with HALF/FLOAT (UINT converted) channels into
 * a new float image (caller calls ts_image_fini). All channels are kept with their names,
 * in the file's (sorted) order; string/int/double/float attributes that are not standard
 * header attributes are copied into attrs (float as TS_ATTR_DOUBLE; attributes whose name
 * or string value does not fit, and any beyond TS_IMAGE_MAX_ATTRS, are skipped).
 * Missing or unreadable file → TS_ERR_IO; truncated or corrupt → TS_ERR_INVALID; deep,
 * multi-part, subsampled or >16 channels → TS_ERR_UNSUPPORTED/TS_ERR_LIMIT; an image whose
 * float pixels would need over 64 MiB and over 4096 bytes per byte of file (a header that
 * lies about the data window: a decompression bomb) → TS_ERR_LIMIT before any pixel
 * memory is allocated. The sentence names the file. On failure *out is empty and nothing
 * is leaked. */
ts_status ts_exr_read(const char *path, ts_image *out, ts_error *err);

/* ts_exr_read of an in-memory file (for fuzzing/HTTP); buf is only read. */
ts_status ts_exr_read_memory(const unsigned char *buf, size_t len, ts_image *out, ts_error *err);

/* The size of an in-memory file's first part as its header says, read without any pixel:
 * false when the header cannot be read (ts_exr_read_memory then says why). So a caller
 * can hold an image to its memory budget before it is decoded. */
bool ts_exr_size_memory(const unsigned char *buf, size_t len, int64_t *width, int64_t *height, int *channels);

#endif
