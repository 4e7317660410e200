/* outputs.c — the -o files of `tessera render` and `tessera merge`; see outputs.h. */
#include "outputs.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "tessera.h"

static const char *extension(const char *path)
{
    const char *dot = strrchr(path, '.');
    const char *slash = strrchr(path, '/');
    return dot && (!slash || dot > slash) ? dot + 1 : "";
}

bool cli_outputs_add(cli_outputs *o, const char *path)
{
    if (o->n == CLI_MAX_OUTPUTS) return false;
    o->tmp[o->n] = NULL;
    o->path[o->n++] = path;
    return true;
}

bool cli_output_is_exr(const char *path) { return strcasecmp(extension(path), "exr") == 0; }

const char *cli_outputs_unsupported(const cli_outputs *o)
{
    for (int i = 0; i < o->n; i++)
        if (!cli_output_is_exr(o->path[i]) && strcasecmp(extension(o->path[i]), "png") != 0) return o->path[i];
    return NULL;
}

/* The folder part of path ("." when it has none), for the sentence of a failure. */
static void folder_of(const char *path, char *out, size_t len)
{
    const char *slash = strrchr(path, '/');
    if (!slash) snprintf(out, len, ".");
    else if (slash == path) snprintf(out, len, "/");
    else snprintf(out, len, "%.*s", (int)(slash - path), path);
}

ts_status cli_outputs_open(cli_outputs *o, ts_error *err)
{
    for (int i = 0; i < o->n; i++) {
        const char *path = o->path[i];
        char folder[4096];
        folder_of(path, folder, sizeof folder);
        struct stat sb;
        if (stat(path, &sb) == 0 && S_ISDIR(sb.st_mode)) {
            cli_outputs_discard(o);
            return ts_error_set(err, TS_ERR_IO, "-o %s: is a folder; name the image file to write", path);
        }
        size_t n = strlen(path) + 48;
        if (!(o->tmp[i] = malloc(n))) {
            cli_outputs_discard(o);
            return ts_error_set(err, TS_ERR_NOMEM, "out of memory");
        }
        snprintf(o->tmp[i], n, "%s.tmp-tessera-%ld-%d", path, (long)getpid(), i);
        int fd = open(o->tmp[i], O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd < 0) {
            int e = errno;
            free(o->tmp[i]);
            o->tmp[i] = NULL;
            cli_outputs_discard(o);
            if (e == ENOENT || e == ENOTDIR)
                return ts_error_set(err, TS_ERR_IO, "-o %s: the folder %s does not exist", path,
                                    folder);
            return ts_error_set(err, TS_ERR_IO, "-o %s: cannot create a file in %s (%s)", path,
                                folder, strerror(e));
        }
        close(fd);
    }
    return TS_OK;
}

/* A failed write names the output, not its temporary. */
static ts_status write_failed(const cli_outputs *o, int i, ts_error *err)
{
    char msg[sizeof err->message];
    snprintf(msg, sizeof msg, "%s", err->message);
    char *at = strstr(msg, o->tmp[i]);
    if (at) { /* "cannot write EXR file 'x.exr.tmp-…'": the output's own name */
        size_t k = strlen(o->tmp[i]);
        char fixed[sizeof msg];
        snprintf(fixed, sizeof fixed, "%.*s%s%s", (int)(at - msg), msg, o->path[i], at + k);
        snprintf(msg, sizeof msg, "%s", fixed);
    }
    return ts_error_set(err, err->status ? err->status : TS_ERR_IO, "%s; no output was written", msg);
}

ts_status cli_outputs_write_image(const cli_outputs *o, const ts_image *img, ts_error *err)
{
    for (int i = 0; i < o->n; i++) {
        ts_status st = cli_output_is_exr(o->path[i]) ? ts_exr_write(o->tmp[i], img, err)
                                                     : ts_png_write(o->tmp[i], img, 0.0f, err);
        if (st) return write_failed(o, i, err);
    }
    return TS_OK;
}

ts_status cli_outputs_write_shard(const cli_outputs *o, const ts_film *film, const ts_shard_info *info, ts_error *err)
{
    for (int i = 0; i < o->n; i++) {
        ts_status st;
        if (cli_output_is_exr(o->path[i])) {
            st = ts_shard_write(o->tmp[i], film, info, err);
        } else {
            ts_image img;
            st = ts_film_to_image(film, TS_FILM_IMAGE_RGB, &img, err);
            if (!st) st = ts_png_write(o->tmp[i], &img, 0.0f, err);
            ts_image_fini(&img);
        }
        if (st) return write_failed(o, i, err);
    }
    return TS_OK;
}

ts_status cli_outputs_commit(cli_outputs *o, ts_error *err)
{
    for (int i = 0; i < o->n; i++) {
        if (rename(o->tmp[i], o->path[i]) != 0) {
            int e = errno;
            cli_outputs_discard(o);
            return ts_error_set(err, TS_ERR_IO, "-o %s: cannot put the file in place: %s", o->path[i], strerror(e));
        }
        free(o->tmp[i]);
        o->tmp[i] = NULL;
    }
    return TS_OK;
}

void cli_outputs_discard(cli_outputs *o)
{
    for (int i = 0; i < o->n; i++) {
        if (o->tmp[i]) unlink(o->tmp[i]);
        free(o->tmp[i]);
        o->tmp[i] = NULL;
    }
}
