/* merge.c — the `tessera merge` command: adds shard files' per-pixel sums (shard.h),
 * refuses mixes with one sentence naming the files, names missing sample ranges, and
 * writes the merged film as a shard EXR (so merges merge again) and/or a PNG view. */
#include "merge.h"

#include <getopt.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>

#include "outputs.h"
#include "tessera.h"
#include "usage.h"

static void usage(FILE *f)
{
    fprintf(f, "usage: tessera merge SHARD.exr... -o OUT.exr|OUT.png [-o ...] [--allow-partial] [--quiet]\n"
               "Adds the shards' samples exactly; refuses shards of different scenes, seeds or overlapping\n"
               "sample ranges; names missing ranges (and merges anyway with --allow-partial).\n"
               "  -o, --output FILE   write FILE (required; may repeat, at most 8): .exr keeps the shard\n"
               "                      layout, so a merge can be merged again; .png is a colour view\n"
               "  --allow-partial     merge even when sample ranges are missing (names them as a warning)\n"
               "  --quiet             no summary\n");
}

#define usage_error(...) (srv_usage_error("tessera merge", usage, __VA_ARGS__), SRV_USAGE_EXIT)

int cli_merge(int argc, char **argv)
{
    enum { OPT_PARTIAL = 256, OPT_QUIET, OPT_HELP };
    static const struct option opts[] = {{"output", required_argument, NULL, 'o'},
                                         {"allow-partial", no_argument, NULL, OPT_PARTIAL},
                                         {"quiet", no_argument, NULL, OPT_QUIET},
                                         {"help", no_argument, NULL, OPT_HELP},
                                         {NULL, 0, NULL, 0}};
    cli_outputs outputs = {0};
    bool allow_partial = false, quiet = false;
    optind = 1;
    opterr = 0;
    int c;
    while ((c = getopt_long(argc, argv, ":o:", opts, NULL)) != -1) {
        switch (c) {
        case 'o':
            if (!cli_outputs_add(&outputs, optarg)) return usage_error("at most %s outputs", "8");
            break;
        case OPT_PARTIAL: allow_partial = true; break;
        case OPT_QUIET: quiet = true; break;
        case OPT_HELP: usage(stdout); return 0;
        case ':': return usage_error("option '%s' needs a value", argv[optind - 1]);
        default: return usage_error("unknown option '%s'", argv[optind - 1]);
        }
    }
    if (optind >= argc) return usage_error("no shard files given");
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
    for (int i = optind; i < argc && rc == 0; i++) {
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
