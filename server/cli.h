/* cli.h — the command line of DESIGN.md §5b. */
#ifndef TS_CLI_H
#define TS_CLI_H
/* Runs `tessera <command> ...`; returns the exit status (0 ok, 1 bad input, 2 usage). */
int ts_cli_main(int argc, char **argv);
#endif
