/* caustic list and caustic --version: the names the library accepts, read from its own
 * tables (cst_list_names), and how the library was built (cst_build_info). */
#include <stdio.h>
#include <string.h>

#include "cli.h"

/* In the order of ARGS_LIST_KINDS (args.c), with the heading `caustic list` prints. */
static const struct { CstNameKind kind; const char *heading; } CLI_LIST[] = {
    {CST_NAMES_INTEGRATOR, "integrators (--integrator)"},
    {CST_NAMES_SAMPLER, "samplers (--sampler)"},
    {CST_NAMES_FILTER, "filters (--filter)"},
    {CST_NAMES_ACCEL, "accels (--accel; the back ends of this build)"},
    {CST_NAMES_MATERIAL, "materials (a JSON material's \"type\")"},
    {CST_NAMES_LIGHT, "lights (a JSON light's \"type\"; area lights are shapes with \"emission\", "
                      "the sky is \"environment\")"},
    {CST_NAMES_OUTPUT_FORMAT, "formats (-o extensions)"},
    {CST_NAMES_METAL, "metals (a conductor's \"metal\")"},
};
#define CLI_LIST_KINDS (sizeof CLI_LIST / sizeof CLI_LIST[0])

int cli_list(const CliArgs *a)
{
    for (size_t k = 0; k < CLI_LIST_KINDS && ARGS_LIST_KINDS[k]; k++) {
        if (a->list_kind) {
            if (strcmp(a->list_kind, ARGS_LIST_KINDS[k]) != 0) continue;
            for (int i = 0; cst_list_names(CLI_LIST[k].kind, i); i++)
                printf("%s\n", cst_list_names(CLI_LIST[k].kind, i));
            return CLI_EXIT_OK;
        }
        printf("%s\n ", CLI_LIST[k].heading);
        for (int i = 0; cst_list_names(CLI_LIST[k].kind, i); i++)
            printf(" %s", cst_list_names(CLI_LIST[k].kind, i));
        printf("\n");
    }
    return CLI_EXIT_OK;
}

int cli_version(void)
{
    CstBuildInfo b;
    cst_build_info(&b);
    printf("caustic %s\n", CST_VERSION_STRING);
    if (strcmp(b.version, CST_VERSION_STRING) != 0)
        printf("library:    %s (the tool is %s)\n", b.version, CST_VERSION_STRING);
    printf("build:      %s\n", b.build_type);
    printf("compiler:   %s\n", b.compiler);
    printf("isa:        %s (the library's vector code)\n", b.isa);
    printf("embree:     %s\n", b.embree ? "yes" : "no");
    printf("mpi:        %s\n", b.mpi ? "yes" : "no");
    /* SDL2 is the CLI's (caustic view), never the library's. */
    printf("sdl2:       %s\n", b.sdl2 || cli_view_available() ? "yes (caustic view)" : "no");
    if (b.sanitizers) printf("sanitizers: address, undefined\n");
    return CLI_EXIT_OK;
}
