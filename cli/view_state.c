/* caustic view's checkpoint (view_state.h): the accumulation as a render's state file. */
#include "view_state.h"

#include <stdio.h>

#include "metadata.h"

bool view_state_write(const char *path, const CstScene *scene, const CstRenderSettings *pass, const CstFilm *acc,
                      int spp, const char *scene_path, char *msg, size_t size)
{
    CstRenderSettings s = *pass;
    s.spp = spp;
    s.first_sample = 0;
    s.progress = NULL;
    s.progress_user = NULL;
    s.photon_cache = NULL;
    /* The scene's id as cli/render.c's cli_passes_setup makes it. */
    char id[96], hex[65];
    if (!scene_path) snprintf(id, sizeof id, "builtin:cornell-box");
    else if (cli_sha256_file(scene_path, hex)) snprintf(id, sizeof id, "sha256:%s", hex);
    else snprintf(id, sizeof id, "unhashed");
    CstError err = {0};
    if (cst_film_state_write(path, acc, scene, &s, id, NULL, &err) != CST_OK) {
        snprintf(msg, size, "%s", err.msg);
        return false;
    }
    return true;
}

void view_state_add(CstFilm **acc, const CstScene *scene, const CstRenderSettings *pass, const CstFilm *film,
                    bool first, bool wanted)
{
    if (first) {
        cst_film_destroy(*acc);
        *acc = NULL;
        if (wanted && cst_film_create(scene, pass, acc, NULL) != CST_OK) *acc = NULL;
    }
    if (*acc && cst_film_add(*acc, film, NULL) != CST_OK) {
        cst_film_destroy(*acc);
        *acc = NULL;
    }
}

bool view_state_checkpoint(const char *name, const CstRenderSettings *pass, const ViewCheckpoint *k)
{
    const char *why = k->refused ? "not in the preview and sppm modes"
                      : k->moved ? "the camera has moved (a state file does not hold the camera; c writes it as JSON)"
                      : !k->acc || k->spp == 0 ? "no pass accumulated yet"
                                               : NULL;
    char msg[512];
    if (why) {
        fprintf(stderr, "caustic: view: no checkpoint: %s\n", why);
        return false;
    }
    if (!view_state_write(name, k->scene, pass, k->acc, k->spp, k->scene_path, msg, sizeof msg)) {
        fprintf(stderr, "caustic: view: checkpoint: %s\n", msg);
        return false;
    }
    printf("view: checkpoint %s (%s, %d passes); continue it with caustic render --integrator %s --resume %s and "
           "the viewer's options\n", name, k->mode_name, k->spp, cst_integrator_name(k->integrator), name);
    fflush(stdout);
    return true;
}
