/* shard.h — farm shards (docs/design.md §7): sample ranges, shard metadata, checkpoints and
 * the exact merge.
 *
 * Design note: shard I of N renders sample indices [⌊I·S/N⌋, ⌊(I+1)·S/N⌋) of every pixel
 * of an S-spp render; because a sample depends only on (seed, pixel, index, dimension) the
 * union of shards is the full render's samples, and merging is adding per-pixel sums
 * (film_image.h's SHARD layout). A region shard is a film crop window with any ranges. A
 * shard file's metadata (proto/shard-exr.md) says what it holds: scene digest, seed, S,
 * window, sample ranges; the merge refuses mixes of scenes or seeds and double-counted
 * samples, and names what is missing. Checkpoints are shard files of a range's prefix.
 * Nothing here touches the environment or signals: callers pass what they read. All
 * functions are thread-safe (no shared state). */
#ifndef TS_SHARD_H
#define TS_SHARD_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "core/error.h"
#include "film/film.h"
#include "image/image.h"
#include "scene/scene.h"

typedef struct ts_sample_range {
    uint32_t begin, end; /* sample indices [begin, end) */
} ts_sample_range;

#define TS_SHARD_MAX_RANGES 16

/* What a shard file holds (its EXR attributes). */
typedef struct ts_shard_info {
    char digest[65];     /* scene digest, hex (scene_digest.h) */
    char scene[128];     /* scene name, for messages */
    char integrator[16]; /* the integrator actually run ("path", "ao", …) */
    char version[32];    /* tessera version that wrote it */
    uint32_t seed;
    uint32_t spp_total; /* S: samples per pixel of the whole render */
    int full_width, full_height, x0, y0, width, height; /* film window */
    int n_ranges;       /* sorted, disjoint, non-adjacent */
    ts_sample_range ranges[TS_SHARD_MAX_RANGES];
    bool uneven;        /* a merge whose pixels do not all hold `ranges` (partial region merge) */
    double render_time_s; /* summed over merged shards */
    double film_scale;    /* the scene's output factor (film.h): in no sum, applied to what is viewed
                           * (tessera_film_scale; 1 when a file lacks it); must agree to merge */
} ts_shard_info;

/* Shard `index` of `count` of spp samples: [⌊index·spp/count⌋, ⌊(index+1)·spp/count⌋). */
ts_sample_range ts_shard_range(uint32_t index, uint32_t count, uint32_t spp);

/* Parses "I/N" (0 ≤ I < N ≤ 1000000). TS_ERR_INVALID with a sentence otherwise. */
ts_status ts_shard_parse(const char *text, uint32_t *index, uint32_t *count, ts_error *err);

/* `--shard auto`: I and N from the scheduler's environment values (NULL when unset).
 * Kubernetes Indexed Job: JOB_COMPLETION_INDEX, with N = shard_count (0 = not given: an
 * error). Slurm job array: SLURM_ARRAY_TASK_ID − SLURM_ARRAY_TASK_MIN (MIN 0 when unset)
 * of SLURM_ARRAY_TASK_COUNT (shard_count, when given, must agree). JOB_COMPLETION_INDEX
 * wins when both are set. `how` receives a sentence saying which variables were used;
 * on failure err says which are missing or malformed. */
ts_status ts_shard_auto(const char *job_completion_index, const char *slurm_task_id, const char *slurm_task_count,
                        const char *slurm_task_min, uint32_t shard_count, uint32_t *index, uint32_t *count, char *how,
                        size_t how_len, ts_error *err);

/* Formats ranges as "[0,4) [8,12)". */
void ts_shard_format_ranges(const ts_sample_range *r, int n, char *out, size_t len);

/* Samples per pixel the ranges hold. */
uint32_t ts_shard_range_samples(const ts_sample_range *r, int n);

/* Fills info for a film of scene holding `ranges` (integrator: the one actually run). */
void ts_shard_info_init(ts_shard_info *info, const ts_scene *scene, const ts_film *film, const char *integrator,
                        const ts_sample_range *ranges, int n_ranges, uint32_t spp_total, double render_time_s);

/* Writes film as a SHARD-layout EXR with info's metadata, atomically (temporary file,
 * then rename). */
ts_status ts_shard_write(const char *path, const ts_film *film, const ts_shard_info *info, ts_error *err);

/* Reads a shard file: its metadata and a new film (caller destroys). A file that is not a
 * shard (e.g. a plain RGB EXR) is refused with a sentence saying so; read errors name the
 * file. */
ts_status ts_shard_read(const char *path, ts_shard_info *info, ts_film **film, ts_error *err);

/* Checkpoint resume: if `path` does not exist, *film = NULL and TS_OK. Otherwise it must
 * be a checkpoint of the same render (digest, seed, S, window, integrator) holding one
 * range [want.begin, e) with e ≤ want.end: *film receives it and *resume_at = e. Anything
 * else is refused with a sentence naming the file and the difference. */
ts_status ts_shard_checkpoint_load(const char *path, const ts_shard_info *want, ts_sample_range want_range,
                                   ts_film **film, uint32_t *resume_at, ts_error *err);

/* ---- merge ---- */

typedef struct ts_merge ts_merge;

/* An empty merge. NULL on out of memory. */
ts_merge *ts_merge_create(ts_error *err);
void ts_merge_destroy(ts_merge *m);

/* Adds one shard file: refused (TS_ERR_INVALID, a sentence naming both files) when it is
 * of a different scene, seed, spp, image size or integrator than the first, or holds
 * samples of pixels that an earlier file already holds. */
ts_status ts_merge_add_file(ts_merge *m, const char *path, ts_error *err);

/* Describes what the shards added so far leave out of the target (every sample [0, S) of
 * every pixel of the common window; of the whole image when windows differ): one line
 * per missing piece in `out` (empty when complete, truncated with "…" when long). Returns
 * the number of missing pieces. */
int ts_merge_missing(const ts_merge *m, char *out, size_t len);

/* The metadata of the i-th file added (0 ≤ i < the files added so far), as read: false
 * beyond. */
bool ts_merge_file_info(const ts_merge *m, int i, ts_shard_info *info);

/* The merged film and its metadata (owned by m; valid until ts_merge_destroy). NULL film
 * before the first successful add. */
const ts_film *ts_merge_result(ts_merge *m, ts_shard_info *info, int *n_files);

#endif
