/* What the library can be asked for by name, and how it was built: cst_list_names reads
 * each kind from the table of the module that owns it; cst_build_info from the compiler. */
#include <string.h>

#include "accel/accel.h"
#include "caustic/caustic.h"
#include "io/image_io.h"
#include "materials/material.h"
#include "scene/json/json_light.h"
#include "scene/json/json_material.h"

/* The index-th entry of a NULL-terminated table. */
static const char *table_entry(const char *const *table, int index)
{
    for (int i = 0; table[i]; i++)
        if (i == index) return table[i];
    return NULL;
}

/* The index-th enumerator from 1 up that `name` knows: the public name functions answer
 * "default" past the last one. */
static const char *enum_entry(const char *(*name)(int), int index)
{
    const char *s = name(index + 1);
    return strcmp(s, "default") == 0 ? NULL : s;
}

static const char *integrator_at(int k) { return cst_integrator_name((CstIntegrator)k); }
static const char *sampler_at(int k) { return cst_sampler_name((CstSampler)k); }
static const char *filter_at(int k) { return cst_filter_name((CstFilter)k); }

const char *cst_list_names(CstNameKind kind, int index)
{
    if (index < 0) return NULL;
    switch (kind) {
    case CST_NAMES_INTEGRATOR: return enum_entry(integrator_at, index);
    case CST_NAMES_SAMPLER: return enum_entry(sampler_at, index);
    case CST_NAMES_FILTER: return enum_entry(filter_at, index);
    case CST_NAMES_ACCEL:
        for (int t = 0; t < ACCEL_TYPE_COUNT; t++)
            if (accel_type_available((AccelType)t) && index-- == 0) return accel_type_name((AccelType)t);
        return NULL;
    case CST_NAMES_MATERIAL: return table_entry(json_material_types, index);
    case CST_NAMES_LIGHT: return table_entry(json_light_types, index);
    case CST_NAMES_OUTPUT_FORMAT: return image_writable_extension(index);
    case CST_NAMES_METAL: return table_entry(material_metal_names, index);
    }
    return NULL;
}

/* ------------------------------------------------------------------ build */

#ifndef CST_BUILD_TYPE
#define CST_BUILD_TYPE "unknown" /* CMake sets it for this file */
#endif

void cst_build_info(CstBuildInfo *info)
{
    memset(info, 0, sizeof *info);
    info->version = CST_VERSION_STRING;
#if defined(__clang__)
    info->compiler = "clang " __clang_version__;
#elif defined(__GNUC__)
    info->compiler = "gcc " __VERSION__;
#else
    info->compiler = "unknown";
#endif
    /* The widest vector extension this file was compiled for: every file of the library
     * gets the same flags (CST_NATIVE: -march=native). */
#if defined(__AVX512F__)
    info->isa = "AVX-512";
#elif defined(__AVX2__)
    info->isa = "AVX2";
#elif defined(__AVX__)
    info->isa = "AVX";
#elif defined(__SSE4_2__)
    info->isa = "SSE4.2";
#elif defined(__SSE2__)
    info->isa = "SSE2";
#else
    info->isa = "generic";
#endif
    info->build_type = CST_BUILD_TYPE[0] ? CST_BUILD_TYPE : "unknown";
    info->embree = accel_type_available(ACCEL_EMBREE);
#ifdef CST_HAVE_MPI
    info->mpi = 1;
#endif
#ifdef CST_HAVE_SDL2
    info->sdl2 = 1;
#endif
#if defined(__SANITIZE_ADDRESS__)
    info->sanitizers = 1;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
    info->sanitizers = 1;
#endif
#endif
}
