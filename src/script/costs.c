/*
 * The work of a script's library functions that is not instructions and
 * not allocation, spent from the slice: the count hook counts one
 * instruction for a call, however long the call runs, and the allocator
 * counts only what the call allocates. A loop of such calls (a
 * table.insert at the front of a big table, a tonumber of megabytes, a
 * full collectgarbage()) would otherwise do a slice's worth of work at
 * every instruction, for a whole slice of instructions.
 *
 * Each function here is Lua's, called in the wrapper's own frame (its C
 * function from the wrapper's upvalue: none of them has upvalues of its
 * own), so its errors name it as before; what it did is spent afterwards
 * (wsg_script_spend), and the slice ends at the next instruction when
 * that uses it up. A single call is still as long as the data a script of
 * the memory cap can hold makes it.
 */
#include <string.h>

#include <lauxlib.h>
#include <lualib.h>

#include "script_impl.h"

/* What each wrapped function's work is measured by. */
enum {
    COST_BYTES,  /* its string arguments' lengths */
    COST_INSERT, /* table.insert at a position: the elements moved */
    COST_REMOVE, /* table.remove at a position: the same */
    COST_CONCAT, /* table.concat: the elements read */
    COST_SORT,   /* table.sort: n log n comparisons */
    COST_COLLECT /* collectgarbage: the memory the collector walks */
};

/* Steps: a byte of a string scanned, an element read or written. */
#define COST_BYTES_PER_STEP    4
#define COST_STEPS_PER_ELEMENT 4
/* Bytes of memory a collection walks in a step. */
#define COST_BYTES_PER_GC_STEP 16

static lua_Integer cost_len(lua_State *L, int arg)
{
    return lua_type(L, arg) == LUA_TTABLE ? (lua_Integer)lua_rawlen(L, arg)
                                          : 0;
}

static lua_Integer cost_opt(lua_State *L, int arg, lua_Integer def)
{
    int ok;
    lua_Integer v = lua_tointegerx(L, arg, &ok);

    return ok ? v : def;
}

/* The work a call with these arguments will do, in steps (an estimate:
 * what matters is that a long call counts as long). */
static lua_Integer cost_of(lua_State *L, int kind)
{
    lua_Integer n = 0, len, i, j;
    int a, top = lua_gettop(L);
    size_t l;

    switch (kind) {
    case COST_BYTES:
        for (a = 1; a <= top; a++)
            if (lua_type(L, a) == LUA_TSTRING) {
                lua_tolstring(L, a, &l);
                n += (lua_Integer)(l / COST_BYTES_PER_STEP);
            }
        return n;
    case COST_INSERT:
    case COST_REMOVE:
        /* At the end (no position) an element; else those after it. */
        if (top < (kind == COST_INSERT ? 3 : 2))
            return 1;
        len = cost_len(L, 1);
        i = cost_opt(L, 2, len);
        return i >= 1 && i <= len ? (len - i + 1) * COST_STEPS_PER_ELEMENT : 1;
    case COST_CONCAT:
        i = cost_opt(L, 3, 1);
        j = cost_opt(L, 4, cost_len(L, 1));
        return j >= i && j - i < WSG_LUA_INTEGER_MAX / COST_STEPS_PER_ELEMENT
                   ? (j - i + 1) * COST_STEPS_PER_ELEMENT
                   : 0;
    case COST_SORT:
        len = cost_len(L, 1);
        for (n = 1, i = len; i > 1; i >>= 1)
            n++;
        return len * n * COST_STEPS_PER_ELEMENT;
    default:
        /* "collect" (the default) and "step" walk what is alive. */
        if (lua_isnoneornil(L, 1) ||
            (lua_type(L, 1) == LUA_TSTRING &&
             (strcmp(lua_tostring(L, 1), "collect") == 0 ||
              strcmp(lua_tostring(L, 1), "step") == 0)))
            return (lua_Integer)(wsg_script_of(L)->memory /
                                 COST_BYTES_PER_GC_STEP);
        return 1;
    }
}

static int api_costly(lua_State *L)
{
    lua_CFunction fn = lua_tocfunction(L, lua_upvalueindex(1));
    int kind = (int)lua_tointeger(L, lua_upvalueindex(2)), n;
    lua_Integer cost = cost_of(L, kind);

    n = fn(L);
    if (cost > 0)
        wsg_script_spend(wsg_script_of(L), L,
                         cost > UINT32_MAX ? UINT32_MAX : (uint32_t)cost);
    return n;
}

/* string.rep: Lua's, but one whose result is empty is "" at once. Lua's
 * allocates the result first, so the memory cap bounds its loop, except
 * for an empty string repeated with an empty separator: that loop copies
 * nothing 2^31 times, some seconds in one call, and allocates nothing the
 * allocator could count. */
static int api_rep(lua_State *L)
{
    lua_CFunction rep = lua_tocfunction(L, lua_upvalueindex(1));
    size_t l, lsep = 0;

    luaL_checklstring(L, 1, &l);
    luaL_checkinteger(L, 2);
    luaL_optlstring(L, 3, "", &lsep);
    if (l == 0 && lsep == 0) {
        lua_pushliteral(L, "");
        return 1;
    }
    return rep(L);
}

static void cost_wrap(lua_State *L, const char *name, int kind)
{
    lua_getfield(L, -1, name);
    lua_pushinteger(L, kind);
    lua_pushcclosure(L, api_costly, 2);
    lua_setfield(L, -2, name);
}

void wsg_script_open_costs(lua_State *L)
{
    lua_getglobal(L, LUA_STRLIBNAME);
    lua_getfield(L, -1, "rep");
    lua_pushcclosure(L, api_rep, 1);
    lua_setfield(L, -2, "rep");
    lua_pop(L, 1);
    lua_getglobal(L, LUA_TABLIBNAME);
    cost_wrap(L, "insert", COST_INSERT);
    cost_wrap(L, "remove", COST_REMOVE);
    cost_wrap(L, "concat", COST_CONCAT);
    cost_wrap(L, "sort", COST_SORT);
    lua_pop(L, 1);
    lua_pushglobaltable(L);
    cost_wrap(L, "tonumber", COST_BYTES);
    cost_wrap(L, "collectgarbage", COST_COLLECT);
    lua_pop(L, 1);
}
