/* usage.c — usage errors of the commands; see usage.h. */
#include "usage.h"

#include <stdarg.h>

void srv_usage_error(const char *command, void (*usage)(FILE *f), const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, "%s: ", command);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
    if (usage) usage(stderr);
    else fprintf(stderr, "(%s --help lists the options)\n", command);
}
