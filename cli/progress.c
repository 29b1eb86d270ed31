/* The progress display on stderr: a bar redrawn in place on a terminal, otherwise one line
 * per 10% of each phase; both with an ETA, so a long job in a log or a pipe says how long
 * it has left. Fed by the library's CstProgressFn and CstPhaseFn. */
#include <stdio.h>
#include <string.h>

#include "cli.h"

/* m:ss, or h:mm:ss from one hour on. */
static void cli_format_clock(double seconds, char *buf, size_t size)
{
    if (!(seconds >= 0.0) || seconds > 359999.0) {
        snprintf(buf, size, "--:--");
        return;
    }
    long s = (long)(seconds + 0.5);
    if (s >= 3600)
        snprintf(buf, size, "%ld:%02ld:%02ld", s / 3600, s / 60 % 60, s % 60);
    else
        snprintf(buf, size, "%ld:%02ld", s / 60, s % 60);
}

/* The time left in the phase, extrapolated from its own elapsed time, or "--:--" while
 * there is too little to go on: the bar waits half a second (the first instants
 * extrapolate badly), a plain line comes at 10% steps and has enough. */
static void cli_progress_eta(const CliProgress *p, double fraction, double elapsed, char *buf, size_t size)
{
    double in_phase = elapsed - p->phase_start;
    if (fraction >= 1.0)
        cli_format_clock(0.0, buf, size);
    else if (fraction > 0.0 && (in_phase >= 0.5 || (!p->tty && in_phase > 0.0)))
        cli_format_clock(in_phase * (1.0 - fraction) / fraction, buf, size);
    else
        snprintf(buf, size, "--:--");
}

/* "photons " before the bar or the percentage of a phase other than the render itself. */
static const char *cli_progress_label(const CliProgress *p)
{
    return p->phase[0] && strcmp(p->phase, CST_PHASE_RENDER) != 0 ? p->phase : "";
}

static void cli_progress_draw(CliProgress *p, double fraction, double elapsed)
{
    enum { BAR = 30 };
    char line[192], eta[32], el[32];
    int filled = (int)(fraction * BAR);
    cli_progress_eta(p, fraction, elapsed, eta, sizeof eta);
    cli_format_clock(elapsed, el, sizeof el);
    const char *label = cli_progress_label(p);
    int n = snprintf(line, sizeof line, "\r%s%s[%.*s%.*s] %3d%%  ETA %s  elapsed %s", label,
                     label[0] ? " " : "", filled, "##############################",
                     BAR - filled, "..............................",
                     (int)(fraction * 100.0), eta, el);
    if (n < 0)
        return;
    if (n >= (int)sizeof line)
        n = (int)sizeof line - 1;
    int len = n - 1; /* without the '\r' */
    fputs(line, stderr);
    if (len < p->last_len)
        fprintf(stderr, "%*s", p->last_len - len, "");
    fflush(stderr);
    p->last_len = len;
    p->drawn = true;
}

/* One plain line: "caustic: [phase ]40% (elapsed 1.2 s, ETA 0:02)"; no ETA at 100%. */
static void cli_progress_line(CliProgress *p, int percent, double elapsed)
{
    const char *label = cli_progress_label(p);
    char eta[32] = "";
    if (percent < 100) {
        char clock[24];
        cli_progress_eta(p, percent / 100.0, elapsed, clock, sizeof clock);
        snprintf(eta, sizeof eta, ", ETA %s", clock);
    }
    fprintf(stderr, "caustic: %s%s%d%% (elapsed %.1f s%s)\n", label, label[0] ? " " : "", percent,
            elapsed, eta);
    fflush(stderr);
}

/* CstProgressFn: called from the rendering (calling) thread about ten times a second.
 * Returns 0: the CLI never cancels a render. */
int cli_progress_report(void *user, double fraction, double elapsed)
{
    CliProgress *p = user;
    if (!(fraction >= 0.0))
        fraction = 0.0;
    if (fraction > 1.0)
        fraction = 1.0;
    p->last_elapsed = elapsed;
    if (p->tty) {
        cli_progress_draw(p, fraction, elapsed);
        return 0;
    }
    /* A long gap between calls may cross several steps; print only the latest. */
    int step = (int)(fraction * 10.0 + 1e-9);
    if (step > p->last_step) {
        p->last_step = step;
        cli_progress_line(p, step * 10, elapsed);
    }
    return 0;
}

/* CstPhaseFn: ends the previous phase's display (its 100%) and starts the next at 0%. */
void cli_progress_phase(void *user, const char *phase)
{
    CliProgress *p = user;
    if (p->phase[0]) { /* a phase before this one: complete it */
        if (p->tty && p->drawn) {
            cli_progress_draw(p, 1.0, p->last_elapsed);
            fputc('\n', stderr);
            p->drawn = false;
            p->last_len = 0;
        } else if (!p->tty && p->last_step < 10) {
            cli_progress_line(p, 100, p->last_elapsed);
        }
    }
    snprintf(p->phase, sizeof p->phase, "%s", phase);
    p->phase_start = p->last_elapsed;
    p->last_step = 0;
}

/* After a successful render: complete the bar, or the 100% line if the library's last
 * report fell short of it (a very short render may not report at all). */
void cli_progress_finish(CliProgress *p, double seconds)
{
    if (p->tty) {
        cli_progress_draw(p, 1.0, seconds);
        fputc('\n', stderr);
        p->drawn = false;
    } else if (p->last_step < 10) {
        p->last_step = 10;
        cli_progress_line(p, 100, seconds);
    }
}

/* After a failed render: end the bar's line so the error message starts on its own. */
void cli_progress_abort(CliProgress *p)
{
    if (p->tty && p->drawn) {
        fputc('\n', stderr);
        p->drawn = false;
    }
}
