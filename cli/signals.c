/* Signal handlers that leave no temporary image file behind, and the render's stop request
 * (cli/signals.h). Handlers call only async-signal-safe functions (POSIX.1-2017 2.4.3):
 * unlink, sigaction, raise, write. */
#define _POSIX_C_SOURCE 200809L

#include "signals.h"

#include <pthread.h>
#include <signal.h>
#include <stdbool.h>
#include <string.h>
#include <unistd.h>

/* The temporary being written; read by the handlers only when cli_temp_set is 1. */
static char cli_temp_path[4096 + 64];
static volatile sig_atomic_t cli_temp_set;
static bool cli_signals_installed;
/* cli_signals_stop_arm: the first SIGINT or SIGTERM only asks the render to stop
 * (cli_stop_signal); the next one, or SIGHUP, ends the process as before. */
static volatile sig_atomic_t cli_stop_armed, cli_stop_signal;

static const int cli_fatal_signals[] = {SIGINT, SIGTERM, SIGHUP};

static void cli_signal_handler(int sig)
{
    if (cli_stop_armed && !cli_stop_signal && (sig == SIGINT || sig == SIGTERM)) {
        cli_stop_signal = sig;
        static const char msg[] = "\ncaustic: interrupted: stopping after the current pass to write what is "
                                  "done (interrupt again to abort at once, writing nothing)\n";
        ssize_t w = write(STDERR_FILENO, msg, sizeof msg - 1);
        (void)w;
        return;
    }
    if (cli_temp_set) unlink(cli_temp_path);
    /* Die of the signal itself, so the shell sees 128 + sig: the default action, raised
     * again; it is delivered when the handler returns (sig is blocked until then). */
    struct sigaction dfl;
    memset(&dfl, 0, sizeof dfl);
    dfl.sa_handler = SIG_DFL;
    sigemptyset(&dfl.sa_mask);
    sigaction(sig, &dfl, NULL);
    raise(sig);
}

static void cli_signals_mask(sigset_t *set)
{
    sigemptyset(set);
    for (size_t i = 0; i < sizeof cli_fatal_signals / sizeof cli_fatal_signals[0]; i++)
        sigaddset(set, cli_fatal_signals[i]);
}

void cli_signals_install(void)
{
    if (cli_signals_installed) return;
    cli_signals_installed = true;
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = cli_signal_handler;
    cli_signals_mask(&sa.sa_mask); /* one handler at a time */
    for (size_t i = 0; i < sizeof cli_fatal_signals / sizeof cli_fatal_signals[0]; i++) {
        struct sigaction old;
        if (sigaction(cli_fatal_signals[i], NULL, &old) == 0 && old.sa_handler != SIG_IGN)
            sigaction(cli_fatal_signals[i], &sa, NULL);
    }
    /* The default action of SIGXFSZ kills the process in the middle of write(2); ignored,
     * the write fails with EFBIG, which the library reports and cleans up after. */
    signal(SIGXFSZ, SIG_IGN);
}

void cli_signals_temp_file(void *user, const char *temp_path)
{
    (void)user;
    sigset_t block, old;
    cli_signals_mask(&block);
    pthread_sigmask(SIG_BLOCK, &block, &old);
    cli_temp_set = 0;
    if (temp_path && strlen(temp_path) < sizeof cli_temp_path) {
        memcpy(cli_temp_path, temp_path, strlen(temp_path) + 1);
        cli_temp_set = 1;
    }
    pthread_sigmask(SIG_SETMASK, &old, NULL);
}

void cli_signals_stop_arm(void)
{
    cli_signals_install();
    cli_stop_armed = 1;
}

void cli_signals_stop_disarm(void)
{
    cli_stop_armed = 0;
}

int cli_signals_stop_requested(void)
{
    return cli_stop_signal;
}
