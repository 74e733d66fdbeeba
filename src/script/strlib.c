/*
 * string.find, match, gmatch and gsub as Lua 5.2 has them (the same
 * arguments, results and errors), over the pattern machine (match.c)
 * instead of Lua's recursive matcher, which a script could keep inside
 * one C call for hours: a %b() over 200 kB, a long set at every position,
 * a backtracking '-'. Each call runs for what is left of the script's
 * slice and then yields across itself (strlib.h), so the daemon serves
 * its other work between the slices of a long match, as it does between
 * those of a long loop.
 *
 * A call's state lives in a userdata on its stack (at STATE, with gsub's
 * output at OUT) while it is suspended: the subject and the pattern are
 * its arguments, which stay on the stack, so the machine's pointers into
 * them stay good. find and match start in a C local and move into the
 * userdata only when they first yield; most calls never do. A plain find
 * compares at most 64 bytes a step, so a long needle yields too.
 */
#include "strlib.h"

#include <ctype.h>
#include <stdint.h>
#include <string.h>

#include <lauxlib.h>

#include "match.h"

/* Where a suspended call keeps its state, and gsub its output. */
#define STATE 5
#define OUT   6
/* gsub's output buffer at first. */
#define OUT_FIRST 256
#define SPECIALS  "^$*+?.([%-"

static const struct wsg_budget *budget_at(lua_State *L, int up)
{
    return lua_touserdata(L, lua_upvalueindex(up));
}

/* Run m for what is left of the slice: YES, NO or MORE; an error of the
 * pattern is raised. */
static int run(lua_State *L, const struct wsg_budget *b, struct wsg_match *m)
{
    uint32_t left = b->left(b->ctx, L), steps = left;
    int r = wsg_match_run(m, &steps);

    b->spend(b->ctx, L, left - steps);
    if (r == WSG_MATCH_ERROR)
        return luaL_error(L, "%s", m->error);
    return r;
}

/* As Lua's posrelatI: a start position, negative from the end, clipped
 * to [1, inf). */
static size_t start_of(lua_Integer pos, size_t len)
{
    if (pos > 0)
        return (size_t)pos;
    if (pos == 0)
        return 1;
    if (pos < -(lua_Integer)len)
        return 1;
    return len + (size_t)pos + 1;
}

/* Capture i of a match from s to e: the whole match when there are no
 * captures and i is 0. */
static void push_one(lua_State *L, const struct wsg_match *m, int i,
                     const char *s, const char *e)
{
    if (i >= m->level) {
        if (i != 0)
            luaL_error(L, "invalid capture index");
        lua_pushlstring(L, s, (size_t)(e - s));
        return;
    }
    if (m->cap[i].len == WSG_MATCH_UNFINISHED)
        luaL_error(L, "unfinished capture");
    if (m->cap[i].len == WSG_MATCH_POSITION)
        lua_pushinteger(L, (m->cap[i].init - m->src) + 1);
    else
        lua_pushlstring(L, m->cap[i].init, (size_t)m->cap[i].len);
}

/* Every capture (or the whole match, s NULL: none), as values. */
static int push_all(lua_State *L, const struct wsg_match *m, const char *s,
                    const char *e)
{
    int i, n = m->level == 0 && s ? 1 : m->level;

    luaL_checkstack(L, n, "too many captures");
    for (i = 0; i < n; i++)
        push_one(L, m, i, s, e);
    return n;
}

/* ---- find and match ---- */

struct find {
    struct wsg_match m;
    const char *s1; /* where the match being tried starts */
    int anchor, find, plain;
    size_t at, done; /* plain: the candidate, and its bytes compared */
};

static int find_k(lua_State *L);

/* The slice is over: go on (0), or yield, the state moved into a
 * userdata first when it is still the C local (the yield leaves this C
 * frame for good). The userdata is made before the budget is asked, so
 * that a failed allocation cannot leave a yield promised and not made. */
static int find_over(lua_State *L, const struct wsg_budget *b, struct find *f,
                     int in_state)
{
    if (!in_state) {
        void *ud = lua_newuserdata(L, sizeof *f);

        memcpy(ud, f, sizeof *f);
    }
    if (!b->over(b->ctx, L)) {
        if (!in_state)
            lua_pop(L, 1);
        return 0;
    }
    return lua_yieldk(L, 0, 0, find_k);
}

/* The plain search: the first byte by memchr, then the rest, 64 bytes a
 * step (Lua's lmemfind compares a needle of any length at once). */
static int plain_run(struct find *f, const char *s, size_t ls, const char *p,
                     size_t lp, uint32_t *steps)
{
    size_t last = ls - lp, n;
    const char *q;

    while (f->at <= last) {
        if (*steps == 0)
            return WSG_MATCH_MORE;
        if (f->done == 0) {
            n = last - f->at + 1;
            if (n / WSG_MATCH_BYTES_PER_STEP >= *steps)
                n = (size_t)*steps * WSG_MATCH_BYTES_PER_STEP;
            *steps -= (uint32_t)((n + WSG_MATCH_BYTES_PER_STEP - 1) /
                                 WSG_MATCH_BYTES_PER_STEP);
            q = memchr(s + f->at, p[0], n);
            if (!q) {
                f->at += n;
                continue;
            }
            f->at = (size_t)(q - s);
            f->done = 1;
        } else {
            (*steps)--;
            n = lp - f->done;
            if (n > WSG_MATCH_BYTES_PER_STEP)
                n = WSG_MATCH_BYTES_PER_STEP;
            if (memcmp(s + f->at + f->done, p + f->done, n) != 0) {
                f->at++;
                f->done = 0;
                continue;
            }
            f->done += n;
        }
        if (f->done == lp)
            return WSG_MATCH_YES;
    }
    return WSG_MATCH_NO;
}

static int find_plain(lua_State *L, const struct wsg_budget *b, struct find *f,
                      int in_state)
{
    size_t ls, lp;
    const char *s = lua_tolstring(L, 1, &ls), *p = lua_tolstring(L, 2, &lp);
    uint32_t left, steps;
    int r;

    for (;;) {
        left = steps = b->left(b->ctx, L);
        r = plain_run(f, s, ls, p, lp, &steps);
        b->spend(b->ctx, L, left - steps);
        if (r == WSG_MATCH_YES) {
            lua_pushinteger(L, (lua_Integer)f->at + 1);
            lua_pushinteger(L, (lua_Integer)(f->at + lp));
            return 2;
        }
        if (r == WSG_MATCH_NO) {
            lua_pushnil(L);
            return 1;
        }
        find_over(L, b, f, in_state);
    }
}

static int find_go(lua_State *L, const struct wsg_budget *b, struct find *f,
                   int in_state)
{
    for (;;) {
        int r = run(L, b, &f->m);

        if (r == WSG_MATCH_YES) {
            if (!f->find)
                return push_all(L, &f->m, f->s1, f->m.end);
            lua_pushinteger(L, (f->s1 - f->m.src) + 1);
            lua_pushinteger(L, f->m.end - f->m.src);
            return push_all(L, &f->m, NULL, NULL) + 2;
        }
        if (r == WSG_MATCH_NO) {
            if (f->s1 >= f->m.src_end || f->anchor) {
                lua_pushnil(L);
                return 1;
            }
            wsg_match_at(&f->m, ++f->s1);
            continue;
        }
        find_over(L, b, f, in_state);
    }
}

static int find_k(lua_State *L)
{
    struct find *f = lua_touserdata(L, STATE);
    const struct wsg_budget *b = budget_at(L, 1);

    if (f->plain)
        return find_plain(L, b, f, 1);
    return find_go(L, b, f, 1);
}

/* No special character in p (NULs included): a find of it is plain. */
static int no_specials(lua_State *L, const struct wsg_budget *b, const char *p,
                       size_t lp)
{
    size_t upto = 0;

    b->spend(b->ctx, L, (uint32_t)(lp / WSG_MATCH_BYTES_PER_STEP));
    do {
        if (strpbrk(p + upto, SPECIALS))
            return 0;
        upto += strlen(p + upto) + 1;
    } while (upto <= lp);
    return 1;
}

static int find_aux(lua_State *L, int find)
{
    const struct wsg_budget *b = budget_at(L, 1);
    size_t ls, lp, init;
    const char *s = luaL_checklstring(L, 1, &ls);
    const char *p = luaL_checklstring(L, 2, &lp);
    struct find f;

    init = start_of(luaL_optinteger(L, 3, 1), ls) - 1;
    if (init > ls) {
        lua_pushnil(L);
        return 1;
    }
    f.find = find;
    f.plain = find && (lua_toboolean(L, 4) || no_specials(L, b, p, lp));
    lua_settop(L, 4);
    if (f.plain) {
        if (lp == 0) {
            lua_pushinteger(L, (lua_Integer)init + 1);
            lua_pushinteger(L, (lua_Integer)init);
            return 2;
        }
        if (lp > ls - init) {
            lua_pushnil(L);
            return 1;
        }
        f.at = init;
        f.done = 0;
        return find_plain(L, b, &f, 0);
    }
    f.anchor = *p == '^';
    if (f.anchor) {
        p++;
        lp--;
    }
    wsg_match_init(&f.m, s, ls, p, lp);
    f.s1 = s + init;
    wsg_match_at(&f.m, f.s1);
    return find_go(L, b, &f, 0);
}

static int str_find(lua_State *L)
{
    return find_aux(L, 1);
}

static int str_match(lua_State *L)
{
    return find_aux(L, 0);
}

/* ---- gmatch ---- */

struct gmatch {
    struct wsg_match m;
    const char *src; /* where the next search starts */
    const char *pos; /* where the match being tried starts */
};

static int gmatch_k(lua_State *L);

/* The iterator's upvalues: the subject, the pattern (kept alive), the
 * state and the budget. */
static int gmatch_go(lua_State *L)
{
    struct gmatch *g = lua_touserdata(L, lua_upvalueindex(3));
    const struct wsg_budget *b = budget_at(L, 4);

    for (;;) {
        int r = run(L, b, &g->m);

        if (r == WSG_MATCH_MORE) {
            if (b->over(b->ctx, L))
                return lua_yieldk(L, 0, 0, gmatch_k);
            continue;
        }
        /* The next call starts where this match ended, one on from
         * an empty match (Lua 5.2's gmatch: an empty match right after
         * a match counts). */
        if (r == WSG_MATCH_YES) {
            g->src = g->m.end == g->pos ? g->m.end + 1 : g->m.end;
            return push_all(L, &g->m, g->pos, g->m.end);
        }
        if (g->pos >= g->m.src_end)
            return 0;
        wsg_match_at(&g->m, ++g->pos);
    }
}

static int gmatch_k(lua_State *L)
{
    return gmatch_go(L);
}

/* A call starts at src: one that ended in an error left the state
 * wherever it was. */
static int gmatch_aux(lua_State *L)
{
    struct gmatch *g = lua_touserdata(L, lua_upvalueindex(3));

    if (g->src > g->m.src_end)
        return 0;
    g->pos = g->src;
    wsg_match_at(&g->m, g->pos);
    return gmatch_go(L);
}

/* Lua 5.2's gmatch has no start position: a third argument is ignored. */
static int str_gmatch(lua_State *L)
{
    size_t ls, lp;
    const char *s = luaL_checklstring(L, 1, &ls);
    const char *p = luaL_checklstring(L, 2, &lp);
    struct gmatch *g;

    lua_settop(L, 2);
    g = lua_newuserdata(L, sizeof *g);
    wsg_match_init(&g->m, s, ls, p, lp);
    g->src = s;
    g->pos = g->src;
    lua_pushvalue(L, lua_upvalueindex(1));
    lua_pushcclosure(L, gmatch_aux, 4);
    return 1;
}

/* ---- gsub ---- */

struct gsub {
    struct wsg_match m;
    const char *src;    /* where the next match is tried */
    const char *e;      /* a replacement called: its match's end */
    lua_Integer n, max; /* replacements made, and allowed */
    int anchor, changed, tr;
    int trying;      /* a match started at src is in progress */
    int calling;     /* the replacement function was called: its value is
                        at the top */
    size_t len, cap; /* the output, in the userdata at OUT */
};

static int gsub_k(lua_State *L);

static void out_add(lua_State *L, struct gsub *g, const char *s, size_t n)
{
    const struct wsg_budget *b = budget_at(L, 1);
    char *buf;

    if (n > g->cap - g->len) {
        size_t cap = g->cap * 2;

        if (cap < g->len + n)
            cap = g->len + n;
        if (cap < g->len)
            luaL_error(L, "resulting string too large");
        buf = lua_newuserdata(L, cap);
        memcpy(buf, lua_touserdata(L, OUT), g->len);
        lua_replace(L, OUT);
        g->cap = cap;
    }
    buf = lua_touserdata(L, OUT);
    memcpy(buf + g->len, s, n);
    g->len += n;
    b->spend(b->ctx, L, (uint32_t)(1 + n / WSG_MATCH_BYTES_PER_STEP));
}

/* The value at the top (a string or number) to the output; popped. */
static void out_value(lua_State *L, struct gsub *g)
{
    size_t n;
    const char *s = lua_tolstring(L, -1, &n);

    out_add(L, g, s, n);
    lua_pop(L, 1);
}

/* A replacement string, its %0..%9 and %% read as Lua reads them. */
static void add_string(lua_State *L, struct gsub *g, const char *s,
                       const char *e)
{
    size_t l;
    const char *news = lua_tolstring(L, 3, &l), *p;

    while ((p = memchr(news, '%', l)) != NULL) {
        out_add(L, g, news, (size_t)(p - news));
        p++;
        if (*p == '%') {
            out_add(L, g, p, 1);
        } else if (*p == '0') {
            out_add(L, g, s, (size_t)(e - s));
        } else if (isdigit((unsigned char)*p)) {
            push_one(L, &g->m, *p - '1', s, e);
            out_value(L, g);
        } else {
            luaL_error(L, "invalid use of '%c' in replacement string", '%');
        }
        l -= (size_t)(p + 1 - news);
        news = p + 1;
    }
    out_add(L, g, news, l);
}

/* A table's or a function's value for the match s..e, at the top: nil or
 * false keeps the match as it was. */
static void add_result(lua_State *L, struct gsub *g, const char *s,
                       const char *e)
{
    if (!lua_toboolean(L, -1)) {
        lua_pop(L, 1);
        out_add(L, g, s, (size_t)(e - s));
        return;
    }
    if (!lua_isstring(L, -1))
        luaL_error(L, "invalid replacement value (a %s)",
                   luaL_typename(L, -1));
    out_value(L, g);
    g->changed = 1;
}

static int gsub_done(lua_State *L, struct gsub *g)
{
    if (!g->changed) {
        lua_pushvalue(L, 1);
    } else {
        out_add(L, g, g->src, (size_t)(g->m.src_end - g->src));
        lua_pushlstring(L, lua_touserdata(L, OUT), g->len);
    }
    lua_pushinteger(L, g->n);
    return 2;
}

/* What follows a match ending at e (NULL: none) tried at src, as in Lua
 * 5.2: past a match that is not empty, else one character copied as it
 * is (so an empty match right after a match counts). 1: done. */
static int gsub_next(lua_State *L, struct gsub *g, const char *e)
{
    g->trying = 0;
    if (e && e > g->src)
        g->src = e;
    else if (g->src < g->m.src_end)
        out_add(L, g, g->src++, 1);
    else
        return 1;
    return g->anchor;
}

static int gsub_go(lua_State *L)
{
    struct gsub *g = lua_touserdata(L, STATE);
    const struct wsg_budget *b = budget_at(L, 1);
    const char *e;
    int r, nargs;

    for (;;) {
        if (g->calling) {
            g->calling = 0;
            add_result(L, g, g->src, g->e);
            if (gsub_next(L, g, g->e))
                break;
        }
        if (!g->trying) {
            if (g->n >= g->max)
                break;
            wsg_match_at(&g->m, g->src);
            g->trying = 1;
        }
        r = run(L, b, &g->m);
        if (r == WSG_MATCH_MORE) {
            if (b->over(b->ctx, L))
                return lua_yieldk(L, 0, 0, gsub_k);
            continue;
        }
        e = r == WSG_MATCH_YES ? g->m.end : NULL;
        if (e) {
            g->n++;
            switch (g->tr) {
            case LUA_TFUNCTION:
                lua_pushvalue(L, 3);
                nargs = push_all(L, &g->m, g->src, e);
                g->e = e;
                g->calling = 1;
                /* The function may yield (be preempted, or yield of its
                 * own): gsub_k takes its value then. */
                lua_callk(L, nargs, 1, 0, gsub_k);
                continue;
            case LUA_TTABLE:
                push_one(L, &g->m, 0, g->src, e);
                lua_gettable(L, 3);
                add_result(L, g, g->src, e);
                break;
            default:
                add_string(L, g, g->src, e);
                g->changed = 1;
                break;
            }
        }
        if (gsub_next(L, g, e))
            break;
    }
    return gsub_done(L, g);
}

static int gsub_k(lua_State *L)
{
    return gsub_go(L);
}

static int str_gsub(lua_State *L)
{
    size_t srcl, lp;
    const char *src = luaL_checklstring(L, 1, &srcl);
    const char *p = luaL_checklstring(L, 2, &lp);
    int tr = lua_type(L, 3);
    lua_Integer max = luaL_optinteger(L, 4, (lua_Integer)srcl + 1);
    struct gsub *g;

    luaL_argcheck(L,
                  tr == LUA_TNUMBER || tr == LUA_TSTRING ||
                      tr == LUA_TFUNCTION || tr == LUA_TTABLE,
                  3, "string/function/table expected");
    lua_settop(L, 4);
    g = lua_newuserdata(L, sizeof *g);
    g->anchor = *p == '^';
    if (g->anchor) {
        p++;
        lp--;
    }
    wsg_match_init(&g->m, src, srcl, p, lp);
    g->src = src;
    g->n = 0;
    /* Lua 5.2 takes the count as a size_t: a negative one is no limit. */
    g->max = max < 0 ? PTRDIFF_MAX : max;
    g->changed = 0;
    g->tr = tr;
    g->trying = 0;
    g->calling = 0;
    g->len = 0;
    g->cap = OUT_FIRST;
    lua_newuserdata(L, OUT_FIRST);
    return gsub_go(L);
}

void wsg_strlib_open(lua_State *L, const struct wsg_budget *b)
{
    static const luaL_Reg fns[] = {{"find", str_find},
                                   {"match", str_match},
                                   {"gmatch", str_gmatch},
                                   {"gsub", str_gsub},
                                   {NULL, NULL}};

    lua_pushlightuserdata(L, (void *)b);
    luaL_setfuncs(L, fns, 1);
}
