/*
 * The script host's layout, private to src/script: host.c runs the
 * interpreter (state, sandbox, scheduling), api.c is the library the
 * script calls (cmd, mc, grasping, finger, ...). Both reach the host from
 * any Lua thread through the state's allocator, whose user data it is.
 *
 * The interpreter is Debian's Lua 5.2 (docs/scripting.md says why): its
 * continuations are plain C functions that ask lua_getctx for the status
 * and the context they were given.
 */
#ifndef WSG_SCRIPT_IMPL_H
#define WSG_SCRIPT_IMPL_H

#include <stddef.h>
#include <stdint.h>

#include <lua.h>

#include "script.h"
#include "strlib.h"
#include "wsg/proto.h"

/* A path as realpath writes one (PATH_MAX on Linux). */
#define WSG_SCRIPT_PATH_MAX 4096
/* Coroutines resumed inside each other that the host keeps track of;
 * deeper ones run on, but cannot be preempted. Lua stops at some 200
 * (its C stack). */
#define WSG_SCRIPT_NEST_CO 256

/* A packet for the script, waiting in cmd.read's queue. */
struct wsg_script_packet {
    uint32_t tag; /* the session it came from: cmd.send answers there */
    uint8_t id;
    uint16_t len;
    uint8_t data[WSG_PAYLOAD_MAX];
};

struct wsg_script {
    struct wsg_device *dev;
    struct wsg_script_config cfg;
    lua_State *L;  /* NULL: no script */
    lua_State *co; /* the script's body, a coroutine of L */
    enum wsg_script_state state;
    uint64_t wake_us;
    int failed;
    char error[512];
    char file[WSG_SCRIPT_PATH_MAX];
    char dir[WSG_SCRIPT_PATH_MAX];
    int quote; /* compile errors may quote the text: in the script dir */
    size_t memory;
    size_t limit;    /* what the allocator allows: the cap, or past it */
    uint32_t budget; /* steps left in this slice (instructions, work) */
    /* Slices run where the script could not yield, not yet earned back:
     * one comes back with each turn the script gets. The script's, not a
     * coroutine's or a call's: a fresh one starts with what is left. */
    unsigned stuck;
    int owed;           /* a slice ran out where it could not yield */
    int preempting;     /* a preemption's yield is on its way to the host */
    lua_State *running; /* the script's thread running now; NULL: none */
    /* The script's coroutines resumed now, outermost first, and whether
     * each one's yield can reach the host (its resumer's could). */
    unsigned nest;
    struct {
        lua_State *co;
        int reach;
    } nested[WSG_SCRIPT_NEST_CO];
    struct wsg_budget slice; /* the string functions' view of the slice */
    uint64_t preempted;
    uint32_t reply_tag; /* session of the packet read last; 0: none */
    struct wsg_script_packet queue[WSG_SCRIPT_QUEUE];
    size_t qhead, qlen;
    uint8_t *tx; /* cmd.send's packet, WSG_SCRIPT_SEND_MAX payload */
    double pid[3];
    char out[WSG_SCRIPT_OUTPUT_MAX]; /* ring of what it printed */
    uint64_t out_total;
};

static inline struct wsg_script *wsg_script_of(lua_State *L)
{
    void *h = NULL;

    lua_getallocf(L, &h);
    return h;
}

/* The largest lua_Integer (Lua 5.2's is a ptrdiff_t). */
#define WSG_LUA_INTEGER_MAX PTRDIFF_MAX

/* The number at idx when it is whole and a lua_Integer holds it: 1 with
 * it in *out, else 0 (Lua 5.2's lua_tointegerx truncates 2.5 to 2). */
int wsg_script_whole(lua_State *L, int idx, lua_Integer *out);

/* The largest script or module file the host loads. */
#define WSG_SCRIPT_SOURCE_MAX (4u << 20)

/* Load the Lua source file at path (text only, never a binary chunk) as
 * a function on L's stack, named "@path" in messages. The file is opened
 * once and read from that descriptor, and a symbolic link as its last
 * component is not followed: a file checked before cannot be swapped for
 * a link to another one. 0 (the function pushed); a Lua error status
 * (its message pushed) when it does not compile; -errno (nothing pushed)
 * when it cannot be read: -ELOOP for a link, -EFBIG past
 * WSG_SCRIPT_SOURCE_MAX. */
int wsg_script_loadfile(lua_State *L, const char *path);
/* The same for a module: the file rel below the directory dir, opened
 * one component at a time without following a link anywhere in rel
 * (-ELOOP), named "@name" in messages. */
int wsg_script_loadmodule(lua_State *L, const char *dir, const char *rel,
                          const char *name);

/* The finger library (finger.c): finger.type, data, power, and the
 * UART and SPI to custom finger electronics. */
void wsg_script_open_finger(lua_State *L);
/* Open the script's libraries (api.c) in L: the sandboxed standard ones,
 * the gripper's and the Lua 5.1/5.2 names. */
void wsg_script_open_api(lua_State *L, struct wsg_script *h);
/* Append text to what the script printed (and to the print callback). */
void wsg_script_print(struct wsg_script *h, const char *text, size_t len);
/* Take the oldest queued packet onto L's stack as id, payload table; the
 * packet's session becomes the one cmd.send answers. Returns 2 values
 * pushed, or 0 with the queue empty. */
int wsg_script_take(struct wsg_script *h, lua_State *L);
/* The simulated time now, us. */
uint64_t wsg_script_now(const struct wsg_script *h);

/* ---- the slice (host.c) ----
 * A script runs in slices of WSG_SCRIPT_SLICE steps: instructions,
 * counted by the count hook, and the work of library functions, counted
 * by them. Where the running code can yield to the host (the body, or a
 * coroutine the body resumed, and not inside a callback from C), the end
 * of a slice is a yield, carried through the coroutines that resumed it;
 * elsewhere it goes on, and a stretch of WSG_SCRIPT_STUCK_MAX slices
 * there ends in an error. */
/* Slices a script may run at a stretch where it cannot yield; they come
 * back one a turn. */
#define WSG_SCRIPT_STUCK_MAX 20u

/* L's yield can reach the host now. */
int wsg_script_preemptible(struct wsg_script *h, lua_State *L);
/* Steps of work L did. When they use up the slice, the count hook comes
 * at L's next instruction to end it there. */
void wsg_script_spend(struct wsg_script *h, lua_State *L, uint32_t steps);
/* The slice is over in L (which is not inside the count hook). 1: L must
 * yield now (lua_yieldk; the host has been told). 0: it cannot, and goes
 * on with a fresh slice. Raises the stuck error past the allowance. */
int wsg_script_slice_over(struct wsg_script *h, lua_State *L);
/* The allowance is used up and L cannot yield: an error caught here must
 * go on up, to where the script can be preempted (pcall, xpcall,
 * coroutine.resume, close and load re-raise it), or a loop catching it
 * would never let the daemon go. */
int wsg_script_doomed(struct wsg_script *h, lua_State *L);
/* coroutine.resume, wrap, pcall, xpcall and load, over Lua's
 * (coro.c), in the libraries opened in L. */
void wsg_script_open_coro(lua_State *L);
/* The library functions whose work is spent from the slice
 * (costs.c). */
void wsg_script_open_costs(lua_State *L);

#endif
