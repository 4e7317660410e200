/* outputs.h — the -o files of `tessera render` and `tessera merge`.
 *
 * Design note: both commands gather their -o paths while parsing the command line, refuse
 * an extension other than .exr or .png before doing any work (a usage error), and then,
 * still before any rendering or merging, make one empty temporary file beside each output
 * (cli_outputs_open): a folder that does not exist or cannot be written, or an output that
 * is a folder, is refused there with its sentence, instead of after the whole render. The
 * images are written into the temporaries once the film is complete, and only when every
 * one is written are they renamed into place (cli_outputs_commit): all the outputs or none
 * (a failed write removes every temporary; an earlier file of the same name is untouched).
 * The extension picks the encoder. A shard film (a farm shard or a merge) goes to .exr in
 * the mergeable SHARD layout (shard.h) and to .png as its colour view. */
#ifndef CLI_OUTPUTS_H
#define CLI_OUTPUTS_H

#include <stdbool.h>

#include "tessera.h"

#define CLI_MAX_OUTPUTS 8

typedef struct cli_outputs {
    const char *path[CLI_MAX_OUTPUTS];
    char *tmp[CLI_MAX_OUTPUTS]; /* the temporaries of cli_outputs_open, or NULL */
    int n;
} cli_outputs;

/* Adds one -o path; false when CLI_MAX_OUTPUTS are already given. */
bool cli_outputs_add(cli_outputs *o, const char *path);
/* NULL when every path ends in .exr or .png (any case), else the first that does not. */
const char *cli_outputs_unsupported(const cli_outputs *o);
/* Whether path's extension is .exr (any case). */
bool cli_output_is_exr(const char *path);
/* Makes the temporary file of every output, in the output's folder; on failure removes
 * those made and says which output cannot be written and why ("-o PATH: …"). */
ts_status cli_outputs_open(cli_outputs *o, ts_error *err);
/* Writes img to every output's temporary (.exr with its statistics, .png 8-bit sRGB). */
ts_status cli_outputs_write_image(const cli_outputs *o, const ts_image *img, ts_error *err);
/* Writes a shard film to every output's temporary: .exr in the SHARD layout, .png its colour view. */
ts_status cli_outputs_write_shard(const cli_outputs *o, const ts_film *film, const ts_shard_info *info, ts_error *err);
/* Renames every temporary onto its output. */
ts_status cli_outputs_commit(cli_outputs *o, ts_error *err);
/* Removes the temporaries still there (after a failure, or with nothing to write). */
void cli_outputs_discard(cli_outputs *o);

#endif
