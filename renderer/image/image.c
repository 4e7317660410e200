/* image.c — float image container and atomic file output; see image.h. */
#include "image/image.h"

#include <errno.h>
#include <fcntl.h>
#include <libgen.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

ts_status ts_image_init(ts_image *img, int width, int height, int n_channels,
                        const char *const *names, ts_error *err)
{
    memset(img, 0, sizeof *img);
    if (width < 1 || height < 1)
        return ts_error_set(err, TS_ERR_INVALID, "image size %dx%d is not positive", width, height);
    if ((int64_t)width * height > TS_IMAGE_MAX_PIXELS)
        return ts_error_set(err, TS_ERR_LIMIT, "image size %dx%d exceeds the limit of %lld pixels",
                            width, height, (long long)TS_IMAGE_MAX_PIXELS);
    if (n_channels < 1 || n_channels > TS_IMAGE_MAX_CHANNELS)
        return ts_error_set(err, TS_ERR_LIMIT, "an image has 1 to %d channels, not %d",
                            TS_IMAGE_MAX_CHANNELS, n_channels);
    if (!names) return ts_error_set(err, TS_ERR_INVALID, "image channel names are missing");
    for (int c = 0; c < n_channels; c++) {
        const char *name = names[c];
        if (!name || !name[0])
            return ts_error_set(err, TS_ERR_INVALID, "image channel %d has no name", c);
        if (strlen(name) >= sizeof img->channel_names[0])
            return ts_error_set(err, TS_ERR_LIMIT, "image channel name '%.40s…' is longer than %zu bytes",
                                name, sizeof img->channel_names[0] - 1);
        for (int k = 0; k < c; k++)
            if (strcmp(names[k], name) == 0)
                return ts_error_set(err, TS_ERR_INVALID, "image channel name '%s' appears twice", name);
    }
    /* ≤ 2^28 pixels × 16 channels × 4 bytes: fits size_t on every 64-bit target. */
    size_t count = (size_t)width * (size_t)height * (size_t)n_channels;
    float *data = calloc(count, sizeof *data);
    if (!data)
        return ts_error_set(err, TS_ERR_NOMEM, "out of memory for a %dx%d image of %d channels",
                            width, height, n_channels);
    img->width = width;
    img->height = height;
    img->n_channels = n_channels;
    for (int c = 0; c < n_channels; c++) strcpy(img->channel_names[c], names[c]);
    img->data = data;
    return TS_OK;
}

void ts_image_fini(ts_image *img)
{
    if (!img) return;
    free(img->data);
    memset(img, 0, sizeof *img);
}

/* The slot for name: the existing attribute of that name, else a new one at the end. */
static ts_status attr_slot(ts_image *img, const char *name, ts_image_attr **out, ts_error *err)
{
    if (!name || !name[0]) return ts_error_set(err, TS_ERR_INVALID, "an image attribute needs a name");
    size_t n = strlen(name);
    if (n >= sizeof img->attrs[0].name)
        return ts_error_set(err, TS_ERR_LIMIT, "image attribute name '%.40s…' is longer than %zu bytes",
                            name, sizeof img->attrs[0].name - 1);
    for (int k = 0; k < img->n_attrs; k++)
        if (strcmp(img->attrs[k].name, name) == 0) {
            *out = &img->attrs[k];
            return TS_OK;
        }
    if (img->n_attrs >= TS_IMAGE_MAX_ATTRS)
        return ts_error_set(err, TS_ERR_LIMIT, "cannot add image attribute '%s': already %d attributes",
                            name, TS_IMAGE_MAX_ATTRS);
    ts_image_attr *a = &img->attrs[img->n_attrs++];
    memset(a, 0, sizeof *a);
    memcpy(a->name, name, n + 1);
    *out = a;
    return TS_OK;
}

ts_status ts_image_set_string(ts_image *img, const char *name, const char *value, ts_error *err)
{
    if (!value) value = "";
    size_t n = strlen(value);
    if (n >= sizeof img->attrs[0].s)
        return ts_error_set(err, TS_ERR_LIMIT, "image attribute '%s': string of %zu bytes is longer than %zu",
                            name ? name : "", n, sizeof img->attrs[0].s - 1);
    ts_image_attr *a;
    ts_status st = attr_slot(img, name, &a, err);
    if (st) return st;
    a->type = TS_ATTR_STRING;
    memcpy(a->s, value, n + 1);
    a->i = 0;
    a->d = 0;
    return TS_OK;
}

ts_status ts_image_set_int(ts_image *img, const char *name, int32_t value, ts_error *err)
{
    ts_image_attr *a;
    ts_status st = attr_slot(img, name, &a, err);
    if (st) return st;
    a->type = TS_ATTR_INT;
    a->s[0] = '\0';
    a->i = value;
    a->d = 0;
    return TS_OK;
}

ts_status ts_image_set_double(ts_image *img, const char *name, double value, ts_error *err)
{
    ts_image_attr *a;
    ts_status st = attr_slot(img, name, &a, err);
    if (st) return st;
    a->type = TS_ATTR_DOUBLE;
    a->s[0] = '\0';
    a->i = 0;
    a->d = value;
    return TS_OK;
}

const ts_image_attr *ts_image_attr_find(const ts_image *img, const char *name)
{
    if (!img || !name) return NULL;
    for (int k = 0; k < img->n_attrs; k++)
        if (strcmp(img->attrs[k].name, name) == 0) return &img->attrs[k];
    return NULL;
}

int ts_image_channel(const ts_image *img, const char *name)
{
    if (!img || !name) return -1;
    for (int c = 0; c < img->n_channels; c++)
        if (strcmp(img->channel_names[c], name) == 0) return c;
    return -1;
}

/* fsync the directory holding path so the rename itself survives a crash (best effort:
 * some file systems refuse fsync on directories). */
static void sync_parent_dir(const char *path)
{
    char *copy = strdup(path);
    if (!copy) return;
    int fd = open(dirname(copy), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd >= 0) {
        (void)fsync(fd);
        close(fd);
    }
    free(copy);
}

ts_status ts_image_write_file_atomic(const char *path, const void *bytes, size_t len, ts_error *err)
{
    if (!path || !path[0]) return ts_error_set(err, TS_ERR_INVALID, "no output file name given");
    /* The temporary name is unique per process and per call, so two threads writing the
     * same file (a server's submission and its checkpointer) never share one. Messages do
     * not name it, so the same failure reads the same every time (callers log a failure
     * when its sentence changes). */
    static atomic_uint serial;
    size_t n = strlen(path) + 48;
    char *tmp = malloc(n);
    if (!tmp) return ts_error_set(err, TS_ERR_NOMEM, "out of memory writing '%s'", path);
    snprintf(tmp, n, "%s.tmp.%ld.%u", path, (long)getpid(), atomic_fetch_add(&serial, 1u));

    ts_status st = TS_OK;
    int fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    if (fd < 0) {
        st = ts_error_set(err, TS_ERR_IO, "cannot write '%s': cannot create a temporary file beside it: %s",
                          path, strerror(errno));
        goto fail_open;
    }
    const unsigned char *p = bytes;
    size_t left = len;
    while (left > 0) {
        ssize_t w = write(fd, p, left);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) {
            st = ts_error_set(err, TS_ERR_IO, "cannot write '%s': writing its temporary file failed: %s", path,
                              w < 0 ? strerror(errno) : "no progress");
            goto fail_written;
        }
        p += w;
        left -= (size_t)w;
    }
    if (fsync(fd) != 0) {
        st = ts_error_set(err, TS_ERR_IO, "cannot write '%s': fsync of its temporary file failed: %s", path,
                          strerror(errno));
        goto fail_written;
    }
    if (close(fd) != 0) {
        fd = -1;
        st = ts_error_set(err, TS_ERR_IO, "cannot write '%s': closing its temporary file failed: %s", path,
                          strerror(errno));
        goto fail_written;
    }
    fd = -1;
    if (rename(tmp, path) != 0) {
        st = ts_error_set(err, TS_ERR_IO, "cannot write '%s': renaming its temporary file onto it failed: %s",
                          path, strerror(errno));
        goto fail_written;
    }
    sync_parent_dir(path);
    free(tmp);
    return TS_OK;

fail_written:
    if (fd >= 0) close(fd);
    unlink(tmp);
fail_open:
    free(tmp);
    return st;
}
