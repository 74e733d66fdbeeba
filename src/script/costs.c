/*
 * The work of a script's library functions that is not instructions and
 * not allocation, spent from the slice: the count hook counts one
 * instruction for a call, however long the call runs, and the allocator
 * counts only what the call allocates. A loop of such calls (a
 * table.insert at the front of a big table, a utf8.len of megabytes, a
 * full collectgarbage()) would otherwise do a slice's worth of work at
 * every instruction, for a whole slice of instructions.
 *
 * Each function here is Lua's, called in the wrapper's own frame (its C
 * function from the wrapper's upvalue: none of them has upvalues of its
 * own), so its errors name it as before; what it did is spent afterwards
 * (wsg_script_spend), and the slice ends at the next instruction when
 * that uses it up. A single call is still as long as the data a script of
 * the memory cap can hold makes it. table.move, which can walk 2^63
 * indexes of nothing, is the project's: it moves a slice's worth at a
 * time and yields across itself in between.
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
        return j >= i && j - i < LUA_MAXINTEGER / COST_STEPS_PER_ELEMENT
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

static void cost_wrap(lua_State *L, const char *name, int kind)
{
    lua_getfield(L, -1, name);
    lua_pushinteger(L, kind);
    lua_pushcclosure(L, api_costly, 2);
    lua_setfield(L, -2, name);
}

/* ---- table.move ---- */

/* As Lua's checktab: a table, or a value whose metatable has the field
 * the use needs (read raw). */
static void move_checktab(lua_State *L, int arg, const char *field)
{
    if (lua_type(L, arg) == LUA_TTABLE)
        return;
    if (lua_getmetatable(L, arg)) {
        lua_pushstring(L, field);
        if (lua_rawget(L, -2) != LUA_TNIL) {
            lua_pop(L, 2);
            return;
        }
    }
    luaL_checktype(L, arg, LUA_TTABLE);
}

/* Stack: a1, f, e, t, a2 (or nil), forward, the elements moved. */
static int move_go(lua_State *L, int status, lua_KContext ctx)
{
    struct wsg_script *h = wsg_script_of(L);
    lua_Integer f = lua_tointeger(L, 2), e = lua_tointeger(L, 3);
    lua_Integer t = lua_tointeger(L, 4), n = e - f + 1, i, k;
    int tt = lua_isnil(L, 5) ? 1 : 5, forward = lua_toboolean(L, 6);
    uint32_t left;

    (void)status;
    (void)ctx;
    for (;;) {
        i = lua_tointeger(L, 7);
        if (i >= n)
            break;
        left = h->slice.left(h, L) / COST_STEPS_PER_ELEMENT;
        for (k = 0; k < (lua_Integer)left && i < n; k++, i++) {
            lua_Integer at = forward ? i : n - 1 - i;

            lua_geti(L, 1, f + at);
            lua_seti(L, tt, t + at);
        }
        lua_pushinteger(L, i);
        lua_replace(L, 7);
        wsg_script_spend(h, L, (uint32_t)k * COST_STEPS_PER_ELEMENT);
        if (i < n && wsg_script_slice_over(h, L))
            return lua_yieldk(L, 0, 0, move_go);
    }
    lua_pushvalue(L, tt);
    return 1;
}

static int api_move(lua_State *L)
{
    lua_Integer f = luaL_checkinteger(L, 2);
    lua_Integer e = luaL_checkinteger(L, 3);
    lua_Integer t = luaL_checkinteger(L, 4);
    int tt = !lua_isnoneornil(L, 5) ? 5 : 1, forward;

    move_checktab(L, 1, "__index");
    move_checktab(L, tt, "__newindex");
    lua_settop(L, 5);
    if (e < f) {
        lua_pushvalue(L, tt);
        return 1;
    }
    luaL_argcheck(L, f > 0 || e < LUA_MAXINTEGER + f, 3,
                  "too many elements to move");
    luaL_argcheck(L, t <= LUA_MAXINTEGER - (e - f + 1) + 1, 4,
                  "destination wrap around");
    /* Overlapping within one table, forward onto itself: from the end. */
    forward = t > e || t <= f || (tt != 1 && !lua_compare(L, 1, tt, LUA_OPEQ));
    lua_pushboolean(L, forward);
    lua_pushinteger(L, 0);
    return move_go(L, LUA_OK, 0);
}

void wsg_script_open_costs(lua_State *L)
{
    static const char *const bytes_utf8[] = {"len", "offset", "codepoint",
                                             NULL};
    const char *const *name;

    lua_getglobal(L, LUA_UTF8LIBNAME);
    for (name = bytes_utf8; *name; name++)
        cost_wrap(L, *name, COST_BYTES);
    lua_pop(L, 1);
    lua_getglobal(L, LUA_TABLIBNAME);
    cost_wrap(L, "insert", COST_INSERT);
    cost_wrap(L, "remove", COST_REMOVE);
    cost_wrap(L, "concat", COST_CONCAT);
    cost_wrap(L, "sort", COST_SORT);
    lua_pushcfunction(L, api_move);
    lua_setfield(L, -2, "move");
    lua_pop(L, 1);
    lua_pushglobaltable(L);
    cost_wrap(L, "tonumber", COST_BYTES);
    cost_wrap(L, "collectgarbage", COST_COLLECT);
    lua_pop(L, 1);
}
