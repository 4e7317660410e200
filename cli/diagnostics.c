/* diagnostics.c — scene warnings and load errors on stderr; see diagnostics.h. */
#include "diagnostics.h"

#include <stdio.h>
#include <string.h>

void cli_print_warning(void *ctx, const char *message)
{
    (void)ctx;
    fprintf(stderr, "tessera: warning: %s\n", message);
}

void cli_print_load_error(const char *path, const char *message)
{
    size_t n = path ? strlen(path) : 0;
    if (!path || (strncmp(message, path, n) == 0 && message[n] == ':'))
        fprintf(stderr, "tessera: %s\n", message);
    else
        fprintf(stderr, "tessera: %s: %s\n", path, message);
}
