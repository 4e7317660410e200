/* bundle.h — a job's files: a tar bundle (optionally gzip-compressed) unpacked into a
 * folder of its own, every entry confined to it.
 *
 * Design note (docs/design.md §5, docs/security.md): libarchive reads the archive (tar:
 * ustar, pax, GNU; compression: none or gzip, detected); this file decides what may be
 * written. Only regular files and folders pass; links (symbolic and hard), devices, FIFOs
 * and sockets are refused, and so are absolute paths, `..` components, empty components,
 * backslashes, control characters, names that are not UTF-8 and duplicate names. Entries
 * are written below a new folder the unpacker creates (mode 0700, files 0600; the tar's
 * modes, owners and times are ignored), never through a link (there are none: only the
 * unpacker writes there). The limits — bundle bytes, entry count, path length, per-entry
 * bytes and expanded bytes — are checked while extracting, so a bomb stops at the limit,
 * not after it. On any failure the folder and everything in it is removed: nothing is left
 * on disk. Thread-safe: unpacks on different threads are independent. */
#ifndef SRV_BUNDLE_H
#define SRV_BUNDLE_H

#include <pthread.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "tessera.h"

typedef struct srv_bundle_limits {
    uint64_t max_bytes;       /* the bundle as posted (compressed) */
    uint32_t max_entries;     /* entries of any kind, folders included */
    uint32_t max_path;        /* bytes of an entry's path */
    uint64_t max_entry_bytes; /* one file's bytes */
    uint64_t max_expanded;    /* all files' bytes together */
    ts_cancel *cancel;        /* a request's load bound (core/cancel.h), polled at each entry and
                               * every MiB written: then TS_ERR_CANCELLED, 422 when timed out, else
                               * 503; NULL (the default): never */
} srv_bundle_limits;

/* The defaults of `tessera serve` (docs/security.md). */
void srv_bundle_limits_default(srv_bundle_limits *lim);

/* What an unpacked bundle holds. */
typedef struct srv_bundle_info {
    uint32_t entries;
    uint64_t expanded_bytes;
    const char *scene_file;   /* "scene.json" or "scene.pbrt" (static), at the folder's root */
} srv_bundle_info;

/* Unpacks the bundle buf[0, len) into dir, which must not exist (its parent must); dir
 * holds the bundle's files on success, with scene.json or scene.pbrt at its root (not
 * both). On failure nothing of dir is left, err holds one sentence naming the entry, and
 * *http_status is 400 (a bad or refused entry, a truncated or unreadable archive, no scene
 * file), 413 (a limit) or 500 (the disk or memory). */
ts_status srv_bundle_unpack(const void *buf, size_t len, const char *dir, const srv_bundle_limits *lim,
                            srv_bundle_info *info, int *http_status, ts_error *err);

/* Removes dir and everything below it, following no link; 0, or -1 with errno when
 * something could not be removed (what could, is). A missing dir is 0. */
int srv_bundle_remove_tree(const char *dir);

/* The folder bundles go under (incoming/ while unpacking, jobs/<id>/files after): --data,
 * or without it a temporary folder of the run, $TMPDIR/tessera-serve-XXXXXX, made at the
 * first bundle (so a server that takes none leaves none behind) and removed by
 * srv_bundle_root_fini. The run holds an flock on the folder's .lock for as long as it
 * lives, so the folder of a run that was killed is found by the next server's
 * srv_bundle_root_sweep (its lock is free) and removed at its start. */
typedef struct srv_bundle_root {
    pthread_mutex_t mu;
    const char *fixed;  /* --data, or NULL */
    char tmp[4200];     /* the temporary folder once made, else "" (guarded by mu) */
    int lock_fd;        /* the open, locked tmp/.lock, or -1 */
} srv_bundle_root;
void srv_bundle_root_init(srv_bundle_root *r, const char *fixed);
/* Removes the temporary folders (tessera-serve-*, owned by this user, under $TMPDIR or
 * /tmp) that no live server holds: their .lock can be locked. A folder without .lock is
 * left alone (a server between making its folder and locking it). Returns how many were
 * removed; the start of a server without --data calls it. */
int srv_bundle_root_sweep(void);
/* The folder, made if needed; NULL with errno when it cannot be. Thread-safe. */
const char *srv_bundle_root_get(srv_bundle_root *r);
/* Removes the temporary folder if one was made (after the server stopped); 0 or -1 with errno. */
int srv_bundle_root_fini(srv_bundle_root *r);

/* True when the media type (a Content-Type value, parameters allowed) is one a bundle is
 * posted as: application/x-tar, application/tar, application/gzip, application/x-gzip,
 * application/x-gtar. */
bool srv_bundle_media_type(const char *content_type);

#endif
