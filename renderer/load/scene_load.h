/* scene_load.h — loading a scene whatever its format: scene format v1 (JSON, scene_json.h)
 * or pbrt-v3 scene text (pbrt_parser.h + pbrt_import.h), and converting pbrt-v3 to JSON v1.
 *
 * Design note: the format is told by the file: a name ending in .pbrt is pbrt-v3, one
 * ending in .json is JSON; any other name is JSON when its first byte past white space
 * (and a UTF-8 byte-order mark) is '{', else pbrt-v3. Both formats end in the one scene
 * builder (scene_builder.h), so a scene loads with the same checks, limits and sentences
 * whichever way it came. pbrt-v3 files resolve every file they name (Include, meshes,
 * maps, .spd) against the top-level file's folder, confined to it (scene_path.h), as
 * pbrt-v3's search directory; JSON files against their own folder, as always. Warnings
 * (pbrt-v3 only: unused parameters, what is mapped approximately — docs/pbrt-v3.md) go to
 * the caller's callback as sentences with their position, each given once. On failure
 * nothing is returned, err holds one sentence naming where, and nothing leaks.
 * Thread-safe: loads on different threads are independent. */
#ifndef TS_SCENE_LOAD_H
#define TS_SCENE_LOAD_H

#include <stdbool.h>
#include <stddef.h>

#include "core/error.h"
#include "pbrt3/pbrt_import.h" /* ts_warning_fn */
#include "scene/scene.h"
#include "build/scene_builder.h"

typedef enum ts_scene_format { TS_SCENE_FORMAT_JSON, TS_SCENE_FORMAT_PBRT } ts_scene_format;

/* The format of a scene named path (may be NULL) whose first bytes are text[0, len) (may
 * be NULL when path tells by its extension): the rule of the design note. */
ts_scene_format ts_scene_format_of(const char *path, const char *text, size_t len);

/* Loads the scene file at path, JSON or pbrt-v3 (the rule above). limits NULL: the
 * defaults; warn may be NULL. The scene's name is the file's name without extension
 * (JSON: unless the document names itself). */
ts_status ts_scene_load_path(const char *path, const ts_scene_limits *limits, ts_warning_fn warn,
                             void *warn_ctx, ts_scene **out, ts_error *err);

/* Loads pbrt-v3 scene text held in memory, called name in positions (NULL: "scene"); the
 * scene's name is name without a final ".pbrt" (a bundle's "scene.pbrt" is the scene
 * "scene"). base_dir: the folder every file it names resolves against and is
 * confined to, or NULL to refuse every file reference (a scene posted to a server without
 * an asset folder). */
ts_status ts_scene_load_pbrt_text(const char *text, size_t len, const char *base_dir, const char *name,
                                  const ts_scene_limits *limits, ts_warning_fn warn, void *warn_ctx,
                                  ts_scene **out, ts_error *err);

/* Converts the pbrt-v3 file at path to the equivalent JSON v1 document (docs/pbrt-v3.md):
 * *json is malloc'd, NUL-terminated, pretty-printed (the caller frees it; *len without the
 * NUL). The scene is built and checked completely first, so a converted document loads.
 * File references (meshes are written inline; maps and Fourier tables are not) keep their
 * paths as written, relative to the pbrt-v3 file's folder. */
ts_status ts_scene_convert_pbrt_path(const char *path, const ts_scene_limits *limits, ts_warning_fn warn,
                                     void *warn_ctx, char **json, size_t *len, ts_error *err);

#endif
