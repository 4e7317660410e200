/* farm.h — farm jobs: a posted job rendered as one Slurm job array (docs/design.md §7, §5).
 *
 * Design note: a farm job is a store job whose scheduler job is external (scheduler.h): no
 * render thread of this server touches it. One farm thread submits it — the scene (and a
 * bundle's files) written under --farm-dir, then one `sbatch --array=0-(N-1)` whose tasks run
 * `tessera render --shard auto --checkpoint … --checkpoint-interval S` — and follows it
 * with Slurm's own tools: squeue for the live tasks, `scontrol show job` (then sacct) for
 * how an ended one ended. Whenever a shard's checkpoint or output file is rewritten it
 * merges all of them again, in task order, with the exact merge (ts_merge_*) and publishes
 * the result to the job (ts_sched_job_publish), so the image, tiles, events, history and
 * ETA are those of a local job, and the last merge equals `tessera merge` of the shards.
 * Cancel is `scancel` of the array (the job stays cancelling until squeue is empty; what
 * was merged stays); a task that ended without its output is requeued (`scontrol
 * requeue`, resuming from its checkpoint) up to --farm-retries times, then the job fails
 * naming the task and its stderr's last lines, and the rest of the array is cancelled.
 *
 * Restarts: the Slurm job id and each task's retries are written to --data's
 * jobs/<id>/farm.json as soon as they are known; a restarted server re-attaches to the
 * arrays recorded there. Before any sbatch it asks squeue for an array already named
 * tessera-<job id> (a crash between sbatch and farm.json), so a job is never submitted
 * twice. Shutdown leaves the arrays running when --data keeps them, and cancels them
 * otherwise (nothing could re-attach).
 *
 * Threads: srv_farm_* are thread-safe; one mutex guards the list of farm jobs and what
 * status documents read of them (task states, spp, Slurm id, error); commands run on the
 * farm thread only, never on an HTTP thread, each bounded by a timeout. */
#ifndef SRV_FARM_H
#define SRV_FARM_H

#include <cjson/cJSON.h>
#include <stdbool.h>
#include <stdint.h>

#include "job_store.h"
#include "log.h"

/* The options of `tessera serve` that concern the farm (--farm, --farm-*, --max-shards). */
#define SRV_FARM_MAX_SBATCH_ARGS 32
typedef struct srv_farm_options {
    bool slurm;                    /* --farm slurm */
    const char *dir;               /* --farm-dir: storage every node sees */
    const char *sbatch_args[SRV_FARM_MAX_SBATCH_ARGS]; /* --farm-sbatch-arg, in order */
    int n_sbatch_args;
    int retries;                   /* --farm-retries: requeues of a task before the job fails (2) */
    uint32_t max_shards;           /* --max-shards: most tasks a job may ask for (1000) */
    double task_checkpoint_s;      /* --farm-checkpoint-interval: the tasks' --checkpoint-interval (10) */
    const char *tessera;           /* --farm-tessera: the tessera the tasks run (default: this binary) */
} srv_farm_options;

void srv_farm_options_default(srv_farm_options *o);
/* Takes one option (name without "--", value): 1 when taken, 0 when not a farm option, -1
 * on a bad value (msg: the sentence). */
int srv_farm_option(srv_farm_options *o, const char *name, const char *value, char *msg, size_t msg_len);
/* Checked after all options: --farm-dir needs --farm and the other way round. False with msg. */
bool srv_farm_options_check(const srv_farm_options *o, char *msg, size_t msg_len);

typedef struct srv_farm srv_farm;

/* Starts the farm (opts->slurm set): makes --farm-dir if needed and checks that files can
 * be written there (false with a sentence naming it otherwise), starts the farm thread.
 * data_dir: --data or NULL. The store must outlive the farm. */
srv_farm *srv_farm_create(const srv_farm_options *opts, srv_store *store, const char *data_dir, srv_log *log,
                          char *err, size_t err_len);
/* Stops the farm thread (after its current command) and cancels the arrays of unfinished
 * jobs when there is no --data; status documents still read the farm. Idempotent; NULL is
 * fine. */
void srv_farm_stop(srv_farm *f);
/* Stops (if needed) and frees the farm, once nothing reads statuses any more (after the
 * HTTP daemon stopped). NULL is fine. */
void srv_farm_destroy(srv_farm *f);

/* A posted JSON document's farm request: *shards 0 when it has no job.farm. On a bad one
 * (job.farm not an object, shards not a whole number in 1 … max_shards, other keys) 400
 * with the JSON path. *stripped: the document without job.farm (malloc'd, for the store
 * and the nodes), when *shards > 0. */
bool srv_farm_parse_request(const char *text, size_t len, uint32_t max_shards, uint32_t *shards, char **stripped,
                            size_t *stripped_len, int *http_status, ts_error *err);
/* A bundle's ?shards=N (NULL: not given, *shards 0): false with a 400 sentence when not a
 * whole number in 1 … max_shards. */
bool srv_farm_parse_shards(const char *value, uint32_t max_shards, uint32_t *shards, ts_error *err);
/* The most shards a job may ask for (f NULL: the default of --max-shards). */
uint32_t srv_farm_max_shards(const srv_farm *f);

/* Submits a farm job of `shards` tasks: 422 when f is NULL (no --farm), 400 with more
 * shards than samples per pixel, else the store's answers; the array is submitted by the
 * farm thread (a refused sbatch fails the job with Slurm's sentence). cancel: the load's
 * bound (srv_store_submit_cancellable). A new reference. */
srv_job *srv_farm_submit(srv_farm *f, srv_store *st, const char *text, size_t len, const srv_submit_files *files,
                         ts_cancel *cancel, uint32_t shards, int *http_status, ts_error *err);

/* After the store restored --data: follows the restored farm jobs again (f NULL: fails the
 * unfinished ones, since this server has no farm). Returns how many it re-attached. */
int srv_farm_attach(srv_farm *f, srv_store *st, const char *data_dir);

/* The status hook (srv_store_config.describe): adds "farm" (scheduler, slurm_job, shards,
 * tasks [{index, state, spp, retries}]) and, for a failed job, "error". */
void srv_farm_describe(void *farm, srv_job *j, cJSON *status);

/* A farm job was deleted: its folder under --farm-dir goes too. */
void srv_farm_forget(srv_farm *f, srv_job *j);

#endif
