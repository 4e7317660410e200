/* tessera.h — the renderer's public interface: what the server and the command line use.
 *
 * Design note: the renderer is a library with no knowledge of HTTP (docs/design.md §1).
 * Its users — server/ and cli/ — include this header and nothing else of renderer/; the
 * `layering` test checks that. The list below is the whole public surface: loading a scene
 * (JSON or pbrt-v3, and the effects it calls for; pbrt-v3 to JSON), rendering it progressively through the scheduler,
 * shards for the farm, the film and its images, and the EXR and PNG encoders. */
#ifndef TS_TESSERA_H
#define TS_TESSERA_H

#include "core/cancel.h"
#include "core/error.h"
#include "film/film.h"
#include "film/film_image.h"
#include "image/exr.h"
#include "image/image.h"
#include "image/png_encode.h"
#include "integrators/effects.h"
#include "render/adaptive.h"
#include "render/render.h"
#include "render/scheduler.h"
#include "render/shard.h"
#include "scene/scene.h"
#include "json/scene_json.h"
#include "load/scene_load.h"

#endif
