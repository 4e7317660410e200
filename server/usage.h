/* usage.h — how every `tessera` command words a usage error (exit status 2).
 *
 * Design note: one helper for the top-level command, render, convert, merge (cli/) and
 * serve (server/serve.c, which cli/ reaches through the server library; docs/design.md §2
 * lets cli/ include server/ headers, not the other way round, so it lives here). The line
 * on stderr names the command ("tessera merge: …"); a command with a short usage text
 * prints it after the sentence, one with a long text says where to find it. Thread-safe as
 * stdio is. */
#ifndef SRV_USAGE_H
#define SRV_USAGE_H

#include <stdio.h>

/* The exit status of a usage error. */
#define SRV_USAGE_EXIT 2

/* Prints "<command>: <fmt, ...>" and a line end on stderr, then usage(stderr), or when
 * usage is NULL "(<command> --help lists the options)". A command's parser wraps it as
 * `#define usage_error(...) (srv_usage_error("tessera X", usage, __VA_ARGS__), SRV_USAGE_EXIT)`
 * so that `return usage_error(…)` is seen to return the constant where it is written. */
void srv_usage_error(const char *command, void (*usage)(FILE *f), const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

#endif
