/* scene_digest.h — the scene digest: SHA-256 of the canonical form of a scene document.
 *
 * Design note: farm shards of one render must come from the same scene, whatever the
 * whitespace, key order or number spelling of the file each node read. The canonical form
 * (normative description: proto/scene-digest.md) is the JSON document with object keys
 * sorted bytewise, no whitespace, minimal string escapes and numbers printed so they read
 * back to the same double; the top-level "job" object (halting and bookkeeping) and
 * "film.crop" (so region shards of one image share a digest) are left out. Files the
 * document references (meshes, maps) are not hashed. SHA-256 is nettle's.
 * Thread-safe: no shared state. */
#ifndef TS_SCENE_DIGEST_H
#define TS_SCENE_DIGEST_H

#include <stddef.h>
#include <stdint.h>

#include "core/error.h"

struct cJSON;

#define TS_SCENE_DIGEST_BYTES 32
#define TS_SCENE_DIGEST_HEX_LEN 64 /* characters, without the NUL */

/* The canonical text of doc (see above) in a malloc'd NUL-terminated buffer the caller
 * frees; *len excludes the NUL. TS_ERR_NOMEM, or TS_ERR_INVALID for a document nested
 * deeper than 256 levels; on failure *out is NULL. */
ts_status ts_scene_canonical_text(const struct cJSON *doc, char **out, size_t *len, ts_error *err);

/* SHA-256 of the canonical text of doc as 64 lower-case hex digits plus NUL. */
ts_status ts_scene_digest(const struct cJSON *doc, char hex[TS_SCENE_DIGEST_HEX_LEN + 1], ts_error *err);

/* SHA-256 of scene text (parsed first; TS_ERR_INVALID with the parser's sentence if it is
 * not JSON). For tools and tests. */
ts_status ts_scene_digest_text(const char *text, size_t len, char hex[TS_SCENE_DIGEST_HEX_LEN + 1], ts_error *err);

#endif
