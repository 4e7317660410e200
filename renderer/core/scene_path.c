/* scene_path.c — confinement and reading of scene files; see scene_path.h.
 *
 * The one place that decides whether a scene may read a file: the mesh loader, the
 * Fourier BSDF reader and the environment-map loader all come through
 * ts_scene_path_read, so a fix here covers every kind of file. */
#ifndef _XOPEN_SOURCE
#define _XOPEN_SOURCE 700 /* realpath, O_CLOEXEC, O_NOFOLLOW */
#endif

#include "core/scene_path.h"

#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static const char *errno_text(int e)
{
    switch (e) { /* strerror is not guaranteed thread-safe; these are the ones users meet */
    case ENOENT:
        return "no such file or directory";
    case EACCES:
        return "permission denied";
    case ENOTDIR:
        return "a component of the path is not a folder";
    case ELOOP:
        return "too many levels of symbolic links";
    case ENAMETOOLONG:
        return "path too long";
    case EISDIR:
        return "is a folder";
    case EIO:
        return "input/output error";
    case ENOMEM:
        return "out of memory";
    default:
        return "system error";
    }
}

/* "<what> '<rel>': <sentence>" (what may be NULL). */
static ts_status fail(ts_error *err, ts_status st, const char *what, const char *rel, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));
static ts_status fail(ts_error *err, ts_status st, const char *what, const char *rel, const char *fmt, ...)
{
    char msg[TS_ERROR_MAX];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return ts_error_set(err, st, "%s%s'%s': %s", what ? what : "", what ? " " : "", rel, msg);
}

/* p is base or below it (both canonical). */
static bool path_inside(const char *p, const char *base)
{
    size_t n = strlen(base);
    if (n == 1 && base[0] == '/') return true;
    return strncmp(p, base, n) == 0 && (p[n] == '/' || p[n] == '\0');
}

/* The lexical part of confinement: not empty, relative, and no `..` above the folder
 * (caught here even when the target does not exist). */
static ts_status check_lexical(const char *what, const char *rel, ts_error *err)
{
    if (!*rel) return fail(err, TS_ERR_INVALID, what, rel, "empty path");
    if (rel[0] == '/') return fail(err, TS_ERR_INVALID, what, rel, "absolute paths are not allowed");
    long depth = 0;
    for (const char *s = rel; *s;) {
        while (*s == '/')
            s++;
        const char *e = s;
        while (*e && *e != '/')
            e++;
        size_t n = (size_t)(e - s);
        if (n == 2 && s[0] == '.' && s[1] == '.') {
            if (--depth < 0) return fail(err, TS_ERR_INVALID, what, rel, "path leaves the scene's folder");
        } else if (n > 0 && !(n == 1 && s[0] == '.')) {
            depth++;
        }
        s = e;
    }
    return TS_OK;
}

/* Resolves base_dir/rel into *real (malloc-owned), confined to realpath(base_dir). */
static ts_status resolve(const char *base_dir, const char *rel, const char *what, char **real, ts_error *err)
{
    *real = NULL;
    if (!rel) rel = "";
    if (!base_dir)
        return fail(err, TS_ERR_INVALID, what, rel,
                    "this scene may not refer to files (no asset folder is configured)");
    ts_status st = check_lexical(what, rel, err);
    if (st) return st;
    char *base = realpath(base_dir, NULL);
    if (!base) {
        int e = errno;
        /* The folder's own path is not named: on a server it is the operator's business. */
        return fail(err, e == ENOMEM ? TS_ERR_NOMEM : TS_ERR_IO, what, rel,
                    "the scene's folder cannot be opened (%s)", errno_text(e));
    }
    size_t nb = strlen(base), nr = strlen(rel);
    char *joined = malloc(nb + nr + 2);
    if (!joined) {
        st = fail(err, TS_ERR_NOMEM, what, rel, "out of memory");
        goto fail_base;
    }
    memcpy(joined, base, nb);
    joined[nb] = '/';
    memcpy(joined + nb + 1, rel, nr + 1);
    *real = realpath(joined, NULL);
    if (!*real) {
        int e = errno;
        if (e == ENOMEM) {
            st = fail(err, TS_ERR_NOMEM, what, rel, "out of memory");
            goto fail_joined;
        }
        /* Say "leaves the folder" rather than "missing" when the part that does exist
         * already resolves outside. */
        for (size_t cut = nb + 1 + nr; cut > nb;) {
            while (cut > nb && joined[cut - 1] != '/')
                cut--;
            if (cut <= nb) break;
            joined[--cut] = '\0';
            char *prefix = realpath(joined, NULL);
            if (prefix) {
                bool inside = path_inside(prefix, base);
                free(prefix);
                if (!inside) {
                    st = fail(err, TS_ERR_INVALID, what, rel, "path leaves the scene's folder");
                    goto fail_joined;
                }
                break;
            }
        }
        st = fail(err, e == ENAMETOOLONG ? TS_ERR_INVALID : TS_ERR_IO, what, rel, "cannot open (%s)",
                  errno_text(e));
        goto fail_joined;
    }
    if (!path_inside(*real, base)) {
        st = fail(err, TS_ERR_INVALID, what, rel, "path leaves the scene's folder");
        free(*real);
        *real = NULL;
    }
fail_joined:
    free(joined);
fail_base:
    free(base);
    return st;
}

ts_status ts_scene_path_resolve(const char *base_dir, const char *rel, char *out, size_t out_len,
                                ts_error *err)
{
    char *real;
    ts_status st = resolve(base_dir, rel, NULL, &real, err);
    if (st) return st;
    size_t n = strlen(real) + 1;
    if (n > out_len)
        st = fail(err, TS_ERR_INVALID, NULL, rel, "path too long");
    else
        memcpy(out, real, n);
    free(real);
    return st;
}

/* Reads the open file fd (name: for messages) whole; closes fd. */
static ts_status read_fd(int fd, const char *what, const char *name, uint64_t max_bytes, bool refuse_empty,
                         char **out, size_t *len, ts_error *err)
{
    ts_status st = TS_OK;
    struct stat sb;
    if (fstat(fd, &sb) != 0) {
        st = fail(err, TS_ERR_IO, what, name, "cannot read (%s)", errno_text(errno));
        goto fail_fd;
    }
    if (!S_ISREG(sb.st_mode)) {
        st = fail(err, TS_ERR_INVALID, what, name, "not a regular file");
        goto fail_fd;
    }
    if (refuse_empty && sb.st_size <= 0) {
        st = fail(err, TS_ERR_INVALID, what, name, "file is empty");
        goto fail_fd;
    }
    uint64_t want = sb.st_size > 0 ? (uint64_t)sb.st_size : 0;
    if ((max_bytes && want > max_bytes) || want >= SIZE_MAX) {
        st = fail(err, TS_ERR_LIMIT, what, name, "file is %llu bytes, more than the limit of %llu",
                  (unsigned long long)want, (unsigned long long)(max_bytes ? max_bytes : SIZE_MAX - 1));
        goto fail_fd;
    }
    char *b = malloc((size_t)want + 1);
    if (!b) {
        st =
            fail(err, TS_ERR_NOMEM, what, name, "out of memory reading %llu bytes", (unsigned long long)want);
        goto fail_fd;
    }
    size_t got = 0;
    while (got < want) {
        ssize_t r = read(fd, b + got, (size_t)want - got);
        if (r < 0) {
            if (errno == EINTR) continue;
            st = fail(err, TS_ERR_IO, what, name, "cannot read (%s)", errno_text(errno));
            free(b);
            goto fail_fd;
        }
        if (r == 0) break; /* shrank since fstat: take what is there */
        got += (size_t)r;
    }
    if (refuse_empty && got == 0) {
        st = fail(err, TS_ERR_INVALID, what, name, "file is empty");
        free(b);
        goto fail_fd;
    }
    b[got] = '\0';
    *out = b;
    *len = got;
fail_fd:
    close(fd);
    return st;
}

ts_status ts_scene_path_read(const char *base_dir, const char *rel, const char *what, uint64_t max_bytes,
                             char **out, size_t *len, ts_error *err)
{
    *out = NULL;
    *len = 0;
    char *real;
    ts_status st = resolve(base_dir, rel, what, &real, err);
    if (st) return st;
    /* O_NOFOLLOW: the resolved path has no symlink left to follow; O_NONBLOCK: opening a
     * FIFO must not hang (it is refused as not regular). */
    int fd = open(real, O_RDONLY | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK);
    free(real);
    if (fd < 0) return fail(err, TS_ERR_IO, what, rel, "cannot open (%s)", errno_text(errno));
    return read_fd(fd, what, rel, max_bytes, true, out, len, err);
}

ts_status ts_scene_path_read_file(const char *path, uint64_t max_bytes, char **out, size_t *len,
                                  ts_error *err)
{
    *out = NULL;
    *len = 0;
    int fd = open(path, O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    if (fd < 0) return fail(err, TS_ERR_IO, NULL, path, "cannot open (%s)", errno_text(errno));
    return read_fd(fd, NULL, path, max_bytes, false, out, len, err);
}

void ts_scene_path_split(const char *path, char *dir, size_t dir_len, char *stem, size_t stem_len)
{
    const char *slash = strrchr(path, '/');
    if (slash)
        snprintf(dir, dir_len, "%.*s", (int)(slash - path == 0 ? 1 : slash - path), path);
    else
        snprintf(dir, dir_len, ".");
    const char *base = slash ? slash + 1 : path;
    const char *dot = strrchr(base, '.');
    int n = dot && dot != base ? (int)(dot - base) : (int)strlen(base);
    snprintf(stem, stem_len, "%.*s", n, base);
}
