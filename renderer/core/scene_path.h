/* scene_path.h — files a scene refers to: confinement to the scene's folder, reading.
 *
 * Design note: docs/design.md §4 says paths inside a scene are relative to the scene file and
 * may not leave its folder. That rule is enforced here, once, for every kind of file a
 * scene names (meshes, Fourier tables, environment maps); for a scene posted to the
 * server the "folder" is the operator's asset folder (`tessera serve --assets DIR`), and
 * with none every file reference is refused. A path is checked lexically first (not
 * empty, not absolute, no `..` that climbs above the folder — refused even when the file
 * does not exist), then resolved with realpath(3), so `..` and symbolic links are
 * followed, and must still lie inside realpath(base_dir). When the file is missing but
 * an existing prefix of the path already resolves outside (a symlinked folder pointing
 * out), the answer is "leaves the scene's folder", not "no such file": a symlink must
 * not become a probe for what exists outside. The resolved path is opened with
 * O_NOFOLLOW | O_NONBLOCK and must be a regular file (a FIFO or device is refused, never
 * waited on); its size is checked against the caller's limit before the buffer is
 * allocated. (A folder rewritten between the check and the open is outside the threat
 * model: the scene's author cannot write into the folder during a load; docs/security.md.)
 *
 * Messages name the file as the scene wrote it, never the resolved absolute path, so a
 * server's answers reveal nothing of its file system: "<what> '<rel>': <problem>", e.g.
 * "mesh file 'a/../../x.obj': path leaves the scene's folder". Thread-safe (no shared
 * state; errno texts come from a fixed table, not strerror). */
#ifndef TS_SCENE_PATH_H
#define TS_SCENE_PATH_H

#include <stddef.h>
#include <stdint.h>

#include "core/error.h"

/* Writes the canonical absolute path of base_dir/rel into out. base_dir NULL: every file
 * reference is refused ("'x': this scene may not refer to files (no asset folder is
 * configured)"). Other errors (TS_ERR_INVALID unless said): "'x': empty path",
 * "'x': absolute paths are not allowed", "'x': path leaves the scene's folder",
 * "'x': cannot open (no such file or directory)" (TS_ERR_IO), "'x': path too long". */
ts_status ts_scene_path_resolve(const char *base_dir, const char *rel, char *out, size_t out_len,
                                ts_error *err);

/* Resolves rel as ts_scene_path_resolve does and reads the whole regular file into a
 * malloc'd, NUL-terminated buffer (*out, *len bytes without the NUL; caller frees).
 * what names the kind of file in messages ("mesh file"; NULL: none). max_bytes (0 = no
 * limit) is checked against the file's size before anything is allocated (TS_ERR_LIMIT
 * "file is N bytes, more than the limit of M"). An empty file is TS_ERR_INVALID. On
 * failure *out is NULL and *len 0. */
ts_status ts_scene_path_read(const char *base_dir, const char *rel, const char *what, uint64_t max_bytes,
                             char **out, size_t *len, ts_error *err);

/* Reads a whole file named by the user (the scene file itself on the command line, no
 * confinement) into a malloc'd, NUL-terminated buffer, at most max_bytes (0 = no limit). */
ts_status ts_scene_path_read_file(const char *path, uint64_t max_bytes, char **out, size_t *len,
                                  ts_error *err);

/* Splits path into its folder ("." if none) and its file name without extension. */
void ts_scene_path_split(const char *path, char *dir, size_t dir_len, char *stem, size_t stem_len);

#endif
