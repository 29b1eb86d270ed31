/* caustic view's script: the commands a test (or a user) feeds the viewer instead of keys
 * and the mouse, one per line (docs/cli.md, "caustic view"). No SDL here: view.c maps them. */
#ifndef CST_CLI_VIEW_SCRIPT_H
#define CST_CLI_VIEW_SCRIPT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

/* The Escape key in script terms (SDL's keycode for it is the ASCII ESC too). */
#define VIEW_KEY_ESCAPE 27

typedef enum ViewScriptOp {
    VIEW_SCRIPT_KEY,      /* key K: as if K were pressed */
    VIEW_SCRIPT_WAIT_SPP, /* wait-spp N: until the image holds at least N samples per pixel */
    VIEW_SCRIPT_SAVE,     /* save PATH: the shown image (.exr/.pfm linear, .png as displayed) */
    VIEW_SCRIPT_ORBIT,    /* orbit DX DY: a left-button drag of DX, DY pixels */
    VIEW_SCRIPT_PAN,      /* pan DX DY: a middle-button drag */
    VIEW_SCRIPT_DOLLY,    /* dolly N: N wheel steps (> 0 towards the target) */
    VIEW_SCRIPT_STATUS,   /* status: one line "view: mode M spp N ..." on stdout */
    VIEW_SCRIPT_QUIT,     /* quit */
    VIEW_SCRIPT_CLICK,    /* click X Y: a left click (no drag) at film pixel X, Y: the focus there */
    VIEW_SCRIPT_CAMERA,   /* camera PATH: the camera as a JSON scene fragment to PATH */
    VIEW_SCRIPT_EXPLAIN   /* explain X Y: a right click at film pixel X, Y: its explanation */
} ViewScriptOp;

typedef struct ViewScriptCmd {
    ViewScriptOp op;
    int line;    /* in the script file, for messages */
    int key;     /* KEY: a lower-case character, '\t', or VIEW_KEY_ESCAPE */
    double a, b; /* WAIT_SPP: a; ORBIT, PAN, CLICK, EXPLAIN: a, b; DOLLY: a */
    char *path;  /* SAVE, CAMERA: owned */
} ViewScriptCmd;

typedef struct ViewScript {
    ViewScriptCmd *cmds;
    int count, cap;
    int next; /* the next command to run */
} ViewScript;

/* Reads and checks the whole script. False with msg "FILE:LINE:COL: what was expected"
 * (or "FILE: reason" when it cannot be read); *out is then empty. */
bool view_script_load(const char *path, ViewScript *out, char *msg, size_t size);
/* The same from memory (text need not end in NUL; a NUL byte is an error); path names it in
 * messages. The fuzz target tests/fuzz/fuzz_view_script.c drives it. */
bool view_script_parse(const char *text, size_t len, const char *path, ViewScript *out, char *msg, size_t size);
void view_script_free(ViewScript *s);

#endif
