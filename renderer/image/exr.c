/* exr.c — EXR encoder/decoder on OpenEXR's core C API; see exr.h.
 *
 * Both directions run on custom stream callbacks whose user data is an exr_io: a memory
 * sink for writing, a memory buffer or a file descriptor (pread) for reading. The same
 * struct catches the first error message the library reports (through the context's
 * error handler), so failures become one sentence in the caller's ts_error. */
#include "image/exr.h"

#include <errno.h>
#include <fcntl.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <openexr.h>

/* Per-call stream state shared by the library's callbacks (user_data). */
/* Reading refuses images whose float pixels would need more than EXR_MAX_EXPANSION bytes
 * per byte of file (and more than EXR_SMALL_IMAGE_BYTES in all): deflate (ZIP, ZIPS,
 * PXR24) expands at most ~1032:1, RLE 64:1, B44 ~11:1, and HALF or UINT samples double
 * at most when stored as float, so only a file that lies about its size (or a perfectly
 * constant giant image in PIZ or DWA) goes past 4096:1. */
#define EXR_MAX_EXPANSION 4096
#define EXR_SMALL_IMAGE_BYTES (64.0 * 1024 * 1024)

typedef struct exr_io {
    /* reading: memory (fd < 0) or a file descriptor */
    const unsigned char *src;
    size_t src_len;
    int fd;
    int64_t file_size;
    int io_errno; /* errno of a failed pread, 0 otherwise */
    /* writing: growing memory sink, written at arbitrary offsets (pwrite semantics) */
    unsigned char *buf;
    size_t len, cap;
    bool out_of_memory;
    /* first message the library reported */
    char msg[256];
} exr_io;

/* Standard header attributes: never copied into ts_image attrs, never written from them. */
static const char *const reserved_attrs[] = {
    "channels",  "compression",        "dataWindow",        "displayWindow", "lineOrder",
    "pixelAspectRatio", "screenWindowCenter", "screenWindowWidth", "tiles",   "type",
    "name",      "version",            "chunkCount",        "maxSamplesPerPixel",
};

static bool is_reserved_attr(const char *name)
{
    for (size_t k = 0; k < sizeof reserved_attrs / sizeof reserved_attrs[0]; k++)
        if (strcmp(reserved_attrs[k], name) == 0) return true;
    return false;
}

static void on_exr_error(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    void *ud = NULL;
    if (!ctxt || exr_get_user_data(ctxt, &ud) != EXR_ERR_SUCCESS || !ud) return;
    exr_io *io = ud;
    if (io->msg[0]) return; /* keep the first, most specific message */
    snprintf(io->msg, sizeof io->msg, "%s", msg && msg[0] ? msg : exr_get_default_error_message(code));
    /* Messages may quote bytes of a corrupt file: keep them printable ASCII (they end up in
     * logs and JSON), and short. */
    size_t n = 0;
    for (unsigned char *p = (unsigned char *)io->msg; *p; p++, n++)
        if (*p < 0x20 || *p > 0x7e) *p = '?';
    if (n > 160) memcpy(io->msg + 157, "...", 4);
}

static int64_t io_read(exr_const_context_t ctxt, void *ud, void *buffer, uint64_t sz, uint64_t offset,
                       exr_stream_error_func_ptr_t error_cb)
{
    exr_io *io = ud;
    if (io->fd < 0) {
        if (offset >= io->src_len) return 0;
        size_t n = io->src_len - (size_t)offset;
        if (sz < n) n = (size_t)sz;
        memcpy(buffer, io->src + offset, n);
        return (int64_t)n;
    }
    if (offset > (uint64_t)INT64_MAX || sz > (uint64_t)INT64_MAX) return 0;
    uint64_t done = 0;
    while (done < sz) {
        ssize_t r = pread(io->fd, (unsigned char *)buffer + done, (size_t)(sz - done), (off_t)(offset + done));
        if (r < 0 && errno == EINTR) continue;
        if (r < 0) {
            io->io_errno = errno;
            if (error_cb)
                error_cb(ctxt, EXR_ERR_READ_IO, "read of %llu bytes at offset %llu failed: %s",
                         (unsigned long long)sz, (unsigned long long)offset, strerror(errno));
            return -1;
        }
        if (r == 0) break; /* end of file: a short read, the library reports it */
        done += (uint64_t)r;
    }
    return (int64_t)done;
}

static int64_t io_size(exr_const_context_t ctxt, void *ud)
{
    (void)ctxt;
    exr_io *io = ud;
    return io->fd < 0 ? (int64_t)io->src_len : io->file_size;
}

static int64_t io_write(exr_const_context_t ctxt, void *ud, const void *buffer, uint64_t sz, uint64_t offset,
                        exr_stream_error_func_ptr_t error_cb)
{
    exr_io *io = ud;
    if (offset > SIZE_MAX / 2 || sz > SIZE_MAX / 2) goto fail_nomem;
    size_t end = (size_t)offset + (size_t)sz;
    if (end > io->cap) {
        size_t cap = io->cap ? io->cap : 65536;
        while (cap < end) cap *= 2;
        unsigned char *p = realloc(io->buf, cap);
        if (!p) goto fail_nomem;
        io->buf = p;
        io->cap = cap;
    }
    if ((size_t)offset > io->len) memset(io->buf + io->len, 0, (size_t)offset - io->len);
    memcpy(io->buf + offset, buffer, (size_t)sz);
    if (end > io->len) io->len = end;
    return (int64_t)sz;

fail_nomem:
    io->out_of_memory = true;
    error_cb(ctxt, EXR_ERR_OUT_OF_MEMORY, "out of memory for %llu bytes of EXR output",
             (unsigned long long)(offset + sz));
    return -1;
}

/* Turns a library failure into a status and a sentence "<what>: <problem>". */
static ts_status exr_fail(ts_error *err, const exr_io *io, exr_result_t rv, const char *what)
{
    ts_status st = TS_ERR_INVALID;
    if (io->io_errno) st = TS_ERR_IO;
    else if (rv == EXR_ERR_OUT_OF_MEMORY || io->out_of_memory) st = TS_ERR_NOMEM;
    else if (rv == EXR_ERR_FEATURE_NOT_IMPLEMENTED) st = TS_ERR_UNSUPPORTED;
    else if (rv == EXR_ERR_READ_IO) /* a short read: the data ends early */
        return ts_error_set(err, st, "%s: the file is truncated (%s)", what,
                            io->msg[0] ? io->msg : exr_get_default_error_message(rv));
    return ts_error_set(err, st, "%s: %s", what, io->msg[0] ? io->msg : exr_get_default_error_message(rv));
}

/* The library's line stride is an int32_t byte count: one interleaved row must fit. */
static bool row_fits_stride(int64_t width, int64_t n_channels)
{
    return width * n_channels * (int64_t)sizeof(float) <= INT32_MAX;
}

/* ---- writing ---- */

static ts_status check_image(const ts_image *img, ts_error *err)
{
    if (!img || !img->data || img->width < 1 || img->height < 1 || img->n_channels < 1 ||
        img->n_channels > TS_IMAGE_MAX_CHANNELS || img->n_attrs < 0 || img->n_attrs > TS_IMAGE_MAX_ATTRS)
        return ts_error_set(err, TS_ERR_INVALID, "the image is empty or not initialised");
    if (!row_fits_stride(img->width, img->n_channels))
        return ts_error_set(err, TS_ERR_LIMIT, "an image row of %d pixels x %d channels is too long for EXR",
                            img->width, img->n_channels);
    for (int c = 0; c < img->n_channels; c++) {
        const char *name = img->channel_names[c];
        if (!name[0] || !memchr(name, '\0', sizeof img->channel_names[c]))
            return ts_error_set(err, TS_ERR_INVALID, "image channel %d has no valid name", c);
        for (int k = 0; k < c; k++)
            if (strcmp(img->channel_names[k], name) == 0)
                return ts_error_set(err, TS_ERR_INVALID, "image channel name '%s' appears twice", name);
    }
    for (int a = 0; a < img->n_attrs; a++) {
        const ts_image_attr *at = &img->attrs[a];
        if (!at->name[0] || !memchr(at->name, '\0', sizeof at->name))
            return ts_error_set(err, TS_ERR_INVALID, "image attribute %d has no valid name", a);
        if (is_reserved_attr(at->name))
            return ts_error_set(err, TS_ERR_INVALID,
                                "image attribute '%s' is a standard EXR header attribute and cannot be set",
                                at->name);
        if (at->type == TS_ATTR_STRING && !memchr(at->s, '\0', sizeof at->s))
            return ts_error_set(err, TS_ERR_INVALID, "image attribute '%s' is not a terminated string",
                                at->name);
        if (at->type != TS_ATTR_STRING && at->type != TS_ATTR_INT && at->type != TS_ATTR_DOUBLE)
            return ts_error_set(err, TS_ERR_INVALID, "image attribute '%s' has an unknown type", at->name);
    }
    return TS_OK;
}

/* Points the encoder's (sorted) channels at the interleaved rows of chunk ci. */
static exr_result_t bind_encode_channels(exr_encode_pipeline_t *enc, const ts_image *img, const exr_chunk_info_t *ci)
{
    int n = img->n_channels;
    for (int k = 0; k < enc->channel_count; k++) {
        exr_coding_channel_info_t *ch = &enc->channels[k];
        int c = ts_image_channel(img, ch->channel_name);
        if (c < 0 || ch->width != img->width || ch->height != ci->height) return EXR_ERR_INVALID_ARGUMENT;
        ch->encode_from_ptr = (const uint8_t *)(img->data + ((size_t)ci->start_y * (size_t)img->width) * (size_t)n + (size_t)c);
        ch->user_pixel_stride = (int32_t)(n * (int)sizeof(float));
        ch->user_line_stride = (int32_t)((size_t)img->width * (size_t)n * sizeof(float));
        ch->user_data_type = EXR_PIXEL_FLOAT;
        ch->user_bytes_per_element = (int16_t)sizeof(float);
    }
    return EXR_ERR_SUCCESS;
}

ts_status ts_exr_write_memory(const ts_image *img, unsigned char **buf, size_t *len, ts_error *err)
{
    *buf = NULL;
    *len = 0;
    ts_status st = check_image(img, err);
    if (st) return st;

    const char *what = "cannot encode EXR image";
    exr_io io = {.fd = -1};
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = on_exr_error;
    init.user_data = &io;
    init.write_fn = io_write;

    exr_context_t ctxt = NULL;
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    bool enc_live = false;
    int part = 0;
    exr_result_t rv = exr_start_write(&ctxt, "<memory>", EXR_WRITE_FILE_DIRECTLY, &init);
    if (rv) goto fail_exr;
    rv = exr_add_part(ctxt, NULL, EXR_STORAGE_SCANLINE, &part);
    if (rv) goto fail_exr;
    rv = exr_initialize_required_attr_simple(ctxt, part, img->width, img->height, EXR_COMPRESSION_ZIP);
    if (rv) goto fail_exr;
    for (int c = 0; c < img->n_channels; c++) {
        /* The library keeps its channel list sorted by name, whatever the insertion order. */
        rv = exr_add_channel(ctxt, part, img->channel_names[c], EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1);
        if (rv) goto fail_exr;
    }
    bool long_names = false;
    for (int a = 0; a < img->n_attrs; a++)
        if (strlen(img->attrs[a].name) > 31) long_names = true;
    if (long_names) {
        rv = exr_set_longname_support(ctxt, 1);
        if (rv) goto fail_exr;
    }
    for (int a = 0; a < img->n_attrs; a++) {
        const ts_image_attr *at = &img->attrs[a];
        switch (at->type) {
        case TS_ATTR_STRING: rv = exr_attr_set_string(ctxt, part, at->name, at->s); break;
        case TS_ATTR_INT: rv = exr_attr_set_int(ctxt, part, at->name, at->i); break;
        case TS_ATTR_DOUBLE: rv = exr_attr_set_double(ctxt, part, at->name, at->d); break;
        }
        if (rv) goto fail_exr;
    }
    rv = exr_write_header(ctxt);
    if (rv) goto fail_exr;

    int32_t lines_per_chunk = 0;
    rv = exr_get_scanlines_per_chunk(ctxt, part, &lines_per_chunk);
    if (rv) goto fail_exr;
    if (lines_per_chunk < 1) {
        rv = EXR_ERR_UNKNOWN;
        goto fail_exr;
    }
    for (int y = 0; y < img->height; y += lines_per_chunk) {
        exr_chunk_info_t ci;
        rv = exr_write_scanline_chunk_info(ctxt, part, y, &ci);
        if (rv) goto fail_exr;
        rv = enc_live ? exr_encoding_update(ctxt, part, &ci, &enc) : exr_encoding_initialize(ctxt, part, &ci, &enc);
        if (rv) goto fail_exr;
        enc_live = true;
        rv = bind_encode_channels(&enc, img, &ci);
        if (rv) goto fail_exr;
        rv = exr_encoding_choose_default_routines(ctxt, part, &enc);
        if (rv) goto fail_exr;
        rv = exr_encoding_run(ctxt, part, &enc);
        if (rv) goto fail_exr;
    }
    exr_encoding_destroy(ctxt, &enc);
    enc_live = false;
    rv = exr_finish(&ctxt); /* writes the chunk offset table */
    if (rv) goto fail_exr;
    *buf = io.buf;
    *len = io.len;
    return TS_OK;

fail_exr:
    st = exr_fail(err, &io, rv, what);
    if (enc_live) exr_encoding_destroy(ctxt, &enc);
    if (ctxt) exr_finish(&ctxt);
    free(io.buf);
    return st;
}

ts_status ts_exr_write(const char *path, const ts_image *img, ts_error *err)
{
    unsigned char *buf = NULL;
    size_t len = 0;
    ts_status st = ts_exr_write_memory(img, &buf, &len, err);
    if (st) {
        ts_error_prefix(err, "cannot write EXR file '%s'", path ? path : "");
        return st;
    }
    st = ts_image_write_file_atomic(path, buf, len, err);
    free(buf);
    return st;
}

/* ---- reading ---- */

/* OpenEXR 3.1's fast path for exactly four HALF channels converted to FLOAT into an
 * interleaved buffer (unpack_half_to_float_4chan_interleave, picked when the four output
 * pointers are consecutive floats) writes the channels in reverse order: a file's A,B,G,R
 * came out as R,G,B,A (measured on Debian's 3.1.5; fixed upstream later). Such chunks are
 * decoded into a scratch block whose pixel stride is one float wider than the image's, so
 * the library takes its generic per-channel path, and then copied into place. */
static bool needs_scratch(const exr_decode_pipeline_t *dec)
{
    if (dec->channel_count != 4) return false;
    for (int k = 0; k < dec->channel_count; k++)
        if (dec->channels[k].data_type != EXR_PIXEL_HALF) return false;
    return true;
}

/* Points the decoder's channels at the interleaved block of chunk ci at (col, row), or at
 * scratch (stride n + 1 floats, ci->width pixels a line) when scratch is given. */
static exr_result_t bind_decode_channels(exr_decode_pipeline_t *dec, ts_image *img, const exr_chunk_info_t *ci,
                                         int64_t col, int64_t row, float *scratch)
{
    int n = img->n_channels;
    if (col < 0 || row < 0 || ci->width < 1 || ci->height < 1 || col + ci->width > img->width ||
        row + ci->height > img->height || dec->channel_count != n)
        return EXR_ERR_CORRUPT_CHUNK;
    for (int k = 0; k < dec->channel_count; k++) {
        exr_coding_channel_info_t *ch = &dec->channels[k];
        int c = ts_image_channel(img, ch->channel_name);
        if (c < 0 || ch->width != ci->width || ch->height != ci->height) return EXR_ERR_CORRUPT_CHUNK;
        if (scratch) {
            ch->decode_to_ptr = (uint8_t *)(scratch + c);
            ch->user_pixel_stride = (int32_t)((n + 1) * (int)sizeof(float));
            ch->user_line_stride = (int32_t)((size_t)ci->width * (size_t)(n + 1) * sizeof(float));
        } else {
            ch->decode_to_ptr =
                (uint8_t *)(img->data + ((size_t)row * (size_t)img->width + (size_t)col) * (size_t)n + (size_t)c);
            ch->user_pixel_stride = (int32_t)(n * (int)sizeof(float));
            ch->user_line_stride = (int32_t)((size_t)img->width * (size_t)n * sizeof(float));
        }
        ch->user_data_type = EXR_PIXEL_FLOAT;
        ch->user_bytes_per_element = (int16_t)sizeof(float);
    }
    return EXR_ERR_SUCCESS;
}

/* A grow-only scratch block for needs_scratch chunks, freed by read_pixels. */
typedef struct decode_scratch {
    float *data;
    size_t n_floats;
} decode_scratch;

static exr_result_t decode_chunk(exr_context_t ctxt, exr_decode_pipeline_t *dec, bool *dec_live, const exr_chunk_info_t *ci,
                                 ts_image *img, int64_t col, int64_t row, decode_scratch *scratch)
{
    exr_result_t rv = *dec_live ? exr_decoding_update(ctxt, 0, ci, dec) : exr_decoding_initialize(ctxt, 0, ci, dec);
    if (rv) return rv;
    *dec_live = true;
    float *block = NULL;
    int n = img->n_channels;
    if (needs_scratch(dec)) {
        /* Checked before allocating, so the block is never larger than the image. */
        if (col < 0 || row < 0 || ci->width < 1 || ci->height < 1 || col + ci->width > img->width ||
            row + ci->height > img->height)
            return EXR_ERR_CORRUPT_CHUNK;
        size_t need = (size_t)ci->width * (size_t)ci->height * (size_t)(n + 1);
        if (need > scratch->n_floats) {
            float *p = realloc(scratch->data, need * sizeof(float));
            if (!p) return EXR_ERR_OUT_OF_MEMORY;
            scratch->data = p;
            scratch->n_floats = need;
        }
        block = scratch->data;
    }
    rv = bind_decode_channels(dec, img, ci, col, row, block);
    if (rv) return rv;
    rv = exr_decoding_choose_default_routines(ctxt, 0, dec);
    if (rv) return rv;
    rv = exr_decoding_run(ctxt, 0, dec);
    if (rv || !block) return rv;
    for (int64_t y = 0; y < ci->height; y++)
        for (int64_t x = 0; x < ci->width; x++)
            memcpy(img->data + ((size_t)(row + y) * (size_t)img->width + (size_t)(col + x)) * (size_t)n,
                   block + ((size_t)y * (size_t)ci->width + (size_t)x) * (size_t)(n + 1), (size_t)n * sizeof(float));
    return EXR_ERR_SUCCESS;
}

/* Copies the non-standard string/int/double/float attributes of part 0 into img. */
static exr_result_t copy_attrs(exr_context_t ctxt, ts_image *img)
{
    int32_t count = 0;
    exr_result_t rv = exr_get_attribute_count(ctxt, 0, &count);
    if (rv) return rv;
    for (int32_t k = 0; k < count && img->n_attrs < TS_IMAGE_MAX_ATTRS; k++) {
        const exr_attribute_t *a = NULL;
        rv = exr_get_attribute_by_index(ctxt, 0, EXR_ATTR_LIST_FILE_ORDER, k, &a);
        if (rv) return rv;
        if (!a || !a->name || is_reserved_attr(a->name) || strlen(a->name) >= sizeof img->attrs[0].name) continue;
        switch (a->type) {
        case EXR_ATTR_STRING: {
            const exr_attr_string_t *s = a->string;
            if (!s || s->length < 0 || (size_t)s->length >= sizeof img->attrs[0].s || (s->length && !s->str)) break;
            char value[sizeof img->attrs[0].s];
            if (s->length) memcpy(value, s->str, (size_t)s->length);
            value[s->length] = '\0';
            ts_image_set_string(img, a->name, value, NULL);
            break;
        }
        case EXR_ATTR_INT: ts_image_set_int(img, a->name, a->i, NULL); break;
        case EXR_ATTR_DOUBLE: ts_image_set_double(img, a->name, a->d, NULL); break;
        case EXR_ATTR_FLOAT: ts_image_set_double(img, a->name, (double)a->f, NULL); break;
        default: break;
        }
    }
    return EXR_ERR_SUCCESS;
}

static ts_status read_pixels(exr_context_t ctxt, exr_storage_t storage, const exr_attr_box2i_t *dw, ts_image *img,
                             exr_io *io, const char *what, ts_error *err)
{
    exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
    bool dec_live = false;
    decode_scratch scratch = {0};
    exr_result_t rv = EXR_ERR_SUCCESS;
    if (storage == EXR_STORAGE_SCANLINE) {
        int32_t lines_per_chunk = 0;
        rv = exr_get_scanlines_per_chunk(ctxt, 0, &lines_per_chunk);
        if (!rv && lines_per_chunk < 1) rv = EXR_ERR_INVALID_ATTR;
        for (int64_t y = dw->min.y; !rv && y <= dw->max.y; y += lines_per_chunk) {
            exr_chunk_info_t ci;
            rv = exr_read_scanline_chunk_info(ctxt, 0, (int)y, &ci);
            if (!rv) rv = decode_chunk(ctxt, &dec, &dec_live, &ci, img, (int64_t)ci.start_x - dw->min.x,
                                       (int64_t)ci.start_y - dw->min.y, &scratch);
        }
    } else {
        int32_t tile_w = 0, tile_h = 0;
        rv = exr_get_tile_sizes(ctxt, 0, 0, 0, &tile_w, &tile_h);
        if (!rv && (tile_w < 1 || tile_h < 1)) rv = EXR_ERR_INVALID_ATTR;
        int64_t tiles_x = rv ? 0 : (img->width + (int64_t)tile_w - 1) / tile_w;
        int64_t tiles_y = rv ? 0 : (img->height + (int64_t)tile_h - 1) / tile_h;
        for (int64_t ty = 0; !rv && ty < tiles_y; ty++)
            for (int64_t tx = 0; !rv && tx < tiles_x; tx++) {
                exr_chunk_info_t ci;
                rv = exr_read_tile_chunk_info(ctxt, 0, (int)tx, (int)ty, 0, 0, &ci);
                if (!rv) rv = decode_chunk(ctxt, &dec, &dec_live, &ci, img, tx * tile_w, ty * tile_h, &scratch);
            }
    }
    if (dec_live) exr_decoding_destroy(ctxt, &dec);
    free(scratch.data);
    return rv ? exr_fail(err, io, rv, what) : TS_OK;
}

static ts_status read_any(exr_io *io, const char *what, ts_image *out, ts_error *err)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = on_exr_error;
    init.user_data = io;
    init.read_fn = io_read;
    init.size_fn = io_size;
    init.flags = EXR_CONTEXT_FLAG_DISABLE_CHUNK_RECONSTRUCTION;

    ts_status st;
    unsigned char magic[4];
    if (io_read(NULL, io, magic, sizeof magic, 0, NULL) != (int64_t)sizeof magic ||
        memcmp(magic, "\x76\x2f\x31\x01", sizeof magic) != 0) {
        if (io->io_errno) return ts_error_set(err, TS_ERR_IO, "%s: %s", what, strerror(io->io_errno));
        return ts_error_set(err, TS_ERR_INVALID, "%s: not an OpenEXR file (no EXR magic number)", what);
    }
    exr_context_t ctxt = NULL;
    exr_result_t rv = exr_start_read(&ctxt, "<exr>", &init);
    if (rv) goto fail_exr;

    int parts = 0;
    rv = exr_get_count(ctxt, &parts);
    if (rv) goto fail_exr;
    if (parts != 1) {
        st = ts_error_set(err, TS_ERR_UNSUPPORTED, "%s: it has %d parts; only single-part files are supported", what, parts);
        goto fail_ctxt;
    }
    exr_storage_t storage;
    rv = exr_get_storage(ctxt, 0, &storage);
    if (rv) goto fail_exr;
    if (storage != EXR_STORAGE_SCANLINE && storage != EXR_STORAGE_TILED) {
        st = ts_error_set(err, TS_ERR_UNSUPPORTED, "%s: deep images are not supported", what);
        goto fail_ctxt;
    }
    exr_attr_box2i_t dw;
    rv = exr_get_data_window(ctxt, 0, &dw);
    if (rv) goto fail_exr;
    int64_t width = (int64_t)dw.max.x - dw.min.x + 1, height = (int64_t)dw.max.y - dw.min.y + 1;
    if (width < 1 || height < 1 || width > INT32_MAX || height > INT32_MAX) {
        st = ts_error_set(err, TS_ERR_INVALID, "%s: the data window (%d,%d)-(%d,%d) is empty", what, dw.min.x,
                          dw.min.y, dw.max.x, dw.max.y);
        goto fail_ctxt;
    }
    const exr_attr_chlist_t *chlist = NULL;
    rv = exr_get_channels(ctxt, 0, &chlist);
    if (rv) goto fail_exr;
    if (!chlist || chlist->num_channels < 1 || chlist->num_channels > TS_IMAGE_MAX_CHANNELS) {
        st = ts_error_set(err, chlist && chlist->num_channels > 0 ? TS_ERR_LIMIT : TS_ERR_INVALID,
                          "%s: it has %d channels; 1 to %d are supported", what, chlist ? chlist->num_channels : 0,
                          TS_IMAGE_MAX_CHANNELS);
        goto fail_ctxt;
    }
    const char *names[TS_IMAGE_MAX_CHANNELS];
    for (int c = 0; c < chlist->num_channels; c++) {
        const exr_attr_chlist_entry_t *e = &chlist->entries[c];
        if (e->x_sampling != 1 || e->y_sampling != 1) {
            st = ts_error_set(err, TS_ERR_UNSUPPORTED, "%s: channel '%s' is subsampled (%d,%d); not supported", what,
                              e->name.str, e->x_sampling, e->y_sampling);
            goto fail_ctxt;
        }
        if (e->pixel_type != EXR_PIXEL_UINT && e->pixel_type != EXR_PIXEL_HALF && e->pixel_type != EXR_PIXEL_FLOAT) {
            st = ts_error_set(err, TS_ERR_INVALID, "%s: channel '%s' has unknown pixel type %d", what, e->name.str,
                              (int)e->pixel_type);
            goto fail_ctxt;
        }
        names[c] = e->name.str;
    }
    if (!row_fits_stride(width, chlist->num_channels)) {
        st = ts_error_set(err, TS_ERR_LIMIT, "%s: a row of %lld pixels x %d channels is too long", what,
                          (long long)width, chlist->num_channels);
        goto fail_ctxt;
    }
    /* The data window is a header field: a file of a few hundred bytes can claim 2³⁰
     * pixels. Refuse an image whose float pixels would take more than EXR_MAX_EXPANSION
     * times the file's size before allocating them (see the constant). */
    int64_t file_bytes = io->fd < 0 ? (int64_t)io->src_len : io->file_size;
    double pixel_bytes = (double)width * (double)height * chlist->num_channels * sizeof(float);
    if (pixel_bytes > EXR_SMALL_IMAGE_BYTES && pixel_bytes > (double)EXR_MAX_EXPANSION * (double)file_bytes) {
        st = ts_error_set(err, TS_ERR_LIMIT,
                          "%s: a %lld x %lld image of %d channels (%.0f MB of pixels) cannot come from %lld bytes "
                          "(refused as a decompression bomb)",
                          what, (long long)width, (long long)height, chlist->num_channels, pixel_bytes / 1e6,
                          (long long)file_bytes);
        goto fail_ctxt;
    }
    st = ts_image_init(out, (int)width, (int)height, chlist->num_channels, names, err);
    if (st) {
        ts_error_prefix(err, "%s", what);
        goto fail_ctxt;
    }
    rv = copy_attrs(ctxt, out);
    if (rv) goto fail_exr;
    st = read_pixels(ctxt, storage, &dw, out, io, what, err);
    if (st) goto fail_ctxt;
    exr_finish(&ctxt);
    return TS_OK;

fail_exr:
    st = exr_fail(err, io, rv, what);
fail_ctxt:
    if (ctxt) exr_finish(&ctxt);
    ts_image_fini(out);
    return st;
}

bool ts_exr_size_memory(const unsigned char *buf, size_t len, int64_t *width, int64_t *height, int *channels)
{
    *width = *height = 0;
    *channels = 0;
    if (!buf || len < 4 || memcmp(buf, "\x76\x2f\x31\x01", 4) != 0) return false;
    exr_io io = {.src = buf, .src_len = len, .fd = -1};
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = on_exr_error;
    init.user_data = &io;
    init.read_fn = io_read;
    init.size_fn = io_size;
    init.flags = EXR_CONTEXT_FLAG_DISABLE_CHUNK_RECONSTRUCTION;
    exr_context_t ctxt = NULL;
    exr_attr_box2i_t dw;
    const exr_attr_chlist_t *chlist = NULL;
    int parts = 0;
    bool ok = exr_start_read(&ctxt, "<exr>", &init) == EXR_ERR_SUCCESS && exr_get_count(ctxt, &parts) == EXR_ERR_SUCCESS &&
              parts >= 1 && exr_get_data_window(ctxt, 0, &dw) == EXR_ERR_SUCCESS &&
              exr_get_channels(ctxt, 0, &chlist) == EXR_ERR_SUCCESS && chlist;
    if (ok) {
        *width = (int64_t)dw.max.x - dw.min.x + 1;
        *height = (int64_t)dw.max.y - dw.min.y + 1;
        *channels = chlist->num_channels;
        ok = *width > 0 && *height > 0;
    }
    if (ctxt) exr_finish(&ctxt);
    return ok;
}

ts_status ts_exr_read_memory(const unsigned char *buf, size_t len, ts_image *out, ts_error *err)
{
    memset(out, 0, sizeof *out);
    char what[96];
    snprintf(what, sizeof what, "cannot read EXR data (%zu bytes)", len);
    if (!buf && len) return ts_error_set(err, TS_ERR_INVALID, "%s: no buffer", what);
    exr_io io = {.src = buf, .src_len = len, .fd = -1};
    return read_any(&io, what, out, err);
}

ts_status ts_exr_read(const char *path, ts_image *out, ts_error *err)
{
    memset(out, 0, sizeof *out);
    if (!path) return ts_error_set(err, TS_ERR_INVALID, "cannot read EXR file: no file name given");
    size_t n = strlen(path) + 40;
    char *what = malloc(n);
    if (!what) return ts_error_set(err, TS_ERR_NOMEM, "cannot read EXR file '%s': out of memory", path);
    snprintf(what, n, "cannot read EXR file '%s'", path);

    ts_status st;
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0) {
        st = ts_error_set(err, TS_ERR_IO, "%s: %s", what, strerror(errno));
        goto fail_open;
    }
    struct stat sb;
    if (fstat(fd, &sb) != 0) {
        st = ts_error_set(err, TS_ERR_IO, "%s: %s", what, strerror(errno));
        goto fail_stat;
    }
    if (!S_ISREG(sb.st_mode)) {
        st = ts_error_set(err, TS_ERR_IO, "%s: not a regular file", what);
        goto fail_stat;
    }
    exr_io io = {.fd = fd, .file_size = (int64_t)sb.st_size};
    st = read_any(&io, what, out, err);
fail_stat:
    close(fd);
fail_open:
    free(what);
    return st;
}
