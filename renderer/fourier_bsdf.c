/* fourier_bsdf.c — placeholder until its module lands. */
typedef int ts_placeholder_fourier_bsdf;
