/* convert.h — `tessera convert SCENE.pbrt [-o OUT.json] [--quiet]` (docs/design.md §5b). */
#ifndef CLI_CONVERT_H
#define CLI_CONVERT_H
/* Runs the convert command (argv[0] is "convert"); returns the exit status: 0 written,
 * 1 the scene was refused or the output could not be written, 2 usage. */
int cli_convert(int argc, char **argv);
#endif
