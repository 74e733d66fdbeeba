/*
 * The functions of a script's standard library that resume its own code
 * or catch its errors, over Lua's: coroutine.resume and wrap, which carry
 * a preemption through, and pcall, xpcall and load,
 * which pass on an error where the script has used up its allowance of
 * slices that cannot yield, and pay the yield such a stretch owes as
 * soon as they return to where the script can yield.
 *
 * With Lua's resume, a coroutine of the script's own cannot be preempted:
 * the count hook's yield would go to its resumer, the script, not to the
 * host, so the host could only let it run and stop it with an error after
 * some slices, and a script that starts a fresh one each time held the
 * daemon for good. Here resume records which coroutine runs inside which
 * (the host's nest) and whether the resumer could itself yield to the
 * host; the hook then yields the coroutine, resume sees that it was the
 * host's yield (h->preempting) and yields its own thread in turn, and so
 * on up to the body and the host. When the host resumes the body, each
 * resume's continuation resumes the coroutine inside it again.
 *
 * What they return and raise is Lua 5.2's (lcorolib.c, lbaselib.c). A
 * continuation (Lua 5.2's) is a C function that asks lua_getctx for its
 * status and context.
 */
#include <lauxlib.h>
#include <lualib.h>

#include "script_impl.h"

/* The values on L's top moved to co (co_run's narg); none on a resume
 * after a preemption. */
#define AGAIN (-1)

/* Resume co from L with narg values from L's top; what it yields or
 * returns moved to L, their count, or -1 with the error on L's top. A
 * preemption on its way to the host is passed on: L yields, and k (with
 * ctx) resumes co again when L is resumed. */
static int co_run(lua_State *L, lua_State *co, int narg, int ctx,
                  lua_CFunction k)
{
    struct wsg_script *h = wsg_script_of(L);
    lua_State *was = h->running;
    int status, nres, reach;

    if (narg == AGAIN) {
        narg = 0;
    } else {
        if (!lua_checkstack(co, narg)) {
            lua_pushliteral(L, "too many arguments to resume");
            return -1;
        }
        /* Lua 5.2's lua_resume leaves this to its caller. */
        if (lua_status(co) == LUA_OK && lua_gettop(co) == 0) {
            lua_pushliteral(L, "cannot resume dead coroutine");
            return -1;
        }
        lua_xmove(L, co, narg);
    }
    for (;;) {
        reach = wsg_script_preemptible(h, L);
        if (h->nest < WSG_SCRIPT_NEST_CO) {
            h->nested[h->nest].co = co;
            h->nested[h->nest].reach = reach;
        }
        h->nest++;
        h->running = co;
        h->preempting = 0;
        status = lua_resume(co, L, narg);
        nres = status == LUA_OK || status == LUA_YIELD ? lua_gettop(co) : 0;
        h->nest--;
        h->running = was;
        if (status != LUA_YIELD || !h->preempting)
            break;
        /* The host's yield: L passes it on, as co could only be
         * preempted if L could yield (reach). */
        lua_pop(co, nres);
        if (reach)
            return lua_yieldk(L, 0, ctx, k);
        h->preempting = 0;
        narg = 0;
    }
    if (status == LUA_OK || status == LUA_YIELD) {
        if (!lua_checkstack(L, nres + 1)) {
            lua_pop(co, nres);
            lua_pushliteral(L, "too many results to resume");
            return -1;
        }
        lua_xmove(co, L, nres);
        return nres;
    }
    lua_xmove(co, L, 1);
    return -1;
}

/* An error caught by one of these functions: passed on where the script
 * used up its allowance and cannot yield (wsg_script_doomed). */
static void pass_on(lua_State *L)
{
    if (wsg_script_doomed(wsg_script_of(L), L))
        lua_error(L);
}

static int pay_k(lua_State *L)
{
    int n = 0;

    lua_getctx(L, &n);
    return n;
}

/* Return the n values at the top, after the yield owed by a stretch that
 * could not yield, when this is where the script can pay it: the hook
 * that would pay it may keep coming inside such stretches (a loop that
 * calls one, its errors caught here), never between them. */
static int pay(lua_State *L, int n)
{
    struct wsg_script *h = wsg_script_of(L);

    if (h->owed && wsg_script_preemptible(h, L) && wsg_script_slice_over(h, L))
        return lua_yieldk(L, 0, n, pay_k);
    return n;
}

static int resume_end(lua_State *L, int r)
{
    if (r < 0) {
        pass_on(L);
        lua_pushboolean(L, 0);
        lua_insert(L, -2);
        return pay(L, 2);
    }
    lua_pushboolean(L, 1);
    lua_insert(L, -(r + 1));
    return pay(L, r + 1);
}

static lua_State *co_arg(lua_State *L)
{
    lua_State *co = lua_tothread(L, 1);

    luaL_argcheck(L, co, 1, "coroutine expected");
    return co;
}

static int co_resume_k(lua_State *L)
{
    return resume_end(L, co_run(L, lua_tothread(L, 1), AGAIN, 0, co_resume_k));
}

static int co_resume(lua_State *L)
{
    lua_State *co = co_arg(L);

    return resume_end(L, co_run(L, co, lua_gettop(L) - 1, 0, co_resume_k));
}

static int wrap_end(lua_State *L, int r)
{
    if (r >= 0)
        return pay(L, r);
    if (lua_isstring(L, -1)) {
        luaL_where(L, 1);
        lua_insert(L, -2);
        lua_concat(L, 2);
    }
    return lua_error(L);
}

static int co_wrap_k(lua_State *L)
{
    lua_State *co = lua_tothread(L, lua_upvalueindex(1));

    return wrap_end(L, co_run(L, co, AGAIN, 0, co_wrap_k));
}

static int co_wrapped(lua_State *L)
{
    lua_State *co = lua_tothread(L, lua_upvalueindex(1));

    return wrap_end(L, co_run(L, co, lua_gettop(L), 0, co_wrap_k));
}

static int co_wrap(lua_State *L)
{
    lua_State *co;

    luaL_checktype(L, 1, LUA_TFUNCTION);
    co = lua_newthread(L);
    lua_pushvalue(L, 1);
    lua_xmove(L, co, 1);
    lua_pushcclosure(L, co_wrapped, 1);
    return 1;
}

/* load: Lua's, called in this frame (so that its errors name it), whose
 * failure (nil and a message: the reader raised an error) is passed on
 * as an error where it must be. Compiling is work: a step a byte. */
static int api_load(lua_State *L)
{
    lua_CFunction load = lua_tocfunction(L, lua_upvalueindex(1));
    size_t len = 0;
    int n;

    if (lua_type(L, 1) == LUA_TSTRING)
        lua_tolstring(L, 1, &len);
    n = load(L);
    wsg_script_spend(wsg_script_of(L), L,
                     len > UINT32_MAX ? UINT32_MAX : (uint32_t)len);
    if (n == 2 && lua_isnil(L, -2) && wsg_script_doomed(wsg_script_of(L), L))
        return lua_error(L);
    return pay(L, n);
}

/* pcall, as Lua's: its results above the true at 1. */
static int pcall_end(lua_State *L, int status, int extra)
{
    if (status != LUA_OK && status != LUA_YIELD) {
        pass_on(L);
        lua_pushboolean(L, 0);
        lua_pushvalue(L, -2);
        return pay(L, 2);
    }
    return pay(L, lua_gettop(L) - (int)extra);
}

static int pcall_k(lua_State *L)
{
    int extra = 0, status = lua_getctx(L, &extra);

    return pcall_end(L, status, extra);
}

static int api_pcall(lua_State *L)
{
    int status;

    luaL_checkany(L, 1);
    lua_pushboolean(L, 1);
    lua_insert(L, 1);
    status = lua_pcallk(L, lua_gettop(L) - 2, LUA_MULTRET, 0, 0, pcall_k);
    return pcall_end(L, status, 0);
}

/* Times xpcall calls a handler that fails, each time on the handler's
 * own error, as Lua calls it again for an error inside it. */
#define XPCALL_TRIES 10

/* xpcall without Lua's message handler: Lua calls one where the error is
 * raised, and for an error the count hook raises (the stuck error), with
 * the hooks still off, so a handler that loops would hold the daemon for
 * good. Here the function runs as in pcall and the handler is called
 * after it failed, a protected call like any other, preemptible; a
 * script sees the same results (without the debug library, a handler
 * cannot see where the error was raised). phase 0: the function ran; n:
 * the handler's n-th call ran. Stack: f, handler, then what the call
 * left. */
static int xpcall_k(lua_State *L);

static int xpcall_end(lua_State *L, int status, int phase)
{
    if (status == LUA_OK || status == LUA_YIELD) {
        if (phase == 0)
            return pay(L, lua_gettop(L) - 2);
        lua_pushboolean(L, 0);
        lua_insert(L, -2);
        return pay(L, 2);
    }
    pass_on(L);
    /* Lua calls no handler for a memory error. */
    if (status == LUA_ERRMEM || phase >= XPCALL_TRIES) {
        lua_pushboolean(L, 0);
        if (phase >= XPCALL_TRIES)
            lua_pushliteral(L, "error in error handling");
        else
            lua_pushvalue(L, -2);
        return pay(L, 2);
    }
    lua_replace(L, 3);
    lua_settop(L, 3);
    lua_pushvalue(L, 2);
    lua_pushvalue(L, 3);
    status = lua_pcallk(L, 1, 1, 0, phase + 1, xpcall_k);
    return xpcall_end(L, status, phase + 1);
}

static int xpcall_k(lua_State *L)
{
    int phase = 0, status = lua_getctx(L, &phase);

    return xpcall_end(L, status, phase);
}

static int api_xpcall(lua_State *L)
{
    int status, n = lua_gettop(L);

    luaL_checktype(L, 2, LUA_TFUNCTION);
    lua_pushboolean(L, 1);
    lua_pushvalue(L, 1);
    lua_insert(L, 3);
    lua_insert(L, 3);
    status = lua_pcallk(L, n - 2, LUA_MULTRET, 0, 0, xpcall_k);
    return xpcall_end(L, status, 0);
}

/* Replace t[name] (t at the top) by fn with the old value as upvalue. */
static void wrap_field(lua_State *L, const char *name, lua_CFunction fn)
{
    lua_getfield(L, -1, name);
    lua_pushcclosure(L, fn, 1);
    lua_setfield(L, -2, name);
}

void wsg_script_open_coro(lua_State *L)
{
    lua_getglobal(L, LUA_COLIBNAME);
    lua_pushcfunction(L, co_resume);
    lua_setfield(L, -2, "resume");
    lua_pushcfunction(L, co_wrap);
    lua_setfield(L, -2, "wrap");
    lua_pop(L, 1);
    lua_pushglobaltable(L);
    lua_pushcfunction(L, api_pcall);
    lua_setfield(L, -2, "pcall");
    lua_pushcfunction(L, api_xpcall);
    lua_setfield(L, -2, "xpcall");
    wrap_field(L, "load", api_load);
    lua_pop(L, 1);
}
