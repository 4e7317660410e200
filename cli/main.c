/* main.c — entry point of the tessera binary: dispatches sub-commands (docs/design.md §5b). */
#include <stdio.h>
#include <string.h>

#include "cli.h"

int main(int argc, char **argv)
{
    return cli_main(argc, argv);
}
