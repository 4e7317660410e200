/* pbrt_import.h — the pbrt-v3 front end's mapping: a parsed pbrt-v3 scene (pbrt_parser.h)
 * onto the scene builder (scene_builder.h), and optionally into the equivalent JSON v1
 * document (for `tessera convert`).
 *
 * Design note: the parser has resolved pbrt-v3's graphics state, so every entity of a
 * ts_pbrt_scene carries its transform, material, area light and parameters; this layer
 * gives the parameters their pbrt-v3 meaning (names, defaults, units — docs/pbrt-v3.md is
 * the table) and hands the builder descriptors in its own terms. The same descriptors are
 * written as JSON v1 when a document is asked for, through the very calls the JSON front
 * end makes from it, so a converted scene renders bit-identically to the .pbrt.
 *
 * What pbrt-v3 would do that tessera cannot is either refused (one sentence,
 * "<file>:<line>:<column>: <Directive> \"<type>\": …", TS_ERR_INVALID or
 * TS_ERR_UNSUPPORTED) or mapped with a warning that says what differs (a sinc filter, a
 * bdpt integrator, a per-light sample count). Every parameter no mapping asked for gets
 * one warning, as pbrt-v3 gives. Warnings go to the caller's callback as whole sentences
 * with their position; a message already given (less its position) is not repeated, and
 * the number of repeats left out is reported once at the end.
 *
 * Materials are mapped when a shape first uses them (an unused material is never
 * checked, as in pbrt-v3 only its parse errors count). Thread-safe: imports on different
 * threads are independent; one ts_pbrt_scene is used by one import at a time (lookups
 * mark its parameters). */
#ifndef TS_PBRT_IMPORT_H
#define TS_PBRT_IMPORT_H

#include "core/error.h"
#include "pbrt3/pbrt_parser.h"
#include "build/scene_builder.h"

struct cJSON;

/* A warning sentence (valid only during the call); ctx is the caller's. */
typedef void (*ts_warning_fn)(void *ctx, const char *message);

/* Maps scene onto b (settings, materials, shapes, lights, name and digest; not finished).
 * doc: NULL, or an empty cJSON object that receives the JSON v1 document. The parser's own
 * warnings are passed on first. On failure err holds the sentence; the builder is left for
 * the caller to destroy (nothing in it is half-added) and doc may hold a partial document
 * the caller discards. */
/* Whether a shape or the camera is in a medium (a MediumInterface names one): pbrt-v3's
 * haveScatteringMedia, for its warning to integrators that do not simulate them. */
bool ts_pbrt_media_used(const ts_pbrt_scene *s);

ts_status ts_pbrt_import(ts_pbrt_scene *scene, ts_scene_builder *b, struct cJSON *doc, ts_warning_fn warn,
                         void *warn_ctx, ts_error *err);

#endif
