/* Signals while an image is written: SIGINT, SIGTERM and SIGHUP remove the temporary file
 * the library announced (CstImageWriteOptions.temp_file) and then end the process as the
 * signal would have; SIGXFSZ is ignored, so a write past `ulimit -f` fails with EFBIG and
 * the library removes its temporary itself. The only signal state of the CLI. */
#ifndef CST_CLI_SIGNALS_H
#define CST_CLI_SIGNALS_H

/* Installs the handlers (a signal ignored when caustic started, as nohup does for SIGHUP,
 * stays ignored). Once per process; later calls do nothing. */
void cli_signals_install(void);

/* A CstTempFileFn (user unused): remembers `temp_path` (NULL: forget it) for the handlers.
 * Signals are blocked while the name changes, so a handler sees a whole name or none. */
void cli_signals_temp_file(void *user, const char *temp_path);

#endif
