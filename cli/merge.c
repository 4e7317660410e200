/* merge.c — the `tessera merge` command: adds shard files' per-pixel sums (shard.h),
 * refuses mixes with one sentence naming the files, names missing sample ranges, and
 * writes the merged film as a shard EXR (so merges merge again) and/or a PNG view. */
#include "merge.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>

#include "outputs.h"
#include "tessera.h"
#include "options.h"
#include "usage.h"

typedef struct merge_args {
    cli_outputs outputs;
    bool allow_partial, quiet;
} merge_args;

static bool take_output(void *opts, const char *name, const char *arg, char *why, size_t why_len)
{
    (void)name;
    if (cli_outputs_add(&((merge_args *)opts)->outputs, arg)) return true;
    snprintf(why, why_len, "at most 8 outputs");
    return false;
}

#define FLAG(name, field, help) \
    {name, 0, NULL, SRV_OPT_FLAG, 0, 0, false, false, NULL, offsetof(merge_args, field), sizeof(bool), help, "", NULL, NULL}

/* Every option of `tessera merge`: --help, the parser and the errors are made from this. */
static const srv_option merge_options[] = {
    {"output", 'o', "FILE", SRV_OPT_CUSTOM, 0, 0, false, false, NULL, 0, 0,
     "write FILE (required; may repeat, at most 8): .exr keeps the shard\nlayout, so a merge can be merged again; "
     ".png is a colour view", "", take_output, NULL},
    FLAG("allow-partial", allow_partial, "merge even when sample ranges are missing (names them as a warning)"),
    FLAG("quiet", quiet, "no summary"),
    {"help", 0, NULL, SRV_OPT_HELP, 0, 0, false, false, NULL, 0, 0, NULL, "", NULL, NULL},
};
#define N_MERGE_OPTIONS (sizeof merge_options / sizeof *merge_options)

static void usage(FILE *f)
{
    fprintf(f, "usage: tessera merge SHARD.exr... -o OUT.exr|OUT.png [-o ...] [--allow-partial] [--quiet]\n"
               "Adds the shards' samples exactly; refuses shards of different scenes, seeds or overlapping\n"
               "sample ranges; names missing ranges (and merges anyway with --allow-partial).\n");
    srv_options_help(f, merge_options, N_MERGE_OPTIONS, NULL);
}

#define usage_error(...) (srv_usage_error("tessera merge", usage, __VA_ARGS__), SRV_USAGE_EXIT)

int cli_merge(int argc, char **argv)
{
    merge_args args = {0};
    char why[600];
    int first = 1;
    int rc_opts = srv_options_parse(merge_options, N_MERGE_OPTIONS, argc, argv, &args, &first, why, sizeof why);
    if (rc_opts == SRV_OPTIONS_HELP) {
        usage(stdout);
        return 0;
    }
    if (rc_opts == SRV_OPTIONS_BAD) return usage_error("%s", why);
    cli_outputs outputs = args.outputs;
    bool allow_partial = args.allow_partial, quiet = args.quiet;
    if (first >= argc) return usage_error("no shard files given");
    if (outputs.n == 0)
        return usage_error("no output: give -o MERGED.exr (mergeable again) and/or -o MERGED.png");
    const char *unsupported = cli_outputs_unsupported(&outputs);
    if (unsupported) return usage_error("-o %s: the extension must be .exr or .png", unsupported);

    ts_error err = {0};
    if (cli_outputs_open(&outputs, &err)) { /* before reading any shard: all the outputs or none */
        fprintf(stderr, "tessera merge: %s\n", err.message);
        return 1;
    }
    ts_merge *m = ts_merge_create(&err);
    if (!m) {
        fprintf(stderr, "tessera merge: %s\n", err.message);
        cli_outputs_discard(&outputs);
        return 1;
    }
    int rc = 0;
    for (int i = first; i < argc && rc == 0; i++) {
        ts_error_clear(&err);
        if (ts_merge_add_file(m, argv[i], &err)) {
            fprintf(stderr, "tessera merge: %s\n", err.message);
            rc = 1;
        }
    }
    char missing[2048];
    int n_missing = rc ? 0 : ts_merge_missing(m, missing, sizeof missing);
    if (n_missing) {
        fprintf(stderr, "tessera merge: %s: %d piece%s missing:\n", allow_partial ? "warning" : "incomplete", n_missing,
                n_missing == 1 ? "" : "s");
        for (char *line = strtok(missing, "\n"); line; line = strtok(NULL, "\n")) fprintf(stderr, "  %s\n", line);
        if (!allow_partial) {
            fprintf(stderr, "tessera merge: add the missing shards, or pass --allow-partial to merge what is there\n");
            rc = 1;
        }
    }
    ts_shard_info info;
    int n_files = 0;
    const ts_film *film = rc ? NULL : ts_merge_result(m, &info, &n_files);
    if (!rc && !film) {
        fprintf(stderr, "tessera merge: out of memory\n");
        rc = 1;
    }
    ts_error_clear(&err);
    if (!rc && (cli_outputs_write_shard(&outputs, film, &info, &err) || cli_outputs_commit(&outputs, &err))) {
        fprintf(stderr, "tessera merge: %s\n", err.message);
        rc = 1;
    }
    if (!rc && !quiet) {
        char ranges[256];
        ts_shard_format_ranges(info.ranges, info.n_ranges, ranges, sizeof ranges);
        fprintf(stderr, "tessera merge: %d file%s of %s: %u spp of %u (samples %s%s), %d×%d, error estimate %.3g%%\n",
                n_files, n_files == 1 ? "" : "s", info.scene[0] ? info.scene : "(unnamed)",
                ts_shard_range_samples(info.ranges, info.n_ranges), info.spp_total, ranges,
                info.uneven ? ", uneven over the image" : "", film->width, film->height,
                100 * ts_film_relative_error(film));
        for (int i = 0; i < outputs.n; i++) fprintf(stderr, "tessera merge: wrote %s\n", outputs.path[i]);
    }
    cli_outputs_discard(&outputs);
    ts_merge_destroy(m);
    return rc;
}
