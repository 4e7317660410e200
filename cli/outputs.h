/* outputs.h — the -o files of `tessera render` and `tessera merge`.
 *
 * Design note: both commands gather their -o paths while parsing the command line, refuse
 * an extension other than .exr or .png before doing any work (a usage error), and write
 * every file once the film is complete; the extension picks the encoder. A shard film (a
 * farm shard or a merge) goes to .exr in the mergeable SHARD layout (shard.h) and to .png
 * as its colour view. */
#ifndef CLI_OUTPUTS_H
#define CLI_OUTPUTS_H

#include <stdbool.h>

#include "tessera.h"

#define CLI_MAX_OUTPUTS 8

typedef struct cli_outputs {
    const char *path[CLI_MAX_OUTPUTS];
    int n;
} cli_outputs;

/* Adds one -o path; false when CLI_MAX_OUTPUTS are already given. */
bool cli_outputs_add(cli_outputs *o, const char *path);
/* NULL when every path ends in .exr or .png (any case), else the first that does not. */
const char *cli_outputs_unsupported(const cli_outputs *o);
/* Whether path's extension is .exr (any case). */
bool cli_output_is_exr(const char *path);
/* Writes a shard film to every output: .exr in the SHARD layout, .png its colour view. */
ts_status cli_outputs_write_shard(const cli_outputs *o, const ts_film *film, const ts_shard_info *info, ts_error *err);

#endif
