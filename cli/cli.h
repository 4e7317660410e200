/* cli.h — the command line of docs/design.md §5b. */
#ifndef CLI_CLI_H
#define CLI_CLI_H
/* Runs `tessera <command> ...`; returns the exit status (0 ok, 1 bad input, 2 usage). */
int cli_main(int argc, char **argv);

#endif
