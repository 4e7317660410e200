/* bundle.c — unpacking a job's tar bundle into its own folder (bundle.h). */
#define _GNU_SOURCE
#include "bundle.h"

#include <archive.h>
#include <archive_entry.h>
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <ftw.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

void srv_bundle_limits_default(srv_bundle_limits *lim)
{
    lim->max_bytes = 256u << 20;
    lim->max_entries = 10000;
    lim->max_path = 1024;
    lim->max_entry_bytes = 256u << 20;
    lim->max_expanded = 1ull << 30;
    lim->cancel = NULL;
}

/* True (st and *http_status set) when the bundle's load has to stop. */
static bool stopped(const srv_bundle_limits *lim, int *http_status, ts_status *st, ts_error *err)
{
    if (!ts_cancel_requested(lim->cancel)) return false;
    *http_status = atomic_load(&lim->cancel->timed_out) ? 422 : 503;
    *st = ts_cancel_check(lim->cancel, err);
    return true;
}

bool srv_bundle_media_type(const char *v)
{
    static const char *const types[] = {"application/x-tar", "application/tar", "application/gzip",
                                        "application/x-gzip", "application/x-gtar"};
    if (!v) return false;
    while (*v == ' ' || *v == '\t') v++;
    for (size_t i = 0; i < sizeof types / sizeof *types; i++) {
        size_t n = strlen(types[i]);
        if (strncasecmp(v, types[i], n) != 0) continue;
        const char *t = v + n;
        while (*t == ' ' || *t == '\t') t++;
        if (*t == '\0' || *t == ';') return true;
    }
    return false;
}

/* ---------------------------------------------------------------- names seen */

/* The entries' normalised names, to refuse duplicates: open addressing, FNV-1a. */
typedef struct name_set {
    char **slot;
    size_t cap, n;
} name_set;

static uint64_t fnv1a(const char *s)
{
    uint64_t h = 1469598103934665603ull;
    for (; *s; s++) h = (h ^ (unsigned char)*s) * 1099511628211ull;
    return h;
}

/* 1 added, 0 already there, -1 out of memory. */
static int name_set_add(name_set *set, const char *name)
{
    if (2 * (set->n + 1) > set->cap) {
        size_t cap = set->cap ? 2 * set->cap : 64;
        char **slot = calloc(cap, sizeof *slot);
        if (!slot) return -1;
        for (size_t i = 0; i < set->cap; i++) {
            if (!set->slot[i]) continue;
            size_t k = fnv1a(set->slot[i]) & (cap - 1);
            while (slot[k]) k = (k + 1) & (cap - 1);
            slot[k] = set->slot[i];
        }
        free(set->slot);
        set->slot = slot, set->cap = cap;
    }
    size_t k = fnv1a(name) & (set->cap - 1);
    for (; set->slot[k]; k = (k + 1) & (set->cap - 1))
        if (!strcmp(set->slot[k], name)) return 0;
    if (!(set->slot[k] = strdup(name))) return -1;
    set->n++;
    return 1;
}

static void name_set_free(name_set *set)
{
    for (size_t i = 0; i < set->cap; i++) free(set->slot[i]);
    free(set->slot);
}

/* ---------------------------------------------------------------- names */

static bool utf8_valid(const unsigned char *s)
{
    while (*s) {
        unsigned c = *s;
        int n = c < 0x80 ? 0 : (c & 0xe0) == 0xc0 ? 1 : (c & 0xf0) == 0xe0 ? 2 : (c & 0xf8) == 0xf0 ? 3 : -1;
        if (n < 0 || (n == 1 && c < 0xc2)) return false;
        unsigned cp = n ? c & (0x3f >> n) : c;
        for (int i = 1; i <= n; i++) {
            if ((s[i] & 0xc0) != 0x80) return false;
            cp = (cp << 6) | (s[i] & 0x3f);
        }
        if ((n == 2 && (cp < 0x800 || (cp >= 0xd800 && cp <= 0xdfff))) || (n == 3 && (cp < 0x10000 || cp > 0x10ffff)))
            return false;
        s += n + 1;
    }
    return true;
}

/* The entry's path relative to the bundle's root in out ("./a/b/" → "a/b"; "" for the
 * root itself), or NULL with the reason in why. */
static const char *normalise(const char *raw, char *out, size_t cap, const char **why)
{
    if (raw[0] == '/') return *why = "an absolute path", NULL;
    while (raw[0] == '.' && raw[1] == '/') raw += 2 + strspn(raw + 2, "/");
    if (!strcmp(raw, ".")) raw = "";
    size_t n = strlen(raw);
    if (n && raw[n - 1] == '/') n--; /* a folder's trailing slash */
    if (n >= cap) return *why = "a path too long", NULL;
    memcpy(out, raw, n);
    out[n] = '\0';
    if (!utf8_valid((const unsigned char *)out)) return *why = "a name that is not UTF-8", NULL;
    for (const char *c = out; n && c <= out + n;) {
        size_t len = strcspn(c, "/");
        if (len == 0) return *why = "an empty path component ('//')", NULL;
        if (len == 2 && c[0] == '.' && c[1] == '.') return *why = "a '..' component (it would leave the bundle)", NULL;
        if (len == 1 && c[0] == '.') return *why = "a '.' component inside the path", NULL;
        if (len > 255) return *why = "a path component longer than 255 bytes", NULL;
        for (size_t i = 0; i < len; i++) {
            unsigned char ch = (unsigned char)c[i];
            if (ch < 0x20 || ch == 0x7f) return *why = "a control character in its name", NULL;
            if (ch == '\\') return *why = "a backslash in its name (use '/' between folders)", NULL;
        }
        c += len + 1;
    }
    return out;
}

static const char *refused_type(struct archive_entry *e)
{
    if (archive_entry_hardlink(e)) return "a hard link";
    switch (archive_entry_filetype(e)) {
    case AE_IFREG: return NULL;
    case AE_IFDIR: return NULL;
    case AE_IFLNK: return "a symbolic link";
    case AE_IFCHR: return "a character device";
    case AE_IFBLK: return "a block device";
    case AE_IFIFO: return "a FIFO";
    case AE_IFSOCK: return "a socket";
    default: return "an entry of unknown type";
    }
}

/* ---------------------------------------------------------------- writing */

/* Creates the folders of rel's parents below root (they may exist as folders). */
static int make_parents(const char *root, const char *rel)
{
    char path[4096];
    int n = snprintf(path, sizeof path, "%s/%s", root, rel);
    if (n < 0 || (size_t)n >= sizeof path) return errno = ENAMETOOLONG, -1;
    for (char *s = path + strlen(root) + 1; (s = strchr(s, '/')); s++) {
        *s = '\0';
        if (mkdir(path, 0700) != 0 && errno != EEXIST) return -1;
        struct stat sb;
        if (lstat(path, &sb) != 0) return -1;
        if (!S_ISDIR(sb.st_mode)) return errno = ENOTDIR, -1;
        *s = '/';
    }
    return 0;
}

static int remove_one(const char *path, const struct stat *sb, int flag, struct FTW *ftw)
{
    (void)sb, (void)flag, (void)ftw;
    (void)remove(path); /* on failure go on: remove what can be (the caller checks the root) */
    return 0;
}

int srv_bundle_remove_tree(const char *dir)
{
    struct stat sb;
    if (lstat(dir, &sb) != 0) return errno == ENOENT ? 0 : -1;
    if (nftw(dir, remove_one, 16, FTW_DEPTH | FTW_PHYS) != 0) return -1;
    return lstat(dir, &sb) == 0 ? (errno = ENOTEMPTY, -1) : 0;
}

void srv_bundle_root_init(srv_bundle_root *r, const char *fixed)
{
    pthread_mutex_init(&r->mu, NULL);
    r->fixed = fixed;
    r->tmp[0] = '\0';
    r->lock_fd = -1;
}

static const char *tmp_base(void)
{
    const char *t = getenv("TMPDIR");
    return t && t[0] && strlen(t) < 4000 ? t : "/tmp";
}

const char *srv_bundle_root_get(srv_bundle_root *r)
{
    if (r->fixed) return r->fixed;
    pthread_mutex_lock(&r->mu);
    if (!r->tmp[0]) {
        snprintf(r->tmp, sizeof r->tmp, "%s/tessera-serve-XXXXXX", tmp_base());
        if (!mkdtemp(r->tmp)) {
            r->tmp[0] = '\0';
        } else {
            /* Held until the process ends (by fini, or by its death): the sweep's sign. */
            char lock[4300];
            snprintf(lock, sizeof lock, "%s/.lock", r->tmp);
            r->lock_fd = open(lock, O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
            if (r->lock_fd >= 0 && flock(r->lock_fd, LOCK_EX | LOCK_NB) != 0) {
                close(r->lock_fd);
                r->lock_fd = -1;
            }
        }
    }
    const char *out = r->tmp[0] ? r->tmp : NULL;
    pthread_mutex_unlock(&r->mu);
    return out;
}

int srv_bundle_root_fini(srv_bundle_root *r)
{
    int rc = r->tmp[0] ? srv_bundle_remove_tree(r->tmp) : 0;
    if (r->lock_fd >= 0) close(r->lock_fd);
    r->lock_fd = -1;
    r->tmp[0] = '\0';
    pthread_mutex_destroy(&r->mu);
    return rc;
}

int srv_bundle_root_sweep(void)
{
    const char *base = tmp_base();
    DIR *d = opendir(base);
    if (!d) return 0;
    int removed = 0;
    struct dirent *e;
    while ((e = readdir(d))) {
        if (strncmp(e->d_name, "tessera-serve-", 14) != 0 || strlen(e->d_name) != 20) continue;
        char dir[4300], lock[4400];
        snprintf(dir, sizeof dir, "%s/%s", base, e->d_name);
        struct stat sb;
        if (lstat(dir, &sb) != 0 || !S_ISDIR(sb.st_mode) || sb.st_uid != geteuid()) continue;
        snprintf(lock, sizeof lock, "%s/.lock", dir);
        int fd = open(lock, O_RDWR | O_NOFOLLOW | O_CLOEXEC);
        if (fd < 0) continue; /* no lock: not ours to judge */
        if (flock(fd, LOCK_EX | LOCK_NB) == 0 && srv_bundle_remove_tree(dir) == 0) removed++;
        close(fd);
    }
    closedir(d);
    return removed;
}

ts_status srv_bundle_unpack(const void *buf, size_t len, const char *dir, const srv_bundle_limits *lim,
                            srv_bundle_info *info, int *http_status, ts_error *err)
{
    memset(info, 0, sizeof *info);
    *http_status = 413;
    if (len > lim->max_bytes)
        return ts_error_set(err, TS_ERR_LIMIT, "the bundle is %zu bytes, more than this server accepts (%llu)", len,
                            (unsigned long long)lim->max_bytes);
    *http_status = 500;
    if (mkdir(dir, 0700) != 0) return ts_error_set(err, TS_ERR_IO, "cannot make the job's folder: %s", strerror(errno));
    struct archive *a = archive_read_new();
    name_set seen = {0};
    char *data = malloc(1 << 16);
    char *rel = malloc((size_t)lim->max_path + 2), *path = malloc((size_t)lim->max_path + 4096);
    char hint[300] = "";
    ts_status st = TS_OK;
    int fd = -1;
    if (!a || !data || !rel || !path) {
        st = ts_error_set(err, TS_ERR_NOMEM, "out of memory for the bundle");
        goto done;
    }
    rel[0] = '\0';
    archive_read_support_format_tar(a);
    archive_read_support_filter_gzip(a);
    if (archive_read_open_memory(a, buf, len) != ARCHIVE_OK) {
        *http_status = 400;
        st = ts_error_set(err, TS_ERR_INVALID, "the body is not a tar archive (plain or gzip-compressed): %s",
                          archive_error_string(a) ? archive_error_string(a) : "unreadable");
        goto done;
    }
    for (;;) {
        struct archive_entry *e;
        if (stopped(lim, http_status, &st, err)) goto done;
        int r = archive_read_next_header(a, &e);
        if (r == ARCHIVE_EOF) break;
        if (r != ARCHIVE_OK && r != ARCHIVE_WARN) {
            *http_status = 400;
            const char *m = archive_error_string(a) ? archive_error_string(a) : "unreadable";
            if (info->entries == 0)
                st = ts_error_set(err, TS_ERR_INVALID, "the body is not a tar archive (plain or gzip-compressed): %s", m);
            else
                st = ts_error_set(err, TS_ERR_INVALID, "the bundle is damaged or truncated after entry %u '%s': %s",
                                  info->entries, rel, m);
            goto done;
        }
        const char *raw = archive_entry_pathname(e);
        if (++info->entries > lim->max_entries) {
            *http_status = 413;
            st = ts_error_set(err, TS_ERR_LIMIT, "the bundle has more than %u entries, more than this server accepts",
                              lim->max_entries);
            goto done;
        }
        *http_status = 400;
        if (!raw || !raw[0]) {
            st = ts_error_set(err, TS_ERR_INVALID, "bundle entry %u has no name", info->entries);
            goto done;
        }
        if (strlen(raw) > lim->max_path) {
            *http_status = 413;
            st = ts_error_set(err, TS_ERR_LIMIT, "bundle entry %u's path is %zu bytes, longer than this server accepts (%u)",
                              info->entries, strlen(raw), lim->max_path);
            goto done;
        }
        const char *why = NULL;
        if (!normalise(raw, rel, (size_t)lim->max_path + 1, &why)) {
            st = ts_error_set(err, TS_ERR_INVALID, "bundle entry '%s' is refused: %s", raw, why);
            goto done;
        }
        if ((why = refused_type(e))) {
            st = ts_error_set(err, TS_ERR_INVALID,
                              "bundle entry '%s' is refused: it is %s (a bundle holds regular files and folders only)", raw,
                              why);
            goto done;
        }
        bool folder = archive_entry_filetype(e) == AE_IFDIR;
        if (!rel[0]) {
            if (folder) continue; /* the root folder itself ("./") */
            st = ts_error_set(err, TS_ERR_INVALID, "bundle entry '%s' is refused: a file named like the root folder", raw);
            goto done;
        }
        int added = name_set_add(&seen, rel);
        if (added < 0) {
            *http_status = 500;
            st = ts_error_set(err, TS_ERR_NOMEM, "out of memory for the bundle");
            goto done;
        }
        if (added == 0) {
            st = ts_error_set(err, TS_ERR_INVALID, "bundle entry '%s' is refused: a second entry of that name", raw);
            goto done;
        }
        if (!hint[0] && !folder) {
            const char *slash = strchr(rel, '/');
            if (slash && !strchr(slash + 1, '/') && (!strcmp(slash + 1, "scene.json") || !strcmp(slash + 1, "scene.pbrt")))
                snprintf(hint, sizeof hint, "%s", rel);
        }
        snprintf(path, (size_t)lim->max_path + 4096, "%s/%s", dir, rel);
        if (make_parents(dir, rel) != 0) {
            st = ts_error_set(err, TS_ERR_INVALID, "bundle entry '%s' cannot be written: %s%s", raw, strerror(errno),
                              errno == ENOTDIR ? " (a file of the bundle has the name of one of its folders)" : "");
            if (errno != ENOTDIR && errno != ENAMETOOLONG) *http_status = 500;
            goto done;
        }
        if (folder) {
            struct stat sb;
            if (mkdir(path, 0700) != 0 && !(errno == EEXIST && lstat(path, &sb) == 0 && S_ISDIR(sb.st_mode))) {
                st = ts_error_set(err, TS_ERR_INVALID, "bundle entry '%s' cannot be written: %s", raw,
                                  errno == EEXIST ? "a file of that name came before" : strerror(errno));
                if (errno != EEXIST) *http_status = 500;
                goto done;
            }
            continue;
        }
        if (archive_entry_size_is_set(e)) {
            uint64_t size = (uint64_t)archive_entry_size(e);
            if (size > lim->max_entry_bytes || info->expanded_bytes + size > lim->max_expanded) {
                *http_status = 413;
                st = size > lim->max_entry_bytes
                         ? ts_error_set(err, TS_ERR_LIMIT, "bundle entry '%s' is %llu bytes, more than this server accepts (%llu)",
                                        raw, (unsigned long long)size, (unsigned long long)lim->max_entry_bytes)
                         : ts_error_set(err, TS_ERR_LIMIT,
                                        "the bundle expands to more than this server accepts (%llu bytes) at entry '%s'",
                                        (unsigned long long)lim->max_expanded, raw);
                goto done;
            }
        }
        fd = open(path, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0600);
        if (fd < 0) {
            st = ts_error_set(err, TS_ERR_INVALID, "bundle entry '%s' cannot be written: %s", raw,
                              errno == EEXIST ? "a folder of that name came before" : strerror(errno));
            if (errno != EEXIST) *http_status = 500;
            goto done;
        }
        uint64_t entry_bytes = 0;
        for (unsigned blocks = 1;; blocks++) {
            if (blocks % 16 == 0 && stopped(lim, http_status, &st, err)) goto done;
            la_ssize_t n = archive_read_data(a, data, 1 << 16);
            if (n == 0) break;
            if (n < 0) {
                st = ts_error_set(err, TS_ERR_INVALID, "the bundle is damaged or truncated in entry '%s': %s", raw,
                                  archive_error_string(a) ? archive_error_string(a) : "unreadable");
                goto done;
            }
            /* Counted as it expands, whatever the header said (a bomb stops here). */
            entry_bytes += (uint64_t)n;
            info->expanded_bytes += (uint64_t)n;
            if (entry_bytes > lim->max_entry_bytes || info->expanded_bytes > lim->max_expanded) {
                *http_status = 413;
                st = entry_bytes > lim->max_entry_bytes
                         ? ts_error_set(err, TS_ERR_LIMIT, "bundle entry '%s' is more than this server accepts (%llu bytes)",
                                        raw, (unsigned long long)lim->max_entry_bytes)
                         : ts_error_set(err, TS_ERR_LIMIT,
                                        "the bundle expands to more than this server accepts (%llu bytes) at entry '%s'",
                                        (unsigned long long)lim->max_expanded, raw);
                goto done;
            }
            for (la_ssize_t w = 0; w < n;) {
                ssize_t k = write(fd, data + w, (size_t)(n - w));
                if (k < 0 && errno == EINTR) continue;
                if (k < 0) {
                    *http_status = 500;
                    st = ts_error_set(err, TS_ERR_IO, "bundle entry '%s' cannot be written: %s", raw, strerror(errno));
                    goto done;
                }
                w += k;
            }
        }
        if (close(fd) != 0) {
            fd = -1;
            *http_status = 500;
            st = ts_error_set(err, TS_ERR_IO, "bundle entry '%s' cannot be written: %s", raw, strerror(errno));
            goto done;
        }
        fd = -1;
    }
    /* The scene: scene.json or scene.pbrt at the root, regular files (they came as such). */
    *http_status = 400;
    struct stat sb;
    snprintf(path, (size_t)lim->max_path + 4096, "%s/scene.json", dir);
    bool json = lstat(path, &sb) == 0 && S_ISREG(sb.st_mode);
    snprintf(path, (size_t)lim->max_path + 4096, "%s/scene.pbrt", dir);
    bool pbrt = lstat(path, &sb) == 0 && S_ISREG(sb.st_mode);
    if (json && pbrt) {
        st = ts_error_set(err, TS_ERR_INVALID, "the bundle holds both scene.json and scene.pbrt at its root: keep one");
        goto done;
    }
    if (!json && !pbrt) {
        if (hint[0])
            st = ts_error_set(err, TS_ERR_INVALID,
                              "the bundle holds no scene.json or scene.pbrt at its root, but '%s': make the tar from inside "
                              "the folder (tar -C FOLDER -czf bundle.tgz .)",
                              hint);
        else st = ts_error_set(err, TS_ERR_INVALID, "the bundle holds no scene.json or scene.pbrt at its root");
        goto done;
    }
    info->scene_file = json ? "scene.json" : "scene.pbrt";
    /* On disk before the job is accepted (its 201), as a checkpoint is: one syncfs. */
    int dfd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dfd >= 0) {
        (void)syncfs(dfd);
        close(dfd);
    }
done:
    if (fd >= 0) close(fd);
    if (a) archive_read_free(a);
    name_set_free(&seen);
    free(data);
    free(rel);
    free(path);
    if (st) srv_bundle_remove_tree(dir);
    else *http_status = 0;
    return st;
}
