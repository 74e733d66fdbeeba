/*
 * Finger devices: custom finger electronics played by a small Lua program,
 * the device model, one per finger. The model gets what the gripper's
 * script sends over the finger's UART (as the wire delivers it, in the
 * step) or SPI, answers as the electronics would, and reads what the
 * finger's pad feels (force, contact patch) to make its values. It is the
 * finger interface's link (wsg/finger.h): it changes the firmware's state
 * only through it, from within the update.
 *
 * Each model runs in a Lua state of its own, sandboxed like scripts (no
 * files, no loading, no modules, no pattern functions or random numbers)
 * with its own memory cap and a bound on the instructions each call may
 * run; breaking either, or an error, is the electronics failing: the
 * finger faults (D17) until its power is cycled, which starts the model
 * afresh from its source. docs/scripting.md describes the model's API.
 */
#ifndef WSG_SCRIPT_FDEV_H
#define WSG_SCRIPT_FDEV_H

#include <stddef.h>
#include <stdint.h>

#include "wsg/finger.h"

/* A model's source at most, its memory by default and the instructions
 * one call (a callback, or the model's body at power-on) may run. */
#define WSG_FDEV_SOURCE_MAX   (256u << 10)
#define WSG_FDEV_MEMORY       (1u << 20)
#define WSG_FDEV_INSTRUCTIONS 1000000u

struct wsg_fdev;

/* Load the model in path (or, with path NULL, the n bytes of src named
 * name) for finger i of fs and attach it: its kind becomes device with the
 * next update, which starts the model if the finger has power. 0, or
 * -errno with a reason in err: -ENOENT and the like for the file, -EFBIG
 * past WSG_FDEV_SOURCE_MAX, -EINVAL when it does not compile. memory 0:
 * WSG_FDEV_MEMORY. */
int wsg_fdev_open(struct wsg_fdev **out, struct wsg_fingers *fs, int i,
                  const char *path, const char *src, size_t n,
                  const char *name, size_t memory, char *err, size_t errcap);
/* Detach it (the finger becomes generic with the next update) and free
 * it. NULL is fine. */
void wsg_fdev_close(struct wsg_fdev *m);
/* The model's last failure ("" none) and its name (the file's). */
const char *wsg_fdev_error(const struct wsg_fdev *m);
const char *wsg_fdev_name(const struct wsg_fdev *m);
/* Bytes the model's state holds now (0 while unpowered). */
size_t wsg_fdev_memory(const struct wsg_fdev *m);

/* The scripts' setmetatable (api.c), which never marks a table for
 * finalization: Lua runs finalizers with hooks off. */
struct lua_State;
int wsg_script_setmetatable(struct lua_State *L);
/* A script's bytes (finger.c): a string, or a table of numbers 0..255
 * (else a Lua error naming the first that is not), into out, at most cap;
 * how many. Scripts' finger.write and finger.spi and the models' dev.*
 * read what they send so. */
size_t wsg_script_bytes(struct lua_State *L, int arg, uint8_t *out,
                        size_t cap);

#endif
