/*
 * Harness 7: a script's pattern functions (src/script/strlib.c over the
 * machine of match.c) against Lua's own (Debian's liblua, the reference):
 * string.find, match, gmatch and gsub of a subject, a pattern and a
 * replacement built from the input, called both ways from the same Lua
 * driver, must give the same values or raise the same error, message for
 * message. The project's call runs with a slice of a few steps, either in
 * a coroutine (so it yields across itself at every slice and is resumed
 * until it returns: what a preempted script sees) or where it cannot
 * yield (so it goes on with a fresh slice each time).
 *
 * The input: byte 0 the call (bits 0-1: find, match, gmatch, gsub; bit
 * 2: find plain; bits 3-4: gsub's replacement: the string, a table, a
 * function joining its arguments, a function keeping the match; bit 5:
 * an init (gsub: a count) is given; bit 6: where it cannot yield; bit 7:
 * the pattern's bytes pick tokens from a list, else they are the pattern),
 * byte 1 the slice's steps less one, byte 2 the init or count (signed),
 * then the subject, the pattern and the replacement, each a length (two
 * bytes, little-endian, at most FM_LEN) and that many bytes. The project's
 * call runs first, for at most FM_STEPS steps: past them Lua's own (the same
 * algorithm, unbounded) might run for hours, and the input is dropped. Set
 * FUZZ_TRACE in the environment to print each outcome.
 */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <lauxlib.h>
#include <lua.h>
#include <lualib.h>

#include "fuzz_check.h"
#include "strlib.h"

#ifndef FUZZ_ENTRY
#define FUZZ_ENTRY LLVMFuzzerTestOneInput
#endif

/* Steps the project's call may take before the input is dropped. */
#define FM_STEPS 200000u
/* The longest subject, pattern and replacement. */
#define FM_LEN 1024

/* The budget of the project's call (strlib.h): slices of slice steps;
 * past FM_STEPS in all, an error that drops the input. */
static struct {
    uint32_t slice, used, slices;
    int capped;
    int yieldable; /* the call runs in the coroutine, not under lua_pcall */
} M;

static uint32_t fm_left(void *ctx, lua_State *L)
{
    (void)ctx;
    (void)L;
    return M.slice;
}

static void fm_spend(void *ctx, lua_State *L, uint32_t steps)
{
    (void)ctx;
    (void)L;
    M.used += steps;
}

static int fm_over(void *ctx, lua_State *L)
{
    (void)ctx;
    M.slices++;
    if (M.used > FM_STEPS) {
        M.capped = 1;
        return luaL_error(L, "fuzz_match: step cap");
    }
    (void)L;
    return M.yieldable;
}

static const struct wsg_budget fm_budget = {fm_left, fm_spend, fm_over, NULL};

/* Pattern tokens for bit 7: classes, sets, quantifiers, captures, the
 * escapes, and the malformed pieces. */
static const char *const fm_tokens[] = {
    "a",    "b",    "c",     "(",      ")",    "()",    ".",     "*",
    "+",    "-",    "?",     "^",      "$",    "%a",    "%d",    "%s",
    "%w",   "%A",   "%p",    "[ab]",   "[^a]", "[a-c]", "[%a_]", "[]]",
    "%b()", "%bab", "%f[a]", "%f[%w]", "%1",   "%2",    "%0",    "%",
    "[",    "]",    "%]",    "x",      " ",    "(a*)",  "%z",    "[%]]"};
#define FM_NTOKENS (sizeof fm_tokens / sizeof fm_tokens[0])

/* The driver: the call's values, or the iterator's, as one string, so
 * that the two runs compare as strings (the error message too). */
static const char fm_driver[] =
    "local fn, kind, s, p, a, b = ...\n"
    "local function ser(...)\n"
    "  local n, out = select('#', ...), {}\n"
    "  for i = 1, n do\n"
    "    local v = select(i, ...)\n"
    "    local t = type(v)\n"
    "    if t == 'string' then out[i] = string.format('%q', v)\n"
    "    elseif t == 'number' then out[i] = 'n' .. tostring(v)\n"
    "    else out[i] = tostring(v) end\n"
    "  end\n"
    "  return n .. '[' .. table.concat(out, ',') .. ']'\n"
    "end\n"
    "if kind == 2 then\n"
    "  local it, parts = fn(s, p, a), {}\n"
    "  for i = 1, 40 do\n"
    "    local r = table.pack(it())\n"
    "    parts[i] = ser(table.unpack(r, 1, r.n))\n"
    "    if r[1] == nil then break end\n"
    "  end\n"
    "  return table.concat(parts, ';')\n"
    "end\n"
    "return ser(fn(s, p, a, b))\n";

struct fm_rd {
    const uint8_t *p;
    size_t n;
};

static unsigned fm_byte(struct fm_rd *r)
{
    if (r->n == 0)
        return 0;
    r->n--;
    return *r->p++;
}

/* A length (two bytes, little-endian, at most FM_LEN) and that many
 * bytes (fewer at the input's end). */
static void fm_bytes(struct fm_rd *r, const uint8_t **p, size_t *n)
{
    *n = fm_byte(r);
    *n |= (size_t)fm_byte(r) << 8;
    if (*n > FM_LEN)
        *n = FM_LEN;
    if (*n > r->n)
        *n = r->n;
    *p = r->p;
    r->p += *n;
    r->n -= *n;
}

/* The replacement of kind k on the stack: the string, a table, a function
 * joining its arguments, a function that keeps the match (nil) or names
 * what it was given. */
static void fm_push_repl(lua_State *L, unsigned k, const uint8_t *r, size_t n)
{
    static const char *const fns[] = {
        "return function(...)\n"
        "  local t = {...}\n"
        "  for i = 1, select('#', ...) do t[i] = tostring(t[i]) end\n"
        "  return select('#', ...) .. ':' .. table.concat(t, ',')\n"
        "end\n",
        "return function(c)\n"
        "  if c == 'b' then return false end\n"
        "  if c == 'c' then return {} end\n"
        "  if c == 'x' then return 7 end\n"
        "  return nil\n"
        "end\n"};

    switch (k) {
    case 0:
        lua_pushlstring(L, (const char *)r, n);
        break;
    case 1:
        lua_createtable(L, 2, 4);
        lua_pushliteral(L, "A");
        lua_setfield(L, -2, "a");
        lua_pushboolean(L, 0);
        lua_setfield(L, -2, "b");
        lua_pushinteger(L, 42);
        lua_setfield(L, -2, "ab");
        lua_newtable(L);
        lua_setfield(L, -2, "c");
        lua_pushliteral(L, "one");
        lua_rawseti(L, -2, 1);
        break;
    default:
        FUZZ_CHECK(luaL_loadstring(L, fns[k - 2]) == LUA_OK);
        lua_call(L, 0, 1);
        break;
    }
}

/* Push the driver and its arguments for fn (the function at index fi);
 * returns the number of arguments. */
static int fm_push_call(lua_State *L, int fi, unsigned op, const char *s,
                        size_t ls, const char *p, size_t lp, const uint8_t *r,
                        size_t lr, int arg)
{
    unsigned kind = op & 3u;

    FUZZ_CHECK(luaL_loadbuffer(L, fm_driver, sizeof fm_driver - 1,
                               "=driver") == LUA_OK);
    lua_pushvalue(L, fi);
    lua_pushinteger(L, kind);
    lua_pushlstring(L, s, ls);
    lua_pushlstring(L, p, lp);
    if (kind == 3) {
        fm_push_repl(L, (op >> 3) & 3u, r, lr);
        if (op & 0x20u)
            lua_pushinteger(L, arg);
        else
            lua_pushnil(L);
    } else {
        if (op & 0x20u)
            lua_pushinteger(L, arg);
        else
            lua_pushnil(L);
        lua_pushboolean(L, kind == 0 && (op & 4u));
    }
    return 6;
}

/* What a run left on the top of L (or co): "ok " and the driver's string,
 * or "error " and the message. */
static void fm_outcome(lua_State *L, int status, char *out, size_t cap)
{
    const char *m = lua_tostring(L, -1);

    snprintf(out, cap, "%s %s", status == LUA_OK ? "ok" : "error",
             m ? m : "(not a string)");
}

static void fm_run(struct fm_rd *rd)
{
    static char got[65536], want[65536];
    unsigned op = fm_byte(rd), ntok, i;
    int arg, st, base;
    const uint8_t *sb, *pb, *rb;
    size_t ls, lp, lr;
    char pat[FM_LEN];
    lua_State *L, *co;

    M.slice = 1 + fm_byte(rd);
    arg = (int)(int8_t)fm_byte(rd);
    fm_bytes(rd, &sb, &ls);
    fm_bytes(rd, &pb, &lp);
    fm_bytes(rd, &rb, &lr);
    if (op & 0x80u) {
        /* Tokens: at most 32, so the pattern stays short. */
        ntok = lp > 32 ? 32 : (unsigned)lp;
        lp = 0;
        for (i = 0; i < ntok; i++) {
            const char *t = fm_tokens[pb[i] % FM_NTOKENS];
            size_t n = strlen(t);

            memcpy(pat + lp, t, n);
            lp += n;
        }
    } else {
        if (lp > sizeof pat)
            lp = sizeof pat;
        memcpy(pat, pb, lp);
    }

    L = luaL_newstate();
    FUZZ_CHECK(L != NULL);
    luaL_openlibs(L);
    /* Lua's four at 1..4, the project's at 5..8. */
    lua_getglobal(L, "string");
    lua_getfield(L, -1, "find");
    lua_getfield(L, -2, "match");
    lua_getfield(L, -3, "gmatch");
    lua_getfield(L, -4, "gsub");
    lua_createtable(L, 0, 4);
    wsg_strlib_open(L, &fm_budget);
    lua_getfield(L, -1, "find");
    lua_getfield(L, -2, "match");
    lua_getfield(L, -3, "gmatch");
    lua_getfield(L, -4, "gsub");
    lua_remove(L, -5);
    lua_remove(L, 1);
    FUZZ_CHECK(lua_gettop(L) == 8);

    /* The project's: in a coroutine, resumed at each yield, or where it
     * cannot yield. */
    M.used = M.slices = 0;
    M.capped = 0;
    M.yieldable = !(op & 0x40u);
    base = lua_gettop(L);
    if (op & 0x40u) {
        fm_push_call(L, 5 + (int)(op & 3u), op, (const char *)sb, ls, pat, lp,
                     rb, lr, arg);
        st = lua_pcall(L, 6, 1, 0);
        fm_outcome(L, st, got, sizeof got);
        lua_settop(L, base);
    } else {
        unsigned yields = 0;

        co = lua_newthread(L);
        lua_pushvalue(L, 5 + (int)(op & 3u));
        lua_xmove(L, co, 1);
        fm_push_call(co, 1, op, (const char *)sb, ls, pat, lp, rb, lr, arg);
        lua_remove(co, 1);
        st = lua_resume(co, L, 6);
        while (st == LUA_YIELD) {
            /* Only the pattern functions yield here: with nothing. */
            FUZZ_CHECK(lua_gettop(co) == 0);
            yields++;
            st = lua_resume(co, L, 0);
        }
        /* As many yields as slices ended, each one where it could. */
        if (!M.capped)
            FUZZ_CHECK(yields == M.slices);
        fm_outcome(co, st, got, sizeof got);
        lua_settop(L, base);
    }

    if (!M.capped) {
        fm_push_call(L, 1 + (int)(op & 3u), op, (const char *)sb, ls, pat, lp,
                     rb, lr, arg);
        st = lua_pcall(L, 6, 1, 0);
        fm_outcome(L, st, want, sizeof want);
        if (getenv("FUZZ_TRACE"))
            fprintf(stderr, "fuzz_match: %s (%u slices)\n", got,
                    (unsigned)M.slices);
        if (strcmp(got, want) != 0)
            fprintf(stderr,
                    "fuzz_match: the project's and Lua's differ\n"
                    "  project: %s\n  lua:     %s\n",
                    got, want);
        FUZZ_CHECK(strcmp(got, want) == 0);
    }
    lua_close(L);
}

int FUZZ_ENTRY(const uint8_t *data, size_t size);

int FUZZ_ENTRY(const uint8_t *data, size_t size)
{
    struct fm_rd r = {data, size};

    if (size < 1)
        return 0;
    fm_run(&r);
    return 0;
}
