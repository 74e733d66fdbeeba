/*
 * What a script on the gripper can call: the sandboxed part of Lua's
 * standard library, the gripper's own libraries (cmd, mc, gripper,
 * grasping, finger, socket) and globals (bton, ntob, etob, E_*, sleep,
 * print, printf), and the Lua 5.1/5.2 names that scripts of the gripper's
 * era still use. docs/scripting.md describes each function, and where the
 * public text leaves a meaning open, what the emulator chose.
 *
 * Motions a script starts carry tag 0: no host waits for their final
 * result; the script watches mc.busy() and grasping.state(). Each request
 * is settled at once, so the next call already sees it (as the dispatcher
 * settles after each command).
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <lauxlib.h>
#include <lualib.h>

#include "script_impl.h"

/* grasping.clamp's closing speed: slow, as the fingers start at the part. */
#define WSG_SCRIPT_CLAMP_SPEED 20.0

/* ---- helpers ---- */

static struct wsg_axis *api_axis(lua_State *L)
{
    return wsg_device_axis(wsg_script_of(L)->dev);
}

/* A blocking call must come from the script's body, where a yield reaches
 * the host: from a coroutine of the script's own it would resume that
 * coroutine's caller instead. */
static struct wsg_script *api_body(lua_State *L, const char *fn)
{
    struct wsg_script *h = wsg_script_of(L);

    if (L != h->co)
        luaL_error(L, "%s: cannot wait inside a coroutine of the script", fn);
    return h;
}

static uint8_t api_byte(lua_State *L, int arg)
{
    lua_Integer v = luaL_checkinteger(L, arg);

    luaL_argcheck(L, v >= 0 && v <= 255, arg, "not a byte (0..255)");
    return (uint8_t)v;
}

static double api_number(lua_State *L, int arg)
{
    double v = luaL_checknumber(L, arg);

    luaL_argcheck(L, !isnan(v), arg, "NaN");
    return v;
}

/* A number for a motion: NaN goes through, for the axis to refuse with
 * E_INVALID_PARAMETER, the status the script gets (as a host gets it for
 * a NaN in a command) rather than an error that would end a script
 * whose controller computed one. */
static double api_motion_number(lua_State *L, int arg)
{
    return luaL_checknumber(L, arg);
}

/* The status a motion request leaves the script with: E_SUCCESS when it
 * started (there is no packet to be pending on), else why not. */
static int api_motion(lua_State *L, uint16_t st)
{
    struct wsg_axis *ax = api_axis(L);

    if (st == WSG_E_CMD_PENDING)
        st = WSG_E_SUCCESS;
    wsg_axis_settle(ax);
    lua_pushinteger(L, st);
    return 1;
}

/* The session cmd.send answers: the one whose packet was read last, else
 * (nothing read yet) the one that sent the gripper anything last. NULL
 * when that one is gone: an answer to a host that left must not go to
 * another one, which never asked for it. */
static struct wsg_session *api_host(struct wsg_script *h)
{
    return wsg_device_session(h->dev,
                              h->reply_tag ? h->reply_tag : h->dev->last_tag);
}

static void api_bytes(lua_State *L, const uint8_t *p, int n)
{
    int i;

    lua_createtable(L, n, 0);
    for (i = 0; i < n; i++) {
        lua_pushinteger(L, p[i]);
        lua_rawseti(L, -2, i + 1);
    }
}

/* ---- globals ---- */

static int api_print(lua_State *L)
{
    struct wsg_script *h = wsg_script_of(L);
    int i, n = lua_gettop(L);
    luaL_Buffer b;

    luaL_buffinit(L, &b);
    for (i = 1; i <= n; i++) {
        if (i > 1)
            luaL_addchar(&b, '\t');
        luaL_tolstring(L, i, NULL);
        luaL_addvalue(&b);
    }
    luaL_addchar(&b, '\n');
    luaL_pushresult(&b);
    {
        size_t len;
        const char *s = lua_tolstring(L, -1, &len);

        wsg_script_print(h, s, len);
    }
    return 0;
}

/* printf's output (the prelude formats). */
static int api_output(lua_State *L)
{
    size_t len;
    const char *s = luaL_checklstring(L, 1, &len);

    wsg_script_print(wsg_script_of(L), s, len);
    return 0;
}

static int api_sleep(lua_State *L)
{
    struct wsg_script *h = api_body(L, "sleep");
    double ms = api_number(L, 1);
    uint64_t us;

    if (ms < 0)
        ms = 0;
    /* Past a year of simulated time, a year: no overflow of the clock. */
    us = ms > 3.2e10 ? 3200000000000ull : (uint64_t)(ms * 1000.0 + 0.5);
    h->wake_us = wsg_script_now(h) + us;
    h->state = WSG_SCRIPT_SLEEPING;
    return lua_yield(L, 0);
}

static int api_bton(lua_State *L)
{
    uint8_t b[4];
    uint32_t u;
    float f;
    int i;

    luaL_checktype(L, 1, LUA_TTABLE);
    for (i = 0; i < 4; i++) {
        lua_Integer v;
        int ok;

        lua_rawgeti(L, 1, i + 1);
        ok = wsg_script_whole(L, -1, &v);
        if (!ok || v < 0 || v > 255)
            return luaL_error(L, "bton: element %d is not a byte", i + 1);
        b[i] = (uint8_t)v;
        lua_pop(L, 1);
    }
    u = wsg_get_u32(b);
    memcpy(&f, &u, sizeof f);
    lua_pushnumber(L, (lua_Number)f);
    return 1;
}

static int api_ntob(lua_State *L)
{
    uint8_t b[4];

    wsg_put_f32(b, (float)luaL_checknumber(L, 1));
    api_bytes(L, b, 4);
    return 1;
}

static int api_etob(lua_State *L)
{
    lua_Integer e = luaL_checkinteger(L, 1);
    uint8_t b[2];

    luaL_argcheck(L, e >= 0 && e <= 0xFFFF, 1, "not a status code");
    wsg_put_u16(b, (uint16_t)e);
    api_bytes(L, b, 2);
    return 1;
}

/* Lua's setmetatable, but a table is never marked for finalization, as
 * Lua 5.1 did with tables: Lua runs finalizers with hooks off, so one
 * that loops could never be preempted and would hold the daemon (at a
 * collection, or in lua_close when the script is stopped). The __gc
 * field stays in the metatable; the table only is not marked, because
 * the field is absent at the moment the metatable is set. Device models
 * (fdev.c) use it too. */
int wsg_script_setmetatable(lua_State *L)
{
    int t = lua_type(L, 2), gc;

    luaL_checktype(L, 1, LUA_TTABLE);
    luaL_argcheck(L, t == LUA_TNIL || t == LUA_TTABLE, 2,
                  "nil or table expected");
    if (luaL_getmetafield(L, 1, "__metatable") != LUA_TNIL)
        return luaL_error(L, "cannot change a protected metatable");
    lua_settop(L, 2);
    /* Raw, as Lua looks for the field: no metamethod of the metatable's
     * own can hide it or keep it from being taken out. */
    if (t == LUA_TTABLE) {
        lua_pushliteral(L, "__gc");
        lua_rawget(L, 2);
        gc = !lua_isnil(L, -1);
    } else {
        gc = 0;
    }
    if (!gc) {
        lua_settop(L, 2);
        lua_setmetatable(L, 1);
        return 1;
    }
    /* Stack: t, mt, the finalizer. */
    lua_pushliteral(L, "__gc");
    lua_pushnil(L);
    lua_rawset(L, 2);
    lua_pushvalue(L, 2);
    lua_setmetatable(L, 1);
    lua_pushliteral(L, "__gc");
    lua_insert(L, -2);
    lua_rawset(L, 2);
    lua_settop(L, 1);
    return 1;
}

/* ---- cmd ---- */

static int cmd_register(lua_State *L)
{
    struct wsg_script *h = wsg_script_of(L);
    uint8_t id = api_byte(L, 1);

    if (wsg_device_register(h->dev, id, 1) < 0) {
        char msg[64];

        /* Formatted here: lua_pushfstring knows no %02X and would raise
         * its own error instead of this one. */
        snprintf(msg, sizeof msg,
                 "cmd.register: %02Xh is a command of the firmware",
                 (unsigned)id);
        return luaL_error(L, "%s", msg);
    }
    lua_pushboolean(L, 1);
    return 1;
}

static int cmd_unregister(lua_State *L)
{
    struct wsg_script *h = wsg_script_of(L);
    uint8_t id = api_byte(L, 1);

    lua_pushboolean(L, wsg_device_register(h->dev, id, 0) == 0);
    return 1;
}

static int cmd_read_k(lua_State *L)
{
    return wsg_script_take(wsg_script_of(L), L);
}

static int cmd_read(lua_State *L)
{
    struct wsg_script *h = api_body(L, "cmd.read");

    if (h->qlen > 0)
        return wsg_script_take(h, L);
    h->state = WSG_SCRIPT_READING;
    return lua_yieldk(L, 0, 0, cmd_read_k);
}

static int cmd_send(lua_State *L)
{
    struct wsg_script *h = wsg_script_of(L);
    uint8_t id = api_byte(L, 1);
    struct wsg_session *s;
    char err[128];
    size_t visits;
    long n;
    uint16_t crc;

    n = wsg_script_flatten(L, 2, h->tx + WSG_HEADER_LEN, WSG_SCRIPT_SEND_MAX,
                           err, sizeof err, &visits);
    /* Each value visited is a step of the slice (the bytes copied are
     * fewer); the next instruction ends the slice when they use it up. */
    wsg_script_spend(h, L, (uint32_t)visits);
    if (n < 0)
        return luaL_error(L, "cmd.send: %s", err);
    s = api_host(h);
    if (!s) {
        /* No host has talked to the gripper, or it has gone: the
         * packet has nowhere to go, as on a gripper with no one
         * connected. */
        lua_pushboolean(L, 0);
        return 1;
    }
    memset(h->tx, WSG_PREAMBLE_BYTE, WSG_PREAMBLE_LEN);
    h->tx[3] = id;
    wsg_put_u16(h->tx + 4, (uint16_t)n);
    crc = wsg_crc_update(WSG_CRC_INIT, h->tx, WSG_HEADER_LEN + (size_t)n);
    wsg_put_u16(h->tx + WSG_HEADER_LEN + n, crc);
    wsg_device_send(h->dev, s, h->tx,
                    WSG_HEADER_LEN + (size_t)n + WSG_CRC_LEN);
    lua_pushboolean(L, 1);
    return 1;
}

static int cmd_online(lua_State *L)
{
    lua_pushboolean(L, api_host(wsg_script_of(L)) != NULL);
    return 1;
}

static int cmd_available(lua_State *L)
{
    lua_pushinteger(L, (lua_Integer)wsg_script_of(L)->qlen);
    return 1;
}

/* The web page's names of the interfaces, from the session's peer. */
static int cmd_interface(lua_State *L)
{
    static const struct {
        const char *prefix, *name;
    } names[] = {{"tcp ", "TCP/IP"},
                 {"udp ", "UDP/IP"},
                 {"can ", "CAN"},
                 {"pty ", "Serial"}};
    struct wsg_session *s = api_host(wsg_script_of(L));
    size_t i;

    for (i = 0; s && i < sizeof names / sizeof names[0]; i++)
        if (strncmp(s->peer, names[i].prefix, strlen(names[i].prefix)) == 0) {
            lua_pushstring(L, names[i].name);
            return 1;
        }
    lua_pushnil(L);
    return 1;
}

static const luaL_Reg cmd_lib[] = {
    {"register", cmd_register},   {"unregister", cmd_unregister},
    {"read", cmd_read},           {"send", cmd_send},
    {"online", cmd_online},       {"available", cmd_available},
    {"interface", cmd_interface}, {NULL, NULL}};

/* ---- mc ---- */

static int mc_position(lua_State *L)
{
    lua_pushnumber(L, wsg_axis_width(api_axis(L)));
    return 1;
}

static int mc_speed(lua_State *L)
{
    struct wsg_script *h = wsg_script_of(L);
    uint16_t st;
    double v;

    if (lua_isnoneornil(L, 1)) {
        lua_pushnumber(L, wsg_axis_speed(api_axis(L)));
        return 1;
    }
    v = api_motion_number(L, 1);
    st = wsg_device_motion_check(h->dev, 1);
    if (st == WSG_E_SUCCESS)
        st = wsg_axis_request_speed(api_axis(L), v, 0);
    return api_motion(L, st);
}

static int mc_blocked(lua_State *L)
{
    lua_pushboolean(L, wsg_axis_pressing(api_axis(L)));
    return 1;
}

static int mc_busy(lua_State *L)
{
    lua_pushboolean(L, wsg_axis_busy(api_axis(L)));
    return 1;
}

static int mc_aforce(lua_State *L)
{
    lua_pushnumber(L, wsg_axis_force(api_axis(L)));
    return 1;
}

static int mc_force(lua_State *L)
{
    struct wsg_axis *ax = api_axis(L);

    if (!lua_isnoneornil(L, 1)) {
        wsg_axis_set_force_limit(ax, api_number(L, 1));
        wsg_axis_settle(ax);
        return 0;
    }
    lua_pushnumber(L, wsg_axis_force(ax));
    lua_pushnumber(L, wsg_axis_force_limit(ax));
    return 2;
}

static int mc_stop(lua_State *L)
{
    struct wsg_axis *ax = api_axis(L);

    wsg_axis_request_stop(ax);
    wsg_axis_settle(ax);
    return 0;
}

static int mc_move(lua_State *L)
{
    struct wsg_script *h = wsg_script_of(L);
    double w = api_motion_number(L, 1), v = api_motion_number(L, 2);
    /* 21h's flags byte: a value no byte can hold is an error, not its low
     * bits. */
    uint8_t flags = lua_isnoneornil(L, 3) ? 0 : api_byte(L, 3);
    uint16_t st = wsg_device_motion_check(h->dev, 1);

    if (st == WSG_E_SUCCESS)
        st = wsg_axis_request_move(
            api_axis(L),
            (uint8_t)(flags & (WSG_MOVE_RELATIVE | WSG_MOVE_STOP_ON_BLOCK)), w,
            v, 0);
    /* The motion controller's, not the grasping state machine's. */
    if (st == WSG_E_CMD_PENDING)
        wsg_axis_request_own(api_axis(L));
    return api_motion(L, st);
}

static int mc_homing(lua_State *L)
{
    struct wsg_script *h = wsg_script_of(L);
    int dir = WSG_HOME_DEFAULT;
    uint16_t st;

    /* As 20h's byte: 0, 1, 2 home, another byte is E_INVALID_PARAMETER
     * (the axis says so); a value no byte can hold is an error, where an
     * int would have kept its low bits (2^32 + 1 homed positive). */
    if (lua_isboolean(L, 1))
        dir = lua_toboolean(L, 1) ? WSG_HOME_POSITIVE : WSG_HOME_NEGATIVE;
    else if (!lua_isnoneornil(L, 1))
        dir = api_byte(L, 1);
    st = wsg_device_motion_check(h->dev, 0);
    if (st == WSG_E_SUCCESS)
        st = wsg_axis_request_homing(api_axis(L), dir, 0);
    return api_motion(L, st);
}

static int mc_pid(lua_State *L)
{
    struct wsg_script *h = wsg_script_of(L);
    int i;

    if (!lua_isnoneornil(L, 1))
        for (i = 0; i < 3; i++)
            h->pid[i] =
                lua_isnoneornil(L, i + 1) ? h->pid[i] : api_number(L, i + 1);
    for (i = 0; i < 3; i++)
        lua_pushnumber(L, h->pid[i]);
    return 3;
}

static const luaL_Reg mc_lib[] = {
    {"position", mc_position}, {"speed", mc_speed},   {"blocked", mc_blocked},
    {"busy", mc_busy},         {"aforce", mc_aforce}, {"force", mc_force},
    {"stop", mc_stop},         {"move", mc_move},     {"homing", mc_homing},
    {"pid", mc_pid},           {NULL, NULL}};

/* ---- gripper, grasping ---- */

static int gripper_state(lua_State *L)
{
    lua_pushinteger(L, wsg_device_flags(wsg_script_of(L)->dev));
    return 1;
}

static const luaL_Reg gripper_lib[] = {{"state", gripper_state}, {NULL, NULL}};

static int grasping_move(lua_State *L)
{
    struct wsg_script *h = wsg_script_of(L);
    double w = api_motion_number(L, 1), v = api_motion_number(L, 2);
    uint16_t st = wsg_device_motion_check(h->dev, 1);

    if (st == WSG_E_SUCCESS)
        st = wsg_axis_request_move(api_axis(L), 0, w, v, 0);
    return api_motion(L, st);
}

/* The optional force of a grasp or clamp, at arg: set as the force limit
 * when it is given and the motion may start (st, the status so far). A
 * NaN sets nothing and refuses the motion, as a NaN width or speed does.
 * Returns the status. */
static uint16_t api_grasp_force(lua_State *L, int arg, uint16_t st)
{
    double f;

    if (lua_isnoneornil(L, arg))
        return st;
    f = api_motion_number(L, arg);
    if (st != WSG_E_SUCCESS)
        return st;
    if (isnan(f))
        return WSG_E_INVALID_PARAMETER;
    wsg_axis_set_force_limit(api_axis(L), f);
    return st;
}

static int grasping_grasp(lua_State *L)
{
    struct wsg_script *h = wsg_script_of(L);
    double w = api_motion_number(L, 1), v = api_motion_number(L, 2);
    uint16_t st = wsg_device_motion_check(h->dev, 1);

    st = api_grasp_force(L, 3, st);
    if (st == WSG_E_SUCCESS)
        st = wsg_axis_request_grasp(api_axis(L), w, v, 0);
    return api_motion(L, st);
}

/* Clamp a part the fingers are at: close at most travel mm from where
 * they are, with the force limit force; a part is held wherever the
 * fingers meet it within that travel. */
static int grasping_clamp(lua_State *L)
{
    struct wsg_script *h = wsg_script_of(L);
    struct wsg_axis *ax = api_axis(L);
    struct wsg_grasp_window win;
    double travel = api_motion_number(L, 1);
    uint16_t st = wsg_device_motion_check(h->dev, 1);

    luaL_argcheck(L, !(travel < 0), 1, "travel must not be negative");
    st = api_grasp_force(L, 2, st);
    win.travel = travel;
    win.tolerance = 0.0;
    if (st == WSG_E_SUCCESS)
        st = wsg_axis_request_grasp_in(ax, wsg_axis_width(ax),
                                       WSG_SCRIPT_CLAMP_SPEED, &win, 0);
    return api_motion(L, st);
}

static int grasping_release(lua_State *L)
{
    struct wsg_script *h = wsg_script_of(L);
    double w = api_motion_number(L, 1), v = api_motion_number(L, 2);
    uint16_t st = wsg_device_motion_check(h->dev, 1);

    if (st == WSG_E_SUCCESS)
        st = wsg_axis_request_release(api_axis(L), w, v, 0);
    return api_motion(L, st);
}

static int grasping_state(lua_State *L)
{
    lua_pushinteger(L, wsg_axis_grasp_state(api_axis(L)));
    return 1;
}

static const luaL_Reg grasping_lib[] = {{"move", grasping_move},
                                        {"grasp", grasping_grasp},
                                        {"clamp", grasping_clamp},
                                        {"stop_clamping", mc_stop},
                                        {"release", grasping_release},
                                        {"state", grasping_state},
                                        {NULL, NULL}};

/* ---- socket ---- */

static int socket_gettime(lua_State *L)
{
    lua_pushnumber(L, (lua_Number)wsg_script_now(wsg_script_of(L)) / 1e6);
    return 1;
}

static int socket_sleep(lua_State *L)
{
    double s = api_number(L, 1);

    lua_settop(L, 0);
    lua_pushnumber(L, s * 1000.0);
    return api_sleep(L);
}

static const luaL_Reg socket_lib[] = {
    {"gettime", socket_gettime}, {"sleep", socket_sleep}, {NULL, NULL}};

/* require "socket" also makes the global socket, as a module of the Lua
 * 5.1 era did (luaL_register): the published scripts write a bare
 * `require "socket"` and then use the global. */
static int open_socket(lua_State *L)
{
    luaL_newlib(L, socket_lib);
    lua_pushvalue(L, -1);
    lua_setglobal(L, "socket");
    return 1;
}

/* ---- require ---- */

/* require's searcher for a script's modules: NAME.lua in the script's
 * directory, each dot of NAME a subdirectory, as Lua text. It reads the
 * directory the host keeps, not package.path, which the script can set
 * (to "/etc/?.lua" or "../?.lua"); with the dots turned into slashes no
 * name climbs out of the directory, and the file is opened one component
 * at a time without following a link (wsg_script_loadmodule), so no link
 * below the directory leads out of it either. Lua's own searcher would
 * also load a precompiled chunk, which no sandbox can trust. */
static int api_searcher(lua_State *L)
{
    struct wsg_script *h = wsg_script_of(L);
    const char *name = luaL_checkstring(L, 1), *path, *rel, *c;
    luaL_Buffer b;
    int r;

    luaL_buffinit(L, &b);
    for (c = name; *c; c++)
        luaL_addchar(&b, *c == '.' ? '/' : *c);
    luaL_addstring(&b, ".lua");
    luaL_pushresult(&b);
    rel = lua_tostring(L, -1);
    path = lua_pushfstring(L, "%s/%s", h->dir, rel);
    r = wsg_script_loadmodule(L, h->dir, rel, path);
    if (r == -ENOENT || r == -ENOTDIR) {
        lua_pushfstring(L, "no file '%s'", path);
        return 1;
    }
    if (r < 0)
        return luaL_error(L, "error loading module '%s' from file '%s':\n\t%s",
                          name, path, strerror(-r));
    if (r != LUA_OK)
        return luaL_error(L, "error loading module '%s' from file '%s':\n\t%s",
                          name, path, lua_tostring(L, -1));
    lua_pushvalue(L, -2); /* the loader's second argument: the file */
    return 2;
}

/* ---- the state ---- */

/* Lua's own libraries that a script gets; io, debug and the rest of os
 * stay out. */
static const luaL_Reg std_libs[] = {{"_G", luaopen_base},
                                    {LUA_LOADLIBNAME, luaopen_package},
                                    {LUA_COLIBNAME, luaopen_coroutine},
                                    {LUA_TABLIBNAME, luaopen_table},
                                    {LUA_STRLIBNAME, luaopen_string},
                                    {LUA_MATHLIBNAME, luaopen_math},
                                    {LUA_BITLIBNAME, luaopen_bit32},
                                    {LUA_OSLIBNAME, luaopen_os},
                                    {NULL, NULL}};

static void set_nil(lua_State *L, const char *table, const char *const *names)
{
    if (table)
        lua_getglobal(L, table);
    else
        lua_pushglobaltable(L);
    for (; *names; names++) {
        lua_pushnil(L);
        lua_setfield(L, -2, *names);
    }
    lua_pop(L, 1);
}

/* Run by the host in the fresh state, trusted: load restricted to text
 * (Lua 5.2's loadstring is its load, which takes a precompiled chunk too),
 * printf, and the Lua 5.1 names that Lua 5.2 dropped and scripts of the
 * gripper's era still use (table.getn, math.mod, string.gfind). load
 * passes its env on only when the script gave one: Lua's load tells an
 * absent env from a nil one, and a nil one leaves the chunk without
 * globals. */
static const char *const prelude[] = {
    "local rawload, output = ...\n",
    "load = function(chunk, name, mode, ...)\n",
    "  return rawload(chunk, name, 't', ...)\n",
    "end\n",
    "loadstring = function(s, name) return rawload(s, name, 't') end\n",
    "local sformat = string.format\n",
    "printf = function(fmt, ...) output(sformat(fmt, ...)) end\n",
    "table.getn = function(t) return #t end\n",
    "math.mod = math.fmod\n",
    "string.gfind = string.gmatch\n",
    NULL};

/* lua_load's reader over the prelude's pieces (C99 caps a string literal
 * at 4095 bytes, so the prelude is an array of them). */
static const char *prelude_read(lua_State *L, void *ud, size_t *size)
{
    const char *const **piece = ud;
    const char *p = **piece;

    (void)L;
    if (!p)
        return NULL;
    (*piece)++;
    *size = strlen(p);
    return p;
}

void wsg_script_open_api(lua_State *L, struct wsg_script *h)
{
    const char *const *piece = prelude;
    static const char *const base_out[] = {"dofile", "loadfile", NULL};
    static const char *const os_out[] = {"execute",   "exit",   "getenv",
                                         "remove",    "rename", "tmpname",
                                         "setlocale", NULL};
    static const char *const package_out[] = {"loadlib", "searchpath", NULL};
    static const struct {
        const char *name;
        int value;
    } statuses[] = {
#define WSG_SCRIPT_STATUS_(v, name) {#name, v},
        WSG_SCHEMA_STATUSES(WSG_SCRIPT_STATUS_)
#undef WSG_SCRIPT_STATUS_
    };
    const luaL_Reg *lib;
    size_t i;

    for (lib = std_libs; lib->func; lib++) {
        luaL_requiref(L, lib->name, lib->func, 1);
        lua_pop(L, 1);
    }
    set_nil(L, NULL, base_out);
    set_nil(L, LUA_OSLIBNAME, os_out);
    set_nil(L, LUA_LOADLIBNAME, package_out);
    /* The pattern functions that yield across themselves (strlib.c), the
     * functions that resume and catch (coro.c), and those whose work is
     * counted (costs.c), before the prelude keeps any of them. */
    lua_getglobal(L, LUA_STRLIBNAME);
    wsg_strlib_open(L, &h->slice);
    lua_pop(L, 1);
    wsg_script_open_coro(L);
    wsg_script_open_costs(L);
    /* require: modules from the script's directory, Lua text only (the
     * preload, then api_searcher). package.path tells where, for scripts
     * that read it; changing it changes nothing. */
    lua_getglobal(L, LUA_LOADLIBNAME);
    lua_pushfstring(L, "%s/?.lua", h->dir);
    lua_setfield(L, -2, "path");
    lua_pushliteral(L, "");
    lua_setfield(L, -2, "cpath");
    lua_getfield(L, -1, "searchers");
    lua_pushnil(L);
    lua_rawseti(L, -2, 4);
    lua_pushnil(L);
    lua_rawseti(L, -2, 3);
    lua_pushcfunction(L, api_searcher);
    lua_rawseti(L, -2, 2);
    lua_pop(L, 1);
    luaL_getsubtable(L, -1, "preload");
    lua_pushcfunction(L, open_socket);
    lua_setfield(L, -2, "socket");
    lua_pop(L, 2);

    lua_register(L, "print", api_print);
    lua_register(L, "setmetatable", wsg_script_setmetatable);
    lua_register(L, "sleep", api_sleep);
    lua_register(L, "bton", api_bton);
    lua_register(L, "ntob", api_ntob);
    lua_register(L, "etob", api_etob);
    for (i = 0; i < sizeof statuses / sizeof statuses[0]; i++) {
        lua_pushinteger(L, statuses[i].value);
        lua_setglobal(L, statuses[i].name);
    }
    luaL_newlib(L, cmd_lib);
    lua_setglobal(L, "cmd");
    luaL_newlib(L, mc_lib);
    lua_setglobal(L, "mc");
    luaL_newlib(L, gripper_lib);
    lua_setglobal(L, "gripper");
    luaL_newlib(L, grasping_lib);
    lua_setglobal(L, "grasping");
    wsg_script_open_finger(L); /* finger.c */

    /* The prelude gets the real load and the output, and keeps them to
     * itself. */
    if (lua_load(L, prelude_read, &piece, "=prelude", "t") == LUA_OK) {
        lua_getglobal(L, "load");
        lua_pushcfunction(L, api_output);
        lua_call(L, 2, 0);
    } else {
        lua_pop(L, 1);
    }
}
