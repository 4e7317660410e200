/* convert.c — `tessera convert`: a pbrt-v3 scene as the equivalent JSON v1 document.
 *
 * The scene is imported and built completely (every check a render makes), then its JSON
 * v1 document (scene_load.h) is written to -o FILE — through a temporary file renamed
 * into place, so a failed conversion leaves nothing — or to stdout without -o. The
 * document's file references (environment maps, image textures, Fourier tables) keep their paths relative
 * to the pbrt-v3 file's folder, where a JSON scene resolves them only when it lies in
 * that folder too: a note says so when -o names another folder. Warnings go to stderr
 * once each, as for render. */
#include "convert.h"

#include <limits.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "diagnostics.h"
#include "tessera.h"
#include "options.h"
#include "usage.h"

typedef struct convert_args {
    const char *out_path;
    bool quiet;
} convert_args;

/* -o once: a second is a usage error rather than the last one silently winning. */
static bool take_output(void *opts, const char *name, const char *arg, char *why, size_t why_len)
{
    (void)name;
    convert_args *a = opts;
    if (a->out_path) {
        snprintf(why, why_len, "given twice");
        return false;
    }
    a->out_path = arg;
    return true;
}

/* Every option of `tessera convert`: --help, the parser and the errors are made from this. */
static const srv_option convert_options[] = {
    {"output", 'o', "FILE", SRV_OPT_CUSTOM, 0, 0, false, false, NULL, 0, 0, "the document",
     "standard output", take_output, NULL},
    {"quiet", 0, NULL, SRV_OPT_FLAG, 0, 0, false, false, NULL, offsetof(convert_args, quiet), sizeof(bool),
     "no warnings", "", NULL, NULL},
    {"help", 0, NULL, SRV_OPT_HELP, 0, 0, false, false, NULL, 0, 0, NULL, "", NULL, NULL},
};
#define N_CONVERT_OPTIONS (sizeof convert_options / sizeof *convert_options)

static void convert_usage(FILE *f)
{
    fprintf(f,
            "usage: tessera convert SCENE.pbrt [-o OUT.json] [--quiet]\n"
            "Writes the pbrt-v3 scene SCENE as the equivalent scene document (JSON, format v1), which\n"
            "renders bit-identically to it. Meshes are written inline; environment maps, image\n"
            "textures and Fourier tables keep their paths, relative to SCENE's folder (write OUT there for them to load).\n");
    srv_options_help(f, convert_options, N_CONVERT_OPTIONS, NULL);
    fprintf(f, "Exit status: 0 written, 1 the scene was refused or OUT could not be written, 2 usage error.\n");
}

#define convert_usage_error(...) (srv_usage_error("tessera convert", NULL, __VA_ARGS__), SRV_USAGE_EXIT)

static void quiet_warning(void *ctx, const char *message) { (void)ctx, (void)message; }

static void folder_of(const char *path, char *out, size_t len)
{
    char *real = realpath(path, NULL);
    const char *p = real ? real : path;
    const char *slash = strrchr(p, '/');
    if (!slash)
        snprintf(out, len, ".");
    else
        snprintf(out, len, "%.*s", (int)(slash - p), p);
    free(real);
}

int cli_convert(int argc, char **argv)
{
    convert_args args = {0};
    char why[600];
    int first = 1;
    int rc_opts = srv_options_parse(convert_options, N_CONVERT_OPTIONS, argc, argv, &args, &first, why, sizeof why);
    if (rc_opts == SRV_OPTIONS_HELP) {
        convert_usage(stdout);
        return 0;
    }
    if (rc_opts == SRV_OPTIONS_BAD) return convert_usage_error("%s", why);
    const char *out_path = args.out_path;
    bool quiet = args.quiet;
    if (first != argc - 1) return convert_usage_error("expected one scene file");
    const char *scene = argv[first];
    if (ts_scene_format_of(scene, NULL, 0) == TS_SCENE_FORMAT_JSON && strstr(scene, ".json"))
        return convert_usage_error("'%s' is a scene document already; convert reads pbrt-v3 scenes", scene);
    ts_scene_limits limits;
    ts_scene_limits_default(&limits);
    ts_error err = {0};
    char *json = NULL;
    size_t len = 0;
    if (ts_scene_convert_pbrt_path(scene, &limits, quiet ? quiet_warning : cli_print_warning, NULL, &json,
                                   &len, &err)) {
        cli_print_load_error(scene, err.message);
        return 1;
    }
    int rc = 0;
    if (!out_path || strcmp(out_path, "-") == 0) {
        if (fwrite(json, 1, len, stdout) != len || fputc('\n', stdout) == EOF || fflush(stdout) != 0) {
            fprintf(stderr, "tessera convert: cannot write the document to standard output\n");
            rc = 1;
        }
    } else {
        char tmp[PATH_MAX];
        snprintf(tmp, sizeof tmp, "%s.tmp-%ld", out_path, (long)getpid());
        FILE *f = fopen(tmp, "wb");
        bool ok = f && fwrite(json, 1, len, f) == len && fputc('\n', f) != EOF;
        if (f && fclose(f) != 0) ok = false;
        if (!ok || rename(tmp, out_path) != 0) {
            remove(tmp);
            fprintf(stderr, "tessera convert: cannot write '%s'\n", out_path);
            rc = 1;
        } else if (!quiet) {
            char a[PATH_MAX], b[PATH_MAX];
            folder_of(scene, a, sizeof a);
            folder_of(out_path, b, sizeof b);
            if (strcmp(a, b) != 0 && (strstr(json, "\"map\"") || strstr(json, "\"file\"")))
                fprintf(stderr,
                        "tessera convert: note: '%s' names files relative to %s; it loads from that folder\n",
                        out_path, a);
        }
    }
    free(json);
    return rc;
}
