/* diagnostics.h — how the command line words a scene's warnings and load errors on stderr
 * (docs/design.md §5b), shared by render and convert. */
#ifndef CLI_DIAGNOSTICS_H
#define CLI_DIAGNOSTICS_H

/* A scene loader's warning on stderr ("tessera: warning: …"); ctx unused (a ts_warning_fn). */
void cli_print_warning(void *ctx, const char *message);

/* A scene that failed to load, on stderr: its path in front unless the sentence starts
 * with it (pbrt-v3 positions do). */
void cli_print_load_error(const char *path, const char *message);

#endif
