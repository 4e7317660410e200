/* scene_path.c — confinement and reading of scene files; see scene_path.h. */
#include "scene_path.h"

#include <errno.h>
#include <stdbool.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

ts_status ts_scene_path_resolve(const char *base_dir, const char *rel, char *out, size_t out_len, ts_error *err)
{
    if (!base_dir) return ts_error_set(err, TS_ERR_INVALID, "'%s': this scene may not refer to files", rel);
    if (rel[0] == '/') return ts_error_set(err, TS_ERR_INVALID, "'%s': absolute paths are not allowed", rel);
    char base[PATH_MAX], joined[PATH_MAX * 2], real[PATH_MAX];
    if (!realpath(base_dir, base))
        return ts_error_set(err, TS_ERR_IO, "'%s': the scene's folder cannot be resolved (%s)", rel, strerror(errno));
    snprintf(joined, sizeof joined, "%s/%s", base, rel);
    if (!realpath(joined, real)) {
        if (errno == ENOENT) return ts_error_set(err, TS_ERR_IO, "'%s': no such file", rel);
        return ts_error_set(err, TS_ERR_IO, "'%s': %s", rel, strerror(errno));
    }
    size_t n = strlen(base);
    bool inside = strncmp(real, base, n) == 0 && (real[n] == '/' || (n == 1 && base[0] == '/'));
    if (!inside) return ts_error_set(err, TS_ERR_INVALID, "'%s': path leaves the scene's folder", rel);
    if (strlen(real) + 1 > out_len) return ts_error_set(err, TS_ERR_INVALID, "'%s': path too long", rel);
    memcpy(out, real, strlen(real) + 1);
    return TS_OK;
}

ts_status ts_scene_path_read_file(const char *path, uint64_t max_bytes, char **out, size_t *len, ts_error *err)
{
    *out = NULL;
    *len = 0;
    FILE *f = fopen(path, "rb");
    if (!f) return ts_error_set(err, TS_ERR_IO, "'%s': %s", path, strerror(errno));
    struct stat st;
    if (fstat(fileno(f), &st) != 0 || !S_ISREG(st.st_mode)) {
        fclose(f);
        return ts_error_set(err, TS_ERR_IO, "'%s': not a regular file", path);
    }
    if (max_bytes && (uint64_t)st.st_size > max_bytes) {
        fclose(f);
        return ts_error_set(err, TS_ERR_LIMIT, "'%s': %lld bytes is more than the limit of %llu", path,
                            (long long)st.st_size, (unsigned long long)max_bytes);
    }
    size_t n = (size_t)st.st_size;
    char *buf = malloc(n + 1);
    if (!buf) {
        fclose(f);
        return ts_error_set(err, TS_ERR_NOMEM, "'%s': out of memory reading %zu bytes", path, n);
    }
    size_t got = fread(buf, 1, n, f);
    int bad = ferror(f);
    fclose(f);
    if (got != n || bad) {
        free(buf);
        return ts_error_set(err, TS_ERR_IO, "'%s': read error", path);
    }
    buf[n] = '\0';
    *out = buf;
    *len = n;
    return TS_OK;
}

void ts_scene_path_split(const char *path, char *dir, size_t dir_len, char *stem, size_t stem_len)
{
    const char *slash = strrchr(path, '/');
    if (slash) snprintf(dir, dir_len, "%.*s", (int)(slash - path == 0 ? 1 : slash - path), path);
    else snprintf(dir, dir_len, ".");
    const char *base = slash ? slash + 1 : path;
    const char *dot = strrchr(base, '.');
    int n = dot && dot != base ? (int)(dot - base) : (int)strlen(base);
    snprintf(stem, stem_len, "%.*s", n, base);
}
