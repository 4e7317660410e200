/* spectrum.h — pbrt-v3's spectral values (sampled spectra, blackbodies) turned into RGB.
 *
 * Design note: tessera renders in linear RGB (docs/design.md §4); pbrt-v3 scenes may give
 * colours as spectra — (wavelength, value) pairs written inline or in a .spd file — or as
 * blackbody temperatures. They are converted once, at import, exactly the way pbrt-v3's
 * default build (RGBSpectrum) converts them: the piecewise-linear spectrum (held constant
 * beyond its first and last samples, sorted by wavelength first) is sampled at the 471
 * wavelengths 360 … 830 nm of the CIE 1931 2° observer (spectrum_cie.c), the sums
 * Σ v(λ)·x̄(λ), ȳ, z̄ scaled by (830 − 360) / (∫ȳ · 471), with pbrt-v3's ∫ȳ = 106.856895,
 * give XYZ, and pbrt-v3's XYZ → linear sRGB matrix gives RGB. A blackbody is Planck's law
 * at those wavelengths, divided by its value at the peak wavelength (Wien's law,
 * 2.8977721e-3 m·K / T), times its scale, then converted as above. Everything is computed
 * in double (pbrt-v3 uses float: the results agree to about 1e-6 relative). Pure
 * functions, thread-safe. */
#ifndef TS_SPECTRUM_H
#define TS_SPECTRUM_H

#include <stddef.h>

#include "core/vecmath.h"

#define TS_CIE_SAMPLES    471 /* 360 … 830 nm, 1 nm apart */
#define TS_CIE_LAMBDA_MIN 360
#define TS_COPPER_SAMPLES 56

extern const float ts_cie_x[TS_CIE_SAMPLES], ts_cie_y[TS_CIE_SAMPLES], ts_cie_z[TS_CIE_SAMPLES];
extern const float ts_copper_nk[TS_COPPER_SAMPLES][3]; /* wavelength nm, n, k */

/* The RGB of the spectrum given by n (wavelength nm, value) pairs, pairs[2i], pairs[2i+1]
 * (n ≥ 1; any order). */
ts_rgb ts_spectrum_to_rgb(const float *pairs, size_t n);

/* The same for separate arrays (lambda ascending or not). */
ts_rgb ts_spectrum_sampled_to_rgb(const double *lambda, const double *value, size_t n);

/* pbrt-v3's normalised blackbody at temperature_k (≤ 0: black), times scale, as RGB. */
ts_rgb ts_spectrum_blackbody_rgb(double temperature_k, double scale);

/* pbrt-v3's XYZ → linear sRGB. */
ts_rgb ts_spectrum_xyz_to_rgb(double x, double y, double z);

/* The RGB of pbrt-v3 metal's default eta and k (copper). */
void ts_spectrum_copper(ts_rgb *eta, ts_rgb *k);

#endif
