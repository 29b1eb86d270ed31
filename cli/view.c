/* caustic view (issue 30): a window (SDL2) that renders a scene progressively through the
 * public API, in the display modes of the tutorial (preview, Whitted, path, light, photon,
 * SPPM, BDPT, VCM, relative error, disagreement with a pinned mode), with an orbit camera
 * and a script for headless tests. The only file of caustic that talks to SDL; the library
 * stays window-free. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

#ifndef CLI_HAVE_SDL2

bool cli_view_available(void) { return false; }

int cli_view(const CliArgs *a)
{
    (void)a;
    fprintf(stderr, "caustic: error: view: this caustic was built without a window system (SDL2); "
                    "install libsdl2-dev and rebuild (cmake -DCST_VIEWER=ON)\n");
    return CLI_EXIT_USAGE;
}

#else

#include <SDL.h>

#include "tev.h"
#include "view_camera.h"
#include "view_script.h"
#include "view_state.h"

bool cli_view_available(void) { return true; }

/* The display modes, numbered as their keys. */
typedef enum ViewMode {
    VIEW_PREVIEW = 1, VIEW_WHITTED, VIEW_PATH, VIEW_LIGHT, VIEW_PHOTON, VIEW_SPPM, VIEW_BDPT, VIEW_VCM
} ViewMode;
static const char *const VIEW_MODE_NAMES[] = {"", "preview", "whitted", "path", "light", "photon",
                                              "sppm", "bdpt", "vcm"};
static const CstIntegrator VIEW_MODE_INTEGRATORS[] = {
    CST_INTEGRATOR_DEFAULT, CST_INTEGRATOR_PATH, CST_INTEGRATOR_WHITTED, CST_INTEGRATOR_PATH,
    CST_INTEGRATOR_LIGHT,   CST_INTEGRATOR_PHOTON, CST_INTEGRATOR_SPPM, CST_INTEGRATOR_BDPT,
    CST_INTEGRATOR_VCM};

/* What the preview mode shows, from the first-hit AOVs (key 1 again, p or Tab cycles). */
typedef enum ViewPreview { VIEW_EYE_LIGHT, VIEW_NORMALS, VIEW_ALBEDO, VIEW_DEPTH, VIEW_PREVIEW_KINDS } ViewPreview;
static const char *const VIEW_PREVIEW_NAMES[] = {"eye light", "normals", "albedo", "depth"};

/* The first image after any change: the preview at this fraction of the resolution per
 * axis (1/16 of the pixels), shown until the mode's first full pass lands. */
#define VIEW_LOW_DIV 4
#define VIEW_AOV_STRIDE 8 /* per pixel: albedo sum (3), normal sum (3), depth sum, depth hits */

typedef struct View {
    const CliArgs *args;
    CstScene *scene;
    CstRenderSettings base; /* the command line's settings, unresolved */
    int w, h;
    double out_exposure;    /* the render's 2^exposure, applied to saved linear images */
    CstCameraDesc cam;
    CstCameraDesc cam0;     /* the scene's camera: a checkpoint needs it unmoved */
    CstFilm *acc;           /* the passes' films added (cst_film_add): what a checkpoint writes */
    ViewMode mode;
    ViewPreview preview;
    bool error_view;
    double exposure;        /* display exposure in stops (keys + and -) */
    int max_spp;            /* --spp: stop refining there; 0 = never */
    /* The accumulation of the current mode and camera: the per-pass films' sums, so the
     * mean after N passes is the one a render of N samples holds (cst_render's
     * first_sample). SPPM instead re-renders 1, 2, 4, ... iterations and keeps the last. */
    int spp;
    double *sum, *sum_sq, *aov;
    double samples, seconds; /* of the passes accumulated: samples/s */
    double error_estimate;   /* view_error_estimate after the last pass (-1: none) */
    bool dirty, quit, failed;
    char fail_msg[256];
    float *low;              /* the low-resolution preview, w/VIEW_LOW_DIV x h/VIEW_LOW_DIV x 3 */
    int lw, lh;
    bool low_pending, low_ready;
    /* display */
    SDL_Window *win;
    SDL_Renderer *ren;
    SDL_Texture *tex;
    uint32_t *argb;
    float *linear;           /* the shown image before tone mapping, w x h x 3 */
    uint8_t srgb_lut[4096];
    bool shown_dirty;
    double last_title;
    /* input */
    ViewScript script;
    int saves;
    double t_loaded, t_window, first_image_ms; /* clock: scene loaded, window open, first image (ms after load) */
    int exit_code;
    /* click focus: a left press not (yet) a drag; a pick waiting for the render to stop */
    bool press, press_moved;
    bool focus_pending;
    int focus_x, focus_y;    /* film pixel of the pending pick */
    bool explain_pending; int explain_x, explain_y; /* a right click (script: explain X Y) */
    int cameras;             /* camera files written by the c key */
    CliTev *tev;             /* --display: the stream, NULL = none */
    float *tev_rgb;
    /* photon mode: the maps, built once for the scene and kept across passes and camera
     * moves (CstRenderSettings.photon_cache); their positions for the points (key o) */
    CstPhotonCache *photons;
    bool show_photons;
    float *photon_xyz[2];    /* global, caustic: x y z per photon */
    size_t photon_n[2];
    int photon_fetched;      /* cst_photon_cache_builds when photon_xyz was filled */
    /* The disagreement map (keys r and 0): a pinned reference, one mode's pixel means and
     * the variances of those means for one camera, and the current mode's accumulation
     * tested against it block by block as `caustic verify` tests two integrators. */
    float *ref_mean, *ref_var, *cur_mean, *cur_var; /* w x h x 3 each */
    double *block_z;         /* per VIEW_DIFF_BLOCK block: the largest |z| over the channels */
    int ref_spp;             /* 0 = nothing pinned */
    ViewMode ref_mode;
    CstCameraDesc ref_cam;
    bool diff_view;
    bool diff_ok;            /* diff and diff_z_crit hold the last comparison */
    CstImageComparison diff;
    double diff_z_crit;
    char diff_why[160];      /* when !diff_ok: why nothing was compared */
} View;

/* The disagreement map's blocks (pixels a side) and family-wise false-alarm rate, as
 * `caustic verify`'s defaults. */
#define VIEW_DIFF_BLOCK 16
#define VIEW_DIFF_ALPHA 0.01

/* ------------------------------------------------------------ camera moves (view_camera.c) */

static void view_orbit(View *v, double dx, double dy)
{
    view_camera_orbit(&v->cam, v->h, dx, dy);
    v->dirty = true;
}

static void view_pan(View *v, double dx, double dy)
{
    view_camera_pan(&v->cam, v->h, dx, dy);
    v->dirty = true;
}

static void view_dolly(View *v, double steps)
{
    if (view_camera_dolly(&v->cam, steps)) v->dirty = true;
}

/* ------------------------------------------------------------ accumulation */

static void view_restart(View *v)
{
    CstError err = {0};
    if (cst_scene_set_camera(v->scene, &v->cam, &err) != CST_OK) {
        /* Only reachable through a degenerate drag: undo it. */
        fprintf(stderr, "caustic: view: %s\n", err.msg);
        cst_scene_camera(v->scene, &v->cam);
    }
    v->spp = 0;
    v->error_estimate = -1.0;
    v->samples = v->seconds = 0.0;
    v->failed = false;
    v->dirty = false;
    v->low_pending = true;
    v->low_ready = false;
    v->shown_dirty = true;
}

static int view_progress(void *user, double fraction, double elapsed);
static double view_error_estimate(const View *v);

/* The settings of the mode's next pass (or of the low-resolution preview). */
static CstRenderSettings view_pass_settings(const View *v, bool low)
{
    CstRenderSettings s = v->base;
    s.width = low ? (v->w + VIEW_LOW_DIV - 1) / VIEW_LOW_DIV : v->w;
    s.height = low ? (v->h + VIEW_LOW_DIV - 1) / VIEW_LOW_DIV : v->h;
    s.time_limit = 0.0;
    for (int k = 0; k < 4; k++) s.crop[k] = 0; /* the whole image */
    s.aovs = 0;
    s.progress = view_progress;
    s.progress_user = (void *)v;
    s.progress_phase = NULL;
    ViewMode mode = low ? VIEW_PREVIEW : v->mode;
    s.integrator = VIEW_MODE_INTEGRATORS[mode];
    s.photon_cache = v->photons; /* photon mode: its maps built once, not every pass */
    if (mode == VIEW_PREVIEW) {
        /* The first hit's AOVs are the preview; one bounce of path tracing is the
         * cheapest integrator that records them. */
        s.max_depth = 1;
        s.aovs = CST_AOV_ALBEDO | CST_AOV_NORMAL | CST_AOV_DEPTH;
    }
    if (mode == VIEW_SPPM) {
        s.spp = v->spp ? 2 * v->spp : 1;
        s.first_sample = 0;
    } else {
        s.spp = 1;
        s.first_sample = low ? 0 : v->spp;
    }
    return s;
}

/* Adds one pass's film to the sums (or, for SPPM, replaces them). */
static bool view_accumulate(View *v, const CstFilm *film, const CstRenderStats *st)
{
    const size_t n = (size_t)v->w * (size_t)v->h;
    const bool replace = v->mode == VIEW_SPPM;
    if (v->spp == 0) { /* the first pass since a restart */
        memset(v->sum, 0, 3 * n * sizeof *v->sum);
        memset(v->sum_sq, 0, 3 * n * sizeof *v->sum_sq);
    }
    const CstRenderSettings ps = view_pass_settings(v, false);
    view_state_add(&v->acc, v->scene, &ps, film, v->spp == 0, !replace && v->mode != VIEW_PREVIEW);
    for (int y = 0; y < v->h; y++)
        for (int x = 0; x < v->w; x++) {
            size_t i = 3 * ((size_t)y * (size_t)v->w + (size_t)x);
            double rgb[3];
            cst_film_pixel(film, x, y, rgb);
            for (int c = 0; c < 3; c++) {
                if (replace) v->sum[i + c] = rgb[c], v->sum_sq[i + c] = 0.0;
                else v->sum[i + c] += rgb[c], v->sum_sq[i + c] += rgb[c] * rgb[c];
            }
        }
    if (v->mode == VIEW_PREVIEW) {
        float *tmp = malloc(n * 3 * sizeof *tmp);
        CstError err = {0};
        if (!tmp) return false;
        if (v->spp == 0) memset(v->aov, 0, n * VIEW_AOV_STRIDE * sizeof *v->aov);
        const int aovs[3] = {CST_AOV_ALBEDO, CST_AOV_NORMAL, CST_AOV_DEPTH};
        for (int a = 0; a < 3; a++) {
            if (cst_film_aov_pixels(film, aovs[a], tmp, &err) != CST_OK) {
                free(tmp);
                return false;
            }
            for (size_t p = 0; p < n; p++) {
                double *o = &v->aov[VIEW_AOV_STRIDE * p];
                if (a < 2)
                    for (int c = 0; c < 3; c++) o[3 * a + c] += (double)tmp[3 * p + (size_t)c];
                else if (isfinite(tmp[p]))
                    o[6] += (double)tmp[p], o[7] += 1.0;
            }
        }
        free(tmp);
    }
    v->spp = replace ? st->spp : v->spp + 1;
    if (replace) v->samples = (double)st->samples, v->seconds = st->seconds;
    else v->samples += (double)st->samples, v->seconds += st->seconds;
    v->error_estimate = view_error_estimate(v);
    v->shown_dirty = true;
    return true;
}

/* ------------------------------------------------------------ the shown image */

/* The mean of pixel i (3 channels) as cst_film_pixel computes it for a render of spp
 * samples: the sum times 1 / spp, then scaled as cst_film_write scales. */
static void view_mean(const View *v, size_t i, double out_scale, float rgb[3])
{
    double inv = v->mode == VIEW_SPPM ? 1.0 : v->spp > 0 ? 1.0 / v->spp : 0.0;
    for (int c = 0; c < 3; c++) {
        rgb[c] = (float)(v->sum[3 * i + (size_t)c] * inv);
        if (out_scale != 1.0) rgb[c] = (float)((double)rgb[c] * out_scale);
    }
}

/* A false-colour ramp over t in [0, 1]: black, blue, cyan, green, yellow, red. */
static void view_ramp(double t, float rgb[3])
{
    static const float STOPS[6][3] = {{0, 0, 0}, {0, 0, 1}, {0, 1, 1}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}};
    t = fmin(fmax(t, 0.0), 1.0) * 5.0;
    int k = t >= 5.0 ? 4 : (int)t;
    float a = (float)(t - k);
    for (int c = 0; c < 3; c++) rgb[c] = STOPS[k][c] * (1.0f - a) + STOPS[k + 1][c] * a;
}

/* The relative error of pixel i's mean: the standard error of its luminance over the
 * luminance (floored at 1e-3 so black pixels do not dominate), from the passes' sums of
 * squares; shown on a log scale from 0.1% (black) to 100% (red). */
/* Pixel i's relative error: the standard error of its luminance's mean over the mean (from
 * the passes' sums of squares; a mean below 1e-3 counts as 1e-3); -1 where there is none
 * (SPPM, fewer than 2 passes). */
static double view_rel_error(const View *v, size_t i)
{
    static const double Y[3] = {0.2126, 0.7152, 0.0722}; /* Rec. 709 luminance */
    double n = v->spp, mean = 0.0, var = 0.0;
    if (v->mode == VIEW_SPPM || n < 2.0) return -1.0;
    for (int c = 0; c < 3; c++) {
        double m = v->sum[3 * i + (size_t)c] / n;
        double s2 = (v->sum_sq[3 * i + (size_t)c] - n * m * m) / (n - 1.0);
        mean += Y[c] * m;
        var += Y[c] * Y[c] * (s2 > 0.0 ? s2 : 0.0) / n; /* channels taken as independent */
    }
    return sqrt(var) / fmax(mean, 1e-3);
}

static void view_error_pixel(const View *v, size_t i, float rgb[3])
{
    double rel = view_rel_error(v, i);
    if (rel < 0.0) {
        rgb[0] = rgb[1] = rgb[2] = 0.0f;
        return;
    }
    view_ramp(rel > 0.0 ? (log10(rel) + 3.0) / 3.0 : 0.0, rgb);
}

/* The status line's estimated error: the root mean square over the pixels of their
 * relative errors (view_rel_error); -1 where there is none. */
static double view_error_estimate(const View *v)
{
    const size_t n = (size_t)v->w * (size_t)v->h;
    double sum = 0.0;
    if (v->mode == VIEW_PREVIEW) return -1.0; /* its image is the AOVs' */
    for (size_t i = 0; i < n; i++) {
        double rel = view_rel_error(v, i);
        if (rel < 0.0) return -1.0;
        sum += rel * rel;
    }
    return n ? sqrt(sum / (double)n) : -1.0;
}

/* The preview of pixel i from the AOV sums: eye light is albedo times |cos| between the
 * normal and the eye ray (a headlight at the camera), depth is 1 / (1 + d / d_target). */
static void view_preview_pixel(const View *v, int x, int y, float rgb[3])
{
    const double *a = &v->aov[VIEW_AOV_STRIDE * ((size_t)y * (size_t)v->w + (size_t)x)];
    double inv = v->spp > 0 ? 1.0 / v->spp : 0.0, n[3] = {a[3], a[4], a[5]};
    double nl = view_v3_norm(n);
    switch (v->preview) {
    case VIEW_NORMALS:
        for (int c = 0; c < 3; c++) rgb[c] = nl > 0.0 ? (float)(0.5 * n[c] + 0.5) : 0.0f;
        return;
    case VIEW_ALBEDO:
        for (int c = 0; c < 3; c++) rgb[c] = (float)(a[c] * inv);
        return;
    case VIEW_DEPTH: {
        double f[3], r[3], u[3], dist = view_camera_frame(&v->cam, f, r, u);
        float d = a[7] > 0.0 ? (float)(1.0 / (1.0 + a[6] / a[7] / dist)) : 0.0f;
        rgb[0] = rgb[1] = rgb[2] = d;
        return;
    }
    default: break;
    }
    /* The eye ray through the pixel centre (pinhole; orthographic: the view axis). */
    double f[3], r[3], u[3], d[3];
    view_camera_frame(&v->cam, f, r, u);
    double t = tan((double)v->cam.fov * VIEW_PI / 360.0), aspect = (double)v->w / v->h;
    double sx = (2.0 * (x + 0.5) / v->w - 1.0) * t * aspect * (v->cam.mirror ? -1.0 : 1.0);
    double sy = (1.0 - 2.0 * (y + 0.5) / v->h) * t;
    for (int k = 0; k < 3; k++)
        d[k] = v->cam.type == CST_CAMERA_ORTHOGRAPHIC ? f[k] : f[k] + sx * r[k] + sy * u[k];
    view_v3_norm(d);
    double cosv = nl > 0.0 ? fabs(view_v3_dot(n, d)) : 0.0;
    for (int c = 0; c < 3; c++) rgb[c] = (float)(a[c] * inv * cosv);
}

/* The photon positions from the cache, again after each (re)build. */
static void view_photons_fetch(View *v)
{
    int builds = cst_photon_cache_builds(v->photons);
    if (builds == v->photon_fetched) return;
    for (int m = 0; m < 2; m++) {
        size_t n = cst_photon_cache_positions(v->photons, m, NULL, 0);
        float *xyz = n ? malloc(3 * n * sizeof *xyz) : NULL;
        free(v->photon_xyz[m]);
        v->photon_xyz[m] = xyz;
        v->photon_n[m] = xyz ? cst_photon_cache_positions(v->photons, m, xyz, n) : 0;
    }
    v->photon_fetched = builds;
}

/* Key o in the photon mode: the photons as points over img (w x h x 3), projected through
 * the camera (the pinhole of a thin lens; the pixel whose centre ray is nearest), the
 * global map's in orange, the caustic map's over them in cyan, each colour times k (so
 * that it shows as that colour after the display exposure). At most one global photon
 * in VIEW_PHOTON_EVERY pixels' worth is drawn (a stride through the map) so the image
 * stays visible under 200,000 of them; every caustic photon is. */
#define VIEW_PHOTON_EVERY 4
static void view_photon_points(View *v, float *img, float k)
{
    static const float COLOURS[2][3] = {{1.0f, 0.55f, 0.1f}, {0.2f, 0.8f, 1.0f}};
    if (!v->show_photons || v->mode != VIEW_PHOTON || v->error_view || v->diff_view || v->spp == 0) return;
    view_photons_fetch(v);
    double f[3], r[3], u[3];
    view_camera_frame(&v->cam, f, r, u);
    const bool ortho = v->cam.type == CST_CAMERA_ORTHOGRAPHIC;
    const double aspect = (double)v->w / v->h, sx = v->cam.mirror ? -1.0 : 1.0;
    const double half_h = ortho ? 0.5 * (double)v->cam.height : tan((double)v->cam.fov * VIEW_PI / 360.0);
    for (int m = 0; m < 2; m++) {
        size_t n = v->photon_n[m], cap = (size_t)v->w * (size_t)v->h / VIEW_PHOTON_EVERY + 1;
        size_t stride = m == 0 && n > cap ? n / cap : 1;
        for (size_t i = 0; i < n; i += stride) {
            const float *p = &v->photon_xyz[m][3 * i];
            double d[3] = {(double)p[0] - (double)v->cam.position[0], (double)p[1] - (double)v->cam.position[1],
                           (double)p[2] - (double)v->cam.position[2]};
            double z = view_v3_dot(d, f);
            if (!(z > 0.0)) continue; /* behind the camera */
            double a = view_v3_dot(d, r) / (ortho ? 1.0 : z), b = view_v3_dot(d, u) / (ortho ? 1.0 : z);
            /* The inverse of the pixel centre ray of view_preview_pixel. */
            double x = (a * sx / (half_h * aspect) + 1.0) * 0.5 * v->w, y = (1.0 - b / half_h) * 0.5 * v->h;
            if (!(x >= 0.0 && x < v->w && y >= 0.0 && y < v->h)) continue;
            float *o = &img[3 * ((size_t)y * (size_t)v->w + (size_t)x)];
            for (int c = 0; c < 3; c++) o[c] = COLOURS[m][c] * k;
        }
    }
}

/* ------------------------------------------------------------ the disagreement map */

/* The current accumulation's pixel means and variances of the means (s^2 / n from the
 * passes' sums of squares); false where it has none: the preview, SPPM (one film, not a
 * sum of passes), fewer than 2 passes. */
static bool view_moments(const View *v, float *mean, float *var)
{
    if (v->mode == VIEW_PREVIEW || v->mode == VIEW_SPPM || v->spp < 2) return false;
    const double n = v->spp;
    const size_t count = 3 * (size_t)v->w * (size_t)v->h;
    for (size_t k = 0; k < count; k++) {
        double m = v->sum[k] / n, s2 = (v->sum_sq[k] - n * m * m) / (n - 1.0);
        mean[k] = (float)m;
        var[k] = (float)((s2 > 0.0 ? s2 : 0.0) / n);
    }
    return true;
}

/* Key r: the current accumulation becomes the reference. */
static void view_pin(View *v)
{
    const size_t n = 3 * (size_t)v->w * (size_t)v->h;
    if (!v->ref_mean) {
        v->ref_mean = malloc(n * sizeof *v->ref_mean);
        v->ref_var = malloc(n * sizeof *v->ref_var);
        v->cur_mean = malloc(n * sizeof *v->cur_mean);
        v->cur_var = malloc(n * sizeof *v->cur_var);
        v->block_z = malloc((size_t)cst_compare_blocks_x(v->w, VIEW_DIFF_BLOCK) *
                            (size_t)cst_compare_blocks_y(v->h, VIEW_DIFF_BLOCK) * sizeof *v->block_z);
        if (!v->ref_mean || !v->ref_var || !v->cur_mean || !v->cur_var || !v->block_z) {
            printf("view: out of memory for the disagreement map\n");
            fflush(stdout);
            return;
        }
    }
    if (!view_moments(v, v->ref_mean, v->ref_var)) {
        printf("view: nothing to pin: %s has no per-pixel variance %s\n", VIEW_MODE_NAMES[v->mode],
               v->mode == VIEW_PREVIEW || v->mode == VIEW_SPPM ? "(pin whitted, path, light, photon, bdpt or vcm)"
                                                               : "before its second pass");
        fflush(stdout);
        return;
    }
    v->ref_spp = v->spp;
    v->ref_mode = v->mode;
    v->ref_cam = v->cam;
    printf("view: reference pinned: %s, %d spp\n", VIEW_MODE_NAMES[v->mode], v->spp);
    fflush(stdout);
    v->shown_dirty = true;
}

/* Tests the current accumulation against the reference (v->diff, v->block_z) and fills
 * v->linear with the map (compare_map_colour's colours: black to blue to yellow under
 * z_crit, red above it), or black with the reason in v->diff_why. */
static void view_diff_compose(View *v)
{
    CstError err = {0};
    char *why = v->diff_why;
    const size_t size = sizeof v->diff_why;
    v->diff_ok = false;
    why[0] = '\0';
    if (v->ref_spp == 0) snprintf(why, size, "no reference pinned (key r)");
    else if (memcmp(&v->ref_cam, &v->cam, sizeof v->cam) != 0)
        snprintf(why, size, "the reference (%s) was pinned for another camera", VIEW_MODE_NAMES[v->ref_mode]);
    else if (!view_moments(v, v->cur_mean, v->cur_var))
        snprintf(why, size, "%s has no per-pixel variance%s", VIEW_MODE_NAMES[v->mode],
                 v->mode == VIEW_PREVIEW || v->mode == VIEW_SPPM ? "" : " yet");
    else if (cst_image_compare(v->cur_mean, v->ref_mean, v->w, v->h, v->cur_var, v->ref_var, VIEW_DIFF_BLOCK,
                               &v->diff, v->block_z, &err) != CST_OK)
        snprintf(why, size, "%.150s", err.msg);
    if (why[0]) {
        memset(v->linear, 0, 3 * (size_t)v->w * (size_t)v->h * sizeof *v->linear);
        return;
    }
    /* Sidak-corrected over the pair's tests: 3 channels x (the image mean + each block). */
    v->diff_z_crit = cst_compare_z_critical(VIEW_DIFF_ALPHA, (double)cst_compare_tests_per_pair(v->w, v->h, VIEW_DIFF_BLOCK));
    cst_compare_map_image(v->block_z, v->w, v->h, VIEW_DIFF_BLOCK, v->diff_z_crit, v->linear);
    v->diff_ok = true;
}

/* The comparison as one line (status and title): "bdpt vs path (64 spp): agree, ...". */
static void view_diff_line(const View *v, char *out, size_t size)
{
    if (!v->diff_ok) {
        snprintf(out, size, "disagreement map: %s", v->diff_why[0] ? v->diff_why : "nothing compared yet");
        return;
    }
    double zi = 0.0;
    for (int c = 0; c < 3; c++) zi = fmax(zi, fabs(v->diff.z_mean[c]));
    snprintf(out, size, "%s vs %s (%d spp): %s, largest block |z| %.2f, image mean |z| %.2f, z_crit %.2f",
             VIEW_MODE_NAMES[v->mode], VIEW_MODE_NAMES[v->ref_mode], v->ref_spp,
             v->diff.max_abs_z > v->diff_z_crit || zi > v->diff_z_crit ? "DISAGREE" : "agree", v->diff.max_abs_z, zi,
             v->diff_z_crit);
}

/* Fills v->linear with what the mode shows (before the display exposure). */
static void view_compose(View *v)
{
    for (int y = 0; y < v->h; y++)
        for (int x = 0; x < v->w; x++) {
            size_t i = (size_t)y * (size_t)v->w + (size_t)x;
            float *o = &v->linear[3 * i];
            if (v->spp == 0) { /* the low-resolution first image, or black */
                if (!v->low_ready) { o[0] = o[1] = o[2] = 0.0f; continue; }
                int lx = x / VIEW_LOW_DIV, ly = y / VIEW_LOW_DIV;
                memcpy(o, &v->low[3 * ((size_t)ly * (size_t)v->lw + (size_t)lx)], 3 * sizeof *o);
            } else if (v->diff_view) {
                continue; /* view_diff_compose below */
            } else if (v->error_view) {
                view_error_pixel(v, i, o);
            } else if (v->mode == VIEW_PREVIEW) {
                view_preview_pixel(v, x, y, o);
            } else {
                view_mean(v, i, 1.0, o);
            }
        }
    if (v->diff_view && v->spp > 0) view_diff_compose(v);
}

static void view_title(View *v)
{
    char title[256], what[64];
    if (v->mode == VIEW_PREVIEW) snprintf(what, sizeof what, "preview (%s)", VIEW_PREVIEW_NAMES[v->preview]);
    else snprintf(what, sizeof what, "%s", VIEW_MODE_NAMES[v->mode]);
    double rate = v->seconds > 0.0 ? v->samples / v->seconds / 1e6 : 0.0;
    if (v->failed)
        snprintf(title, sizeof title, "caustic view - %s - %.160s", what, v->fail_msg);
    else if (v->diff_view) {
        char line[200];
        view_diff_line(v, line, sizeof line);
        snprintf(title, sizeof title, "caustic view - %.200s", line);
    } else {
        char err[48] = "";
        if (v->spp >= 2 && v->error_estimate >= 0.0)
            snprintf(err, sizeof err, " - error %.3g%%", 100.0 * v->error_estimate);
        snprintf(title, sizeof title, "caustic view - %s%s - %d %s - %.2f M samples/s%s - exposure %+.1f",
                 what, v->error_view ? " relative error" : "", v->spp, v->mode == VIEW_SPPM ? "iterations" : "spp",
                 rate, err, v->exposure);
    }
    SDL_SetWindowTitle(v->win, title);
}

/* Tone maps (exposure, clamp, the sRGB curve through a 4096-entry table) and shows. */
static void view_present(View *v)
{
    if (!v->shown_dirty) return;
    v->shown_dirty = false;
    view_compose(v);
    const float scale = (float)(v->error_view || v->diff_view ? 1.0 : exp2(v->exposure));
    view_photon_points(v, v->linear, 1.0f / scale);
    size_t n = (size_t)v->w * (size_t)v->h;
    for (size_t i = 0; i < n; i++) {
        uint32_t px = 0xff000000u;
        for (int c = 0; c < 3; c++) {
            float x = v->linear[3 * i + (size_t)c] * scale;
            int k = x > 0.0f ? (x >= 1.0f ? 4095 : (int)(x * 4095.0f + 0.5f)) : 0;
            px |= (uint32_t)v->srgb_lut[k] << (16 - 8 * c);
        }
        v->argb[i] = px;
    }
    SDL_UpdateTexture(v->tex, NULL, v->argb, v->w * 4);
    SDL_RenderClear(v->ren);
    SDL_RenderCopy(v->ren, v->tex, NULL, NULL);
    SDL_RenderPresent(v->ren);
    view_title(v);
    if (v->first_image_ms < 0.0 && v->low_ready) {
        double now = cli_clock_seconds();
        v->first_image_ms = (now - v->t_loaded) * 1e3;
        if (!v->args->quiet)
            fprintf(stderr, "caustic: view: first image %.0f ms after loading the scene (%.0f ms after the "
                    "window opened)\n", v->first_image_ms, (now - v->t_window) * 1e3);
    }
}

/* ------------------------------------------------------------ click focus */

static CstStatus view_pick_crop_error(CstError *err)
{
    snprintf(err->msg, sizeof err->msg, "the pick's film is not the one pixel cropped");
    return CST_ERR_INVALID_ARG;
}

/* A click at film pixel (x, y): asks for a pick, made by view_focus_pick once no pass is
 * running (the current one is cancelled: the scene's camera cannot change during a render). */
static void view_click(View *v, int x, int y)
{
    if (x < 0 || y < 0 || x >= v->w || y >= v->h) return;
    v->focus_pending = true;
    v->focus_x = x;
    v->focus_y = y;
    v->dirty = true;
}

/* The thin lens's plane of focus through what pixel (x, y) sees: the first hit's depth
 * along the view axis (the plane of focus is perpendicular to it: camera.c), from the depth
 * AOV of a one-pixel crop rendered through the pinhole of the same camera (the pixel's
 * rays, not the lens's: 4 samples, their hits' mean depth). Nothing hit, or an orthographic
 * camera: the focus stays, with a message. Always followed by view_restart. */
static void view_focus_pick(View *v)
{
    const int x = v->focus_x, y = v->focus_y;
    v->focus_pending = false;
    if (v->cam.type == CST_CAMERA_ORTHOGRAPHIC) {
        printf("view: click (%d, %d): an orthographic camera has no focus\n", x, y);
        fflush(stdout);
        return;
    }
    CstCameraDesc pin = v->cam;
    pin.aperture_radius = 0.0f;
    pin.focus_distance = 0.0f;
    CstError err = {0};
    CstRenderSettings s = view_pass_settings(v, false);
    s.integrator = CST_INTEGRATOR_PATH;
    s.max_depth = 1;
    s.aovs = CST_AOV_DEPTH;
    s.spp = 4;
    s.first_sample = 0;
    s.crop[0] = x, s.crop[1] = x + 1, s.crop[2] = y, s.crop[3] = y + 1;
    s.progress = NULL;
    s.progress_user = NULL;
    CstFilm *film = NULL;
    CstRenderStats st = {0};
    float d = 0.0f; /* the film holds the crop only: its one pixel */
    CstStatus status = cst_scene_set_camera(v->scene, &pin, &err);
    if (status == CST_OK) status = cst_render(v->scene, &s, &film, &st, &err);
    if (status == CST_ERR_NONFINITE) status = CST_OK;
    if (status == CST_OK && (cst_film_width(film) != 1 || cst_film_height(film) != 1))
        status = view_pick_crop_error(&err);
    if (status == CST_OK) status = cst_film_aov_pixels(film, CST_AOV_DEPTH, &d, &err);
    cst_film_destroy(film);
    if (status != CST_OK) {
        fprintf(stderr, "caustic: view: click (%d, %d): %s\n", x, y, err.msg);
    } else if (!(isfinite(d) && d > 0.0f)) {
        printf("view: click (%d, %d): nothing there; the focus stays\n", x, y);
    } else {
        v->cam.focus_distance = d;
        printf("view: focus distance %.9g (click at %d, %d)%s\n", (double)d, x, y,
               v->cam.aperture_radius > 0.0f ? "" : " (a pinhole: sharp at every distance)");
    }
    fflush(stdout);
    v->dirty = true; /* view_restart sets the camera back (with its new focus) */
}

/* ------------------------------------------------------------ click to explain */

/* A right click at film pixel (x, y): its explanation once no pass is running. */
static void view_explain_click(View *v, int x, int y)
{
    if (x >= 0 && y >= 0 && x < v->w && y < v->h) v->explain_pending = true, v->explain_x = x, v->explain_y = y;
}
/* The explanation in the current mode and camera at the accumulation's last sample. */
static void view_explain(View *v)
{
    v->explain_pending = false;
    CstRenderSettings s = view_pass_settings(v, false);
    s.progress = NULL, s.progress_user = NULL, s.photon_cache = NULL;
    cli_explain_view(v->scene, &s, v->explain_x, v->explain_y, v->spp > 0 && v->mode != VIEW_SPPM ? v->spp - 1 : 0,
                     v->mode == VIEW_PREVIEW ? NULL : VIEW_MODE_NAMES[v->mode]);
}

/* ------------------------------------------------------------ saving, camera JSON */

/* The shown image, w x h x 3 floats: linear (for EXR, PFM and the tev stream) the mode's
 * means times the render's 2^exposure (the preview and error views as shown), else times
 * the display exposure (what the window shows before the sRGB curve). */
static void view_image(View *v, float *img, bool linear)
{
    size_t n = (size_t)v->w * (size_t)v->h;
    view_compose(v);
    const bool false_colour = v->error_view || v->diff_view;
    bool raw = v->spp > 0 && !false_colour && v->mode != VIEW_PREVIEW;
    double scale = linear ? (raw ? v->out_exposure : 1.0) : (false_colour ? 1.0 : exp2(v->exposure));
    for (size_t i = 0; i < n; i++) {
        if (raw) view_mean(v, i, scale, &img[3 * i]);
        else for (int c = 0; c < 3; c++) img[3 * i + (size_t)c] = (float)((double)v->linear[3 * i + (size_t)c] * scale);
    }
}

/* --display: the linear image to tev after each pass (what `save x.exr` would write). */
static void view_stream(View *v)
{
    if (!cli_tev_connected(v->tev)) return;
    if (!v->tev_rgb && !(v->tev_rgb = malloc((size_t)v->w * (size_t)v->h * 3 * sizeof *v->tev_rgb))) return;
    view_image(v, v->tev_rgb, true);
    cli_tev_send(v->tev, v->tev_rgb, v->w, v->h);
}

/* The shown image to path: EXR and PFM linear (the mode's means times the render's
 * exposure, as `caustic render` writes them; the preview and error views as shown), PNG
 * as displayed (display exposure, sRGB). Atomic, through cst_image_write. */
static bool view_save(View *v, const char *path)
{
    CstError err = {0};
    if (!cst_image_path_writable(path)) {
        fprintf(stderr, "caustic: error: view: save '%s': expected a name ending in .png, .exr or .pfm\n", path);
        return false;
    }
    size_t n = (size_t)v->w * (size_t)v->h;
    float *img = malloc(n * 3 * sizeof *img);
    if (!img) return false;
    bool linear = cst_image_path_is_exr(path) || !cli_has_suffix(path, ".png");
    view_image(v, img, linear);
    if (!linear) view_photon_points(v, img, 1.0f); /* a PNG is what the window shows */
    CstStatus st = cst_image_write(path, img, v->w, v->h, &err);
    free(img);
    if (st != CST_OK) {
        cli_print_error(&err, st);
        return false;
    }
    printf("view: saved %s (%s, %d %s)\n", path, VIEW_MODE_NAMES[v->mode], v->spp,
           v->mode == VIEW_SPPM ? "iterations" : "spp");
    fflush(stdout);
    return true;
}

/* The camera as the JSON scene format's "camera" section (docs/scene-format.md), on f.
 * %.9g: every float reads back as the same float. */
static void view_write_camera(const View *v, FILE *f)
{
    const CstCameraDesc *c = &v->cam;
    const char *type = c->type == CST_CAMERA_ORTHOGRAPHIC ? "orthographic"
                       : c->aperture_radius > 0.0f      ? "thinlens" : "pinhole";
    fprintf(f, "\"camera\": {\"type\": \"%s\", \"position\": [%.9g, %.9g, %.9g], \"look_at\": [%.9g, %.9g, %.9g], "
           "\"up\": [%.9g, %.9g, %.9g]", type, (double)c->position[0], (double)c->position[1],
           (double)c->position[2], (double)c->look_at[0], (double)c->look_at[1], (double)c->look_at[2],
           (double)c->up[0], (double)c->up[1], (double)c->up[2]);
    if (c->type == CST_CAMERA_ORTHOGRAPHIC) fprintf(f, ", \"height\": %.9g", (double)c->height);
    else fprintf(f, ", \"fov\": %.9g", (double)c->fov);
    if (c->aperture_radius > 0.0f)
        fprintf(f, ", \"aperture_radius\": %.9g, \"focus_distance\": %.9g", (double)c->aperture_radius,
                (double)c->focus_distance);
    fprintf(f, "}");
}

/* The camera to path as a JSON object {"camera": {...}}: a scene file's camera section,
 * to paste into the scene (or merge with a script). Written to path.tmp, then renamed. */
static bool view_save_camera(const View *v, const char *path)
{
    char tmp[4096];
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    FILE *f = fopen(tmp, "w");
    bool ok = f != NULL;
    if (ok) {
        fprintf(f, "{");
        view_write_camera(v, f);
        fprintf(f, "}\n");
        ok = !ferror(f);
        ok = fclose(f) == 0 && ok;
        ok = ok && rename(tmp, path) == 0;
        if (!ok) remove(tmp);
    }
    if (!ok) {
        fprintf(stderr, "caustic: error: view: writing the camera to '%s': %s\n", path, strerror(errno));
        return false;
    }
    printf("view: camera saved %s\n", path);
    fflush(stdout);
    return true;
}

/* The c key: the camera on stdout, and to caustic-view-camera-NNN.json. */
static void view_print_camera(View *v)
{
    view_write_camera(v, stdout);
    printf("\n");
    fflush(stdout);
    char name[64];
    snprintf(name, sizeof name, "caustic-view-camera-%03d.json", v->cameras++);
    view_save_camera(v, name);
}

static void view_status(View *v)
{
    printf("view: mode %s%s spp %d samples %.0f first_image_ms %.1f photon_maps_built %d error %.6g\n",
           VIEW_MODE_NAMES[v->mode], v->error_view ? " (relative error)" : "", v->spp, v->samples, v->first_image_ms,
           cst_photon_cache_builds(v->photons), v->error_estimate);
    if (v->diff_view) { /* the comparison of the accumulation as it stands now */
        char line[240];
        if (v->spp > 0) view_diff_compose(v);
        view_diff_line(v, line, sizeof line);
        printf("view: %s\n", line);
    }
    fflush(stdout);
}

/* k: the mode's accumulation as a state file for `caustic render --resume` (view_state.c). */
static void view_checkpoint(View *v)
{
    const ViewCheckpoint k = {v->scene, v->acc, v->spp, v->args->scene_path, VIEW_MODE_NAMES[v->mode],
                              VIEW_MODE_INTEGRATORS[v->mode], v->mode == VIEW_PREVIEW || v->mode == VIEW_SPPM,
                              view_camera_moved(&v->cam, &v->cam0)};
    const CstRenderSettings ps = view_pass_settings(v, false);
    char name[64];
    snprintf(name, sizeof name, "caustic-view-%03d.state", v->saves);
    if (view_state_checkpoint(name, &ps, &k)) v->saves++;
}

/* ------------------------------------------------------------ input */

static void view_key(View *v, SDL_Keycode key)
{
    if (key >= '1' && key <= '8') {
        ViewMode m = (ViewMode)(key - '0');
        if (m == VIEW_PREVIEW && v->mode == VIEW_PREVIEW && !v->error_view) {
            v->preview = (v->preview + 1) % VIEW_PREVIEW_KINDS;
            v->shown_dirty = true;
        } else if (m != v->mode) {
            v->mode = m;
            v->dirty = true;
        }
        v->error_view = false;
        v->shown_dirty = true;
        return;
    }
    switch (key) {
    case '9': v->error_view = !v->error_view, v->diff_view = false; v->shown_dirty = true; break;
    case '0': v->diff_view = !v->diff_view, v->error_view = false; v->shown_dirty = true; break;
    case 'r': view_pin(v); break;
    case 'p': case '\t':
        if (v->mode == VIEW_PREVIEW) v->preview = (v->preview + 1) % VIEW_PREVIEW_KINDS;
        v->shown_dirty = true;
        break;
    case '+': case '=': case SDLK_KP_PLUS: v->exposure += 0.5; v->shown_dirty = true; break;
    case '-': case SDLK_KP_MINUS: v->exposure -= 0.5; v->shown_dirty = true; break;
    case '[': case ']':
        if (v->cam.type != CST_CAMERA_ORTHOGRAPHIC) {
            float fov = v->cam.fov + (key == '[' ? -5.0f : 5.0f);
            v->cam.fov = fov < 5.0f ? 5.0f : fov > 170.0f ? 170.0f : fov;
            v->dirty = true;
        }
        break;
    case 's': {
        char name[64];
        snprintf(name, sizeof name, "caustic-view-%03d.exr", v->saves);
        bool ok = view_save(v, name);
        snprintf(name, sizeof name, "caustic-view-%03d.png", v->saves++);
        if (ok) view_save(v, name);
        break;
    }
    case 'c': view_print_camera(v); break;
    case 'k': view_checkpoint(v); break;
    case 'o': v->show_photons = !v->show_photons; v->shown_dirty = true; break;
    case 'q': case SDLK_ESCAPE: v->quit = true; break;
    default: break;
    }
}

static void view_event(View *v, const SDL_Event *e)
{
    switch (e->type) {
    case SDL_QUIT: v->quit = true; break;
    case SDL_KEYDOWN: {
        SDL_Keycode k = e->key.keysym.sym;
        if (k == SDLK_EQUALS && (e->key.keysym.mod & KMOD_SHIFT)) k = '+';
        view_key(v, k);
        break;
    }
    case SDL_MOUSEBUTTONDOWN:
        if (e->button.button == SDL_BUTTON_LEFT) v->press = true, v->press_moved = false;
        break;
    case SDL_MOUSEBUTTONUP:
        /* A left click without a drag: the focus there (the window may show the film scaled). */
        if (e->button.button == SDL_BUTTON_LEFT && v->press && !v->press_moved) {
            int ww = 1, wh = 1;
            SDL_GetWindowSize(v->win, &ww, &wh);
            view_click(v, (int)((double)e->button.x * v->w / (ww > 0 ? ww : 1)),
                       (int)((double)e->button.y * v->h / (wh > 0 ? wh : 1)));
        }
        if (e->button.button == SDL_BUTTON_RIGHT) { /* the pixel's `caustic explain` */
            int ww = 1, wh = 1;
            SDL_GetWindowSize(v->win, &ww, &wh);
            view_explain_click(v, (int)((double)e->button.x * v->w / (ww > 0 ? ww : 1)),
                               (int)((double)e->button.y * v->h / (wh > 0 ? wh : 1)));
        }
        if (e->button.button == SDL_BUTTON_LEFT) v->press = false;
        break;
    case SDL_MOUSEMOTION: {
        uint32_t b = e->motion.state;
        bool shift = (SDL_GetModState() & KMOD_SHIFT) != 0;
        if (b & SDL_BUTTON_LMASK) v->press_moved = true;
        if ((b & SDL_BUTTON_MMASK) || ((b & SDL_BUTTON_LMASK) && shift)) view_pan(v, e->motion.xrel, e->motion.yrel);
        else if (b & SDL_BUTTON_LMASK) view_orbit(v, e->motion.xrel, e->motion.yrel);
        break;
    }
    case SDL_MOUSEWHEEL: view_dolly(v, e->wheel.y); break;
    case SDL_WINDOWEVENT: v->shown_dirty = true; break;
    default: break;
    }
}

/* Runs the script's commands up to the first that must wait (wait-spp not yet reached). */
static void view_script_step(View *v)
{
    ViewScript *s = &v->script;
    while (s->next < s->count && !v->quit) {
        const ViewScriptCmd *c = &s->cmds[s->next];
        if (c->op == VIEW_SCRIPT_WAIT_SPP) {
            if (v->failed) {
                fprintf(stderr, "caustic: error: view: script line %d: wait-spp %g in mode %s, which failed: %s\n",
                        c->line, c->a, VIEW_MODE_NAMES[v->mode], v->fail_msg);
                v->exit_code = CLI_EXIT_INTERNAL;
                v->quit = true;
                return;
            }
            if (v->dirty || v->spp < (int)c->a) return;
            s->next++;
            continue;
        }
        s->next++;
        switch (c->op) {
        case VIEW_SCRIPT_KEY: view_key(v, c->key == VIEW_KEY_ESCAPE ? SDLK_ESCAPE : c->key); break;
        case VIEW_SCRIPT_SAVE:
            if (!view_save(v, c->path)) {
                v->exit_code = CLI_EXIT_INTERNAL;
                v->quit = true;
            }
            break;
        case VIEW_SCRIPT_ORBIT: view_orbit(v, c->a, c->b); break;
        case VIEW_SCRIPT_PAN: view_pan(v, c->a, c->b); break;
        case VIEW_SCRIPT_DOLLY: view_dolly(v, c->a); break;
        case VIEW_SCRIPT_STATUS: view_status(v); break;
        case VIEW_SCRIPT_QUIT: v->quit = true; break;
        case VIEW_SCRIPT_CLICK: view_click(v, (int)c->a, (int)c->b); break;
        case VIEW_SCRIPT_EXPLAIN: view_explain_click(v, (int)c->a, (int)c->b); break;
        case VIEW_SCRIPT_CAMERA:
            if (!view_save_camera(v, c->path)) {
                v->exit_code = CLI_EXIT_INTERNAL;
                v->quit = true;
            }
            break;
        case VIEW_SCRIPT_WAIT_SPP: break;
        }
        if (v->dirty || v->explain_pending) return; /* the restart (explanation) comes before the next command */
    }
}

/* Events and script; then the window, at most 10 times a second from inside a pass. */
static void view_poll(View *v)
{
    SDL_Event e;
    while (SDL_PollEvent(&e)) view_event(v, &e);
    if (!v->dirty && !v->explain_pending) view_script_step(v);
    view_present(v);
}

/* The passes' progress callback: the window stays live during a pass, and any change
 * cancels it (CST_ERR_CANCELLED) so the next pass starts from the new state. */
static int view_progress(void *user, double fraction, double elapsed)
{
    (void)fraction;
    (void)elapsed;
    View *v = user;
    view_poll(v);
    return v->dirty || v->quit;
}

/* ------------------------------------------------------------ the loop */

/* One render: the low-resolution preview or the mode's next pass. */
static void view_step(View *v)
{
    bool low = v->low_pending;
    CstRenderSettings s = view_pass_settings(v, low);
    CstFilm *film = NULL;
    CstRenderStats stats = {0};
    CstError err = {0};
    CstStatus st = cst_render(v->scene, &s, &film, &stats, &err);
    if (st == CST_ERR_NONFINITE) st = CST_OK; /* a pass's few NaNs: shown, counted in the render's stats */
    if (st == CST_ERR_CANCELLED) {
        cst_film_destroy(film);
        return;
    }
    if (st != CST_OK) {
        cst_film_destroy(film);
        if (low) { /* no preview (no AOVs for this scene?): go straight to the mode */
            v->low_pending = false;
            return;
        }
        snprintf(v->fail_msg, sizeof v->fail_msg, "%.200s", err.msg);
        fprintf(stderr, "caustic: error: view: %s: %s\n", VIEW_MODE_NAMES[v->mode], err.msg);
        v->failed = true;
        v->shown_dirty = true;
        return;
    }
    if (low) {
        v->low_pending = false;
        float *alb = malloc((size_t)v->lw * (size_t)v->lh * 3 * sizeof *alb);
        float *nrm = malloc((size_t)v->lw * (size_t)v->lh * 3 * sizeof *nrm);
        if (alb && nrm && cst_film_aov_pixels(film, CST_AOV_ALBEDO, alb, &err) == CST_OK &&
            cst_film_aov_pixels(film, CST_AOV_NORMAL, nrm, &err) == CST_OK) {
            /* Eye light at the view axis: enough for a first look. */
            double f[3], r[3], u[3];
            view_camera_frame(&v->cam, f, r, u);
            for (size_t i = 0; i < (size_t)v->lw * (size_t)v->lh; i++) {
                double n[3] = {(double)nrm[3 * i], (double)nrm[3 * i + 1], (double)nrm[3 * i + 2]};
                float k = (float)fabs(view_v3_dot(n, f));
                for (int c = 0; c < 3; c++) v->low[3 * i + (size_t)c] = alb[3 * i + (size_t)c] * k;
            }
            v->low_ready = true;
            v->shown_dirty = true;
        }
        free(alb);
        free(nrm);
    } else if (!view_accumulate(v, film, &stats)) {
        snprintf(v->fail_msg, sizeof v->fail_msg, "out of memory");
        v->failed = true;
    } else {
        view_stream(v);
    }
    cst_film_destroy(film);
}

static void view_loop(View *v)
{
    while (!v->quit) {
        view_poll(v);
        if (v->explain_pending && !v->quit) view_explain(v);
        if (v->focus_pending && !v->quit) view_focus_pick(v);
        if (v->dirty) view_restart(v);
        if (v->quit) break;
        bool done = v->failed || (v->max_spp > 0 && v->spp >= v->max_spp && !v->low_pending);
        if (done) {
            /* Nothing to refine: sleep until an event (the script runs between waits). */
            SDL_Event e;
            if (SDL_WaitEventTimeout(&e, 50)) view_event(v, &e);
            continue;
        }
        view_step(v);
    }
}

/* ------------------------------------------------------------ setup */

/* The display, a hidden window and its renderer, before the scene loads: SDL_Init and above
 * all the renderer's start-up (SDL_CreateRenderer: 240 ms under Xvfb with Mesa's software
 * OpenGL, 2026-12-08) would otherwise stand between the loaded scene and the first image
 * (issue 30: within 100 ms of load), and the window is there while a large scene loads. */
static int view_video_init(View *v)
{
    if (SDL_Init(SDL_INIT_VIDEO) != 0) {
        fprintf(stderr, "caustic: error: view: cannot open a window: %s (is DISPLAY set? headless: "
                        "xvfb-run caustic view ...)\n", SDL_GetError());
        return CLI_EXIT_USAGE;
    }
    v->win = SDL_CreateWindow("caustic view", SDL_WINDOWPOS_UNDEFINED, SDL_WINDOWPOS_UNDEFINED, 640, 480,
                              SDL_WINDOW_RESIZABLE | SDL_WINDOW_HIDDEN);
    if (v->win) v->ren = SDL_CreateRenderer(v->win, -1, 0);
    if (v->win && !v->ren) v->ren = SDL_CreateRenderer(v->win, -1, SDL_RENDERER_SOFTWARE);
    if (!v->ren) {
        fprintf(stderr, "caustic: error: view: cannot open a window: %s\n", SDL_GetError());
        return CLI_EXIT_INTERNAL;
    }
    /* One draw of a texture, so that the renderer's first-use costs (Mesa compiles its
     * shaders at the first draw: 44 ms under Xvfb) are paid here too, not by the first image. */
    SDL_Texture *t = SDL_CreateTexture(v->ren, SDL_PIXELFORMAT_ARGB8888, SDL_TEXTUREACCESS_STREAMING, 1, 1);
    if (t) {
        const uint32_t black = 0xff000000u;
        SDL_UpdateTexture(t, NULL, &black, 4);
        SDL_RenderClear(v->ren);
        SDL_RenderCopy(v->ren, t, NULL, NULL);
        SDL_RenderPresent(v->ren);
        SDL_DestroyTexture(t);
    }
    return CLI_EXIT_OK;
}

/* The window at the film's size (a big film shown scaled), shown, and the film's texture. */
static int view_open(View *v)
{
    int ww = v->w, wh = v->h;
    while (ww > 1600 || wh > 1000) ww /= 2, wh /= 2;
    SDL_SetWindowSize(v->win, ww > 0 ? ww : 1, wh > 0 ? wh : 1);
    SDL_ShowWindow(v->win);
    v->tex = SDL_CreateTexture(v->ren, SDL_PIXELFORMAT_ARGB8888, SDL_TEXTUREACCESS_STREAMING, v->w, v->h);
    if (!v->tex) {
        fprintf(stderr, "caustic: error: view: cannot open a window: %s\n", SDL_GetError());
        return CLI_EXIT_INTERNAL;
    }
    return CLI_EXIT_OK;
}

static void view_close(View *v)
{
    if (v->tex) SDL_DestroyTexture(v->tex);
    if (v->ren) SDL_DestroyRenderer(v->ren);
    if (v->win) SDL_DestroyWindow(v->win);
    SDL_Quit();
    free(v->sum);
    free(v->sum_sq);
    free(v->aov);
    free(v->low);
    free(v->argb);
    free(v->linear);
    free(v->tev_rgb);
    cli_tev_destroy(v->tev);
    free(v->photon_xyz[0]);
    free(v->photon_xyz[1]);
    free(v->ref_mean);
    free(v->ref_var);
    free(v->cur_mean);
    free(v->cur_var);
    free(v->block_z);
    cst_photon_cache_destroy(v->photons); /* before the scene (cli_view) */
    cst_film_destroy(v->acc);
    view_script_free(&v->script);
}

/* The first mode: --integrator's, else the scene's, else path. */
static ViewMode view_initial_mode(const CstRenderSettings *resolved)
{
    for (int m = VIEW_WHITTED; m <= VIEW_VCM; m++)
        if (VIEW_MODE_INTEGRATORS[m] == resolved->integrator) return (ViewMode)m;
    return VIEW_PATH; /* path-nee and path-bsdf: the path mode (MIS) */
}

static int view_init(View *v, const CliArgs *a)
{
    CstRenderSettings r;
    cst_render_settings_resolve(v->scene, &a->settings, &r);
    v->args = a;
    v->base = a->settings;
    v->w = r.width;
    v->h = r.height;
    v->out_exposure = r.exposure != 0.0 ? exp2(r.exposure) : 1.0;
    v->exposure = r.exposure;
    v->max_spp = a->settings.spp > 0 ? a->settings.spp : 0;
    v->base.spp = CST_UNSET;
    v->mode = view_initial_mode(&r);
    v->first_image_ms = -1.0;
    cst_scene_camera(v->scene, &v->cam);
    v->cam0 = v->cam;
    const size_t n = (size_t)v->w * (size_t)v->h;
    v->lw = (v->w + VIEW_LOW_DIV - 1) / VIEW_LOW_DIV;
    v->lh = (v->h + VIEW_LOW_DIV - 1) / VIEW_LOW_DIV;
    v->sum = calloc(3 * n, sizeof *v->sum);
    v->sum_sq = calloc(3 * n, sizeof *v->sum_sq);
    v->aov = calloc(VIEW_AOV_STRIDE * n, sizeof *v->aov);
    v->low = calloc(3 * (size_t)v->lw * (size_t)v->lh, sizeof *v->low);
    v->argb = calloc(n, sizeof *v->argb);
    v->linear = calloc(3 * n, sizeof *v->linear);
    v->photons = cst_photon_cache_create();
    if (!v->sum || !v->sum_sq || !v->aov || !v->low || !v->argb || !v->linear || !v->photons) {
        fprintf(stderr, "caustic: error: view: out of memory for a %dx%d image\n", v->w, v->h);
        return CLI_EXIT_INTERNAL;
    }
    for (int k = 0; k < 4096; k++) { /* the sRGB transfer function (IEC 61966-2-1) */
        double x = k / 4095.0, s = x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055;
        v->srgb_lut[k] = (uint8_t)(s * 255.0 + 0.5);
    }
    v->dirty = true;
    if (a->display && !(v->tev = cli_tev_create(a->display_host, a->display_port, "caustic view"))) {
        fprintf(stderr, "caustic: error: view: out of memory for --display\n");
        return CLI_EXIT_INTERNAL;
    }
    return CLI_EXIT_OK;
}

int cli_view(const CliArgs *a)
{
    View v;
    memset(&v, 0, sizeof v);
    char msg[1024];
    const char *script = a->script_path ? a->script_path : getenv("CAUSTIC_VIEW_SCRIPT");
    if (script && script[0] && !view_script_load(script, &v.script, msg, sizeof msg)) {
        fprintf(stderr, "caustic: error: view: %s\n", msg);
        return CLI_EXIT_USAGE;
    }
    if (!cli_check_scene_path(a)) {
        view_script_free(&v.script);
        return CLI_EXIT_USAGE;
    }
    int code = view_video_init(&v);
    double read_seconds = 0.0;
    if (code == CLI_EXIT_OK) code = cli_load_scene(a, &v.scene, &read_seconds);
    if (code != CLI_EXIT_OK) {
        view_close(&v); /* the window, SDL and the script */
        return code;
    }
    v.t_loaded = cli_clock_seconds();
    if ((code = view_init(&v, a)) == CLI_EXIT_OK && (code = view_open(&v)) == CLI_EXIT_OK) {
        v.t_window = cli_clock_seconds();
        view_loop(&v);
        code = v.exit_code;
    }
    view_close(&v);
    cst_scene_destroy(v.scene);
    return code;
}

#endif
