/*
 * Finger devices (fdev.h): a device model's Lua state, its sandbox and
 * bounds, and the link that ties it to its finger.
 *
 * The state lives while the finger has power: power on makes a fresh one
 * from the model's source and runs it (its body, then on_power(true)),
 * power off closes it, so a power cycle is the electronics starting
 * again, as the public scripts that cycle a finger's power expect. Every
 * call into the model runs under a count hook that ends it after
 * WSG_FDEV_INSTRUCTIONS instructions and an allocator that refuses memory
 * past the cap; the library functions whose work the hook cannot see
 * (the pattern functions) are left out, as are those that reach outside
 * (files, loading, modules) or are not the same on every run (random
 * numbers), so a model's answers are exact in lockstep.
 *
 * Written to the part of the C API that Lua 5.2 and 5.4 share.
 */
#define _GNU_SOURCE

#include "fdev.h"

#include <errno.h>
#include <fcntl.h>
#include <lauxlib.h>
#include <lua.h>
#include <lualib.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* The count hook's period, in instructions. */
#define FDEV_HOOK_EVERY 1000

struct wsg_fdev {
    struct wsg_fingers *fs;
    int finger;
    lua_State *L; /* NULL: unpowered, or failed */
    size_t memory, cap;
    unsigned long ticks; /* hook periods left in this call */
    char *src;
    size_t srclen;
    char name[128];
    char error[512];
};

static void *fdev_alloc(void *ud, void *ptr, size_t osize, size_t nsize)
{
    struct wsg_fdev *m = ud;
    void *p;

    if (!ptr)
        osize = 0;
    if (nsize == 0) {
        free(ptr);
        m->memory -= osize;
        return NULL;
    }
    if (nsize > osize && m->memory + (nsize - osize) > m->cap)
        return NULL;
    p = realloc(ptr, nsize);
    if (p)
        m->memory = m->memory - osize + nsize;
    return p;
}

static struct wsg_fdev *fdev_of(lua_State *L)
{
    struct wsg_fdev *m;

    lua_getfield(L, LUA_REGISTRYINDEX, "wsg.fdev");
    m = lua_touserdata(L, -1);
    lua_pop(L, 1);
    return m;
}

static void fdev_hook(lua_State *L, lua_Debug *ar);

/* The call's bound used up: from now on every instruction raises the
 * error again, so a model that catches it with pcall (in a loop, or
 * before returning) still ends, in that error. */
static void fdev_spent(lua_State *L)
{
    lua_sethook(L, fdev_hook, LUA_MASKCOUNT, 1);
    /* %d: lua_pushfstring knows no %u. */
    luaL_error(L, "ran over its %d instructions", (int)WSG_FDEV_INSTRUCTIONS);
}

static void fdev_hook(lua_State *L, lua_Debug *ar)
{
    struct wsg_fdev *m = fdev_of(L);

    (void)ar;
    if (m->ticks == 0)
        fdev_spent(L);
    m->ticks--;
}

/* Work a library call does in C, which the count hook sees as one
 * instruction, charged as instructions (units of the hook's period). */
static void fdev_charge(lua_State *L, double instructions)
{
    struct wsg_fdev *m = fdev_of(L);
    double t = instructions / FDEV_HOOK_EVERY;

    if (t >= (double)m->ticks) {
        m->ticks = 0;
        fdev_spent(L);
    }
    m->ticks -= (unsigned long)t;
}

/* What a wrapped library function's work is measured by. */
enum {
    COST_BYTES, /* its string arguments' lengths */
    COST_LEN,   /* the elements of its first argument (a table) */
    COST_SORT,  /* n log n comparisons of the table's n */
    COST_REP    /* the string it makes */
};

/* Bytes that cost one instruction's worth. */
#define FDEV_BYTES_PER_INSTRUCTION 16

/* A library function (upvalue 1) called after its work (upvalue 2 says
 * how it is measured) is charged: a loop of calls that each take long
 * (table.insert at the front of a big table, string.rep of an empty
 * string 2^31 times) ends at the bound as a loop of instructions does. */
static int fdev_costly(lua_State *L)
{
    int kind = (int)lua_tointeger(L, lua_upvalueindex(2));
    int top = lua_gettop(L), k;
    double cost = 0;
    size_t l, lsep;

    switch (kind) {
    case COST_BYTES:
        for (k = 1; k <= top; k++)
            if (lua_type(L, k) == LUA_TSTRING) {
                lua_tolstring(L, k, &l);
                cost += (double)l / FDEV_BYTES_PER_INSTRUCTION;
            }
        break;
    case COST_LEN:
    case COST_SORT:
        if (lua_type(L, 1) == LUA_TTABLE)
            cost = (double)lua_rawlen(L, 1);
        if (kind == COST_SORT && cost > 1)
            cost *= log2(cost);
        break;
    case COST_REP:
        if (lua_type(L, 1) == LUA_TSTRING || lua_type(L, 1) == LUA_TNUMBER) {
            lua_Number n = luaL_checknumber(L, 2);

            luaL_checklstring(L, 1, &l);
            luaL_optlstring(L, 3, "", &lsep);
            if (n >= 1 && l + lsep == 0) { /* empty, however many */
                lua_pushliteral(L, "");
                return 1;
            }
            if (n >= 1)
                cost = n * (double)(l + lsep) / FDEV_BYTES_PER_INSTRUCTION;
        }
        break;
    }
    fdev_charge(L, cost);
    lua_pushvalue(L, lua_upvalueindex(1));
    lua_insert(L, 1);
    lua_call(L, top, LUA_MULTRET);
    return lua_gettop(L);
}

/* Wrap lib.name (lib NULL: a global) as fdev_costly with kind. */
static void fdev_wrap(lua_State *L, const char *lib, const char *name,
                      int kind)
{
    if (lib)
        lua_getglobal(L, lib);
    else
        lua_pushglobaltable(L);
    lua_getfield(L, -1, name);
    if (lua_type(L, -1) != LUA_TFUNCTION) {
        lua_pop(L, 2);
        return;
    }
    lua_pushinteger(L, kind);
    lua_pushcclosure(L, fdev_costly, 2);
    lua_setfield(L, -2, name);
    lua_pop(L, 1);
}

static void fdev_costs(lua_State *L)
{
    static const char *const bytes[] = {"byte",  "char",    "format",
                                        "lower", "reverse", "sub",
                                        "upper", "len",     NULL};
    const char *const *p;

    for (p = bytes; *p; p++)
        fdev_wrap(L, "string", *p, COST_BYTES);
    fdev_wrap(L, "string", "rep", COST_REP);
    fdev_wrap(L, NULL, "tostring", COST_BYTES);
    fdev_wrap(L, NULL, "tonumber", COST_BYTES);
    fdev_wrap(L, NULL, "unpack", COST_LEN);
    fdev_wrap(L, "table", "unpack", COST_LEN);
    fdev_wrap(L, "table", "insert", COST_LEN);
    fdev_wrap(L, "table", "remove", COST_LEN);
    fdev_wrap(L, "table", "concat", COST_LEN);
    fdev_wrap(L, "table", "sort", COST_SORT);
}

/* ---- what the model calls: dev.* ---- */

/* dev.send(bytes): over the UART towards the gripper; the count taken. */
static int dev_send(lua_State *L)
{
    struct wsg_fdev *m = fdev_of(L);
    uint8_t buf[WSG_FINGER_FIFO];
    size_t n = wsg_script_bytes(L, 1, buf, sizeof buf);

    lua_pushinteger(
        L, (lua_Integer)wsg_finger_device_send(m->fs, m->finger, buf, n));
    return 1;
}

/* dev.contact(): force N, patch centre x, y and size w, h in mm. */
static int dev_contact(lua_State *L)
{
    struct wsg_fdev *m = fdev_of(L);
    const struct wsg_contact *c = &m->fs->f[m->finger].contact;

    lua_pushnumber(L, c->force);
    lua_pushnumber(L, c->x);
    lua_pushnumber(L, c->y);
    lua_pushnumber(L, c->w);
    lua_pushnumber(L, c->h);
    return 5;
}

/* dev.time(): simulated seconds. */
static int dev_time(lua_State *L)
{
    lua_pushnumber(L, (lua_Number)fdev_of(L)->fs->now_ns / 1e9);
    return 1;
}

static int dev_finger(lua_State *L)
{
    lua_pushinteger(L, fdev_of(L)->finger);
    return 1;
}

/* dev.baud(): the UART's bit rate the gripper set (0: none). */
static int dev_baud(lua_State *L)
{
    struct wsg_fdev *m = fdev_of(L);
    const struct wsg_finger *f = &m->fs->f[m->finger];

    lua_pushinteger(L, f->iface == WSG_FINGER_IFACE_UART ? (lua_Integer)f->baud
                                                         : 0);
    return 1;
}

static const luaL_Reg dev_lib[] = {
    {"send", dev_send},     {"contact", dev_contact}, {"time", dev_time},
    {"finger", dev_finger}, {"baud", dev_baud},       {NULL, NULL}};

/* ---- the state ---- */

static void fdev_remove(lua_State *L, const char *lib,
                        const char *const *names)
{
    if (lib) {
        lua_getglobal(L, lib);
        if (!lua_istable(L, -1)) {
            lua_pop(L, 1);
            return;
        }
    } else {
        lua_pushglobaltable(L);
    }
    for (; *names; names++) {
        lua_pushnil(L);
        lua_setfield(L, -2, *names);
    }
    lua_pop(L, 1);
}

/* Run the function on top with nargs under it, within the bounds: 0, or
 * -1 with the error kept. Leaves nres results. */
static int fdev_call(struct wsg_fdev *m, int nargs, int nres)
{
    lua_State *L = m->L;

    m->ticks = WSG_FDEV_INSTRUCTIONS / FDEV_HOOK_EVERY;
    lua_sethook(L, fdev_hook, LUA_MASKCOUNT, FDEV_HOOK_EVERY);
    if (lua_pcall(L, nargs, nres, 0) != LUA_OK) {
        const char *e = lua_tostring(L, -1);

        /* Lua's message names the model and the line already. */
        snprintf(m->error, sizeof m->error, "%s",
                 e ? e : "an error without a message");
        lua_pop(L, 1);
        return -1;
    }
    return 0;
}

static void fdev_stop(struct wsg_fdev *m)
{
    if (m->L)
        lua_close(m->L);
    m->L = NULL;
    m->memory = 0;
}

/* A fresh state with the sandbox, the model's body run. 0 or -1. */
static int fdev_start(struct wsg_fdev *m)
{
    static const char *const base_out[] = {
        "dofile", "loadfile", "load", "loadstring", "require", "module",
        "print", "collectgarbage",
        /* Lua calls a message handler again for an error inside it, and
         * the bound's error comes at every instruction once it is spent:
         * a handler would be called past any bound. pcall stays. */
        "xpcall", NULL};
    static const char *const string_out[] = {"find", "match", "gmatch",
                                             "gsub", "dump",  NULL};
    static const char *const math_out[] = {"random", "randomseed", NULL};
    lua_State *L;

    fdev_stop(m);
    L = lua_newstate(fdev_alloc, m);
    if (!L) {
        snprintf(m->error, sizeof m->error, "%s: out of memory", m->name);
        return -1;
    }
    m->L = L;
    lua_pushlightuserdata(L, m);
    lua_setfield(L, LUA_REGISTRYINDEX, "wsg.fdev");
    luaL_requiref(L, "_G", luaopen_base, 1);
    luaL_requiref(L, "string", luaopen_string, 1);
    luaL_requiref(L, "table", luaopen_table, 1);
    luaL_requiref(L, "math", luaopen_math, 1);
    lua_pop(L, 4);
    fdev_remove(L, NULL, base_out);
    fdev_remove(L, "string", string_out);
    fdev_remove(L, "math", math_out);
    fdev_costs(L);
    /* No finalizers: Lua runs them with hooks off. */
    lua_register(L, "setmetatable", wsg_script_setmetatable);
    lua_newtable(L);
    luaL_setfuncs(L, dev_lib, 0);
    lua_setglobal(L, "dev");
    lua_sethook(L, fdev_hook, LUA_MASKCOUNT, FDEV_HOOK_EVERY);
    if (luaL_loadbufferx(L, m->src, m->srclen, m->name, "t") != LUA_OK) {
        snprintf(m->error, sizeof m->error, "%s",
                 lua_tostring(L, -1) ? lua_tostring(L, -1) : "load failed");
        fdev_stop(m);
        return -1;
    }
    if (fdev_call(m, 0, 0) < 0) {
        fdev_stop(m);
        return -1;
    }
    return 0;
}

/* The model's global function name pushed: 1, or 0 (nothing pushed). */
static int fdev_function(struct wsg_fdev *m, const char *name)
{
    lua_getglobal(m->L, name);
    if (lua_type(m->L, -1) == LUA_TFUNCTION)
        return 1;
    lua_pop(m->L, 1);
    return 0;
}

/* A failed call: the state goes (the finger faults) until power is
 * cycled. */
static int fdev_failed(struct wsg_fdev *m)
{
    fdev_stop(m);
    return -1;
}

/* ---- the link ---- */

static int link_power(void *ctx, int i, int on)
{
    struct wsg_fdev *m = ctx;

    (void)i;
    if (!on) {
        fdev_stop(m);
        return 0;
    }
    m->error[0] = '\0';
    if (fdev_start(m) < 0)
        return -1;
    if (!fdev_function(m, "on_power"))
        return 0;
    lua_pushboolean(m->L, 1);
    return fdev_call(m, 1, 0) < 0 ? fdev_failed(m) : 0;
}

static int link_uart(void *ctx, int i, const uint8_t *p, size_t n)
{
    struct wsg_fdev *m = ctx;

    (void)i;
    if (!m->L)
        return -1;
    if (!fdev_function(m, "on_uart"))
        return 0; /* electronics that do not listen */
    lua_pushlstring(m->L, (const char *)p, n);
    return fdev_call(m, 1, 0) < 0 ? fdev_failed(m) : 0;
}

static int link_spi(void *ctx, int i, const uint8_t *tx, uint8_t *rx, size_t n)
{
    struct wsg_fdev *m = ctx;
    size_t k;
    const char *s;

    (void)i;
    if (!m->L)
        return -1;
    if (!fdev_function(m, "on_spi"))
        return 0; /* the idle line */
    lua_pushlstring(m->L, (const char *)tx, n);
    if (fdev_call(m, 1, 1) < 0)
        return fdev_failed(m);
    s = lua_tolstring(m->L, -1, &k);
    if (s) /* what it answers; the rest stays 0xFF */
        memcpy(rx, s, k < n ? k : n);
    lua_pop(m->L, 1);
    return 0;
}

static int link_data(void *ctx, int i, uint8_t *out, size_t cap)
{
    struct wsg_fdev *m = ctx;
    size_t k;
    const char *s;

    (void)i;
    if (!m->L)
        return -1;
    if (!fdev_function(m, "data"))
        return 0;
    if (fdev_call(m, 0, 1) < 0)
        return fdev_failed(m);
    s = lua_tolstring(m->L, -1, &k);
    if (!s) /* not a string: no data (memcpy must not see NULL) */
        k = 0;
    if (k > cap)
        k = cap;
    if (k)
        memcpy(out, s, k);
    lua_pop(m->L, 1);
    return (int)k;
}

static const struct wsg_finger_link fdev_link = {link_power, link_uart,
                                                 link_spi, link_data};

/* ---- opening ---- */

static int fdev_read(const char *path, char **out, size_t *n, char *err,
                     size_t errcap)
{
    struct stat st;
    char *buf;
    ssize_t r;
    size_t got = 0;
    int fd = open(path, O_RDONLY | O_CLOEXEC | O_NONBLOCK);

    if (fd < 0) {
        r = -errno;
        snprintf(err, errcap, "%s: %s", path, strerror(errno));
        return (int)r;
    }
    if (fstat(fd, &st) < 0 || !S_ISREG(st.st_mode)) {
        close(fd);
        snprintf(err, errcap, "%s: not a file", path);
        return -EINVAL;
    }
    if ((unsigned long long)st.st_size > WSG_FDEV_SOURCE_MAX) {
        close(fd);
        snprintf(err, errcap, "%s: larger than %u KiB", path,
                 WSG_FDEV_SOURCE_MAX >> 10);
        return -EFBIG;
    }
    buf = malloc(WSG_FDEV_SOURCE_MAX + 1u);
    if (!buf) {
        close(fd);
        snprintf(err, errcap, "out of memory");
        return -ENOMEM;
    }
    while (got <= WSG_FDEV_SOURCE_MAX) {
        r = read(fd, buf + got, WSG_FDEV_SOURCE_MAX + 1u - got);
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0)
            break;
        got += (size_t)r;
    }
    close(fd);
    if (got > WSG_FDEV_SOURCE_MAX) {
        free(buf);
        snprintf(err, errcap, "%s: larger than %u KiB", path,
                 WSG_FDEV_SOURCE_MAX >> 10);
        return -EFBIG;
    }
    *out = buf;
    *n = got;
    return 0;
}

int wsg_fdev_open(struct wsg_fdev **out, struct wsg_fingers *fs, int i,
                  const char *path, const char *src, size_t n,
                  const char *name, size_t memory, char *err, size_t errcap)
{
    struct wsg_fdev *m;
    lua_Number size = 0;
    int r;

    *out = NULL;
    if (i < 0 || i >= WSG_FINGER_COUNT) {
        snprintf(err, errcap, "a finger is 0 or 1");
        return -EINVAL;
    }
    m = calloc(1, sizeof *m);
    if (!m) {
        snprintf(err, errcap, "out of memory");
        return -ENOMEM;
    }
    m->fs = fs;
    m->finger = i;
    m->cap = memory ? memory : WSG_FDEV_MEMORY;
    if (path) {
        const char *base = strrchr(path, '/');

        r = fdev_read(path, &m->src, &m->srclen, err, errcap);
        if (r < 0)
            goto fail;
        snprintf(m->name, sizeof m->name, "@%s", base ? base + 1 : path);
    } else {
        if (n > WSG_FDEV_SOURCE_MAX) {
            snprintf(err, errcap, "larger than %u KiB",
                     WSG_FDEV_SOURCE_MAX >> 10);
            r = -EFBIG;
            goto fail;
        }
        m->src = malloc(n ? n : 1);
        if (!m->src) {
            snprintf(err, errcap, "out of memory");
            r = -ENOMEM;
            goto fail;
        }
        memcpy(m->src, src, n);
        m->srclen = n;
        snprintf(m->name, sizeof m->name, "=%s", name ? name : "model");
    }
    /* Compiled and run once now, for its errors and its DATA_SIZE; the
     * finger's power-on runs it afresh. */
    if (fdev_start(m) < 0) {
        snprintf(err, errcap, "%s", m->error);
        r = -EINVAL;
        goto fail;
    }
    lua_getglobal(m->L, "DATA_SIZE");
    if (lua_type(m->L, -1) == LUA_TNUMBER)
        size = lua_tonumber(m->L, -1);
    lua_pop(m->L, 1);
    fdev_stop(m);
    if (!(size >= 0 && size <= WSG_FINGER_DATA_MAX)) {
        snprintf(err, errcap, "%s: DATA_SIZE must be 0..%u", m->name,
                 WSG_FINGER_DATA_MAX);
        r = -EINVAL;
        goto fail;
    }
    wsg_finger_attach(fs, i, &fdev_link, m, (uint16_t)size);
    *out = m;
    return 0;
fail:
    free(m->src);
    free(m);
    return r;
}

void wsg_fdev_close(struct wsg_fdev *m)
{
    if (!m)
        return;
    if (m->fs->f[m->finger].link_ctx == m)
        wsg_finger_attach(m->fs, m->finger, NULL, NULL, 0);
    fdev_stop(m);
    free(m->src);
    free(m);
}

const char *wsg_fdev_error(const struct wsg_fdev *m)
{
    return m->error;
}

const char *wsg_fdev_name(const struct wsg_fdev *m)
{
    return m->name + 1;
}

size_t wsg_fdev_memory(const struct wsg_fdev *m)
{
    return m->memory;
}
