/* fourier_bsdf.c — being written (see fourier_bsdf.h); a stub that refuses files. */
#include "fourier_bsdf.h"

#include <stdlib.h>

ts_status ts_fourier_table_load(const char *path, struct ts_fourier_table **out, ts_error *err)
{
    *out = NULL;
    return ts_error_set(err, TS_ERR_UNSUPPORTED, "%s: Fourier BSDF files are not supported yet", path);
}

void ts_fourier_table_destroy(struct ts_fourier_table *t) { free(t); }
