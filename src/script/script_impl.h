/*
 * The script host's layout, private to src/script: host.c runs the
 * interpreter (state, sandbox, scheduling), api.c is the library the
 * script calls (cmd, mc, grasping, finger, ...). Both reach the host from
 * any Lua thread through the state's extra space.
 */
#ifndef WSG_SCRIPT_IMPL_H
#define WSG_SCRIPT_IMPL_H

#include <lua.h>

#include "script.h"
#include "wsg/proto.h"

/* A path as realpath writes one (PATH_MAX on Linux). */
#define WSG_SCRIPT_PATH_MAX 4096

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
    uint32_t budget; /* instructions left in this slice */
    unsigned stuck;  /* slices run where the script could not yield */
    int owed;        /* a slice ran out where it could not yield */
    uint64_t preempted;
    uint32_t reply_tag; /* session of the packet read last; 0: none */
    struct wsg_script_packet queue[WSG_SCRIPT_QUEUE];
    size_t qhead, qlen;
    uint8_t *tx; /* cmd.send's packet, WSG_SCRIPT_SEND_MAX payload */
    double pid[3];
    int finger_power[2];
    char out[WSG_SCRIPT_OUTPUT_MAX]; /* ring of what it printed */
    uint64_t out_total;
};

static inline struct wsg_script *wsg_script_of(lua_State *L)
{
    return *(struct wsg_script **)lua_getextraspace(L);
}

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

#endif
