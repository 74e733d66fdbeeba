/*
 * cmd.send's payload: its arguments flattened in order into bytes, as the
 * gripper's scripts build their answers (etob(E_SUCCESS), a state byte,
 * ntob(x) tables, strings). It reads tables raw, so a script's metamethods
 * cannot run (or yield, or loop) in the middle of a send, and it reports
 * errors instead of raising them, so the caller decides how the script
 * hears of them and the fuzzer can call it outside a protected call.
 *
 * A table may be an element of another many times, and nesting multiplies
 * that: five levels of 100 references to one table are 100^5 values to
 * visit, all of them empty strings that add nothing to the payload. So it
 * counts the values it visits, not only the bytes it writes, and gives up
 * past WSG_SCRIPT_SEND_VISITS.
 */
#include <stdio.h>

#include <lua.h>

#include "script_impl.h"

struct flat {
    uint8_t *out;
    size_t cap, len;
    size_t visits;
    char *err;
    size_t errlen;
};

static int flat_fail(struct flat *f, const char *what, int depth)
{
    snprintf(f->err, f->errlen, "%s%s", what,
             depth > 0 ? " (inside a table)" : "");
    return -1;
}

static int flat_byte(struct flat *f, lua_Integer v)
{
    if (f->len >= f->cap)
        return -1;
    f->out[f->len++] = (uint8_t)v;
    return 0;
}

/* The value at the top of L's stack, at table depth depth (0: an
 * argument). */
static int flat_value(lua_State *L, struct flat *f, int depth)
{
    lua_Integer v, i, n;
    const char *s;
    size_t len;
    int isint;

    if (++f->visits > WSG_SCRIPT_SEND_VISITS) {
        snprintf(f->err, f->errlen,
                 "more than %lu values (tables nested or repeated too "
                 "often)",
                 (unsigned long)WSG_SCRIPT_SEND_VISITS);
        return -1;
    }
    switch (lua_type(L, -1)) {
    case LUA_TNUMBER:
        isint = wsg_script_whole(L, -1, &v);
        if (!isint || v < 0 || v > 255)
            return flat_fail(f,
                             "a number must be a whole byte in 0..255 "
                             "(ntob(x) sends a float)",
                             depth);
        if (flat_byte(f, v) < 0)
            goto full;
        return 0;
    case LUA_TBOOLEAN:
        if (flat_byte(f, lua_toboolean(L, -1)) < 0)
            goto full;
        return 0;
    case LUA_TSTRING:
        s = lua_tolstring(L, -1, &len);
        if (len > f->cap - f->len)
            goto full;
        for (; len > 0; len--)
            f->out[f->len++] = (uint8_t)*s++;
        return 0;
    case LUA_TTABLE:
        if (depth >= WSG_SCRIPT_NEST_MAX)
            return flat_fail(f, "tables nested more than 5 deep", 0);
        if (!lua_checkstack(L, 2))
            return flat_fail(f, "out of stack", depth);
        n = (lua_Integer)lua_rawlen(L, -1);
        for (i = 1; i <= n; i++) {
            lua_rawgeti(L, -1, i);
            if (flat_value(L, f, depth + 1) < 0) {
                lua_pop(L, 1);
                return -1;
            }
            lua_pop(L, 1);
        }
        return 0;
    default:
        snprintf(f->err, f->errlen, "cannot send a %s%s",
                 lua_typename(L, lua_type(L, -1)),
                 depth > 0 ? " (inside a table)" : "");
        return -1;
    }
full:
    snprintf(f->err, f->errlen, "payload longer than %lu bytes",
             (unsigned long)f->cap);
    return -1;
}

long wsg_script_flatten(lua_State *L, int first, uint8_t *out, size_t cap,
                        char *err, size_t errlen, size_t *visits)
{
    struct flat f = {out, cap, 0, 0, err, errlen};
    int i, top = lua_gettop(L);
    long r = -1;

    if (!lua_checkstack(L, 2)) {
        snprintf(err, errlen, "out of stack");
        goto out;
    }
    for (i = first; i <= top; i++) {
        lua_pushvalue(L, i);
        if (flat_value(L, &f, 0) < 0) {
            lua_settop(L, top);
            goto out;
        }
        lua_pop(L, 1);
    }
    r = (long)f.len;
out:
    if (visits)
        *visits = f.visits;
    return r;
}
