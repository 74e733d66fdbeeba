/*
 * Harness 5: the script host (src/script), in two halves picked by bit 0 of
 * the first byte.
 *
 * Bit 0 set, cmd.send's flattening: the rest of the input builds Lua values
 * on a bare lua_State (booleans, integers in and out of 0..255, floats
 * whole and not, NaN, strings with NULs and past 64 KiB, nil, functions,
 * userdata, threads, tables nested past the five levels allowed, with
 * holes, with keys beyond their sequence, with metatables whose __len and
 * __index would lie, tables that contain themselves, and tables shared by
 * several others, which multiply what a send visits), then calls
 * wsg_script_flatten on them directly, outside any protected call. This
 * file keeps its own model of every value built and flattens that model
 * the way docs/scripting.md says cmd.send does; the function must return
 * -1 or exactly the bytes of that reference, having visited as many values
 * as the model (never more than the bound), write nothing past its cap or
 * its error buffer, leave the stack as it found it, call no metamethod and
 * never raise (a raise here reaches the panic handler, which aborts).
 *
 * Bit 0 clear, packets to registered IDs: a gripper with a script host
 * running the script below (fb_script), which registers B0h..B9h, BBh and
 * BDh * and answers each from the packet's bytes (an echo, lengths and nested
 * tables, floats through bton and ntob, errors inside pcall, a sleep in
 * simulated time, a loop long enough to be preempted, allocations past the
 * memory cap, speed mode, registering BAh on and off, its own failure or
 * end, what cmd.available and cmd.online say, and the rest of its library
 * called inside pcall with the packet's numbers). The input is records as in
 * harness 2 ([ID][control][length][payload]), wrapped into valid frames
 * and mixed with the firmware's IDs, on two sessions, with time stepped in
 * between. Every answer carries the script's count of packets read, so
 * each is matched to the packet it answers: every packet delivered to the
 * script is answered, on its session, in order, with the bytes this file
 * expects, or refused E_OVERRUN at once (only with 64 waiting); the host's
 * queue holds what the harness counts as waiting, in order (read through
 * the host's private layout, script_impl.h), and its state, D19/D20, the
 * registered IDs and the memory in use stay consistent after every event.
 * Set FUZZ_TRACE in the environment to print the events of a replayed
 * input.
 */
#define _POSIX_C_SOURCE 200809L /* mkdtemp */

#include <errno.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <lauxlib.h>
#include <lua.h>

#include "fuzz_check.h"
#include "fuzz_ids.h"
#include "script_impl.h"
#include "wsg/device.h"
#include "wsg/proto.h"

#ifndef FUZZ_ENTRY
#define FUZZ_ENTRY LLVMFuzzerTestOneInput
#endif

/* The input, read to its end and then as zeros: every value is built. */
struct rd {
    const uint8_t *p;
    size_t n;
};

static unsigned rd_byte(struct rd *r)
{
    if (r->n == 0)
        return 0;
    r->n--;
    return *r->p++;
}

/* Eight bytes, little-endian: the bits of a lua_Integer or a double. */
static uint64_t rd_u64(struct rd *r)
{
    uint64_t u = 0;
    int j;

    for (j = 0; j < 64; j += 8)
        u |= (uint64_t)rd_byte(r) << j;
    return u;
}

/* ==== (a) cmd.send's flattening ==== */

#define FA_NODES  4096
#define FA_KIDS   16384
#define FA_TABLES 1024
/* Tables are built nested this deep: past the five levels cmd.send takes. */
#define FA_DEPTH 8
/* Elements of a table; with references, 8^5 leaves at most per argument. */
#define FA_FANOUT 9
/* A long string: up to twice what any cap allows. */
#define FA_LONG_MAX (2u << 16)
/* Bytes past the cap and past the error buffer that must stay untouched. */
#define FA_GUARD 64

enum fa_kind { FA_NIL, FA_BOOL, FA_INT, FA_FLOAT, FA_STR, FA_TABLE, FA_OTHER };

struct fa_node {
    enum fa_kind kind;
    lua_Integer i;    /* FA_BOOL (0 or 1), FA_INT */
    double d;         /* FA_FLOAT */
    const uint8_t *s; /* FA_STR: bytes of the input; NULL: len bytes of fill */
    size_t len;
    uint8_t fill;
    int kid0, nkids; /* FA_TABLE: t[1..nkids] are nodes kids[kid0..] */
    int table;       /* FA_TABLE: its index in the registry's list */
};

static struct {
    lua_State *L;
    struct fa_node node[FA_NODES]; /* node 0: nil */
    int kids[FA_KIDS];
    int table_node[FA_TABLES];
    int nnode, nkid, ntable;
    unsigned meta_calls;
    uint8_t fill[FA_LONG_MAX];
} A;

/* Where the tables built are kept, so that later values can refer to
 * them (and a table to itself). */
#define FA_LIST "fuzz_script.tables"

static int fa_panic(lua_State *L)
{
    const char *m = lua_tostring(L, -1);

    fprintf(stderr, "fuzz_script: a Lua error outside a protected call: %s\n",
            m ? m : "(not a string)");
    abort();
}

/* __len, __index and the functions built: a metamethod that runs counts. */
static int fa_meta(lua_State *L)
{
    A.meta_calls++;
    lua_pushinteger(L, 1000);
    return 1;
}

static int fa_new(enum fa_kind k)
{
    struct fa_node *n;

    if (A.nnode >= FA_NODES)
        return -1;
    n = &A.node[A.nnode];
    memset(n, 0, sizeof *n);
    n->kind = k;
    return A.nnode++;
}

static int fa_value(struct rd *r, int depth);

/* A table of count elements built from the input, the value at the top.
 * extras: also an element past a gap of nils (so #t may be either
 * border) and keys outside the sequence; meta: a metatable whose __len and
 * __index answer 1000. */
static int fa_table(struct rd *r, int depth, unsigned count, int extras,
                    int meta)
{
    lua_State *L = A.L;
    int k, kid0, i;
    unsigned gap;

    if (depth >= FA_DEPTH || A.ntable >= FA_TABLES ||
        A.nkid + (int)count + 4 > FA_KIDS || (k = fa_new(FA_TABLE)) < 0)
        return -1;
    kid0 = A.nkid;
    A.nkid += (int)count + 4;
    for (i = 0; i < (int)count + 4; i++)
        A.kids[kid0 + i] = 0;
    A.node[k].kid0 = kid0;
    A.node[k].nkids = (int)count;
    A.node[k].table = A.ntable;
    A.table_node[A.ntable] = k;
    /* With extras the elements start in the hash part: #t's border search
     * takes another path there. */
    lua_createtable(L, extras ? 0 : (int)count, extras ? 4 : 0);
    lua_getfield(L, LUA_REGISTRYINDEX, FA_LIST);
    lua_pushvalue(L, -2);
    lua_rawseti(L, -2, ++A.ntable);
    lua_pop(L, 1);
    for (i = 0; i < (int)count; i++) {
        A.kids[kid0 + i] = fa_value(r, depth + 1);
        lua_rawseti(L, -2, i + 1);
    }
    if (extras) {
        gap = 1 + rd_byte(r) % 4;
        A.kids[kid0 + (int)count + (int)gap - 1] = fa_value(r, depth + 1);
        lua_rawseti(L, -2, (lua_Integer)(count + gap));
        A.node[k].nkids = (int)(count + gap);
        lua_pushinteger(L, 7);
        lua_rawseti(L, -2, 0);
        lua_pushinteger(L, 7);
        lua_rawseti(L, -2, -1);
        lua_pushnumber(L, 1.5);
        lua_pushinteger(L, 7);
        lua_rawset(L, -3);
        lua_pushliteral(L, "n");
        lua_pushinteger(L, 7);
        lua_rawset(L, -3);
    }
    if (meta) {
        lua_createtable(L, 0, 2);
        lua_pushliteral(L, "__len");
        lua_pushcfunction(L, fa_meta);
        lua_rawset(L, -3);
        lua_pushliteral(L, "__index");
        lua_pushcfunction(L, fa_meta);
        lua_rawset(L, -3);
        lua_setmetatable(L, -2);
    }
    return k;
}

/* One value from the input, pushed; returns its node (0: nil). The low
 * nibble of the first byte is the kind, the high one its argument. */
static int fa_value(struct rd *r, int depth)
{
    static const lua_Integer edge[16] = {
        -1,  0,   1,    2,   127,  128,   254,         255,
        256, 257, -256, 511, -128, 65535, PTRDIFF_MIN, PTRDIFF_MAX};
    static const double frac[4] = {0.0, 0.5, 0.25, 1e-9};
    lua_State *L = A.L;
    unsigned b = rd_byte(r), arg = b >> 4;
    lua_Integer iv;
    double dv;
    size_t len;
    int k = -1;

    if (!lua_checkstack(L, 8))
        goto nil;
    switch (b & 15u) {
    case 0:
        goto nil;
    case 1:
        if ((k = fa_new(FA_BOOL)) < 0)
            goto nil;
        A.node[k].i = arg & 1u;
        lua_pushboolean(L, (int)(arg & 1u));
        return k;
    case 2:
    case 3:
    case 4:
        if ((b & 15u) == 2) {
            iv = (lua_Integer)rd_byte(r);
        } else if ((b & 15u) == 3) {
            iv = edge[arg];
        } else {
            uint64_t u = rd_u64(r);

            memcpy(&iv, &u, sizeof iv);
        }
        if ((k = fa_new(FA_INT)) < 0)
            goto nil;
        A.node[k].i = iv;
        lua_pushinteger(L, iv);
        return k;
    case 5:
    case 6:
    case 7:
        if ((b & 15u) == 5) {
            static const double special[16] = {0.0,    -0.0,
                                               1.0,    0.5,
                                               255.0,  255.5,
                                               256.0,  -1.0,
                                               127.0,  9007199254740992.0,
                                               9.3e18, -9.3e18,
                                               1e-300, 254.99999999999997,
                                               NAN,    INFINITY};

            dv = special[arg];
        } else if ((b & 15u) == 6) {
            dv = (double)rd_byte(r) + frac[arg & 3u];
            if (arg & 4u)
                dv = -dv;
            if (arg & 8u)
                dv *= 256.0;
        } else {
            uint64_t u = rd_u64(r);

            memcpy(&dv, &u, sizeof dv);
        }
        if ((k = fa_new(FA_FLOAT)) < 0)
            goto nil;
        A.node[k].d = dv;
        lua_pushnumber(L, dv);
        return k;
    case 8:
        len = rd_byte(r) % 48u;
        if (len > r->n)
            len = r->n;
        if ((k = fa_new(FA_STR)) < 0)
            goto nil;
        A.node[k].s = r->p;
        A.node[k].len = len;
        lua_pushlstring(L, (const char *)r->p, len);
        r->p += len;
        r->n -= len;
        return k;
    case 9:
        len = rd_byte(r);
        len |= (size_t)rd_byte(r) << 8;
        len |= (size_t)(arg & 1u) << 16;
        if ((k = fa_new(FA_STR)) < 0)
            goto nil;
        A.node[k].len = len;
        A.node[k].fill = (uint8_t)(arg * 17u);
        memset(A.fill, A.node[k].fill, len);
        lua_pushlstring(L, (const char *)A.fill, len);
        return k;
    case 10:
    case 11:
    case 12:
        k = fa_table(r, depth, arg % FA_FANOUT, (b & 15u) == 11,
                     (b & 15u) == 12);
        if (k < 0)
            goto nil;
        return k;
    case 13:
        if ((k = fa_new(FA_OTHER)) < 0)
            goto nil;
        if (arg & 1u) {
            lua_pushcfunction(L, fa_meta);
        } else {
            lua_pushinteger(L, (lua_Integer)arg);
            lua_pushcclosure(L, fa_meta, 1);
        }
        return k;
    case 14:
        /* A table built before, perhaps one still being filled: the
         * value then contains itself. */
        if (A.ntable == 0)
            goto nil;
        k = A.table_node[arg % (unsigned)A.ntable];
        lua_getfield(L, LUA_REGISTRYINDEX, FA_LIST);
        lua_rawgeti(L, -1, (lua_Integer)(arg % (unsigned)A.ntable) + 1);
        lua_remove(L, -2);
        return k;
    default:
        if ((k = fa_new(FA_OTHER)) < 0)
            goto nil;
        if (arg % 3u == 0)
            lua_newuserdata(L, 8);
        else if (arg % 3u == 1)
            lua_pushlightuserdata(L, &A);
        else
            lua_newthread(L);
        return k;
    }
nil:
    lua_pushnil(L);
    return 0;
}

/* #t of table number t as the interpreter has it (raw): which border a
 * table with holes reports is the implementation's to choose. */
static size_t fa_rawlen(int t)
{
    size_t n;

    lua_getfield(A.L, LUA_REGISTRYINDEX, FA_LIST);
    lua_rawgeti(A.L, -1, t + 1);
    n = (size_t)lua_rawlen(A.L, -1);
    lua_pop(A.L, 2);
    return n;
}

static int fa_put(uint8_t *out, size_t cap, size_t *len, uint8_t v)
{
    if (*len >= cap)
        return -1;
    out[(*len)++] = v;
    return 0;
}

/* The reference: node k at table depth depth into out, from the model,
 * counting the values visited in *visits (each one once per visit, the
 * failing one too), at most WSG_SCRIPT_SEND_VISITS. */
static int fa_ref(int k, int depth, uint8_t *out, size_t cap, size_t *len,
                  size_t *visits)
{
    const struct fa_node *n = &A.node[k];
    size_t border;
    int i;

    if (++*visits > WSG_SCRIPT_SEND_VISITS)
        return -1;
    switch (n->kind) {
    case FA_BOOL:
        return fa_put(out, cap, len, (uint8_t)n->i);
    case FA_INT:
        if (n->i < 0 || n->i > 255)
            return -1;
        return fa_put(out, cap, len, (uint8_t)n->i);
    case FA_FLOAT:
        /* A whole float in range is its byte; -0.0 is 0. NaN fails. */
        if (!(n->d >= 0.0 && n->d <= 255.0 && n->d == floor(n->d)))
            return -1;
        return fa_put(out, cap, len, (uint8_t)n->d);
    case FA_STR:
        if (n->len > cap - *len)
            return -1;
        if (n->s)
            memcpy(out + *len, n->s, n->len);
        else
            memset(out + *len, n->fill, n->len);
        *len += n->len;
        return 0;
    case FA_TABLE:
        if (depth >= WSG_SCRIPT_NEST_MAX)
            return -1;
        border = fa_rawlen(n->table);
        /* A border of the model: t[border] set (or 0), t[border+1] not. */
        FUZZ_CHECK(border <= (size_t)n->nkids);
        FUZZ_CHECK(border == 0 || A.kids[n->kid0 + (int)border - 1] != 0);
        FUZZ_CHECK(border == (size_t)n->nkids ||
                   A.kids[n->kid0 + (int)border] == 0);
        for (i = 0; i < (int)border; i++)
            if (fa_ref(A.kids[n->kid0 + i], depth + 1, out, cap, len, visits) <
                0)
                return -1;
        return 0;
    default:
        return -1;
    }
}

static size_t fa_cap(struct rd *r)
{
    static const size_t caps[16] = {0,    1,     2,     3,    4,   5,
                                    8,    16,    64,    255,  256, 1000,
                                    4096, 65534, 65535, 65536};
    unsigned b = rd_byte(r);

    if (b & 0x10u)
        return rd_byte(r) | (size_t)rd_byte(r) << 8;
    return caps[b % 16u];
}

static void fa_run(struct rd *r)
{
    static const size_t errlens[5] = {0, 1, 2, 16, 128};
    int args[8];
    size_t cap, errlen, want_len = 0, want_visits = 0, visits, i;
    unsigned narg, first, pass;
    uint8_t *want;
    long want_n, n;
    lua_State *L;

    L = luaL_newstate();
    FUZZ_CHECK(L != NULL);
    lua_atpanic(L, fa_panic);
    A.L = L;
    A.nnode = 1;
    A.node[0].kind = FA_NIL;
    A.nkid = A.ntable = 0;
    A.meta_calls = 0;
    lua_newtable(L);
    lua_setfield(L, LUA_REGISTRYINDEX, FA_LIST);

    narg = rd_byte(r) % 8u;
    cap = fa_cap(r);
    errlen = errlens[rd_byte(r) % 5u];
    /* first: 1 (every value), up to past the last (nothing to send). */
    first = 1 + rd_byte(r) % (narg + 1);
    FUZZ_CHECK(lua_checkstack(L, (int)narg + 8));
    for (i = 0; i < narg; i++)
        args[i] = fa_value(r, 0);
    FUZZ_CHECK(lua_gettop(L) == (int)narg);

    want = malloc(cap ? cap : 1);
    FUZZ_CHECK(want != NULL);
    want_n = 0;
    for (i = first - 1; i < narg; i++)
        if (fa_ref(args[i], 0, want, cap, &want_len, &want_visits) < 0) {
            want_n = -1;
            break;
        }
    if (want_n == 0)
        want_n = (long)want_len;

    /* Twice, over buffers filled differently: a stray write shows in
     * one of them, and the result must not depend on them. */
    for (pass = 0; pass < 2; pass++) {
        uint8_t fill = pass ? 0xFF : 0x00;
        uint8_t *out = malloc(cap + FA_GUARD);
        char *err = malloc(errlen + FA_GUARD);

        FUZZ_CHECK(out != NULL && err != NULL);
        memset(out, fill, cap + FA_GUARD);
        memset(err, 0x5A, errlen + FA_GUARD);
        n = wsg_script_flatten(L, (int)first, out, cap, err, errlen, &visits);
        FUZZ_CHECK(lua_gettop(L) == (int)narg);
        FUZZ_CHECK(A.meta_calls == 0);
        /* As many values as the model visited, up to the one that
         * failed: a table shared or nested is visited each time. */
        FUZZ_CHECK(visits == want_visits);
        if (n != want_n)
            fprintf(stderr,
                    "fuzz_script: flatten gave %ld, the reference %ld "
                    "(cap %lu)\n",
                    n, want_n, (unsigned long)cap);
        FUZZ_CHECK(n == want_n);
        if (n >= 0) {
            FUZZ_CHECK(memcmp(out, want, (size_t)n) == 0);
            /* Nothing written past what it returned. */
            for (i = (size_t)n; i < cap + FA_GUARD; i++)
                FUZZ_CHECK(out[i] == fill);
        } else {
            for (i = cap; i < cap + FA_GUARD; i++)
                FUZZ_CHECK(out[i] == fill);
            /* A reason, terminated within errlen. */
            if (errlen > 0)
                FUZZ_CHECK(memchr(err, '\0', errlen) != NULL);
            if (errlen > 1)
                FUZZ_CHECK(err[0] != '\0');
        }
        for (i = errlen; i < errlen + FA_GUARD; i++)
            FUZZ_CHECK(err[i] == 0x5A);
        free(out);
        free(err);
    }
    free(want);
    lua_close(L);
    A.L = NULL;
}

/* ==== (b) packets to registered IDs ==== */

/* The script, in pieces (C99 promises string literals of 4095 bytes
 * only). Every answer starts with head(s, kind): E_SUCCESS, the marker
 * A5h, the count of packets read before this one (16 bits) and a kind per
 * ID, so the harness matches it to its packet. B3h may send one more
 * packet first, of kind FFh, from inside a pcall. */
static const char *const fb_script[] = {
    "local socket = require 'socket'\n"
    "local ids = {0xB0, 0xB1, 0xB2, 0xB3, 0xB4, 0xB5, 0xB6, 0xB7, 0xB8,\n"
    "             0xB9, 0xBB, 0xBD}\n"
    "for _, id in ipairs(ids) do cmd.register(id) end\n"
    "local seq = 0\n"
    "local function head(s, kind)\n"
    "  return {etob(E_SUCCESS), 0xA5, bit32.band(s, 0xFF), bit32.rshift(s, "
    "8), kind}\n"
    "end\n"
    "local function u32(v)\n"
    "  local b, r = bit32.band, bit32.rshift\n"
    "  return {b(v, 0xFF), b(r(v, 8), 0xFF), b(r(v, 16), 0xFF), r(v, 24)}\n"
    "end\n"
    "local H = {}\n"
    "H[0xB0] = function(id, p, s) cmd.send(id, head(s, 0), p) end\n"
    "H[0xBA] = H[0xB0]\n"
    "H[0xB1] = function(id, p, s)\n"
    "  local n = #p\n"
    "  cmd.send(id, head(s, 1), bit32.band(n, 0xFF), bit32.rshift(n, 8), "
    "{{{{{p[1] or 0}}}}},\n"
    "           string.char(table.unpack(p)), (p[1] or 0) > 127)\n"
    "end\n"
    "H[0xB2] = function(id, p, s)\n"
    "  local out = {}\n"
    "  for i = 1, #p - 3, 4 do\n"
    "    out[#out + 1] = ntob(bton({p[i], p[i + 1], p[i + 2], p[i + 3]}))\n"
    "  end\n"
    "  cmd.send(id, head(s, 2), out)\n"
    "end\n",
    "local deep = {{{{{{1}}}}}}\n"
    "H[0xB3] = function(id, p, s)\n"
    "  local tries = {\n"
    "    function() cmd.send(id, 256) end,\n"
    "    function() cmd.send(id, -1) end,\n"
    "    function() cmd.send(id, 1.5) end,\n"
    "    function() cmd.send(id, deep) end,\n"
    "    function() cmd.send(id, string.rep('x', 65536)) end,\n"
    "    function() cmd.send(id, {print}) end,\n"
    "    function() cmd.send(id, nil) end,\n"
    "    function() cmd.send(256) end,\n"
    "    function() bton({p[1] or 0, 300, 0, 0}) end,\n"
    "    function() etob(-1) end,\n"
    "    function() cmd.register(0x43) end,\n"
    "    function() error({}) end,\n"
    "  }\n"
    "  local fails = 0\n"
    "  for _, f in ipairs(tries) do\n"
    "    if not pcall(f) then fails = fails + 1 end\n"
    "  end\n"
    "  pcall(cmd.send, id, head(s, 0xFF), (p[1] or 300) * 2)\n"
    "  cmd.send(id, head(s, 3), fails)\n"
    "end\n"
    "H[0xB4] = function(id, p, s)\n"
    "  local t0 = socket.gettime()\n"
    "  sleep((p[1] or 0) / 4)\n"
    "  local us = math.floor((socket.gettime() - t0) * 1e6 + 0.5)\n"
    "  cmd.send(id, head(s, 4), u32(us))\n"
    "end\n"
    "H[0xB5] = function(id, p, s)\n"
    "  local acc = 0\n"
    "  for i = 1, (p[1] or 0) * 400 do acc = (acc * 31 + i) % 65521 end\n"
    "  cmd.send(id, head(s, 5), bit32.band(acc, 0xFF), bit32.rshift(acc, 8))\n"
    "end\n"
    "H[0xB6] = function(id, p, s)\n"
    "  local k = p[1] or 0\n"
    "  local ok, str = pcall(string.rep, 'x', k * 16384)\n"
    "  local ok2 = pcall(function()\n"
    "    local t = {}\n"
    "    for i = 1, k * 200 do t[i] = {i} end\n"
    "  end)\n"
    "  cmd.send(id, head(s, 6), ok, ok and u32(#str) or u32(0), ok2)\n"
    "end\n"
    "H[0xB7] = function(id, p, s)\n"
    "  local ok, st = pcall(function()\n"
    "    return mc.speed(bton({p[1] or 0, p[2] or 0, p[3] or 0, p[4] or 0}))\n"
    "  end)\n"
    "  if (p[5] or 0) % 2 == 1 then mc.stop() end\n"
    "  cmd.send(id, head(s, 7), ok, etob(ok and st or 0xFFFF), mc.busy(),\n"
    "           mc.blocked())\n"
    "end\n"
    "H[0xB8] = function(id, p, s)\n"
    "  local r\n"
    "  if (p[1] or 0) % 2 == 1 then r = cmd.register(0xBA)\n"
    "  else r = cmd.unregister(0xBA) end\n"
    "  cmd.send(id, head(s, 8), r, (pcall(cmd.register, 0x43)))\n"
    "end\n"
    "H[0xB9] = function(id, p, s)\n"
    "  if p[1] == 0xEE then error('requested failure') end\n"
    "  if p[1] == 0xED then return true end\n"
    "  if p[1] == 0xEC then local x = string.rep('x', 2 ^ 22) end\n"
    "  if p[1] == 0xEB then\n"
    "    local t = {}\n"
    "    for i = 1, 2 ^ 22 do t[i] = {i} end\n"
    "  end\n"
    "  cmd.send(id, head(s, 9), bit32.band(#p, 0xFF))\n"
    "end\n"
    "H[0xBB] = function(id, p, s)\n"
    "  local iface = cmd.interface() or '?'\n"
    "  cmd.send(id, head(s, 11), cmd.available(), cmd.online(), "
    "iface:byte(1))\n"
    "end\n",
    "local function f(p, i)\n"
    "  return bton({p[i] or 0, p[i + 1] or 0, p[i + 2] or 0, p[i + 3] or 0})\n"
    "end\n"
    "local calls = {\n"
    "  function(a, b, c) return mc.move(a, b, c) end,\n"
    "  function(a, b, c) return mc.homing(c % 3) end,\n"
    "  function(a, b, c) return mc.force(a) end,\n"
    "  function(a, b, c) return mc.force() end,\n"
    "  function(a, b, c) return mc.pid(a, b, c) end,\n"
    "  function(a, b, c) return grasping.grasp(a, b, c) end,\n"
    "  function(a, b, c) return grasping.release(a, b) end,\n"
    "  function(a, b, c) return grasping.clamp(a, b) end,\n"
    "  function(a, b, c) return grasping.move(a, b) end,\n"
    "  function(a, b, c) return grasping.stop_clamping() end,\n"
    "  function(a, b, c) return grasping.state() end,\n"
    "  function(a, b, c) return finger.type(c % 3) end,\n"
    "  function(a, b, c) return finger.data(c) end,\n"
    "  function(a, b, c) return finger.power(c % 3, a > 0) end,\n"
    "  function(a, b, c) return finger.read(c % 2, a) end,\n"
    "  function(a, b, c) return gripper.state() end,\n"
    "  function(a, b, c) printf('%d %x %5.2f %s', a, b, c, tostring(a)) end,\n"
    "  function(a, b, c) print(a, b, c, nil, {}) end,\n"
    "  function(a, b, c) return bit32.extract(c, a, 3), bit32.lrotate(b, c) "
    "end,\n"
    "  function(a, b, c) return cmd.online(), cmd.interface() end,\n"
    "  function(a, b, c) return mc.speed(), mc.position(), mc.aforce() end,\n"
    "  function(a, b, c) return mc.stop() end,\n"
    "  function(a, b, c) return load(string.dump(function() end)) end,\n"
    "  function(a, b, c) return load('return ' .. c)() end,\n"
    "  function(a, b, c) return coroutine.wrap(cmd.read)() end,\n"
    "  function(a, b, c) return coroutine.wrap(sleep)(c) end,\n"
    "  function(a, b, c) return require('x' .. c) end,\n"
    "  function(a, b, c) return socket.sleep(c / 1e4) end,\n"
    "  function(a, b, c) return string.format('%d', b), os.time() end,\n"
    "  function(a, b, c) return etob(c * 300), ntob(a), math.frexp(b) end,\n"
    "}\n"
    "H[0xBD] = function(id, p, s)\n"
    "  local call = calls[(p[1] or 0) % #calls + 1]\n"
    "  local ok = pcall(call, f(p, 2), f(p, 6), p[10] or 0)\n"
    "  cmd.send(id, head(s, 13), ok)\n"
    "end\n"
    "while true do\n"
    "  local id, p = cmd.read()\n"
    "  local s = seq\n"
    "  seq = bit32.band(seq + 1, 0xFFFF)\n"
    "  if H[id](id, p, s) then return end\n"
    "end\n"};

#define FB_MARK 0xA5u
/* IDs the script registers at start; BAh only through B8h. */
static const uint8_t fb_ids[] = {0xB0, 0xB1, 0xB2, 0xB3, 0xB4, 0xB5,
                                 0xB6, 0xB7, 0xB8, 0xB9, 0xBB, 0xBD};
/* What a record's ID byte below 80h picks: the script's IDs, BAh, and
 * BCh, which nothing registers. */
static const uint8_t fb_pick[] = {0xB0, 0xB1, 0xB2, 0xB3, 0xB4, 0xB5, 0xB6,
                                  0xB7, 0xB8, 0xB9, 0xBA, 0xBB, 0xBC, 0xBD};
#define FB_NPICK (sizeof fb_pick / sizeof fb_pick[0])

#define FB_SESSIONS 2
/* Packets delivered and not answered yet: the host's queue, the one being
 * handled, and those whose session closed before their answer. */
#define FB_FIFO 2048u
/* Slices the script may run per input, and after each chunk of input (one,
 * as the daemon gives a preempted script one turn per round of its loop,
 * so packets queue behind a long computation). */
#define FB_SLICES    256u
#define FB_RUNS      1u
#define FB_DRAIN     20000u
#define FB_MEMORY    (1u << 20)
#define FB_BUSY_LOOP 400 /* B5h's iterations per unit of its byte */

struct fb_entry {
    uint16_t seq; /* the script's count of packets read before it */
    uint8_t id;
    int sess;
    uint32_t tag; /* its session's, when it came */
    int orphan; /* its session closed: its answer goes elsewhere or nowhere */
    int pre;    /* B3h: the packet from inside the pcall came */
    uint64_t t_us;
    uint16_t len;
    uint8_t data[WSG_PAYLOAD_MAX];
};

struct fb_sess {
    struct wsg_session s;
    struct wsg_parser parser;
    int closing;
};

static struct {
    struct wsg_device dev;
    struct fb_sess sess[FB_SESSIONS];
    struct wsg_script *h;
    int running; /* started and not seen ending */
    uint32_t next_tag;
    struct fb_entry fifo[FB_FIFO];
    size_t fhead, flen;
    uint16_t next_seq;
    struct fb_entry *just; /* delivered by the event being dispatched */
    /* The event being dispatched, when the firmware answers it. */
    int fw;
    int fw_sess;
    uint8_t fw_id;
    unsigned fw_answers;
    int woken;
    unsigned slices;
    int trace;
} B;

static uint64_t fb_now(void)
{
    return wsg_axis_time(wsg_device_axis_const(&B.dev));
}

static struct fb_entry *fb_at(size_t i)
{
    return &B.fifo[(B.fhead + i) % FB_FIFO];
}

static void fb_pop(void)
{
    B.fhead = (B.fhead + 1) % FB_FIFO;
    B.flen--;
}

static int fb_is_script_id(uint8_t id)
{
    return id >= 0xB0 && id <= 0xBD;
}

/* B5h's sum, as the script computes it. */
static unsigned fb_busy(unsigned k)
{
    unsigned long acc = 0, i;

    for (i = 1; i <= (unsigned long)k * FB_BUSY_LOOP; i++)
        acc = (acc * 31 + i) % 65521;
    return (unsigned)acc;
}

/* A script's answer to e, of this kind, its bytes after the head. */
static void fb_check_answer(const struct fb_entry *e, int si, unsigned kind,
                            const uint8_t *p, size_t n)
{
    unsigned b0 = e->len ? e->data[0] : 0;
    size_t i;

    switch (e->id) {
    case 0xB0:
    case 0xBA:
        FUZZ_CHECK(kind == 0 && n == e->len);
        FUZZ_CHECK(memcmp(p, e->data, n) == 0);
        break;
    case 0xB1:
        FUZZ_CHECK(kind == 1 && n == 4u + e->len);
        FUZZ_CHECK(p[0] == (e->len & 0xFF) && p[1] == e->len >> 8);
        FUZZ_CHECK(p[2] == b0);
        FUZZ_CHECK(memcmp(p + 3, e->data, e->len) == 0);
        FUZZ_CHECK(p[3 + e->len] == (b0 > 127));
        break;
    case 0xB2:
        FUZZ_CHECK(kind == 2 && n == (e->len / 4u) * 4u);
        for (i = 0; i < n; i += 4) {
            /* A float32 and back through a double: the same bits, but
             * for a NaN, which may come back quieted. */
            if (isnan(wsg_get_f32(e->data + i)))
                FUZZ_CHECK(isnan(wsg_get_f32(p + i)));
            else
                FUZZ_CHECK(memcmp(p + i, e->data + i, 4) == 0);
        }
        break;
    case 0xB3:
        FUZZ_CHECK(kind == 3 && n == 1);
        FUZZ_CHECK(p[0] == 12); /* every try failed, and was caught */
        FUZZ_CHECK(e->pre == (e->len >= 1 && b0 <= 127));
        break;
    case 0xB4: {
        uint32_t us;

        FUZZ_CHECK(kind == 4 && n == 4);
        us = wsg_get_u32(p);
        /* It slept at least what it asked for, and no longer than since
         * the packet came. */
        FUZZ_CHECK(us >= b0 * 250u);
        FUZZ_CHECK(us <= fb_now() - e->t_us + 1);
        break;
    }
    case 0xB5:
        FUZZ_CHECK(kind == 5 && n == 2);
        FUZZ_CHECK(wsg_get_u16(p) == fb_busy(b0));
        break;
    case 0xB6:
        FUZZ_CHECK(kind == 6 && n == 6);
        FUZZ_CHECK(p[0] <= 1 && p[5] <= 1);
        if (p[0])
            FUZZ_CHECK(wsg_get_u32(p + 1) == b0 * 16384u);
        else
            FUZZ_CHECK(wsg_get_u32(p + 1) == 0);
        /* Past the cap, string.rep fails. */
        if (b0 * 16384u >= FB_MEMORY)
            FUZZ_CHECK(p[0] == 0);
        break;
    case 0xB7: {
        uint8_t f[4] = {0, 0, 0, 0};

        FUZZ_CHECK(kind == 7 && n == 5);
        memcpy(f, e->data, e->len < 4 ? e->len : 4);
        FUZZ_CHECK(p[0] <= 1 && p[3] <= 1 && p[4] <= 1);
        if (!p[0])
            FUZZ_CHECK(wsg_get_u16(p + 1) == 0xFFFF);
        /* mc.speed(NaN) is no error but a refusal, as a host gets one for
         * a NaN in a command (docs/scripting.md): E_INVALID_PARAMETER, or
         * what refuses any motion first. */
        if (isnan(wsg_get_f32(f)))
            FUZZ_CHECK(p[0] == 1 && wsg_get_u16(p + 1) != WSG_E_SUCCESS);
        break;
    }
    case 0xB8:
        FUZZ_CHECK(kind == 8 && n == 2);
        FUZZ_CHECK(p[0] == 1 && p[1] == 0);
        FUZZ_CHECK(wsg_device_registered(&B.dev, 0xBA) == (int)(b0 & 1u));
        break;
    case 0xB9:
        FUZZ_CHECK(kind == 9 && n == 1);
        FUZZ_CHECK(b0 < 0xEB || b0 > 0xEE);
        FUZZ_CHECK(p[0] == (e->len & 0xFF));
        break;
    case 0xBB: {
        const char *peer = B.sess[si].s.peer;

        FUZZ_CHECK(kind == 11 && n == 3);
        /* What waits in the host's queue: the packets delivered after this
         * one. */
        FUZZ_CHECK(p[0] == B.flen - 1);
        FUZZ_CHECK(p[1] == 1);
        FUZZ_CHECK(p[2] == (peer[0] == 't' ? 'T' : 'U'));
        break;
    }
    case 0xBD:
        FUZZ_CHECK(kind == 13 && n == 1 && p[0] <= 1);
        break;
    default:
        FUZZ_CHECK(0);
    }
}

/* A packet of the script's. */
static void fb_answer(int si, uint8_t id, const uint8_t *p, size_t n)
{
    struct fb_entry *e;
    unsigned seq, kind;

    FUZZ_CHECK(n >= 6);
    FUZZ_CHECK(wsg_get_u16(p) == WSG_E_SUCCESS && p[2] == FB_MARK);
    seq = wsg_get_u16(p + 3);
    kind = p[5];
    if (B.trace)
        fprintf(stderr, "t=%llu out s%d %02x script seq %u kind %u len %lu\n",
                (unsigned long long)fb_now(), si, id, seq, kind,
                (unsigned long)n);
    /* Packets read before it whose answers went nowhere: their session
     * closed and no other had sent anything since. Every other packet
     * before it was answered. */
    while (B.flen > 0 && fb_at(0)->seq != seq) {
        FUZZ_CHECK(fb_at(0)->orphan);
        fb_pop();
    }
    FUZZ_CHECK(B.flen > 0);
    e = fb_at(0);
    FUZZ_CHECK(e->id == id);
    FUZZ_CHECK(e->orphan || e->sess == si);
    if (kind == 0xFF) {
        /* B3h's send from inside its pcall: only a byte that fits. */
        FUZZ_CHECK(id == 0xB3 && !e->pre && n == 7);
        FUZZ_CHECK(e->len >= 1 && e->data[0] <= 127 && p[6] == e->data[0] * 2);
        e->pre = 1;
        return;
    }
    fb_check_answer(e, si, kind, p + 6, n - 6);
    fb_pop();
}

static void fb_send(struct wsg_session *s, const uint8_t *pkt, size_t len)
{
    struct fb_sess *fs = s->ctx;
    int si = (int)(fs - B.sess);
    size_t n;
    uint8_t id;

    FUZZ_CHECK(si >= 0 && si < FB_SESSIONS && !fs->closing);
    FUZZ_CHECK(len >= WSG_HEADER_LEN + WSG_CRC_LEN);
    FUZZ_CHECK(pkt[0] == 0xAA && pkt[1] == 0xAA && pkt[2] == 0xAA);
    FUZZ_CHECK(wsg_crc_update(WSG_CRC_INIT, pkt, len) == 0);
    n = wsg_get_u16(pkt + 4);
    FUZZ_CHECK(len == WSG_HEADER_LEN + n + WSG_CRC_LEN);
    id = pkt[3];
    /* The firmware answers the script's IDs with a status alone; the
     * script always sends more. */
    if (fb_is_script_id(id) && n > 2) {
        fb_answer(si, id, pkt + WSG_HEADER_LEN, n);
        return;
    }
    FUZZ_CHECK(n >= 2);
    if (B.trace)
        fprintf(stderr, "t=%llu out s%d %02x status %u len %lu\n",
                (unsigned long long)fb_now(), si, id,
                wsg_get_u16(pkt + WSG_HEADER_LEN), (unsigned long)n);
    if (n == 2 && wsg_get_u16(pkt + WSG_HEADER_LEN) == WSG_E_OVERRUN &&
        B.just && B.just->id == id && B.just->sess == si) {
        /* The queue was full: refused at once, never read. */
        FUZZ_CHECK(B.flen > 0 && fb_at(B.flen - 1) == B.just);
        FUZZ_CHECK(B.h->qlen == WSG_SCRIPT_QUEUE);
        B.flen--;
        B.next_seq--;
        B.just = NULL;
        return;
    }
    if (B.fw && B.fw_sess == si && B.fw_id == id)
        B.fw_answers++;
}

static struct wsg_session *fb_lookup(void *ctx, uint32_t tag)
{
    int i;

    (void)ctx;
    for (i = 0; i < FB_SESSIONS; i++)
        if (!B.sess[i].closing && B.sess[i].s.tag == tag)
            return &B.sess[i].s;
    return NULL;
}

static void fb_wake(void *ctx)
{
    (void)ctx;
    B.woken = 1;
}

/* The script ended by itself: only the packets that ask for it end it:
 * B9h EEh with D20 and its error, EDh without, ECh and EBh with D20 and
 * "not enough memory" (one allocation past the cap, or many small ones,
 * outside a pcall). */
static void fb_check_ended(void)
{
    struct wsg_script_status st;
    const struct fb_entry *e = NULL;
    size_t i;

    if (!B.running)
        return;
    wsg_script_status(B.h, &st);
    if (st.running)
        return;
    for (i = 0; i < B.flen; i++) {
        e = fb_at(i);
        if (e->id == 0xB9 && e->len >= 1 && e->data[0] >= 0xEB &&
            e->data[0] <= 0xEE)
            break;
        FUZZ_CHECK(e->orphan);
    }
    if (i == B.flen)
        fprintf(stderr, "fuzz_script: the script ended unasked: %s\n",
                st.error ? st.error : "(no error)");
    FUZZ_CHECK(i < B.flen);
    if (e->data[0] == 0xED) {
        FUZZ_CHECK(!st.failed);
    } else {
        if (B.trace)
            fprintf(stderr, "script error: %s\n", st.error);
        FUZZ_CHECK(st.failed && st.error);
        FUZZ_CHECK(strstr(st.error, e->data[0] == 0xEE ? "requested failure"
                                                       : "not enough memory"));
    }
    if (B.trace)
        fprintf(stderr, "t=%llu script ended%s\n",
                (unsigned long long)fb_now(), st.failed ? ", failed" : "");
    /* What it had not read is gone with it. */
    B.running = 0;
    B.flen = 0;
    B.woken = 0;
}

/* The preempted script's turns, as the daemon's runner gives them. */
static void fb_run(unsigned max)
{
    while (B.woken && max-- > 0 && B.slices < FB_SLICES) {
        B.woken = 0;
        B.slices++;
        wsg_script_run(B.h);
        wsg_axis_settle(wsg_device_axis(&B.dev));
        fb_check_ended();
    }
}

static void fb_steps(unsigned n)
{
    while (n-- > 0) {
        wsg_device_step(&B.dev);
        wsg_device_poll_streaming(&B.dev);
        wsg_script_poll(B.h);
        fb_check_ended();
        fb_run(1);
    }
}

/* The previous event got its firmware answer. */
static void fb_event_done(void)
{
    if (B.fw)
        FUZZ_CHECK(B.fw_answers >= 1);
    B.fw = 0;
    B.just = NULL;
}

static void fb_trace_in(void *ctx, const struct wsg_session *s,
                        const struct wsg_frame *f, enum wsg_parse_event ev)
{
    int si = (int)((const struct fb_sess *)s->ctx - B.sess);
    struct fb_entry *e;

    (void)ctx;
    fb_event_done();
    fb_check_ended();
    if (B.trace)
        fprintf(stderr, "t=%llu in  s%d %02x ev %d len %u\n",
                (unsigned long long)fb_now(), si, f->id, (int)ev,
                (unsigned)f->len);
    if (ev == WSG_PARSE_FRAME && B.dev.user_cmd &&
        wsg_device_registered(&B.dev, f->id) && !s->announced) {
        /* For the script: it will answer this, or the firmware refuses it
         * with E_OVERRUN at once. */
        FUZZ_CHECK(B.running && fb_is_script_id(f->id));
        FUZZ_CHECK(B.flen < FB_FIFO);
        e = fb_at(B.flen++);
        e->seq = B.next_seq++;
        e->id = f->id;
        e->sess = si;
        e->tag = s->tag;
        e->orphan = 0;
        e->pre = 0;
        e->t_us = fb_now();
        e->len = f->len;
        memcpy(e->data, f->payload, f->len);
        B.just = e;
    } else {
        B.fw = 1;
        B.fw_sess = si;
        B.fw_id = f->id;
        B.fw_answers = 0;
    }
}

static void fb_feed(int si, const uint8_t *pkt, size_t n, int datagram)
{
    if (datagram)
        wsg_device_input_datagram(&B.dev, &B.sess[si].s, 1, pkt, n);
    else
        wsg_device_input(&B.dev, &B.sess[si].s, &B.sess[si].parser, pkt, n);
    fb_event_done();
    fb_check_ended();
    fb_run(FB_RUNS);
}

/* The script's file: written for each start into a directory of its own
 * and removed with it once loaded (the host reads it at start only), so
 * no run leaves one behind, and its require finds no module of anyone
 * else's there. */
static void fb_start(void)
{
    const char *tmp = getenv("TMPDIR");
    char dir[512], path[600], err[512];
    FILE *f;
    int r;
    size_t k, len;

    snprintf(dir, sizeof dir, "%s/fuzz_script_XXXXXX",
             tmp && *tmp ? tmp : "/tmp");
    FUZZ_CHECK(mkdtemp(dir) != NULL);
    snprintf(path, sizeof path, "%s/fuzz.lua", dir);
    f = fopen(path, "w");
    FUZZ_CHECK(f != NULL);
    for (k = 0; k < sizeof fb_script / sizeof fb_script[0]; k++) {
        len = strlen(fb_script[k]);
        FUZZ_CHECK(fwrite(fb_script[k], 1, len, f) == len);
    }
    FUZZ_CHECK(fclose(f) == 0);
    r = wsg_script_start(B.h, path, err, sizeof err);
    unlink(path);
    rmdir(dir);
    if (r != 0)
        fprintf(stderr, "fuzz_script: the script did not start: %s\n", err);
    FUZZ_CHECK(r == 0);
    B.running = 1;
    B.next_seq = 0;
    B.flen = 0;
}

static void fb_stop(void)
{
    fb_check_ended();
    FUZZ_CHECK(wsg_script_stop(B.h) == (B.running ? 0 : -ESRCH));
    B.running = 0;
    B.flen = 0;
    B.woken = 0;
}

/* The host's queue (its private layout, script_impl.h) is the newest
 * packets of the FIFO, in order, as they came; before them, at most one
 * packet read and not answered yet (the one the script handles) but
 * those whose answer went nowhere. */
static void fb_check_queue(void)
{
    const struct wsg_script *h = B.h;
    size_t q = h->qlen, i, handled = 0;

    FUZZ_CHECK(q <= WSG_SCRIPT_QUEUE && q <= B.flen);
    for (i = 0; i < q; i++) {
        const struct wsg_script_packet *p =
            &h->queue[(h->qhead + i) % WSG_SCRIPT_QUEUE];
        const struct fb_entry *e = fb_at(B.flen - q + i);

        FUZZ_CHECK(p->id == e->id && p->tag == e->tag && p->len == e->len);
        FUZZ_CHECK(memcmp(p->data, e->data, e->len) == 0);
    }
    for (i = 0; i < B.flen - q; i++)
        handled += !fb_at(i)->orphan;
    FUZZ_CHECK(handled <= 1);
}

/* The host, the flags and the registered IDs agree with what the harness
 * saw. */
static void fb_check_state(void)
{
    struct wsg_script_status st;
    uint32_t flags = wsg_device_flags(&B.dev);
    uint8_t ids[256];
    size_t n, i, k;

    fb_check_ended();
    wsg_script_status(B.h, &st);
    FUZZ_CHECK(st.running == B.running);
    FUZZ_CHECK(!!(flags & WSG_SF_SCRIPT_RUNNING) == st.running);
    FUZZ_CHECK(!!(flags & WSG_SF_SCRIPT_FAILURE) == st.failed);
    FUZZ_CHECK(st.memory_max == FB_MEMORY);
    n = wsg_script_registered(B.h, ids, sizeof ids);
    if (!st.running) {
        FUZZ_CHECK(st.state == WSG_SCRIPT_STOPPED && n == 0 && B.flen == 0);
        FUZZ_CHECK(st.memory == 0);
        return;
    }
    FUZZ_CHECK(st.memory > 0 && st.memory <= st.memory_max);
    for (k = 0; k < sizeof fb_ids; k++)
        FUZZ_CHECK(wsg_device_registered(&B.dev, fb_ids[k]));
    for (i = 0; i < n; i++)
        FUZZ_CHECK(memchr(fb_ids, ids[i], sizeof fb_ids) || ids[i] == 0xBA);
    FUZZ_CHECK(n ==
               sizeof fb_ids + (size_t)wsg_device_registered(&B.dev, 0xBA));
    fb_check_queue();
    switch (st.state) {
    case WSG_SCRIPT_READING:
        /* Everything delivered was read and answered, but where the
         * answer went nowhere. */
        for (i = 0; i < B.flen; i++)
            FUZZ_CHECK(fb_at(i)->orphan);
        FUZZ_CHECK(B.h->qlen == 0);
        B.flen = 0;
        FUZZ_CHECK(!B.woken);
        break;
    case WSG_SCRIPT_SLEEPING:
        FUZZ_CHECK(wsg_script_next(B.h) != UINT64_MAX);
        FUZZ_CHECK(wsg_script_next(B.h) >= fb_now());
        FUZZ_CHECK(st.wake_us == wsg_script_next(B.h));
        break;
    case WSG_SCRIPT_RUNNABLE:
        FUZZ_CHECK(B.woken); /* it asked for its turn */
        break;
    default:
        FUZZ_CHECK(0); /* RUNNING only inside the host, STOPPED not running */
    }
}

static void fb_sess_open(int i)
{
    struct fb_sess *fs = &B.sess[i];

    wsg_session_init(&fs->s, B.next_tag++, i == 0 ? WSG_SESSION_CONNECTION : 0,
                     fb_send, fs);
    snprintf(fs->s.peer, sizeof fs->s.peer, "%s",
             i == 0 ? "tcp fuzz" : "udp fuzz");
    wsg_parser_init(&fs->parser, 1);
    fs->closing = 0;
}

/* The peer went: its packets not answered yet are orphans now, and it
 * comes back under a fresh tag. */
static void fb_sess_close(int i)
{
    size_t k;

    for (k = 0; k < B.flen; k++)
        if (fb_at(k)->sess == i)
            fb_at(k)->orphan = 1;
    B.sess[i].closing = 1;
    wsg_device_session_closed(&B.dev, &B.sess[i].s);
    fb_sess_open(i);
    fb_check_ended();
    fb_run(FB_RUNS);
}

static void fb_begin(uint8_t cfg)
{
    struct wsg_script_config sc = {FB_MEMORY, NULL, fb_wake, NULL, NULL};
    struct wsg_axis_config ac;
    int i;

    B.trace = getenv("FUZZ_TRACE") != NULL;
    FUZZ_CHECK(wsg_axis_config_init(&ac, "wsg50") == 0);
    wsg_device_init(&B.dev, &ac);
    B.dev.lookup = fb_lookup;
    B.dev.trace_in = fb_trace_in;
    B.next_tag = 1;
    for (i = 0; i < FB_SESSIONS; i++)
        fb_sess_open(i);
    B.fhead = B.flen = 0;
    B.just = NULL;
    B.fw = 0;
    B.woken = 0;
    B.slices = 0;
    B.running = 0;
    FUZZ_CHECK(wsg_script_new(&B.h, &B.dev, &sc) == 0);
    fb_start();
    fb_check_state();
    if (cfg & 2u) {
        /* Referenced first, so speed mode may start. */
        uint8_t pkt[WSG_HEADER_LEN + 1 + WSG_CRC_LEN], dir = 0;
        size_t n = wsg_frame_encode(pkt, sizeof pkt, WSG_CMD_HOMING, &dir, 1);

        fb_feed(0, pkt, n, 0);
        fb_steps(2000);
        fb_check_state();
    }
}

/* Let the script finish what it has: every packet delivered is answered
 * then. A script still busy once its slices are used up is stopped. */
static void fb_end(void)
{
    struct wsg_script_status st;
    unsigned k;

    for (k = 0; B.running && k < FB_DRAIN; k++) {
        wsg_script_status(B.h, &st);
        if (st.state == WSG_SCRIPT_READING)
            break;
        if (st.state == WSG_SCRIPT_RUNNABLE) {
            if (B.slices >= FB_SLICES)
                break;
            fb_run(1);
        } else {
            fb_steps(1);
        }
    }
    fb_check_ended();
    wsg_script_status(B.h, &st);
    if (B.running && st.state != WSG_SCRIPT_READING)
        fb_stop();
    fb_check_state();
    FUZZ_CHECK(B.flen == 0);
    fb_stop();
    fb_check_state();
    wsg_script_free(B.h);
    B.h = NULL;
    FUZZ_CHECK(B.dev.user_cmd == NULL);
}

static void fb_run_input(const uint8_t *data, size_t size)
{
    static const unsigned steps[8] = {0, 1, 2, 5, 10, 50, 200, 1000};
    uint8_t pkt[WSG_HEADER_LEN + WSG_PAYLOAD_MAX + WSG_CRC_LEN];
    size_t i = 1;

    fb_begin(data[0]);
    while (i + 3 <= size) {
        unsigned sel = data[i], ctl = data[i + 1], ev = ctl >> 4;
        size_t len = data[i + 2], n;
        int si = (int)(ctl & 1u);
        uint8_t id = sel < 0x80u              ? fb_pick[sel % FB_NPICK]
                     : sel < FUZZ_RAW_ID_FROM ? fuzz_ids[sel % FUZZ_NIDS]
                                              : (uint8_t)sel;

        i += 3;
        if (len > size - i)
            len = size - i;
        n = wsg_frame_encode(pkt, sizeof pkt, id, data + i, len);
        i += len;
        FUZZ_CHECK(n > 0);
        /* Control bits 4-7: 0-8 nothing more; 9 the frame as a datagram;
         * 10 its checksum broken; 11 fed in two parts with a step
         * between; 12 the script restarted first; 13 stopped first; 14
         * the session closed after it; 15 a power cycle after it. */
        if (ev == 12) {
            fb_stop();
            fb_start();
        } else if (ev == 13) {
            fb_stop();
        }
        if (ev == 10)
            pkt[n - 1] ^= 0x55;
        if (ev == 11) {
            size_t cut = 1 + len % (n - 1);

            fb_feed(si, pkt, cut, 0);
            fb_steps(1);
            fb_feed(si, pkt + cut, n - cut, 0);
        } else {
            fb_feed(si, pkt, n, ev == 9);
        }
        if (ev == 14)
            fb_sess_close(si);
        if (ev == 15)
            wsg_device_reset(&B.dev);
        fb_steps(steps[(ctl >> 1) & 7u]);
        fb_check_state();
    }
    fb_end();
}

int FUZZ_ENTRY(const uint8_t *data, size_t size);

int FUZZ_ENTRY(const uint8_t *data, size_t size)
{
    struct rd r;

    if (size < 1)
        return 0;
    if (data[0] & 1u) {
        r.p = data + 1;
        r.n = size - 1;
        fa_run(&r);
    } else {
        fb_run_input(data, size);
    }
    return 0;
}
