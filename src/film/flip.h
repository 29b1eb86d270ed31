/* FLIP, the perceptual difference of a test image against a reference as seen flipping
 * between them (Andersson et al., "FLIP: A Difference Evaluator for Alternating Images",
 * HPG 2020), and HDR-FLIP, its maximum over a bracket of tone-mapped exposures (Andersson
 * et al., "Visualizing Errors in Rendered High Dynamic Range Images", EG 2021). */
#ifndef CST_FILM_FLIP_H
#define CST_FILM_FLIP_H

#include "caustic/caustic.h"

/* Pixels per degree of visual angle the papers assume by default: a 0.7 m wide monitor of
 * 3840 pixels seen from 0.7 m, 0.7 * (3840 / 0.7) * pi / 180 = 67.02. */
#define FLIP_DEFAULT_PPD (0.7 * (3840.0 / 0.7) * 3.14159265358979323846 / 180.0)

/* LDR-FLIP of linear RGB images (w x h x 3, row 0 = top; values are clamped to [0, 1],
 * i.e. what an 8-bit sRGB display shows): fills err (w x h, each in [0, 1]) and returns
 * CST_OK, or CST_ERR_OOM. */
CstStatus flip_ldr(const float *reference, const float *test, int w, int h, double ppd, float *err,
                   CstError *error);

/* HDR-FLIP: the ACES-fitted tone mapper at exposures from start to stop (stops), LDR-FLIP
 * of each pair, and per pixel the maximum. start/stop/count as the 2021 paper computes them
 * from the reference unless given (flip_exposure_range). */
CstStatus flip_hdr(const float *reference, const float *test, int w, int h, double ppd, double start,
                   double stop, int count, float *err, CstError *error);

/* The paper's automatic exposure range (HDR-FLIP paper): start such that the brightest
 * reference luminance maps to 0.85 after tone mapping, stop such that the median one does;
 * count = max(2, ceil(stop - start)) (1 when start == stop). A reference that is black
 * everywhere gives 0, 0, 1. Where more than half the pixels are black the median is taken
 * over the non-black ones (the paper's median 0 would ask for an infinite exposure). */
void flip_exposure_range(const float *reference, int w, int h, double *start, double *stop, int *count);

/* The ACES fit the paper uses (Narkowicz 2016, with its 0.6 pre-exposure folded in), of a
 * linear value at 2^exposure, clamped to [0, 1]. */
double flip_tone_map(double v, double exposure);

#endif
