/* The reproducibility metadata `caustic render` stores in PNG and EXR outputs: version,
 * command line, scene file and its SHA-256, integrator, sampler, filter, seed, spp and
 * render time (keys in docs/cli.md). */
#ifndef CST_CLI_METADATA_H
#define CST_CLI_METADATA_H

#include "caustic/caustic.h"

#include <stdbool.h>

enum { CLI_METADATA_MAX = 12 };

typedef struct CliMetadata {
    CstImageMetadata entry[CLI_METADATA_MAX];
    int count;
    char *command, *scene;  /* shell-quoted, malloc'd (NULL when unknown) */
    char sha256[65];        /* hex, "" when the scene is not a readable regular file */
    char seed[24], spp[16], seconds[32];
} CliMetadata;

/* Before rendering: the command line and the scene file (NULL = the built-in Cornell
 * box), hashed as it is when the render starts. */
void cli_metadata_begin(CliMetadata *md, const char *scene_path);
/* After rendering: the settings the render used (resolved) and its statistics; fills
 * md->entry. */
void cli_metadata_finish(CliMetadata *md, const CstRenderSettings *used, const CstRenderStats *stats);
/* Accepts a zeroed or finished CliMetadata. */
void cli_metadata_free(CliMetadata *md);

/* SHA-256 (FIPS 180-4) of a regular file's bytes as 64 hex digits; false if it cannot be
 * read or is not a regular file. */
bool cli_sha256_file(const char *path, char hex[65]);

#endif
