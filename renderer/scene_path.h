/* scene_path.h — files a scene refers to: confinement to the scene's folder, reading.
 *
 * Design note: DESIGN.md §4 says paths inside a scene are relative to the scene file and
 * may not leave its folder. That rule is enforced here, once, for every kind of file a
 * scene names (meshes, Fourier tables, environment maps): absolute paths are refused, and
 * the path is resolved with realpath(3) — so `..` and symbolic links are followed — and
 * must still lie inside realpath(base_dir). Thread-safe. */
#ifndef TS_SCENE_PATH_H
#define TS_SCENE_PATH_H

#include <stddef.h>
#include <stdint.h>

#include "error.h"

/* Writes the canonical absolute path of base_dir/rel into out. base_dir NULL: every file
 * reference is refused. Errors: "'x': absolute paths are not allowed", "'x': path leaves
 * the scene's folder", "'x': no such file". */
ts_status ts_scene_path_resolve(const char *base_dir, const char *rel, char *out, size_t out_len, ts_error *err);

/* Reads a whole file (at most max_bytes; 0 = no limit) into a malloc'd, NUL-terminated
 * buffer. */
ts_status ts_scene_path_read_file(const char *path, uint64_t max_bytes, char **out, size_t *len, ts_error *err);

/* Splits path into its folder ("." if none) and its file name without extension. */
void ts_scene_path_split(const char *path, char *dir, size_t dir_len, char *stem, size_t stem_len);

#endif
