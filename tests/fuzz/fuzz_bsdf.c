/* fuzz_bsdf.c — libFuzzer harness: pbrt-v3 Fourier BSDF tables (fourier_bsdf.h).
 * A table the loader accepts is then evaluated, sampled and its pdf taken at directions
 * drawn from a hash of the input: the loader promises that evaluation never reads out of
 * bounds for any table it accepts (ASan checks that), and pdfs are never negative. */
#include "fuzz_common.h"

#include <math.h>

#include "materials/fourier_bsdf.h"

static ts_vec3 direction(uint64_t *state)
{
    float z = 2 * fuzz_unit(state) - 1, phi = 6.2831853f * fuzz_unit(state);
    float r = sqrtf(fmaxf(0.0f, 1 - z * z));
    return (ts_vec3){r * cosf(phi), r * sinf(phi), z};
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    ts_fourier_table *t = NULL;
    ts_error err = {0};
    ts_status st = ts_fourier_table_load_memory(data, size, "fuzz.bsdf", &t, &err);
    if (st != TS_OK) {
        FUZZ_CHECK(t == NULL && err.status == st && err.message[0] != '\0');
        return 0;
    }
    FUZZ_CHECK(t && t->n_mu >= 2);
    uint64_t state = fuzz_hash(data, size);
    for (int k = 0; k < 8; k++) {
        ts_vec3 wo = direction(&state), wi = direction(&state);
        if (k == 0) wo = wi = (ts_vec3){0, 0, 1}; /* the poles: μ = ±1 exactly */
        if (k == 1) wo = (ts_vec3){0, 0, -1};
        (void)ts_fourier_f(t, wo, wi);
        float pdf = ts_fourier_pdf(t, wo, wi);
        FUZZ_CHECK(!(pdf < 0));
        ts_vec2 u = {fuzz_unit(&state), fuzz_unit(&state)};
        ts_vec3 ws;
        float spdf = 0;
        (void)ts_fourier_sample(t, wo, u, &ws, &spdf);
        FUZZ_CHECK(!(spdf < 0));
    }
    ts_fourier_table_destroy(t);
    return 0;
}
