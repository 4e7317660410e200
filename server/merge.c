/* merge.c — the `tessera merge` command: adds shard files' per-pixel sums (shard.h),
 * refuses mixes with one sentence naming the files, names missing sample ranges, and
 * writes the merged film as a shard EXR (so merges merge again) and/or a PNG view. */
#include "merge.h"

#include <getopt.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>

#include "exr.h"
#include "film_image.h"
#include "png_encode.h"
#include "render.h"
#include "shard.h"

#define MAX_OUTPUTS 8

static void usage(FILE *f)
{
    fprintf(f, "usage: tessera merge SHARD.exr... [-o OUT.exr] [-o OUT.png] [--allow-partial] [--quiet]\n"
               "Adds the shards' samples exactly; refuses shards of different scenes, seeds or overlapping\n"
               "sample ranges; names missing ranges (and merges anyway with --allow-partial).\n");
}

static const char *extension(const char *path)
{
    const char *dot = strrchr(path, '.');
    const char *slash = strrchr(path, '/');
    return dot && (!slash || dot > slash) ? dot + 1 : "";
}

static int usage_error(const char *fmt, const char *arg)
{
    fprintf(stderr, "tessera merge: ");
    fprintf(stderr, fmt, arg);
    fprintf(stderr, "\n");
    usage(stderr);
    return 2;
}

static ts_status write_png(const char *path, const ts_film *film, ts_error *err)
{
    ts_image img;
    ts_status st = ts_film_to_image(film, TS_FILM_IMAGE_RGB, &img, err);
    if (st) return st;
    st = ts_png_write(path, &img, 0.0f, err);
    ts_image_fini(&img);
    return st;
}

int ts_cli_merge(int argc, char **argv)
{
    enum { OPT_PARTIAL = 256, OPT_QUIET, OPT_HELP };
    static const struct option opts[] = {{"output", required_argument, NULL, 'o'},
                                         {"allow-partial", no_argument, NULL, OPT_PARTIAL},
                                         {"quiet", no_argument, NULL, OPT_QUIET},
                                         {"help", no_argument, NULL, OPT_HELP},
                                         {NULL, 0, NULL, 0}};
    char *outputs[MAX_OUTPUTS];
    int n_outputs = 0;
    bool allow_partial = false, quiet = false;
    optind = 1;
    opterr = 0;
    int c;
    while ((c = getopt_long(argc, argv, ":o:", opts, NULL)) != -1) {
        switch (c) {
        case 'o':
            if (n_outputs == MAX_OUTPUTS) return usage_error("at most %s outputs", "8");
            outputs[n_outputs++] = optarg;
            break;
        case OPT_PARTIAL: allow_partial = true; break;
        case OPT_QUIET: quiet = true; break;
        case OPT_HELP: usage(stdout); return 0;
        case ':': return usage_error("option '%s' needs a value", argv[optind - 1]);
        default: return usage_error("unknown option '%s'", argv[optind - 1]);
        }
    }
    if (optind >= argc) return usage_error("%s", "no shard files given");
    for (int i = 0; i < n_outputs; i++) {
        const char *ext = extension(outputs[i]);
        if (strcasecmp(ext, "exr") != 0 && strcasecmp(ext, "png") != 0)
            return usage_error("-o %s: the extension must be .exr or .png", outputs[i]);
    }

    ts_error err = {0};
    ts_merge *m = ts_merge_create(&err);
    if (!m) {
        fprintf(stderr, "tessera merge: %s\n", err.message);
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
    for (int i = 0; !rc && i < n_outputs; i++) {
        ts_error_clear(&err);
        ts_status st = strcasecmp(extension(outputs[i]), "exr") == 0 ? ts_shard_write(outputs[i], film, &info, &err)
                                                                     : write_png(outputs[i], film, &err);
        if (st) {
            fprintf(stderr, "tessera merge: %s\n", err.message);
            rc = 1;
        }
    }
    if (!rc && !quiet) {
        char ranges[256];
        ts_shard_format_ranges(info.ranges, info.n_ranges, ranges, sizeof ranges);
        fprintf(stderr, "tessera merge: %d file%s of %s: %u spp of %u (samples %s%s), %d×%d, error estimate %.3g%%\n",
                n_files, n_files == 1 ? "" : "s", info.scene[0] ? info.scene : "(unnamed)",
                ts_shard_range_samples(info.ranges, info.n_ranges), info.spp_total, ranges,
                info.uneven ? ", uneven over the image" : "", film->width, film->height,
                100 * ts_film_relative_error(film));
        for (int i = 0; i < n_outputs; i++) fprintf(stderr, "tessera merge: wrote %s\n", outputs[i]);
    }
    ts_merge_destroy(m);
    return rc;
}
