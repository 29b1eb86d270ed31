/* The Camera directive, and at the end of the file the camera it leaves to the scene
 * (pbrt's screen window and field of view onto caustic's camera). */
#ifndef CST_SCENE_PBRT_PBRT_CAMERA_H
#define CST_SCENE_PBRT_PBRT_CAMERA_H

#include "scene/pbrt/pbrt_loader.h"

/* Directive handler, called through the table in pbrt_scene.c. */
CstStatus pbrt_camera_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname);

/* The CameraDesc equal to pbrt's view: position and axes from world-from-camera; pbrt's
 * image right is the camera's +x, ours forward x up, so a frame where those disagree
 * (every plain LookAt: x = up x dir) is rendered mirrored (Scene.camera_mirror). fov spans the shorter image
 * axis in pbrt and the vertical one in caustic. */
CstStatus pbrt_camera_finish(Loader *ld);

#endif
