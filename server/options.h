/* options.h — a command's options as one table: name, value, range, default, field and help.
 *
 * Design note: every command — `tessera serve`, and `render`, `merge` and `convert` (cli/,
 * which may include server/ headers) — describes each option once, in a table of srv_option; the parser (getopt_long underneath),
 * the usage errors and the --help text are all made from it, so the range an error names,
 * the range and default --help shows and the value the command uses cannot drift apart.
 * The defaults shown are read from the options struct as the command initialised it (or
 * are a text, for defaults that are not a value, "one per core"). README.md and
 * docs/design.md §5b list the same options; tests/docs/options.sh checks that they do.
 *
 * Errors are one sentence, "--NAME: expected …, got 'VALUE'", printed by the caller with
 * srv_usage_error (usage.h). Single-threaded (getopt). */
#ifndef SRV_OPTIONS_H
#define SRV_OPTIONS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

typedef enum srv_opt_type {
    SRV_OPT_UINT,   /* a whole number in [min, max] into an unsigned or int field of `size` bytes */
    SRV_OPT_NUMBER, /* a finite number in [min, max] ((min, max] with min_exclusive) into a double */
    SRV_OPT_STRING, /* a value kept as it is (const char *); non_empty refuses "" */
    SRV_OPT_FLAG,   /* no value: sets a bool */
    SRV_OPT_CUSTOM, /* parse() takes the value */
    SRV_OPT_HELP,   /* --help: the parser returns SRV_OPTIONS_HELP */
} srv_opt_type;

typedef struct srv_option {
    const char *name;    /* without "--" */
    char short_name;     /* e.g. 'o' for -o, or 0 */
    const char *metavar; /* the value's name in --help ("N", "BYTES"); NULL for flags */
    srv_opt_type type;
    double min, max;     /* UINT, NUMBER */
    bool min_exclusive;  /* NUMBER: above min */
    bool non_empty;      /* STRING */
    const char *unit;    /* "bytes", "seconds" in sentences (STRING: the value's noun, "token"), or NULL */
    size_t offset, size; /* the field in the options struct; UINT: its size (1, 2, 4, 8) */
    const char *help;    /* what it does; "\n" breaks a line (continuations are indented) */
    /* the default as --help shows it: NULL shows the field's initial value ("(default 8080)",
     * a NULL string "(default: none)"), "" shows none, a number's text "(default 1e13)", any
     * other text "(default: TEXT)" */
    const char *deflt;
    /* CUSTOM: takes arg for option `name` into opts; false with a sentence (without the
     * option's name) in why */
    bool (*parse)(void *opts, const char *name, const char *arg, char *why, size_t why_len);
    const char *heading; /* a line --help prints before this option, or NULL */
} srv_option;

#define SRV_OPTIONS_GO -1   /* parsed: go ahead */
#define SRV_OPTIONS_HELP -2 /* --help was given */
#define SRV_OPTIONS_BAD -3  /* a usage error: the sentence is in why */

/* Parses argv[1..argc) by the table t[0..n) into opts (which holds the defaults already).
 * SRV_OPTIONS_GO (then *first_arg is the index of the first non-option argument),
 * SRV_OPTIONS_HELP, or SRV_OPTIONS_BAD with the sentence in why. */
int srv_options_parse(const srv_option *t, size_t n, int argc, char **argv, void *opts, int *first_arg, char *why,
                      size_t why_len);

/* The table's lines of --help, each "  --name VALUE" padded to a column, then its help, its
 * range (numbers) and its default read from defaults (opts as initialised). */
void srv_options_help(FILE *f, const srv_option *t, size_t n, const void *defaults);

#endif
