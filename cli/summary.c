/* What a render costs: the memory check before it (the images' estimated bytes against
 * the memory available) and the --json summary after it (times per phase, work, peak
 * memory). */
#include <errno.h>
#include <inttypes.h>
#include <jansson.h>
#include <stdio.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

#include "cli.h"

/* Bytes the system can give without swapping: /proc/meminfo's MemAvailable (Linux 3.14+,
 * counts reclaimable caches), else the free physical pages; 0 if neither is known. */
uint64_t cli_available_memory(void)
{
    FILE *fp = fopen("/proc/meminfo", "r");
    if (fp) {
        char line[256];
        unsigned long long kb;
        while (fgets(line, sizeof line, fp))
            if (sscanf(line, "MemAvailable: %llu kB", &kb) == 1) {
                fclose(fp);
                return (uint64_t)kb * 1024u;
            }
        fclose(fp);
    }
    long pages = sysconf(_SC_AVPHYS_PAGES), size = sysconf(_SC_PAGESIZE);
    return pages > 0 && size > 0 ? (uint64_t)pages * (uint64_t)size : 0;
}

/* The process's peak resident set (getrusage: ru_maxrss, kilobytes on Linux). */
static uint64_t cli_peak_rss(void)
{
    struct rusage ru;
    if (getrusage(RUSAGE_SELF, &ru) != 0 || ru.ru_maxrss < 0) return 0;
    return (uint64_t)ru.ru_maxrss * 1024u;
}

bool cli_check_memory(const CstScene *scene, const CstRenderSettings *settings, bool force,
                      uint64_t *estimate)
{
    *estimate = cst_render_memory_estimate(scene, settings);
    uint64_t avail = cli_available_memory();
    if (avail == 0 || *estimate <= avail) return true;
    CstRenderSettings rs;
    cst_render_settings_resolve(scene, settings, &rs);
    if (force) {
        fprintf(stderr, "caustic: warning: the %dx%d render needs about %.1f GB for its images, more "
                "than the %.1f GB available; rendering anyway (--force)\n", rs.width, rs.height,
                (double)*estimate / 1e9, (double)avail / 1e9);
        return true;
    }
    fprintf(stderr, "caustic: error: the %dx%d render needs about %.1f GB for its images (%.0f bytes "
            "per pixel) but only %.1f GB of memory are available; expected a smaller --width/--height "
            "or --crop, or --force to render anyway\n", rs.width, rs.height, (double)*estimate / 1e9,
            (double)*estimate / ((double)rs.width * (double)rs.height), (double)avail / 1e9);
    return false;
}

/* Opens --json=FILE before the render, so an unwritable path is refused (exit 2) before
 * any work; NULL path: stdout. Prints the error and returns NULL on failure. */
FILE *cli_summary_open(const char *path)
{
    if (!path) return stdout;
    FILE *f = fopen(path, "w");
    if (!f)
        fprintf(stderr, "caustic: error: --json=%s: cannot open for writing: %s\n", path, strerror(errno));
    return f;
}

/* The summary as one JSON object and a newline. Returns false on a write error. */
bool cli_summary_write(FILE *f, const CliSummary *s)
{
    const CstRenderStats *st = &s->stats;
    double rate = st->seconds > 0.0 ? 1.0 / st->seconds : 0.0;
    json_t *o = json_object();
    json_object_set_new(o, "caustic", json_string(CST_VERSION_STRING));
    json_object_set_new(o, "scene", s->scene ? json_string(s->scene) : json_null());
    json_object_set_new(o, "output", json_string(s->output));
    json_object_set_new(o, "integrator", json_string(cst_integrator_name(st->integrator)));
    json_object_set_new(o, "width", json_integer(st->width));
    json_object_set_new(o, "height", json_integer(st->height));
    json_object_set_new(o, "spp", json_integer(st->spp));
    json_object_set_new(o, "threads", json_integer(st->threads));
    json_t *t = json_object();
    json_object_set_new(t, "load", json_real(s->load_seconds));
    json_object_set_new(t, "accel", json_real(s->accel_seconds));
    json_object_set_new(t, "render", json_real(st->seconds));
    json_object_set_new(t, "write", json_real(s->write_seconds));
    json_object_set_new(t, "total", json_real(s->total_seconds));
    json_object_set_new(o, "seconds", t);
    json_object_set_new(o, "samples", json_integer((json_int_t)st->samples));
    json_object_set_new(o, "rays", json_integer((json_int_t)st->rays));
    json_object_set_new(o, "samples_per_second", json_real((double)st->samples * rate));
    json_object_set_new(o, "rays_per_second", json_real((double)st->rays * rate));
    json_object_set_new(o, "nonfinite_discarded", json_integer((json_int_t)st->nonfinite));
    if (st->noise_blocks > 0) { /* --noise: render/adaptive.h's estimate (caustic.h, CstRenderStats) */
        json_t *z = json_object();
        json_object_set_new(z, "rms", json_real(st->noise_rms));
        json_object_set_new(z, "rms_ci95", json_pack("[ff]", st->noise_rms_lo, st->noise_rms_hi));
        json_object_set_new(z, "max", json_real(st->noise_max));
        json_object_set_new(z, "blocks", json_integer(st->noise_blocks));
        json_object_set_new(z, "blocks_above_target", json_integer(st->noise_blocks_over));
        json_object_set_new(z, "spp_min", json_integer(st->spp_min));
        json_object_set_new(o, "noise", z);
    }
    json_object_set_new(o, "image_memory_estimate_bytes", json_integer((json_int_t)s->memory_estimate));
    json_object_set_new(o, "peak_rss_bytes", json_integer((json_int_t)cli_peak_rss()));
    int rc = o ? json_dumpf(o, f, JSON_COMPACT | JSON_REAL_PRECISION(6)) : -1;
    json_decref(o);
    if (rc == 0) fputc('\n', f);
    return rc == 0 && fflush(f) == 0 && !ferror(f);
}
