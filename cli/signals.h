/* Signals while an image is written: SIGINT, SIGTERM and SIGHUP remove the temporary file
 * the library announced (CstImageWriteOptions.temp_file) and then end the process as the
 * signal would have; SIGXFSZ is ignored, so a write past `ulimit -f` fails with EFBIG and
 * the library removes its temporary itself. During a render (cli_signals_stop_arm) the
 * first SIGINT or SIGTERM is a stop request instead: the render stops after its pass and
 * writes what it has (docs/cli.md, "Interrupting a render"). The only signal state of the
 * CLI. */
#ifndef CST_CLI_SIGNALS_H
#define CST_CLI_SIGNALS_H

/* Installs the handlers (a signal ignored when caustic started, as nohup does for SIGHUP,
 * stays ignored). Once per process; later calls do nothing. */
void cli_signals_install(void);

/* A CstTempFileFn (user unused): remembers `temp_path` (NULL: forget it) for the handlers.
 * Signals are blocked while the name changes, so a handler sees a whole name or none. */
void cli_signals_temp_file(void *user, const char *temp_path);

/* Installs the handlers and arms the stop request: from now on the first SIGINT or
 * SIGTERM is remembered (and said on stderr) instead of ending the process; a second one,
 * or SIGHUP, removes the announced temporary and ends it. */
void cli_signals_stop_arm(void);
/* Back to ending the process at the first signal (the image write after a render: an
 * interrupted write leaves no file, and any earlier output stays as it was). */
void cli_signals_stop_disarm(void);
/* The signal number of the stop request, 0 when none came. */
int cli_signals_stop_requested(void);

#endif
