/* cli.c — placeholder until the CLI lands. */
#include <stdio.h>
#include "cli.h"
int ts_cli_main(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    fprintf(stderr, "tessera: not built yet\n");
    return 2;
}
