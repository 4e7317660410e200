/* persist.h — checkpoints of jobs under --data DIR, and restoring them at start.
 *
 * Design note: each job has a folder DIR/jobs/<id>/ with scene.json (the posted
 * document), film.bin (the accumulated film: per-tile spp and every pixel's sums in
 * double, exactly as the renderer holds them) and job.json (state, counters, halt
 * settings). Files are written atomically (temporary file, fsync, rename), film first, so
 * a crash leaves the previous checkpoint or the new one, and perhaps a temporary file,
 * which the next start-up (or the job's last checkpoint) removes. film.bin carries a
 * SHA-256 of its bytes; restore reads only regular files (no FIFO, device or symbolic
 * link) and a damaged checkpoint makes the job render again from its scene, never turns it
 * into a failed or finished one. Checkpoints read the scheduler's tile snapshots, never the
 * working film, so they never stop rendering. Error sentences name files relative to DIR
 * ("jobs/ID/film.bin"): they reach job statuses. */
#ifndef SRV_PERSIST_H
#define SRV_PERSIST_H

#include "job_store.h"

/* What checkpoints and restore counted (GET /metrics); atomics, shared by the maintenance
 * thread, the HTTP threads and start-up. */
typedef struct srv_persist_stats {
    atomic_uint_fast64_t temporaries_removed; /* *.tmp.* files swept (start-up, job completion) */
    atomic_uint_fast64_t stray_entries;       /* entries under DIR/jobs that are not job folders (at start-up) */
    atomic_uint_fast64_t damaged;             /* checkpoints refused at restore (their jobs render again) */
    atomic_uint_fast64_t failures;            /* checkpoint attempts that failed */
} srv_persist_stats;

/* How failed checkpoints are retried: after first_s, then twice as long each time, at most
 * max_s apart (per job), until one lands. */
typedef struct srv_persist_retry {
    double first_s, max_s;
} srv_persist_retry;

/* Creates DIR/jobs if needed. */
ts_status srv_persist_init(const char *dir, ts_error *err);
/* Checkpoints one job (whatever its version). */
ts_status srv_persist_save(const char *dir, srv_job *j, ts_error *err);
/* Records a job just submitted (scene.json and job.json, no film yet), before its 201 is
 * sent, so an accepted job survives a crash before its first checkpoint. */
ts_status srv_persist_save_submitted(const char *dir, srv_job *j, ts_error *err);
/* Checkpoints every job whose version changed since its last checkpoint; returns how
 * many were written. A failure goes into the job's checkpoint_error until a later
 * checkpoint succeeds, and to stderr once when the job's checkpoints start failing and
 * once when they land again; the server keeps running. With retry, a failing job is
 * tried again only after its backoff; without (shutdown), every changed job is tried.
 * Maintenance thread (or shutdown) only. stats may be NULL. */
int srv_persist_save_changed(const char *dir, srv_store *st, const srv_persist_retry *retry, srv_persist_stats *stats);
/* Deletes a removed job's folder; nothing writes it again afterwards. */
void srv_persist_remove(const char *dir, srv_job *j);
/* Restores every job found under DIR/jobs into the store (unfinished ones resume); their
 * scenes load with the same limits and asset folder (NULL: none) as posted ones. First
 * removes temporary files in the job folders (one log line, counted) and counts entries
 * that are not job folders (left alone, not listed). Returns how many jobs; a job whose
 * scene is unreadable or no longer loads is listed as failed, one whose checkpoint is
 * damaged renders again. stats may be NULL. */
int srv_persist_restore_all(const char *dir, srv_store *st, const ts_scene_limits *limits, const char *assets_dir,
                            srv_persist_stats *stats);

#endif
