/* The help texts: one per command (caustic COMMAND --help, caustic help COMMAND) and all
 * of them together (caustic --help). Kept beside each other so that the sections cannot
 * drift apart; docs/cli.md says the same at more length. */
#include "args.h"

#define HELP_HEADER "caustic " CST_VERSION_STRING ": a physically based renderer\n\n"

static const char HELP_USAGE_ALL[] =
"Usage:\n"
"  caustic render [SCENE] [options]\n"
"  caustic info [SCENE] [--accel NAME]\n"
"  caustic bench rays [MESH | --cornell] [--stadium] [--accel NAME[,NAME...]]\n"
"                     [--threads N] [--json]\n"
"  caustic verify [SCENE] --integrators NAME,NAME[,...] [--spp N | --time S]\n"
"                 [--threads N] [--seed S] [--alpha A] [--block N] [--map OUT.png]\n"
"                 [--convergence K] [--json] [--width W] [--height H] [--quiet]\n"
"                 [--subsurface walk|bssrdf]\n"
"  caustic list [KIND]\n"
"  caustic view [SCENE] [render options] [--script FILE]\n"
"  caustic compare A B [--map OUT.png] [--json] [--variance-a VA] [--variance-b VB]\n"
"                  [--block N] [--flip ldr|hdr|auto] [--ppd P]\n"
"  caustic explain [SCENE] --pixel X,Y [--sample I] [--integrator NAME] [--json]\n"
"                  [render options]\n"
"  caustic COMMAND --help | caustic help COMMAND   (one command's options)\n"
"  caustic --help | -h\n"
"  caustic --version\n"
"\n";

static const char HELP_RENDER[] =
"Render: caustic render [SCENE] [options]\n"
"Renders SCENE, a caustic JSON scene file (*.json, see docs/scene-format.md) or a\n"
"pbrt-v4 scene (*.pbrt or gzip-compressed *.pbrt.gz, see docs/pbrt-compat.md), or the\n"
"built-in Cornell box when SCENE is omitted, and writes one image.\n"
"\n"
"Options (both --opt VALUE and --opt=VALUE are accepted; a later option wins):\n"
"  -o, --output OUT     output image; the format follows the extension: .png (8-bit\n"
"                       sRGB), .exr or .pfm (linear float). Default: the scene file's\n"
"                       \"output\", else <scene file stem>.png in the current directory,\n"
"                       cornell-box.png for the built-in scene. The extension and the\n"
"                       directory are checked before rendering starts.\n"
"      --spp N          samples per pixel, N >= 1 (default: the scene's, else 16)\n"
"      --time SECONDS   render for SECONDS, > 0: progressive passes (for sppm, vcm,\n"
"                       bdpt and light: iterations) until the time is up, over any spp\n"
"                       the scene file sets; with --spp too, stops at whichever comes\n"
"                       first (default: no time limit)\n"
"      --noise TARGET   adaptive sampling: render in rounds until every 16x16 block's\n"
"                       estimated relative standard error (of its mean luminance) is\n"
"                       at most TARGET, > 0 (0.01 = 1%); camera integrators sample\n"
"                       only the blocks above it, light/bdpt/vcm the whole image; not\n"
"                       sppm or pssmlt. --spp caps each pixel (default 65536), --time\n"
"                       the render\n"
"      --threads N      render threads, 0..1024; 0 = one per core (the default)\n"
"      --seed S         random seed, any unsigned 64-bit integer, decimal or 0x-hex\n"
"                       (default: the scene's, else 0)\n"
"      --integrator NAME  path (default: NEE and BSDF sampling combined by MIS),\n"
"                       path-nee (emitters reached by NEE only), path-bsdf (BSDF\n"
"                       sampling only), light (light tracing from the emitters; --spp\n"
"                       counts iterations of W x H light paths; misses what is seen in\n"
"                       mirrors or through glass), whitted (mirror and glass recursion\n"
"                       with direct light only; biased by design), photon (photon\n"
"                       mapping with final gathering; consistent but biased, photon\n"
"                       count and radius from the scene file), sppm (stochastic\n"
"                       progressive photon mapping; --spp counts iterations, each one\n"
"                       camera sample per pixel and one photon pass; consistent but\n"
"                       biased), bdpt (bidirectional path tracing, all\n"
"                       connection strategies with MIS; --spp counts iterations of one\n"
"                       light and one camera path per pixel), vcm (vertex connection\n"
"                       and merging: bdpt plus photon merging with a shrinking radius,\n"
"                       the first from the scene's \"radius\", else automatic;\n"
"                       consistent), pssmlt (Metropolis light transport in primary\n"
"                       sample space over the path tracer; --spp counts mutations per\n"
"                       pixel; chains, large steps, sigma and bootstrap from the scene\n"
"                       file; consistent), mmlt (multiplexed MLT over bdpt, chains per\n"
"                       path length up to the max depth, 0 = 5; as pssmlt otherwise);\n"
"                       default: the scene's, else path\n"
"      --filter NAME    box, tent, gaussian or mitchell (default: the scene's, else box)\n"
"      --width W        image width in pixels, 1..65536 (default: the scene's, else 512)\n"
"      --height H       image height in pixels, 1..65536 (default: the scene's, else\n"
"                       512); --width and --height may each be given alone\n"
"      --accel NAME     acceleration structure: bvh (default), kdtree, grid, list (brute\n"
"                       force), embree (when built with Embree) or octree; default: the\n"
"                       scene's\n"
"      --light-sampler NAME  how next-event estimation picks a light: power, bvh (light\n"
"                       BVH, Conty & Kulla 2018) or uniform; default: the scene's, else\n"
"                       bvh above 64 lights with a position, power below\n"
"      --light-sampling NAME  a point on a triangle light for next-event estimation:\n"
"                       area (uniform by area) or solid_angle (Arvo 1995, where pbrt-v4\n"
"                       does); default: the scene's (pbrt scenes: solid_angle)\n"
"      --sampler NAME   random numbers of camera paths: zsobol (the default, as\n"
"                       pbrt-v4's: Sobol' over Morton-ordered pixels; about half\n"
"                       independent's error at equal spp, see docs/benchmarks.md),\n"
"                       independent (PCG32), stratified (jittered; 2D strata nx x ny\n"
"                       = spp, so choose square or power-of-two spp) or sobol\n"
"                       (Owen-scrambled Sobol', padded; slower per sample).\n"
"                       Light paths (light, photon, sppm, bdpt, vcm) stay independent\n"
"      --spectral       spectral rendering: 4 wavelengths per path, RGB inputs upsampled\n"
"                       (Jakob & Hanika 2019), the film through the CIE 1931 curves, as\n"
"                       pbrt-v4 (default for pbrt scenes)\n"
"      --rgb            RGB rendering: three channels per path (default for JSON scenes\n"
"                       and the built-in one); the last of --spectral/--rgb wins\n"
"      --max-depth N    maximum bounces of a path, 0..2147483647; 0 = unbounded, also\n"
"                       over a scene's own limit (default: the scene's, else unbounded)\n"
"      --subsurface M   how path, path-nee and path-bsdf render subsurface materials:\n"
"                       bssrdf (default; pbrt-v4's diffusion BSSRDF) or walk (a random\n"
"                       walk of the medium, as light, bdpt, vcm and mmlt always do)\n"
"      --exposure EV    scale the written image by 2^EV, -64..64 (default: the scene's,\n"
"                       else 0); the film's stored means are not changed\n"
"      --png-linear     write PNG values linearly (no sRGB curve; tagged gAMA 1.0)\n"
"      --aov LIST       extra EXR channels, comma-separated: albedo (albedo.R/G/B),\n"
"                       normal (N.X/Y/Z), depth (Z), variance (variance.R/G/B); needs an\n"
"                       .exr output (docs/cli.md)\n"
"      --crop X0,X1,Y0,Y1  render and write only the pixels X0 <= x < X1, Y0 <= y < Y1\n"
"                       (y = 0 the top row) of the image; each holds the value it has in\n"
"                       the whole image (default: the scene's crop, else none)\n"
"      --json[=FILE]    after writing, a JSON summary (times of load, accel build,\n"
"                       render and write; samples, rays, NaN/Inf discarded, peak\n"
"                       memory, output path) on stdout, or in FILE\n"
"      --force          render even when the images' estimated memory exceeds the\n"
"                       memory available (otherwise refused before rendering, exit 2)\n"
"      --checkpoint FILE  write the render's state (film sums, samples done, what\n"
"                       they are valid for) to FILE between passes, every\n"
"                       --checkpoint-every seconds (default 300) and at the end;\n"
"                       every integrator (docs/state-format.md)\n"
"      --resume FILE    continue the render a state file holds: same scene and\n"
"                       settings, --spp at least its samples; the image is the one an\n"
"                       uninterrupted render makes, byte for byte (a mismatch: exit 2)\n"
"      --display tev[:HOST:PORT]  stream the image as it converges to a running tev\n"
"                       viewer (default 127.0.0.1:14158), tile by tile after each\n"
"                       pass; no tev there: one warning, the render goes on\n"
"      --first-sample N render samples (light, bdpt, vcm: iterations) [N, N + spp)\n"
"                       of every pixel, each as a render from 0 computes it (default 0)\n"
"      --sample-block B sum the film in blocks of B samples [kB, (k+1)B), each block's\n"
"                       sums added in order (default 1: sample by sample), so that\n"
"                       blocks rendered apart merge bit for bit (caustic merge, mpirun)\n"
"  -q, --quiet          no job line, progress or summary; warnings and errors remain\n"
"  -h, --help           show this help and exit\n"
"\n"
"Progress goes to stderr: a redrawn bar with an ETA when stderr is a terminal, otherwise\n"
"one line per 10% of each phase (the photon pass, then the render) with its ETA. The\n"
"image is written atomically (temporary file, rename). A scene without any light, and a\n"
"mesh whose .mtl file is missing, draw a warning.\n"
"\n";

static const char HELP_INFO[] =
"Scene information: caustic info [SCENE] [--accel NAME]\n"
"Loads SCENE (or the built-in Cornell box), builds its acceleration structure and prints\n"
"the load time, its size (triangles, spheres, emitters, materials), the structure's\n"
"build time and memory.\n"
"      --accel NAME     bvh (default), kdtree, grid, list, embree or octree (see caustic\n"
"                       list)\n"
"  -h, --help           show this help and exit\n"
"\n";

static const char HELP_MERGE[] =
"Merge states: caustic merge STATE... -o IMAGE [-q]\n"
"Adds up state files (render --checkpoint) of one scene and one set of settings that\n"
"hold disjoint sample ranges (--first-sample, --spp) and writes the image of their\n"
"union: byte for byte the image of one render of the union with the same settings. The\n"
"ranges must leave no gap; every state but the one that starts the union must be one\n"
"block of --sample-block samples (render each part with --sample-block = its --spp).\n"
"States of different renders, overlaps, gaps and corrupted files: exit 2, naming what\n"
"differs. Under mpirun, render splits the blocks over the ranks itself (docs/cli.md).\n"
"  -o, --output IMAGE   the image to write (.png, .exr, .pfm)\n"
"  -q, --quiet          no summary line\n"
"  -h, --help           show this help and exit\n"
"\n";

static const char HELP_EXPLAIN[] =
"Explain a pixel: caustic explain [SCENE] --pixel X,Y [--sample I] [render options]\n"
"Replays sample I (bdpt, vcm, sppm, pssmlt, mmlt: iteration I) of pixel (X, Y) with the\n"
"random numbers `caustic render` gives it under the same options (--seed,\n"
"--integrator, --sampler, --spp for the stratified samplers' strata, --width,\n"
"--height, --max-depth, ...) and prints its path: every vertex (position, normal,\n"
"material), every decision (the light NEE chose, the BSDF lobe, Russian roulette's\n"
"survival probability), the densities (pdf_w per solid angle, pdf_a per area) and MIS\n"
"weight of every strategy and its contribution; then checks that the contributions\n"
"sum, bit for bit, to the value the\n"
"render's film accumulates for that sample (bdpt, vcm: the camera path's, and the light\n"
"paths' t = 1 splats on the pixel added to it as the film adds them; each strategy's MIS\n"
"weight, merges and splats included, is also computed from every strategy's pdfs of its\n"
"whole path, and those weights sum to 1). whitted: the ray tree; light: every light\n"
"path's splat on the pixel in the iteration, summed to the film's value. pssmlt, mmlt:\n"
"the Metropolis steps (chain, step, acceptance, splat weight) whose splats reached the\n"
"pixel in iteration I (the render run from its start), summed to the iteration's value.\n"
"sppm: iteration I's visible point, the photons it gathered and its progressive update\n"
"(iterations 0..I replayed), equal to the film of a --spp I+1 render. Every integrator is\n"
"explained (photon through media and in spectral mode too: the walk's flights, medium\n"
"vertices, the volume map's photons and estimate; the sample's wavelengths and set).\n"
"  --pixel X,Y          the pixel, 0,0 the top left (required)\n"
"  --sample I           the sample (iteration) index, >= 0 (default 0)\n"
"  --why-bright         one line instead: the event carrying most of the value and what\n"
"                       made it large (its density, MIS weight, the least likely scatter)\n"
"  --why-dark           one line instead: how the path ended, which light samples were\n"
"                       blocked, what little there is\n"
"  --json               one JSON object on stdout instead of text (--json=FILE: there)\n"
"Exit: 0 explained and the sum matches; 1 the sum does not match (a bug); 2 bad input.\n"
"\n";

static const char HELP_VIEW[] =
"Interactive viewer: caustic view [SCENE] [render options] [--script FILE]\n"
"Opens a window (SDL2) and renders SCENE (or the built-in Cornell box) progressively:\n"
"a low-resolution preview first, then one sample (light, bdpt, vcm: one iteration) per\n"
"pass, the image after N passes being the one `caustic render --spp N` computes; sppm\n"
"re-renders 1, 2, 4, ... iterations. Render options (--integrator: the first mode,\n"
"--spp: stop refining there, --width, --height, --seed, --threads, ...) as for render.\n"
"Keys: 1 preview (again, p or Tab: eye light, normals, albedo, depth), 2 whitted,\n"
"3 path, 4 light, 5 photon, 6 sppm, 7 bdpt, 8 vcm, 9 relative error (toggle);\n"
"+/- display exposure; [ ] field of view; o photons as points (photon mode);\n"
"s save caustic-view-NNN.exr and .png; k save a checkpoint caustic-view-NNN.state\n"
"(render --resume continues it);\n"
"c print the camera as JSON (and write caustic-view-camera-NNN.json); q or Esc\n"
"quit. Mouse: left click sets the thin lens's focus where it points, left drag\n"
"orbits, middle or shift-left drag pans, the wheel dollies. Any change of mode or\n"
"camera restarts.\n"
"      --script FILE    run FILE's commands (also $CAUSTIC_VIEW_SCRIPT): key K,\n"
"                       wait-spp N, save PATH, orbit DX DY, pan DX DY, dolly N,\n"
"                       click X Y, camera PATH, status, quit; one per line,\n"
"                       # comments (docs/cli.md)\n"
"      --display tev[:HOST:PORT]  stream the image to tev after each pass\n"
"Without a display: xvfb-run -a caustic view ... A build without SDL2 says so (exit 2).\n"
"\n";

static const char HELP_BENCH[] =
"Benchmark: caustic bench rays\n"
"Traces the acceleration benchmark's three ray sets (/work/shared/bench/RAYSETS.md:\n"
"primary closest hits, secondary bounce rays generated once and shared by every back\n"
"end, and the bounce rays as occlusion queries) through each back end with 1 thread and\n"
"with N threads, and prints build time, bytes per triangle, M rays/s, the speed ratios to\n"
"Embree (its default configuration) and to Embree in its robust mode (robust box test,\n"
"edge-consistent triangle test: the guarantees of our BVH), hits and sum of t, checked\n"
"against the published checksums (or, for scenes without them, against the first back\n"
"end).\n"
"  MESH                 a triangle mesh file (read through the mesh importer, e.g. a\n"
"                       PLY of /work/shared/meshes); default: the built-in Cornell box\n"
"      --cornell        the built-in Cornell box (the default)\n"
"      --stadium        put the scene inside a huge box of 12 triangles (teapot in a\n"
"                       stadium); alone: a built-in 20,480-triangle bumpy ball inside it\n"
"      --accel LIST     comma-separated back ends: bvh, kdtree, grid, list, embree,\n"
"                       embree-robust, octree (default: all this build has; list\n"
"                       only for scenes of at most 1,000 triangles)\n"
"      --threads N      the second thread count, 0..1024; 0 = one per core (default)\n"
"      --json           one JSON object per line on stdout instead of the table\n"
"  -h, --help           show this help and exit\n"
"\n";

static const char HELP_VERIFY[] =
"Consistency check: caustic verify\n"
"Renders SCENE (or the built-in Cornell box) once per integrator, each with its own seed,\n"
"and tests every pair for agreement: per channel, the z-score of the difference of the\n"
"image means and of every NxN block mean, z = (mean_a - mean_b) / sqrt(var_a + var_b),\n"
"with variances from the per-pixel sample variances. A pair disagrees if any |z| exceeds\n"
"the critical z of a Sidak correction over all tests of all pairs at family-wise\n"
"significance A. Prints one row per pair (image-mean z per channel, largest |block z|,\n"
"failing blocks) and the critical z; see docs/cli.md for the statistics.\n"
"Consistent but biased integrators (photon, sppm, vcm) are judged by convergence\n"
"instead, against the first unbiased integrator in the list (the reference, e.g. path):\n"
"each is rendered twice (independent seeds) at K levels of work, 1, 4, 16, ... times the\n"
"base (sppm, vcm: --spp iterations; photon: the scene's photon count, and its radius\n"
"halved per level if the scene fixes one); the disagreement D (the mean squared block\n"
"bias, estimated net of noise) and the image mean must be within noise at the last\n"
"level, or D must fall significantly at every step.\n"
"  SCENE                a caustic JSON or pbrt-v4 scene; default: the built-in Cornell box\n"
"      --integrators LIST  comma-separated, at least two (any name --integrator takes;\n"
"                       a name may repeat: a same-integrator pair checks the test itself)\n"
"      --spp N          samples per pixel of each render (default: the scene's, else 16)\n"
"      --time SECONDS   render each integrator for SECONDS (equal time); with --spp\n"
"                       (or a scene's spp) too, each stops at whichever comes first\n"
"      --seed S         base seed (default: the scene's, else 0); integrator k (0-based,\n"
"                       in list order) renders with SplitMix64's output k+1 from S, shown\n"
"                       in the report, so 'caustic render --seed' reproduces it\n"
"      --alpha A        family-wise significance, 0 < A < 1 (default: 0.01)\n"
"      --block N        block side in pixels, 1..65536 (default: 16); edge blocks are\n"
"                       partial and tested with their own pixel counts. Each block needs\n"
"                       many samples (block^2 x spp >= 65536, else a warning) for z to be\n"
"                       near normal with heavy-tailed estimators such as path-bsdf\n"
"      --map OUT        false-colour map of the largest block |z| over channels and\n"
"                       pairs, at the image's size (.png, .exr or .pfm): black to blue\n"
"                       up to z_crit/2, blue to yellow at z_crit, red beyond\n"
"      --convergence K  levels of the convergence check, 2..6 (default: 3)\n"
"      --json           one JSON object per pair (then per convergence check) on stdout\n"
"                       instead of the report\n"
"      --width W, --height H, --threads N, --subsurface M, -q/--quiet: as for render\n"
"                       (--subsurface walk: path, path-nee and path-bsdf render what light,\n"
"                       bdpt, vcm and mmlt render of subsurface materials, so they compare)\n"
"  -h, --help           show this help and exit\n"
"\n";

static const char HELP_LIST[] =
"Names: caustic list [KIND]\n"
"Prints the names this build accepts, read from the library's own tables: integrators,\n"
"samplers, filters, accels (the back ends built in), materials and lights (a JSON\n"
"scene's \"type\"s), formats (output image extensions), metals (conductor presets).\n"
"With KIND, only those names, one per line (for scripts).\n"
"\n";

static const char HELP_COMPARE[] =
"Image comparison: caustic compare A B\n"
"Compares image A with the reference B (each .exr, .pfm, .png or .hdr; same size, else\n"
"exit 2) and prints per channel the means of A and B, their difference (absolute and\n"
"relative to B's mean), RMSE and relMSE = mean of (a - b)^2 / (b^2 + 0.01); then FLIP\n"
"(Andersson et al. 2020), the perceived difference in [0, 1]: LDR-FLIP when both images\n"
"are PNGs, else HDR-FLIP (LDR-FLIP's maximum over tone-mapped exposures, 2021), at 67\n"
"pixels per degree (a 0.7 m wide 4K monitor seen from 0.7 m). With the variances of the\n"
"pixel values (--variance-a/-b, or the variance AOV of an EXR written with --aov\n"
"variance, used by default), the z-score of every NxN block mean difference,\n"
"z = (mean_a - mean_b) / sqrt(var_a + var_b), summarised as the largest |z| and the\n"
"fraction of block tests with |z| > 4; see docs/cli.md.\n"
"  A, B                 the images; B is the reference (relMSE, FLIP)\n"
"      --map OUT        the per-pixel FLIP error as a grey image (0 black to 1 white;\n"
"                       .png, .exr or .pfm), written atomically\n"
"      --json           the same numbers as one JSON object on stdout\n"
"      --variance-a VA  an image of the variances of A's pixel values (e.g. the\n"
"                       variance.R/G/B of caustic render --aov variance: give the EXR\n"
"                       itself, its variance channels are read); default: A's own\n"
"                       variance AOV if A is an EXR that has one\n"
"      --variance-b VB  the same for B; an image without variances counts as exact\n"
"      --block N        z blocks' side in pixels, 1..65536 (default: 16)\n"
"      --flip KIND      ldr, hdr or auto (default: auto, as above)\n"
"      --ppd P          FLIP's pixels per degree of visual angle (default: 67.02)\n"
"  -h, --help           show this help and exit\n"
"Exit status: 0 the comparison was made (whatever the difference); 1 internal error\n"
"(out of memory, the map could not be written); 2 bad usage, an image that is missing,\n"
"unreadable or of another size than the other, variances of the wrong size.\n"
"\n";

static const char HELP_EXIT[] =
"Exit status:\n"
"  0  success: the image was written (bench rays: every check passed; verify: every\n"
"     pair of integrators agrees and every consistent one converges)\n"
"  1  internal error: out of memory, a library failure, or an I/O error while writing\n"
"     the image although its directory was checked writable before rendering\n"
"     (disk full, file system error)\n"
"     bench rays: a checksum did not match; verify: a pair of integrators disagrees\n"
"     or a consistent integrator is not shown to converge\n"
"  2  bad input or usage: unknown command or option, invalid value, unsupported scene\n"
"     or output format, a scene file that is missing, unreadable or invalid, an output\n"
"     directory that does not exist or is not writable (checked before rendering),\n"
"     a --resume state that is truncated, corrupted or made for another render\n"
"  130, 143  render: stopped by SIGINT (Ctrl-C) or SIGTERM after the current pass,\n"
"     the image of the passes done (and --checkpoint's state) written; a second\n"
"     signal ends caustic at once, writing nothing\n"
"\n";

static const char HELP_EXAMPLES_RENDER[] =
"  caustic render --spp 64 -o box.png\n"
"  caustic render scenes/cornell-box.json --time 60 --threads 8 -o box.exr\n"
"  caustic render scene.json --width=1920 --height=1080 --integrator=path-nee\n"
"  caustic render --spp 4 --json=summary.json -o box.png\n"
"  caustic render scene.json --spp 4096 --checkpoint scene.state -o scene.exr\n"
"  caustic render scene.json --spp 4096 --resume scene.state --checkpoint scene.state -o scene.exr\n";
static const char HELP_EXAMPLES_BENCH[] =
"  caustic bench rays ../shared/meshes/bunny.ply --accel bvh,embree --json\n";
static const char HELP_EXAMPLES_VERIFY[] =
"  caustic verify --integrators path,path-nee,path-bsdf --spp 64 --map z.png\n";
static const char HELP_EXAMPLES_EXPLAIN[] =
"  caustic explain --pixel 256,300 --sample 3 --integrator bdpt --width 64 --height 64\n";
static const char HELP_EXAMPLES_COMPARE[] =
"  caustic compare new.exr reference.exr --map flip.png\n";

void args_print_help(FILE *f, ArgsCommand command)
{
    fputs(HELP_HEADER, f);
    switch (command) {
    case ARGS_CMD_RENDER:
        fputs(HELP_RENDER, f);
        fputs(HELP_EXIT, f);
        fprintf(f, "Examples:\n%s\n", HELP_EXAMPLES_RENDER);
        break;
    case ARGS_CMD_INFO:
        fputs(HELP_INFO, f);
        fputs(HELP_EXIT, f);
        break;
    case ARGS_CMD_VIEW:
        fputs(HELP_VIEW, f);
        fputs(HELP_EXIT, f);
        break;
    case ARGS_CMD_BENCH_RAYS:
        fputs(HELP_BENCH, f);
        fputs(HELP_EXIT, f);
        fprintf(f, "Example:\n%s\n", HELP_EXAMPLES_BENCH);
        break;
    case ARGS_CMD_VERIFY:
        fputs(HELP_VERIFY, f);
        fputs(HELP_EXIT, f);
        fprintf(f, "Example:\n%s\n", HELP_EXAMPLES_VERIFY);
        break;
    case ARGS_CMD_LIST:
        fputs(HELP_LIST, f);
        break;
    case ARGS_CMD_COMPARE:
        fputs(HELP_COMPARE, f);
        fprintf(f, "Example:\n%s\n", HELP_EXAMPLES_COMPARE);
        break;
    case ARGS_CMD_MERGE:
        fputs(HELP_MERGE, f);
        break;
    case ARGS_CMD_EXPLAIN:
        fputs(HELP_EXPLAIN, f);
        fprintf(f, "Example:\n%s\n", HELP_EXAMPLES_EXPLAIN);
        break;
    case ARGS_CMD_HELP:
    case ARGS_CMD_VERSION:
        fputs(HELP_USAGE_ALL, f);
        fputs(HELP_RENDER, f);
        fputs(HELP_INFO, f);
        fputs(HELP_BENCH, f);
        fputs(HELP_VERIFY, f);
        fputs(HELP_LIST, f);
        fputs(HELP_COMPARE, f);
        fputs(HELP_VIEW, f);
        fputs(HELP_MERGE, f);
        fputs(HELP_EXPLAIN, f);
        fputs("      --version        print the version and the build (compiler, ISA, Embree,\n"
              "                       MPI, SDL2, build type) and exit\n\n", f);
        fputs(HELP_EXIT, f);
        fprintf(f, "Examples:\n%s%s%s%s", HELP_EXAMPLES_RENDER, HELP_EXAMPLES_BENCH, HELP_EXAMPLES_VERIFY,
                HELP_EXAMPLES_COMPARE);
        break;
    }
    if (command != ARGS_CMD_HELP && command != ARGS_CMD_VERSION)
        fputs("Every command: caustic --help; the names an option takes: caustic list.\n", f);
}
