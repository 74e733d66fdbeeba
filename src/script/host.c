/*
 * The script host: one Lua state per script run, made fresh at each start
 * and closed when the script ends, so nothing of one run leaks into the
 * next. The script's body runs as a coroutine; the host resumes it when
 * what it waits for has come (a packet, its time, the processor) and
 * tells the owner, through wsg_script_next and the wake callback, what
 * that is. The memory cap is the allocator's. Preemption ends a slice of
 * steps, spent by the count hook (instructions), the allocator (bytes)
 * and library functions (their work): where the running code can yield
 * to the host (the body, or a coroutine the body resumed, through
 * coro.c), it yields; elsewhere it runs on within an allowance of stuck
 * slices that is the script's, not the stretch's. A module is opened
 * below the script's directory one component at a time, following no
 * link.
 */
#define _GNU_SOURCE /* realpath, O_NOFOLLOW, O_DIRECTORY, openat */

#include "script_impl.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <lauxlib.h>

/* The count hook runs every this many instructions. */
#define WSG_SCRIPT_HOOK_COUNT 1000
/* Bytes an allocation may take for a step: copying a string, filling a
 * table, which a single instruction (a concatenation) can do by the
 * megabyte. */
#define WSG_SCRIPT_BYTES_PER_STEP 16
/* Memory the host may use past the cap to report a failure. */
#define WSG_SCRIPT_HEADROOM (256u << 10)
/* The smallest cap: the libraries alone take some 100 KiB, and they are
 * opened where a failed allocation could not be caught. */
#define WSG_SCRIPT_MEMORY_MIN (1u << 20)

static void script_hook(lua_State *L, lua_Debug *ar);

int wsg_script_whole(lua_State *L, int idx, lua_Integer *out)
{
    lua_Number d;

    if (!lua_isnumber(L, idx))
        return 0;
    d = lua_tonumber(L, idx);
    if (!(d >= (lua_Number)PTRDIFF_MIN && d < -(lua_Number)PTRDIFF_MIN) ||
        d != floor(d))
        return 0;
    *out = (lua_Integer)d;
    return 1;
}

uint64_t wsg_script_now(const struct wsg_script *h)
{
    return wsg_axis_time(wsg_device_axis_const(h->dev));
}

/* Lua 5.2 has no lua_isyieldable (5.3 added it, to read the same field):
 * a thread can yield when no call on its stack was made without a
 * continuation, which Lua 5.2 counts in its lua_State (nny) and shows
 * through no function. The members up to it are mirrored here from Lua
 * 5.2's lstate.h, and the mirror is checked against Lua itself before a
 * script first runs (mirror_check): where it does not hold, no script is
 * ever preempted, and one that runs long fails with the stuck error
 * instead of holding the daemon. */
struct lua52_state {
    void *next;
    unsigned char tt, marked, status;
    void *top, *l_G, *ci;
    const void *oldpc;
    void *stack_last, *stack;
    int stacksize;
    unsigned short nny, nCcalls;
    unsigned char hookmask, allowhook;
    int basehookcount, hookcount;
};

static int lua52_yieldable(lua_State *L)
{
    return ((const struct lua52_state *)(const void *)L)->nny == 0;
}

/* -1: not checked yet; 0: the mirror does not hold; 1: it does. */
static int mirror_ok = -1;

static void mirror_hook(lua_State *L, lua_Debug *ar)
{
    (void)L;
    (void)ar;
}

/* Records, in the integer at upvalue 1's address, L's nny. */
static int mirror_probe(lua_State *L)
{
    unsigned *seen = lua_touserdata(L, lua_upvalueindex(1));

    *seen = ((const struct lua52_state *)(const void *)L)->nny;
    return 0;
}

/* What Lua 5.2 says of the fields the mirror reads: a fresh thread's
 * count hook is in basehookcount, nny is 0 while the thread runs
 * resumed, and 2 in a function the main thread calls from C (1 for the
 * main thread, 1 for the call). */
static int mirror_check(lua_State *L)
{
    const struct lua52_state *m;
    unsigned in_co = 99, in_call = 99;
    lua_State *co;
    int ok;

    if (!lua_checkstack(L, 4))
        return 0;
    co = lua_newthread(L);
    m = (const struct lua52_state *)(const void *)co;
    lua_sethook(co, mirror_hook, LUA_MASKCOUNT, 4321);
    ok = m->basehookcount == 4321 && m->hookmask == LUA_MASKCOUNT &&
         m->nny == 1;
    lua_sethook(co, NULL, 0, 0);
    lua_pushlightuserdata(L, &in_co);
    lua_pushcclosure(L, mirror_probe, 1);
    lua_xmove(L, co, 1);
    ok = ok && lua_resume(co, L, 0) == LUA_OK;
    lua_pushlightuserdata(L, &in_call);
    lua_pushcclosure(L, mirror_probe, 1);
    ok = ok && lua_pcall(L, 0, 0, 0) == LUA_OK;
    lua_pop(L, 1); /* the thread */
    return ok && in_co == 0 && in_call == 2;
}

int wsg_script_preemptible(struct wsg_script *h, lua_State *L)
{
    if (mirror_ok != 1 || !lua52_yieldable(L))
        return 0;
    if (h->nest == 0)
        return L == h->co;
    if (h->nest > WSG_SCRIPT_NEST_CO)
        return 0;
    return L == h->nested[h->nest - 1].co && h->nested[h->nest - 1].reach;
}

/* The slice is used up: the count hook comes at L's next instruction, not
 * up to a thousand instructions on (each of which could be another call
 * that works for a slice). The hook puts the count back. */
static void script_arm(lua_State *L)
{
    if (L && lua_gethookcount(L) != 1)
        lua_sethook(L, script_hook, LUA_MASKCOUNT, 1);
}

void wsg_script_spend(struct wsg_script *h, lua_State *L, uint32_t steps)
{
    if (steps < h->budget) {
        h->budget -= steps;
        return;
    }
    h->budget = 0;
    script_arm(L);
}

/* The allocator: every byte the state holds is counted against the cap,
 * and an allocation past it fails as Lua expects ("not enough memory").
 * What it grows by is work done, spent from the slice: a concatenation
 * or a library call can copy megabytes in one instruction. */
static void *script_alloc(void *ud, void *ptr, size_t osize, size_t nsize)
{
    struct wsg_script *h = ud;
    size_t old = ptr ? osize : 0, grow;
    void *p;

    if (nsize == 0) {
        free(ptr);
        h->memory -= old;
        return NULL;
    }
    if (nsize > old && h->memory + (nsize - old) > h->limit)
        return NULL;
    p = realloc(ptr, nsize);
    if (!p)
        return NULL;
    h->memory = h->memory - old + nsize;
    if (nsize > old) {
        grow = (nsize - old) / WSG_SCRIPT_BYTES_PER_STEP;
        wsg_script_spend(h, h->running,
                         grow > UINT32_MAX ? UINT32_MAX : (uint32_t)grow);
    }
    return p;
}

static int script_stuck_error(lua_State *L)
{
    /* %d: lua_pushfstring knows no %u, and would raise its own error
     * in place of this one. */
    return luaL_error(L,
                      "ran %d slices of %d steps where it cannot be "
                      "preempted (in a function called from C: a "
                      "metamethod, a message handler, a load reader): "
                      "stopped",
                      (int)WSG_SCRIPT_STUCK_MAX, (int)WSG_SCRIPT_SLICE);
}

int wsg_script_doomed(struct wsg_script *h, lua_State *L)
{
    return h->stuck >= WSG_SCRIPT_STUCK_MAX && !wsg_script_preemptible(h, L);
}

int wsg_script_slice_over(struct wsg_script *h, lua_State *L)
{
    h->budget = WSG_SCRIPT_SLICE;
    /* The host's own calls (the traceback) are not the script's. */
    if (L == h->L)
        return 0;
    if (wsg_script_preemptible(h, L)) {
        h->state = WSG_SCRIPT_RUNNABLE;
        h->preempted++;
        h->preempting = 1;
        return 1;
    }
    h->owed = 1;
    if (h->stuck < WSG_SCRIPT_STUCK_MAX)
        h->stuck++;
    if (h->stuck >= WSG_SCRIPT_STUCK_MAX)
        script_stuck_error(L);
    return 0;
}

/* Preemption: the slice is used up, by instructions (counted here) or by
 * work (wsg_script_spend). Where the running code can yield to the host,
 * it yields. Where it cannot (a function called from C), it runs on,
 * owing the yield, and a stretch of WSG_SCRIPT_STUCK_MAX slices there
 * ends in an error. The yield owed is paid at the next hook where the
 * code can yield, whatever is left of the slice then: the error may come
 * back to a loop that catches it, and the slices would otherwise keep
 * running out where no yield is possible. Until the allowance comes back
 * (one slice a turn), every hook where the code cannot yield raises the
 * error again, so such a loop costs a hook's instructions a turn, not a
 * slice's; and the functions that catch errors pass it on there
 * (wsg_script_doomed). */
static void script_hook(lua_State *L, lua_Debug *ar)
{
    struct wsg_script *h = wsg_script_of(L);
    uint32_t ran = (uint32_t)lua_gethookcount(L);
    int pre = wsg_script_preemptible(h, L);

    (void)ar;
    if (ran != WSG_SCRIPT_HOOK_COUNT)
        lua_sethook(L, script_hook, LUA_MASKCOUNT, WSG_SCRIPT_HOOK_COUNT);
    if (!pre && h->stuck >= WSG_SCRIPT_STUCK_MAX)
        script_stuck_error(L);
    if (pre && h->owed) {
        h->budget = 0;
    } else if (h->budget > ran) {
        h->budget -= ran;
        return;
    }
    if (wsg_script_slice_over(h, L))
        lua_yield(L, 0);
}

/* The string functions' view of the slice (strlib.h). */
static uint32_t budget_left(void *ctx, lua_State *L)
{
    struct wsg_script *h = ctx;

    if (h->owed && wsg_script_preemptible(h, L))
        return 0;
    return h->budget;
}

static void budget_spend(void *ctx, lua_State *L, uint32_t steps)
{
    wsg_script_spend(ctx, L, steps);
}

static int budget_over(void *ctx, lua_State *L)
{
    return wsg_script_slice_over(ctx, L);
}

void wsg_script_print(struct wsg_script *h, const char *text, size_t len)
{
    size_t i;

    if (h->cfg.print && len > 0)
        h->cfg.print(h->cfg.ctx, text, len);
    /* Only the tail fits the ring. */
    if (len > WSG_SCRIPT_OUTPUT_MAX) {
        h->out_total += len - WSG_SCRIPT_OUTPUT_MAX;
        text += len - WSG_SCRIPT_OUTPUT_MAX;
        len = WSG_SCRIPT_OUTPUT_MAX;
    }
    for (i = 0; i < len; i++)
        h->out[(h->out_total + i) % WSG_SCRIPT_OUTPUT_MAX] = text[i];
    h->out_total += len;
}

uint64_t wsg_script_output(const struct wsg_script *h, uint64_t from,
                           char *buf, size_t cap, size_t *n, uint64_t *end)
{
    uint64_t oldest = h->out_total > WSG_SCRIPT_OUTPUT_MAX
                          ? h->out_total - WSG_SCRIPT_OUTPUT_MAX
                          : 0;
    size_t i = 0;

    if (from < oldest)
        from = oldest;
    if (from > h->out_total)
        from = h->out_total;
    for (; i < cap && from + i < h->out_total; i++)
        buf[i] = h->out[(from + i) % WSG_SCRIPT_OUTPUT_MAX];
    *n = i;
    *end = h->out_total;
    return from;
}

/* The script is over: its IDs go back to the firmware (E_CMD_UNKNOWN),
 * a speed-mode motion it left on stops (nothing drives it any more), and
 * D19 clears; D20 tells whether it failed. */
static void script_end(struct wsg_script *h, const char *error)
{
    struct wsg_axis *ax = wsg_device_axis(h->dev);

    wsg_device_unregister_all(h->dev);
    if (wsg_axis_speed_mode(ax)) {
        wsg_axis_request_stop(ax);
        wsg_axis_settle(ax);
    }
    if (h->L)
        lua_close(h->L);
    h->L = NULL;
    h->co = NULL;
    h->state = WSG_SCRIPT_STOPPED;
    h->qlen = 0;
    h->reply_tag = 0;
    h->dev->ext_flags &= ~(uint32_t)WSG_SF_SCRIPT_RUNNING;
    if (error) {
        h->failed = 1;
        snprintf(h->error, sizeof h->error, "%s", error);
        h->dev->ext_flags |= WSG_SF_SCRIPT_FAILURE;
    }
}

/* luaL_traceback in a protected call: it allocates, and an error outside
 * one would end the process. */
static int script_traceback(lua_State *L)
{
    luaL_traceback(L, lua_touserdata(L, 1), lua_touserdata(L, 2), 0);
    return 1;
}

/* The error of a failed resume, with where it happened, to the output and
 * the status; the first line is the status's error. */
static void script_fail(struct wsg_script *h, int status)
{
    char msg[sizeof h->error];
    const char *m, *tb;
    size_t len;

    if (status == LUA_ERRMEM)
        snprintf(msg, sizeof msg, "not enough memory (limit %lu bytes)",
                 (unsigned long)h->cfg.memory_max);
    else if ((m = lua_tostring(h->co, -1)) != NULL)
        snprintf(msg, sizeof msg, "%s", m);
    else
        snprintf(msg, sizeof msg, "error object is a %s value",
                 luaL_typename(h->co, -1));
    /* Room for the traceback past the cap: the state is closed next. */
    h->limit = h->cfg.memory_max + WSG_SCRIPT_HEADROOM;
    lua_pushcfunction(h->L, script_traceback);
    lua_pushlightuserdata(h->L, h->co);
    lua_pushlightuserdata(h->L, msg);
    if (lua_pcall(h->L, 2, 1, 0) == LUA_OK &&
        (tb = lua_tolstring(h->L, -1, &len)) != NULL) {
        wsg_script_print(h, "error: ", 7);
        wsg_script_print(h, tb, len);
        wsg_script_print(h, "\n", 1);
    }
    script_end(h, msg);
}

/* Run the body until it waits, is preempted, ends or fails. nargs values
 * on the body's stack are what the wait it was in returns. */
static void script_resume(struct wsg_script *h, int nargs)
{
    int st;

    h->state = WSG_SCRIPT_RUNNING;
    h->budget = WSG_SCRIPT_SLICE;
    /* A turn: one stuck slice is earned back, not all of them, or a loop
     * that gets stuck again at once would stall the daemon for the whole
     * allowance at every turn. */
    if (h->stuck > 0)
        h->stuck--;
    h->owed = 0;
    h->preempting = 0;
    h->nest = 0;
    h->running = h->co;
    st = lua_resume(h->co, h->L, nargs);
    h->running = NULL;
    h->preempting = 0;
    if (st == LUA_YIELD) {
        lua_settop(h->co, 0);
        if (h->state == WSG_SCRIPT_RUNNING) {
            /* A yield of the script's own (coroutine.yield in the body):
             * nothing to wait for; it goes on at the next turn. */
            h->state = WSG_SCRIPT_RUNNABLE;
        }
        if (h->state == WSG_SCRIPT_RUNNABLE)
            h->cfg.wake(h->cfg.ctx);
        return;
    }
    if (st == LUA_OK)
        script_end(h, NULL);
    else
        script_fail(h, st);
}

int wsg_script_take(struct wsg_script *h, lua_State *L)
{
    struct wsg_script_packet *p;
    uint16_t i;

    if (h->qlen == 0)
        return 0;
    p = &h->queue[h->qhead];
    h->qhead = (h->qhead + 1) % WSG_SCRIPT_QUEUE;
    h->qlen--;
    h->reply_tag = p->tag;
    lua_pushinteger(L, p->id);
    lua_createtable(L, p->len, 0);
    for (i = 0; i < p->len; i++) {
        lua_pushinteger(L, p->data[i]);
        lua_rawseti(L, -2, i + 1);
    }
    return 2;
}

/* The device's hook: a packet with a registered ID. */
static void script_packet(void *ctx, struct wsg_session *s,
                          const struct wsg_frame *f)
{
    struct wsg_script *h = ctx;
    struct wsg_script_packet *p;

    if (!h->L || h->qlen == WSG_SCRIPT_QUEUE) {
        uint8_t pkt[WSG_HEADER_LEN + 2 + WSG_CRC_LEN];
        size_t n = wsg_frame_encode_reply(
            pkt, sizeof pkt, f->id, h->L ? WSG_E_OVERRUN : WSG_E_CMD_UNKNOWN,
            NULL, 0);

        wsg_device_send(h->dev, s, pkt, n);
        return;
    }
    p = &h->queue[(h->qhead + h->qlen) % WSG_SCRIPT_QUEUE];
    p->tag = s->tag;
    p->id = f->id;
    p->len = f->len;
    memcpy(p->data, f->payload, f->len);
    h->qlen++;
    /* cmd.read's continuation takes it, inside the body, where an
     * allocation that fails is the script's error and not the daemon's. */
    if (h->state == WSG_SCRIPT_READING)
        script_resume(h, 0);
}

int wsg_script_new(struct wsg_script **out, struct wsg_device *d,
                   const struct wsg_script_config *cfg)
{
    struct wsg_script *h = calloc(1, sizeof *h);

    *out = NULL;
    if (!h)
        return -ENOMEM;
    h->dev = d;
    h->cfg = *cfg;
    if (h->cfg.memory_max == 0)
        h->cfg.memory_max = WSG_SCRIPT_MEMORY_DEFAULT;
    if (h->cfg.memory_max < WSG_SCRIPT_MEMORY_MIN)
        h->cfg.memory_max = WSG_SCRIPT_MEMORY_MIN;
    d->user_cmd = script_packet;
    d->user_ctx = h;
    *out = h;
    return 0;
}

void wsg_script_free(struct wsg_script *h)
{
    if (!h)
        return;
    if (h->L)
        script_end(h, NULL);
    if (h->dev->user_ctx == h) {
        h->dev->user_cmd = NULL;
        h->dev->user_ctx = NULL;
    }
    free(h->tx);
    free(h);
}

/* A compile error of a file outside the script directory, made safe to
 * show: that file may be any the daemon can read (a private key), and
 * Lua's message quotes the text where the parse failed ("near '...'") or
 * a name of the file's. What stays is the file, the line and Lua's words
 * before anything quoted. The line comes from a second parse under the
 * empty name "=", whose message starts ":LINE:" whatever the file's
 * name holds. Replaces the message on top of L. */
static void syntax_unquoted(lua_State *L, const char *buf, size_t len,
                            const char *name)
{
    char words[128];
    unsigned long line = 0;
    const char *m = NULL;
    size_t n = 0;
    int st;

    st = luaL_loadbufferx(L, buf, len, "=", "t");
    if (st == LUA_ERRSYNTAX)
        m = lua_tostring(L, -1);
    if (m && m[0] != ':') {
        /* No position: the loader's own words (a binary chunk refused),
         * none of the file's. Lua's message stays. */
        lua_pop(L, 1);
        return;
    }
    if (m) {
        char *end;

        line = strtoul(m + 1, &end, 10);
        m = *end == ':' ? end + 1 : "";
        while (*m == ' ')
            m++;
        /* Up to a quote, a "<name>"-like token, " near " or " (". */
        while (m[n] && n < sizeof words - 1 && !strchr("'\"<", m[n]) &&
               strncmp(m + n, " near ", 6) != 0 &&
               strncmp(m + n, " (", 2) != 0)
            n++;
        while (n > 0 && (m[n - 1] == ' ' || m[n - 1] == ':'))
            n--;
        memcpy(words, m, n);
    }
    words[n] = '\0';
    lua_pop(L, 2); /* the second parse's result, and Lua's message */
    lua_pushfstring(L,
                    "%s:%d: %s (the file's text is not shown: it is not in "
                    "the script directory)",
                    name, (int)line, n ? words : "syntax error");
}

/* Load the Lua text read from fd as a function on L's stack, named
 * "@name". As wsg_script_loadfile, from a descriptor already open. */
static int load_fd(lua_State *L, int fd, const char *name)
{
    struct stat st;
    size_t len = 0, skip = 0;
    char *buf = NULL;
    ssize_t n;
    int r;

    if (fstat(fd, &st) < 0)
        return -errno;
    if (!S_ISREG(st.st_mode))
        return -EINVAL;
    if (st.st_size > (off_t)WSG_SCRIPT_SOURCE_MAX)
        return -EFBIG;
    buf = malloc((size_t)st.st_size + 1);
    if (!buf)
        return -ENOMEM;
    /* What the file holds now, even if it grew since fstat. */
    while (len < (size_t)st.st_size &&
           (n = read(fd, buf + len, (size_t)st.st_size - len)) != 0) {
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0) {
            r = -errno;
            goto out;
        }
        len += (size_t)n;
    }
    /* A first line starting with '#' (a "#!" line) is skipped, as Lua's
     * loadfile skips it; a blank in its place keeps the line numbers. */
    if (len && buf[0] == '#')
        while (skip < len && buf[skip] != '\n')
            buf[skip++] = ' ';
    lua_pushfstring(L, "@%s", name);
    r = luaL_loadbufferx(L, buf, len, lua_tostring(L, -1), "t");
    lua_remove(L, -2); /* the name */
    if (r == LUA_ERRSYNTAX && !wsg_script_of(L)->quote)
        syntax_unquoted(L, buf, len, name);
out:
    free(buf);
    return r;
}

int wsg_script_loadfile(lua_State *L, const char *path)
{
    int fd, r;

    fd = open(path, O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0)
        return -errno;
    r = load_fd(L, fd, path);
    close(fd);
    return r;
}

/* Open rel below the directory dir, one component at a time, following
 * no link: each directory is opened with O_NOFOLLOW from the one before,
 * so a link anywhere in rel (to a directory outside, or swapped in for
 * one after a check) fails with ELOOP. Empty components are skipped, as
 * a path resolves "a//b". An fd, or -errno. */
static int script_open_beneath(const char *dir, const char *rel)
{
    char comp[WSG_SCRIPT_PATH_MAX];
    const char *p = rel, *end;
    int dfd, fd;
    size_t n;

    dfd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dfd < 0)
        return -errno;
    for (;;) {
        while (*p == '/')
            p++;
        end = strchr(p, '/');
        n = end ? (size_t)(end - p) : strlen(p);
        if (n >= sizeof comp) {
            fd = -ENAMETOOLONG;
            break;
        }
        memcpy(comp, p, n);
        comp[n] = '\0';
        p += n;
        while (*p == '/')
            p++;
        if (*p == '\0') {
            /* O_NONBLOCK: a FIFO is refused by load_fd, not waited on. */
            fd = openat(dfd, comp,
                        O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
            if (fd < 0)
                fd = -errno;
            break;
        }
        fd =
            openat(dfd, comp, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
        if (fd < 0) {
            struct stat st;

            /* Linux says ENOTDIR for a link where O_DIRECTORY wants a
             * directory: a link is ELOOP here as at the end. */
            fd = -errno;
            if (fd == -ENOTDIR &&
                fstatat(dfd, comp, &st, AT_SYMLINK_NOFOLLOW) == 0 &&
                S_ISLNK(st.st_mode))
                fd = -ELOOP;
            break;
        }
        close(dfd);
        dfd = fd;
    }
    close(dfd);
    return fd;
}

int wsg_script_loadmodule(lua_State *L, const char *dir, const char *rel,
                          const char *name)
{
    int fd = script_open_beneath(dir, rel), r;

    if (fd < 0)
        return fd;
    r = load_fd(L, fd, name);
    close(fd);
    return r;
}

/* Load the file (read from fd) as the body of a fresh state. 0, or
 * -errno/-EINVAL with the reason in err (a compile error fails the
 * script). */
static int script_load(struct wsg_script *h, int fd, char *err, size_t errlen)
{
    int st;

    h->memory = 0;
    h->limit = h->cfg.memory_max;
    h->stuck = 0;
    h->running = NULL;
    h->slice.left = budget_left;
    h->slice.spend = budget_spend;
    h->slice.over = budget_over;
    h->slice.ctx = h;
    h->L = lua_newstate(script_alloc, h);
    if (!h->L) {
        snprintf(err, errlen, "not enough memory for a Lua state");
        return -ENOMEM;
    }
    if (mirror_ok < 0)
        mirror_ok = mirror_check(h->L);
    wsg_script_open_api(h->L, h);
    h->co = lua_newthread(h->L);
    /* Kept in the registry so the collector leaves it while it runs. */
    lua_setfield(h->L, LUA_REGISTRYINDEX, "wsg.body");
    st = load_fd(h->co, fd, h->file);
    if (st != LUA_OK) {
        const char *m = st > 0 ? lua_tostring(h->co, -1) : NULL;

        if (st < 0)
            snprintf(err, errlen, "cannot read %s: %s", h->file,
                     strerror(-st));
        else
            snprintf(err, errlen, "%s", m ? m : "cannot load the script");
        wsg_script_print(h, "error: ", 7);
        wsg_script_print(h, err, strlen(err));
        wsg_script_print(h, "\n", 1);
        script_end(h, err);
        return -EINVAL;
    }
    lua_sethook(h->co, script_hook, LUA_MASKCOUNT, WSG_SCRIPT_HOOK_COUNT);
    return 0;
}

int wsg_script_open_at(int dfd, const char *name)
{
    struct stat st;
    int fd;

    /* O_NONBLOCK: a FIFO planted in the script's place must not hold the
     * daemon in open(); it is refused below like any other non-file. */
    fd = openat(dfd, name,
                O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
    if (fd < 0)
        return -errno;
    if (fstat(fd, &st) < 0) {
        int r = -errno;

        close(fd);
        return r;
    }
    if (!S_ISREG(st.st_mode)) {
        close(fd);
        return -ENOEXEC;
    }
    return fd;
}

int wsg_script_open(const char *path, char *file, size_t cap)
{
    char dir[WSG_SCRIPT_PATH_MAX], real[WSG_SCRIPT_PATH_MAX];
    const char *slash = strrchr(path, '/'), *name = slash ? slash + 1 : path;
    size_t n = slash ? (size_t)(slash - path) : 0;
    int dfd, fd;

    if (*name == '\0')
        return -EISDIR;
    if (n >= sizeof dir)
        return -ENAMETOOLONG;
    /* The directory as given ("" is the root, none the current one). */
    memcpy(dir, slash ? path : ".", slash ? n : 1);
    dir[slash ? n : 1] = '\0';
    if (!realpath(dir[0] ? dir : "/", real))
        return -errno;
    dfd = open(real, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dfd < 0)
        return -errno;
    fd = wsg_script_open_at(dfd, name);
    close(dfd);
    if (fd >= 0 && file &&
        (size_t)snprintf(file, cap, "%s/%s", strcmp(real, "/") ? real : "",
                         name) >= cap) {
        close(fd);
        return -ENAMETOOLONG;
    }
    return fd;
}

const char *wsg_script_open_strerror(int r)
{
    if (r == -ELOOP)
        return "a symbolic link (not followed)";
    if (r == -ENOEXEC)
        return "not a regular file";
    return strerror(-r);
}

/* Is the script's directory (h->dir) the script directory, or below it?
 * Then its compile errors may quote its text. */
static int in_script_dir(const struct wsg_script *h)
{
    char top[WSG_SCRIPT_PATH_MAX], dir[WSG_SCRIPT_PATH_MAX];
    size_t n;

    if (!h->cfg.script_dir || !realpath(h->cfg.script_dir, top) ||
        !realpath(h->dir, dir))
        return 0;
    n = strlen(top);
    if (strcmp(top, "/") == 0)
        return 1;
    return strncmp(dir, top, n) == 0 && (dir[n] == '\0' || dir[n] == '/');
}

int wsg_script_start_fd(struct wsg_script *h, int fd, const char *file,
                        char *err, size_t errlen)
{
    char *slash;
    int r;

    if (h->L) {
        snprintf(err, errlen, "a script is running (%s): stop it first",
                 h->file);
        return -EBUSY;
    }
    if ((size_t)snprintf(h->file, sizeof h->file, "%s", file) >=
        sizeof h->file) {
        snprintf(err, errlen, "the script's path is too long");
        h->file[0] = '\0';
        return -ENAMETOOLONG;
    }
    /* Its modules are beside it: the gripper's /user directory. */
    snprintf(h->dir, sizeof h->dir, "%s", h->file);
    slash = strrchr(h->dir, '/');
    if (slash)
        slash[slash == h->dir ? 1 : 0] = '\0';
    else
        snprintf(h->dir, sizeof h->dir, ".");
    h->quote = in_script_dir(h);
    if (!h->tx) {
        h->tx = malloc(WSG_HEADER_LEN + WSG_SCRIPT_SEND_MAX + WSG_CRC_LEN);
        if (!h->tx) {
            snprintf(err, errlen, "not enough memory");
            return -ENOMEM;
        }
    }
    /* A new start clears D20 (and the old error). */
    h->failed = 0;
    h->error[0] = '\0';
    h->dev->ext_flags &= ~(uint32_t)WSG_SF_SCRIPT_FAILURE;
    h->pid[0] = 1.0;
    h->pid[1] = h->pid[2] = 0.0;
    h->qlen = 0;
    h->reply_tag = 0;
    h->dev->ext_flags |= WSG_SF_SCRIPT_RUNNING;
    r = script_load(h, fd, err, errlen);
    if (r < 0) {
        if (r != -EINVAL)
            script_end(h, err);
        return r;
    }
    script_resume(h, 0);
    if (h->failed) {
        snprintf(err, errlen, "%s", h->error);
        return -EINVAL;
    }
    return 0;
}

int wsg_script_start(struct wsg_script *h, const char *path, char *err,
                     size_t errlen)
{
    char file[WSG_SCRIPT_PATH_MAX];
    int fd, r;

    if (h->L) {
        snprintf(err, errlen, "a script is running (%s): stop it first",
                 h->file);
        return -EBUSY;
    }
    fd = wsg_script_open(path, file, sizeof file);
    if (fd < 0) {
        snprintf(err, errlen, "%s: %s", path, wsg_script_open_strerror(fd));
        return fd == -EINVAL ? -EIO : fd;
    }
    r = wsg_script_start_fd(h, fd, file, err, errlen);
    close(fd);
    return r;
}

int wsg_script_stop(struct wsg_script *h)
{
    if (!h->L)
        return -ESRCH;
    script_end(h, NULL);
    return 0;
}

void wsg_script_status(const struct wsg_script *h,
                       struct wsg_script_status *st)
{
    memset(st, 0, sizeof *st);
    st->state = h->state;
    st->running = h->L != NULL;
    st->failed = h->failed;
    st->error = h->error[0] ? h->error : NULL;
    st->file = h->file[0] ? h->file : NULL;
    st->memory = h->L ? h->memory : 0;
    st->memory_max = h->cfg.memory_max;
    st->wake_us = h->wake_us;
    st->preempted = h->preempted;
}

size_t wsg_script_registered(const struct wsg_script *h, uint8_t *ids,
                             size_t cap)
{
    size_t n = 0;
    unsigned id;

    for (id = 0; id < 256 && n < cap; id++)
        if (wsg_device_registered(h->dev, (uint8_t)id))
            ids[n++] = (uint8_t)id;
    return n;
}

uint64_t wsg_script_next(const struct wsg_script *h)
{
    return h->state == WSG_SCRIPT_SLEEPING ? h->wake_us : UINT64_MAX;
}

void wsg_script_poll(struct wsg_script *h)
{
    if (h->state == WSG_SCRIPT_SLEEPING && wsg_script_now(h) >= h->wake_us)
        script_resume(h, 0);
}

void wsg_script_run(struct wsg_script *h)
{
    if (h->state == WSG_SCRIPT_RUNNABLE)
        script_resume(h, 0);
}
