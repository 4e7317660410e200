/* persist.h — checkpoints of jobs under --data DIR, and restoring them at start.
 *
 * Design note: each job has a folder DIR/jobs/<id>/ with scene.json (the posted
 * document), film.bin (the accumulated film: per-tile spp and every pixel's sums in
 * double, exactly as the renderer holds them) and job.json (state, counters, halt
 * settings). Files are written atomically (temporary file, fsync, rename), film first, so
 * a crash leaves the previous checkpoint or the new one. Checkpoints read the scheduler's
 * tile snapshots, never the working film, so they never stop rendering. */
#ifndef SRV_PERSIST_H
#define SRV_PERSIST_H

#include "job_store.h"

/* Creates DIR/jobs if needed. */
ts_status srv_persist_init(const char *dir, ts_error *err);
/* Checkpoints one job (whatever its version). */
ts_status srv_persist_save(const char *dir, srv_job *j, ts_error *err);
/* Records a job just submitted (scene.json and job.json, no film yet), before its 201 is
 * sent, so an accepted job survives a crash before its first checkpoint. */
ts_status srv_persist_save_submitted(const char *dir, srv_job *j, ts_error *err);
/* Checkpoints every job whose version changed since its last checkpoint; returns how
 * many were written. A failure goes to stderr (when its reason changes) and into the
 * job's checkpoint_error until a later checkpoint succeeds; the server keeps running. */
int srv_persist_save_changed(const char *dir, srv_store *st);
/* Deletes a removed job's folder; nothing writes it again afterwards. */
void srv_persist_remove(const char *dir, srv_job *j);
/* Restores every job found under DIR/jobs into the store (unfinished ones resume); their
 * scenes load with the same limits and asset folder (NULL: none) as posted ones.
 * Returns how many; unreadable ones are listed as failed. */
int srv_persist_restore_all(const char *dir, srv_store *st, const ts_scene_limits *limits, const char *assets_dir);

#endif
