/* merge.h — `tessera merge SHARD.exr... [-o OUT.exr] [-o OUT.png] [--allow-partial]`
 * (docs/design.md §5b, §7). */
#ifndef CLI_MERGE_H
#define CLI_MERGE_H
/* Runs the merge command (argv[0] is "merge"); returns the exit status: 0 merged, 1 a
 * file was refused or missing samples without --allow-partial, 2 usage. */
int cli_merge(int argc, char **argv);
#endif
