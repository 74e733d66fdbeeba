/*
 * A script's pattern functions (string.find, match, gmatch, gsub) and
 * what they spend: each call runs the pattern machine (match.h) for what
 * is left of the script's slice, then asks whether it may yield across
 * itself. Where it may, it yields (lua_yieldk) and goes on from where it
 * was when the coroutine is resumed; where it may not (inside a callback
 * from C), it goes on with a fresh slice, and whoever counts the slices
 * ends it with an error if they never end. The budget is the caller's
 * (the script host's; the fuzzer has its own), through struct wsg_budget.
 */
#ifndef WSG_STRLIB_H
#define WSG_STRLIB_H

#include <stdint.h>

#include <lua.h>

struct wsg_budget {
    /* Steps L may run before its slice is over; 0: over now. */
    uint32_t (*left)(void *ctx, lua_State *L);
    /* Steps L ran (within what left gave, or work already done). */
    void (*spend)(void *ctx, lua_State *L, uint32_t steps);
    /* L's slice is over. 1: L yields now (the function yields with its
     * continuation, and whoever resumes L resumes it). 0: L cannot, and
     * goes on with a fresh slice. It may raise an error instead. */
    int (*over)(void *ctx, lua_State *L);
    void *ctx;
};

/* Set find, match, gmatch and gsub in the table at the top of L's stack
 * (the string library) to the project's, spending through b, which must
 * outlive L. */
void wsg_strlib_open(lua_State *L, const struct wsg_budget *b);

#endif
