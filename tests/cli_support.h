/* cli_support.h — helpers for tests that run the tessera binary as a user would.
 *
 * Design note: the binary's path comes from TS_BINARY (set by ctest). A child's stderr goes
 * to a log file the test names, its stdout to /dev/null; the farm's scheduler variables
 * (JOB_COMPLETION_INDEX, SLURM_ARRAY_*) are cleared in the child so the machine's own
 * environment cannot leak into a test. Failures go through cmocka's fail_msg. */
#ifndef TS_TESTS_CLI_SUPPORT_H
#define TS_TESTS_CLI_SUPPORT_H

#include <stdbool.h>
#include <sys/types.h>

/* Starts `tessera args...` (args NULL-terminated) with optional "NAME=value" additions to
 * its environment (NULL-terminated, or NULL); stderr goes to errlog. */
pid_t cli_start(const char *errlog, const char *const *args, const char *const *env);
/* Waits for pid: its exit status, or 128 + the signal that ended it. */
int cli_finish(pid_t pid);
/* cli_start then cli_finish. */
int cli_run(const char *errlog, const char *const *args, const char *const *env);
/* The first 8 KiB of errlog (a static buffer, overwritten by the next call). */
const char *cli_read_log(const char *errlog);
void cli_write_file(const char *path, const char *text);
bool cli_exists(const char *path);

#endif
