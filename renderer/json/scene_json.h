/* scene_json.h — scene format v1 (JSON, docs/design.md §4, proto/scene.schema.json): the JSON
 * front end of the scene builder.
 *
 * Design note: the loader walks the document in order and checks every value as JSON
 * (types, ranges, unknown keys, references to materials by name), so a bad document is
 * refused with one sentence that starts with the JSON path of the offending value,
 * "shapes[1].radius: expected a positive number, got -1"; what it has checked it hands to
 * the scene builder (scene_builder.h) in the builder's terms — object space and a
 * transform, ids for names — and the builder's own sentences about an element get the
 * element's path in front ("shapes[3]: a transformed vertex is not a finite float"). The
 * scene digest, the SHA-256 of the canonical document (scene_digest.h), is computed here
 * and handed to the builder. Nothing is half-loaded: on any failure everything is freed.
 * Thread-safe: loads on different threads are independent. */
#ifndef TS_SCENE_JSON_H
#define TS_SCENE_JSON_H

#include <stddef.h>

#include "core/error.h"
#include "scene/scene.h"
#include "build/scene_builder.h"

/* Loads a scene file (JSON). Relative paths inside it resolve against its folder and may
 * not leave it. limits NULL: the defaults. On failure: NULL *out, err holds the sentence
 * (JSON path first for content errors), nothing leaks. */
ts_status ts_scene_load_file(const char *path, const ts_scene_limits *limits, ts_scene **out, ts_error *err);

/* Loads a scene from text. base_dir: folder for relative file paths, or NULL to refuse
 * every file reference. name: used when the document has no "name" (NULL: "untitled"). */
ts_status ts_scene_load_text(const char *text, size_t len, const char *base_dir, const char *name,
                             const ts_scene_limits *limits, ts_scene **out, ts_error *err);

/* The built-in default scene (the classic Cornell box, scenes/cornell-box.json). */
ts_status ts_scene_load_builtin(const ts_scene_limits *limits, ts_scene **out, ts_error *err);
const char *ts_scene_builtin_text(size_t *len);

#endif
