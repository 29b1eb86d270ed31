/* Input files: the one gate every reader of a scene, include, mesh, texture or image opens
 * its file through (regular files only, bounded in size), and whole-file reads. */
#ifndef CST_CORE_FILE_H
#define CST_CORE_FILE_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "caustic/caustic.h"

/* Largest input file caustic reads: 4 GiB (docs/scene-format.md, docs/cli.md). Larger than
 * any mesh or image we render, small enough that a wrong path cannot fill memory. */
#define FILE_MAX_INPUT_BYTES ((uint64_t)4 << 30)

/* Opens path for reading when it is a regular file (after following symlinks) of at most
 * FILE_MAX_INPUT_BYTES. The check never blocks: the file is opened with O_NONBLOCK and
 * examined with fstat before anything is read, so a FIFO, a directory or a device (a
 * symlink to /dev/zero) is an error, not a read without end. Errors: CST_ERR_IO ("PATH:
 * cannot open: REASON", "PATH: is not a regular file (a FIFO); expected a file"),
 * CST_ERR_UNSUPPORTED (too large). On success the caller owns *out: fclose(). *size_out
 * (may be NULL) gets the file's size at the check. */
CstStatus file_open_input(const char *path, FILE **out, uint64_t *size_out, CstError *err);

/* The same check, then closes the file: for readers that must hand a path to a library. */
CstStatus file_check_input(const char *path, CstError *err);

/* Reads all of path (through file_open_input) into a new malloc'd buffer, NUL-terminated
 * one byte past *out_len (which does not count it). Errors (CST_ERR_IO, CST_ERR_OOM,
 * CST_ERR_UNSUPPORTED) name the path and the reason. */
CstStatus file_read_all(const char *path, char **out, size_t *out_len, CstError *err);

#endif
