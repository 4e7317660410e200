/* mesh_file.h — triangle meshes read from the files `mesh` shapes name: OBJ or PLY by
 * extension.
 *
 * Design note: a mesh file is untrusted scene input. The path is confined to the scene's
 * folder (docs/design.md §4) after every symlink is resolved (scene_path.h, the one
 * confinement rule for every file a scene names); the whole file is read into memory
 * (bounded by max_file_bytes, checked before the buffer is allocated: open with
 * O_NOFOLLOW, regular files only) and handed, NUL-terminated, to the reader its extension
 * picks (.obj: mesh_obj.h, .ply: mesh_ply.h, case-insensitive), which checks every count
 * against the limits and the file size before anything of that size is allocated. Parse
 * errors name the file and the line (OBJ, ASCII PLY) or the byte offset and element
 * (binary PLY). The result is a plain indexed triangle list in the file's object space
 * (mesh_read.h); the scene builder transforms and copies it into its arena. */
#ifndef TS_MESH_FILE_H
#define TS_MESH_FILE_H

#include <stddef.h>
#include <stdint.h>

#include "core/error.h"
#include "mesh/mesh_read.h"

/* Loads base_dir/rel_path into *out (base_dir NULL or "" means the current directory;
 * limits may be NULL for no limits). rel_path must be relative and, once every symlink is
 * resolved, stay inside realpath(base_dir); otherwise TS_ERR_INVALID with "mesh file 'x':
 * path leaves the scene's folder" (or "absolute paths are not allowed"). Errors: TS_ERR_IO
 * (cannot open or read), TS_ERR_INVALID (bad path, unknown extension, not a regular file,
 * empty file, parse errors such as "mesh file 'bunny.obj', line 12: face index 40 out of
 * range (file has 38 vertices)"), TS_ERR_UNSUPPORTED (big-endian PLY), TS_ERR_LIMIT (a
 * limit exceeded; checked before the large allocation), TS_ERR_NOMEM. On failure *out is
 * zeroed and nothing leaks; on success the caller frees with ts_mesh_data_free.
 * Thread-safe (no shared state). */
ts_status ts_mesh_file_load(const char *base_dir, const char *rel_path, const ts_mesh_limits *limits,
                            ts_mesh_data *out, ts_error *err);

/* Parses an in-memory file image (for fuzzing and callers that already hold the bytes):
 * name is used in messages and its extension (.obj or .ply) picks the format; bytes (size
 * bytes, need not be NUL-terminated) are only read. Same results, limits (max_file_bytes
 * applies to size) and errors as ts_mesh_file_load without the path checks. Thread-safe. */
ts_status ts_mesh_load_memory(const char *name, const void *bytes, size_t size, const ts_mesh_limits *limits,
                              ts_mesh_data *out, ts_error *err);

#endif
