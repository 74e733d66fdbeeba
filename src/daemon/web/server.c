/*
 * The web page's server. GNU libmicrohttpd (MHD) runs in its "external
 * epoll" mode: MHD_USE_EPOLL without an internal polling thread. It keeps
 * its own epoll set of the listening socket and the connections, and that
 * set's descriptor is one watch of the reactor: when it is readable, or
 * when the timeout MHD_get_timeout asks for has passed (one timerfd),
 * MHD_run does what is ready and returns. No thread of its own, so the
 * request handlers act on the gripper as every other watch does, between
 * the model's steps.
 *
 * Server push (GET /events, Server-Sent Events): the answer is a stream
 * of unknown length whose reader hands out state events. With nothing new
 * to send it suspends the connection (MHD then neither polls it nor times
 * it out), and a new state resumes it. A resumed connection is taken up
 * only by MHD_run, and in this mode nothing of MHD's makes its epoll
 * descriptor readable for it (it has no inter-thread channel without a
 * thread), so a resume is a kick: MHD runs again at once, through the
 * timer when the push comes from the hook after a batch, once more
 * before MHD_run's caller returns when it comes from a handler. A
 * suspended connection's hang-up is not seen by MHD, so its socket is
 * watched here meanwhile (EPOLLRDHUP), and a client that closed the page
 * does not keep its slot until the next change.
 *
 * When is there a new state? After each batch of events (a reactor hook)
 * the first gripper's state is formatted without its time and compared
 * with the last one pushed. Whatever changes the gripper happens in a
 * batch (a timer step, a command, the control channel), so no change is
 * missed, and with no one subscribed nothing is formatted. Pushes are at
 * least WSG_WEB_PUSH_MIN_NS apart; a change sooner arms the timer for
 * then, and the hook after that wake pushes the state as it is by then.
 * So a page open on an idle gripper costs nothing: no change, no timer,
 * no wake.
 */
#define _GNU_SOURCE

#include "impl.h"

#include <errno.h>
#include <fcntl.h>
#include <microhttpd.h>
#include <netinet/in.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

#include "assets.h"
#include "gripper.h"
#include "state.h"
#include "web_host.h"
#include "web_sse.h"
#include "wsg/schema.h"

#define NS_PER_S  1000000000ull
#define NS_PER_MS 1000000ull
/* A connection on which nothing moves for this long is closed (MHD's
 * timeout): one whose client does not read its answer. One that waits
 * for a request is closed sooner, at the request's deadline
 * (WSG_WEB_REQUEST_S). A suspended event stream does not time out (MHD
 * stops its clock while suspended). */
#define WEB_IDLE_TIMEOUT_S 60u
/* MHD_run rounds in a row while resumes come in during them (a new
 * stream's first event): one more does it, the rest only bound the loop;
 * past them the timer runs MHD at once. Closing uses as many to let the
 * resumed streams end. */
#define WEB_RUN_ROUNDS 4
#define WEB_INFO_MAX   1536u

/* A subscriber's buffer takes a whole state event and any log event
 * (C99 has no _Static_assert: an array of negative size fails the
 * build). */
typedef char
    web_state_event_fits[WSG_WEB_EVENT_MAX <= WSG_WEB_LOG_EVENT_MAX ? 1 : -1];
typedef char
    web_log_event_fits[WSG_WEB_SSE_LOG_MIN <= WSG_WEB_LOG_EVENT_MAX ? 1 : -1];

/* One client of /events. It sends its own copy of an event, so a newer
 * one can be made while it is half sent; a slow client skips to the
 * newest state, never queues states. The log is read from the ring at the
 * client's own offset, a chunk of whole lines at a time. */
struct web_sub {
    struct wsg_web *web;
    struct MHD_Connection *conn;
    struct sockaddr_storage peer; /* its client's address */
    struct wsg_watch hup;         /* its socket while suspended; fd -1: not */
    int suspended;
    int gone;         /* hung up: end the stream */
    uint64_t seq;     /* the state event it has (or is sending) */
    uint64_t log_off; /* the log bytes it has */
    size_t len, off;
    char buf[WSG_WEB_LOG_EVENT_MAX];
    struct web_sub *prev, *next;
};

/* A connection, from MHD's notice of it to its close (its socket
 * context): when the request it is receiving started, for the deadline
 * of its head and body (WSG_WEB_REQUEST_S). */
struct web_conn {
    struct MHD_Connection *conn;
    uint64_t since; /* 0: no request is being received (one is answered) */
    struct web_conn *prev, *next;
};

static uint64_t mono_ns(void)
{
    struct timespec ts;

    /* CLOCK_MONOTONIC cannot fail with a valid pointer. */
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * NS_PER_S + (uint64_t)ts.tv_nsec;
}

/* ---- the timer and MHD's turns ---- */

/* Arm the timer for the earliest deadline, or disarm it. */
static void web_arm(struct wsg_web *web)
{
    struct itimerspec its;
    uint64_t due = web->mhd_due;

    if (web->push_due && (!due || web->push_due < due))
        due = web->push_due;
    if (web->conn_due && (!due || web->conn_due < due))
        due = web->conn_due;
    if (due == web->armed)
        return;
    memset(&its, 0, sizeof its);
    its.it_value.tv_sec = (time_t)(due / NS_PER_S);
    its.it_value.tv_nsec = (long)(due % NS_PER_S);
    /* It cannot fail on a valid timerfd with a valid time; were it to,
     * the next batch would try again (armed stays as it was). */
    if (timerfd_settime(web->timer.fd, TFD_TIMER_ABSTIME, &its, NULL) == 0)
        web->armed = due;
}

/* Let MHD do what is ready (again while connections were resumed
 * meanwhile), and ask it when it wants to run next. */
static void web_run(struct wsg_web *web)
{
    MHD_UNSIGNED_LONG_LONG ms;
    int round = 0;

    do {
        web->kicked = 0;
        web->in_run = 1;
        MHD_run(web->mhd);
        web->in_run = 0;
    } while (web->kicked && ++round < WEB_RUN_ROUNDS);
    if (web->kicked)
        web->mhd_due = mono_ns(); /* the timer: at once */
    else if (MHD_get_timeout(web->mhd, &ms) == MHD_YES)
        web->mhd_due = mono_ns() + (uint64_t)ms * NS_PER_MS;
    else
        web->mhd_due = 0;
    web_arm(web);
}

/* Connections were resumed (kicked): MHD must run to take them up.
 * Inside MHD_run (a handler's push) web_run goes round once more. In the
 * hook after a batch it must not run: a request it answers there would
 * act on a gripper after the scheduler's own hook has rescheduled the
 * ones touched in the batch. So the timer runs it at once, in a batch of
 * its own. */
static void web_kick(struct wsg_web *web)
{
    if (!web->kicked || web->in_run)
        return;
    web->mhd_due = mono_ns();
    web_arm(web);
}

static void on_mhd(struct wsg_watch *w, uint32_t events)
{
    (void)events;
    web_run(w->ctx);
}

static void conns_expire(struct wsg_web *web, uint64_t now);

static void on_timer(struct wsg_watch *w, uint32_t events)
{
    struct wsg_web *web = w->ctx;
    uint64_t expirations, now = mono_ns();

    (void)events;
    if (read(w->fd, &expirations, sizeof expirations) < 0)
        (void)0; /* EAGAIN: woken for a time since moved */
    web->armed = 0;
    /* The hook after this batch pushes what changed meanwhile. */
    if (web->push_due && web->push_due <= now)
        web->push_due = 0;
    if (web->conn_due && web->conn_due <= now)
        conns_expire(web, now);
    if (web->mhd_due && web->mhd_due <= now)
        web_run(web);
    else
        web_arm(web);
}

/* ---- the event stream ---- */

static void on_hup(struct wsg_watch *w, uint32_t events);

/* Back into MHD's hands: its socket leaves the reactor, MHD polls it
 * again once it has run (the caller kicks it, web_kick). Safe from
 * anywhere, MHD's callbacks included. */
static void sub_resume(struct web_sub *sub)
{
    if (!sub->suspended)
        return;
    if (sub->hup.fd >= 0) {
        wsg_reactor_del(sub->web->reactor, &sub->hup);
        sub->hup.fd = -1;
    }
    sub->suspended = 0;
    MHD_resume_connection(sub->conn);
    sub->web->kicked = 1;
}

/* Nothing new to send: out of MHD's polling until there is, with the
 * socket watched for the client's close meanwhile. Without that watch
 * (no memory for it) the stream works all the same; a closed page then
 * holds its slot until the next state is pushed to it. */
static void sub_suspend(struct web_sub *sub)
{
    const union MHD_ConnectionInfo *ci;

    MHD_suspend_connection(sub->conn);
    sub->suspended = 1;
    ci = MHD_get_connection_info(sub->conn, MHD_CONNECTION_INFO_CONNECTION_FD);
    if (!ci)
        return;
    wsg_watch_init(&sub->hup, ci->connect_fd, on_hup, sub);
    if (wsg_reactor_add(sub->web->reactor, &sub->hup, EPOLLRDHUP) < 0)
        sub->hup.fd = -1;
}

static void on_hup(struct wsg_watch *w, uint32_t events)
{
    struct web_sub *sub = w->ctx;

    (void)events;
    /* Its reader ends the stream, and MHD closes the connection. */
    sub->gone = 1;
    sub_resume(sub);
    /* A watch's callback, in a batch: MHD may run here and now. */
    web_run(sub->web);
}

/* The next "log" event for sub: the lines it has not had, as many whole
 * ones as fit, packed by web_sse.c (bounded by the buffer, whatever the
 * lines are). 0: nothing to send. */
static size_t log_event(struct wsg_web *web, struct web_sub *sub)
{
    struct wsg_web_ring ring;

    ring.buf = web->log_ring;
    ring.size = WSG_WEB_LOG_RING;
    ring.oldest = web->log_head > WSG_WEB_LOG_RING
                      ? web->log_head - WSG_WEB_LOG_RING
                      : 0;
    ring.end = web->log_pushed;
    return wsg_web_sse_log(sub->buf, sizeof sub->buf, &ring, &sub->log_off);
}

void wsg_web_log_line(struct wsg_web *web, const char *line, size_t len)
{
    size_t at, first;

    /* Only while someone watches (the ring is there), and a log line is
     * far shorter than the ring. */
    if (!web->log_ring || len > WSG_WEB_LOG_RING)
        return;
    at = (size_t)(web->log_head % WSG_WEB_LOG_RING);
    first = WSG_WEB_LOG_RING - at < len ? WSG_WEB_LOG_RING - at : len;
    memcpy(web->log_ring + at, line, first);
    memcpy(web->log_ring, line + first, len - first);
    web->log_head += len;
}

/* MHD asks for the next bytes of the stream. */
static ssize_t sub_read(void *cls, uint64_t pos, char *buf, size_t max)
{
    struct web_sub *sub = cls;
    struct wsg_web *web = sub->web;
    size_t n;

    (void)pos;
    /* The end of a stream whose client left (or that closes with the
     * server): not an error, and not one for MHD's log. */
    if (sub->gone)
        return MHD_CONTENT_READER_END_OF_STREAM;
    if (sub->off == sub->len) {
        if (sub->seq != web->seq) {
            /* It fits (web_state_event_fits); bounded all the same. */
            sub->len = web->event_len < sizeof sub->buf ? web->event_len
                                                        : sizeof sub->buf;
            memcpy(sub->buf, web->event, sub->len);
            sub->seq = web->seq;
        } else {
            sub->len =
                sub->log_off < web->log_pushed ? log_event(web, sub) : 0;
        }
        sub->off = 0;
        if (sub->len == 0) {
            /* Returning 0 has MHD ask again at its next run: suspended,
             * it does not run for this connection until resumed. */
            sub_suspend(sub);
            return 0;
        }
    }
    n = sub->len - sub->off < max ? sub->len - sub->off : max;
    memcpy(buf, sub->buf + sub->off, n);
    sub->off += n;
    return (ssize_t)n;
}

/* The stream's response is destroyed: its connection is closed (or it
 * was never queued). */
static void sub_free(void *cls)
{
    struct web_sub *sub = cls;
    struct wsg_web *web = sub->web;

    if (sub->hup.fd >= 0)
        wsg_reactor_del(web->reactor, &sub->hup);
    if (sub->prev)
        sub->prev->next = sub->next;
    else
        web->subs = sub->next;
    if (sub->next)
        sub->next->prev = sub->prev;
    web->nsubs--;
    free(sub);
    if (!web->nsubs)
        wsg_web_world_watch(web, 0);
}

/* Push what is new: the state (key: it without its time) when it
 * changed, and the log lines since the last push; every stream that
 * waits is resumed. */
static void web_push(struct wsg_web *web, const char *key, size_t key_len,
                     uint64_t now)
{
    char json[WSG_STATE_JSON_MAX];
    struct web_sub *sub;
    int n;

    if (key) {
        wsg_state_format(json, sizeof json, web->g, web->sched, WSG_STATE_ALL);
        n = snprintf(web->event, sizeof web->event,
                     "event: state\ndata: %s\n\n", json);
        if (n < 0 || (size_t)n >= sizeof web->event)
            return; /* cannot happen: the room is the state's and the
                       frame's */
        memcpy(web->key, key, key_len);
        web->key_len = key_len;
        web->event_len = (size_t)n;
        web->seq++;
    }
    web->log_pushed = web->log_head;
    web->pushed = now;
    for (sub = web->subs; sub; sub = sub->next)
        sub_resume(sub);
    web_kick(web);
}

/* Push the state if it changed and the log if it grew, or have them
 * pushed when the last push is WSG_WEB_PUSH_MIN_NS old. */
static void web_check(struct wsg_web *web)
{
    char key[WSG_STATE_JSON_MAX];
    size_t len;
    uint64_t now;
    int changed;

    if (!web->nsubs || web->push_due)
        return;
    len = wsg_state_format(key, sizeof key, web->g, web->sched,
                           WSG_STATE_NO_TIME);
    changed =
        !web->seq || len != web->key_len || memcmp(key, web->key, len) != 0;
    if (!changed && web->log_head == web->log_pushed)
        return;
    now = mono_ns();
    if (web->seq && now - web->pushed < WSG_WEB_PUSH_MIN_NS) {
        web->push_due = web->pushed + WSG_WEB_PUSH_MIN_NS;
        web_arm(web);
        return;
    }
    web_push(web, changed ? key : NULL, len, now);
}

/* After each batch of the reactor's events. */
static void web_after(void *ctx)
{
    web_check(ctx);
}

/* ---- connections and the deadline of a request ---- */

/* MHD's idle timeout (WEB_IDLE_TIMEOUT_S) is not enough: every byte
 * restarts it, so a client that sends a byte of its request's head now
 * and then (slowloris) holds its slot for ever. So each connection has
 * a clock, started when it opens and again when an answer on it is
 * done; while it runs, the request's head and body must come within
 * WSG_WEB_REQUEST_S, else its socket is shut down and MHD closes it. The
 * clock stops once the request is answered: an answer being sent, such
 * as an event stream that is idle by design, is not cut. */

#define WEB_REQUEST_NS ((uint64_t)WSG_WEB_REQUEST_S * NS_PER_S)

static struct web_conn *conn_of(struct MHD_Connection *conn)
{
    const union MHD_ConnectionInfo *ci =
        MHD_get_connection_info(conn, MHD_CONNECTION_INFO_SOCKET_CONTEXT);

    return ci ? ci->socket_context : NULL;
}

/* Shut the connection's socket down: MHD sees its end at its next run
 * and closes it as any connection its client closed. */
static void conn_cut(struct MHD_Connection *conn)
{
    const union MHD_ConnectionInfo *ci =
        MHD_get_connection_info(conn, MHD_CONNECTION_INFO_CONNECTION_FD);

    if (ci)
        shutdown(ci->connect_fd, SHUT_RDWR);
}

/* The earliest deadline of the requests being received, anew: after a
 * clock stopped, so that no timer is left for a request that is gone. */
static void conns_due(struct wsg_web *web)
{
    const struct web_conn *c;
    uint64_t due = 0;

    for (c = web->conns; c; c = c->next)
        if (c->since && (!due || c->since + WEB_REQUEST_NS < due))
            due = c->since + WEB_REQUEST_NS;
    web->conn_due = due;
}

/* Start (now) or stop (0) the clock of conn's request. Called from
 * MHD's callbacks, inside MHD_run: web_run arms the timer after it. */
static void conn_clock(struct wsg_web *web, struct MHD_Connection *conn,
                       uint64_t now)
{
    struct web_conn *c = conn_of(conn);

    if (!c || c->since == now)
        return;
    c->since = now;
    if (!now)
        conns_due(web);
    else if (!web->conn_due || now + WEB_REQUEST_NS < web->conn_due)
        web->conn_due = now + WEB_REQUEST_NS;
}

/* The timer: cut the connections whose request is late. */
static void conns_expire(struct wsg_web *web, uint64_t now)
{
    struct web_conn *c;

    for (c = web->conns; c; c = c->next) {
        if (!c->since || now - c->since < WEB_REQUEST_NS)
            continue;
        conn_cut(c->conn);
        c->since = 0;
        web->mhd_due = now; /* MHD closes it at once */
    }
    conns_due(web);
}

static void on_connection(void *cls, struct MHD_Connection *conn,
                          void **socket_context,
                          enum MHD_ConnectionNotificationCode code)
{
    struct wsg_web *web = cls;
    struct web_conn *c = *socket_context;

    if (code == MHD_CONNECTION_NOTIFY_STARTED) {
        c = calloc(1, sizeof *c);
        if (!c) {
            /* Without a clock it would have no deadline: refused. */
            conn_cut(conn);
            return;
        }
        c->conn = conn;
        c->next = web->conns;
        if (web->conns)
            web->conns->prev = c;
        web->conns = c;
        *socket_context = c;
        conn_clock(web, conn, mono_ns());
        return;
    }
    if (!c)
        return;
    if (c->prev)
        c->prev->next = c->next;
    else
        web->conns = c->next;
    if (c->next)
        c->next->prev = c->prev;
    free(c);
    *socket_context = NULL;
    conns_due(web);
}

/* ---- answers ---- */

/* An answer with the headers every answer has, and one more (name NULL:
 * none). */
static enum MHD_Result answer_with(struct MHD_Connection *conn,
                                   unsigned status, const char *type,
                                   const void *body, size_t len, int is_static,
                                   const char *name, const char *value)
{
    struct MHD_Response *r;
    enum MHD_Result ret;

    /* MHD_RESPMEM_PERSISTENT does not write to body: the cast only
     * meets the old prototype. */
    r = MHD_create_response_from_buffer(len, (void *)(uintptr_t)body,
                                        is_static ? MHD_RESPMEM_PERSISTENT
                                                  : MHD_RESPMEM_MUST_COPY);
    if (!r)
        return MHD_NO;
    /* The page's own files may be cached (revalidated: the daemon may be
     * a newer one); answers never. */
    if (MHD_add_response_header(r, MHD_HTTP_HEADER_CONTENT_TYPE, type) !=
            MHD_YES ||
        MHD_add_response_header(r, MHD_HTTP_HEADER_CACHE_CONTROL,
                                is_static ? "no-cache" : "no-store") !=
            MHD_YES ||
        MHD_add_response_header(r, "X-Content-Type-Options", "nosniff") !=
            MHD_YES ||
        (name && MHD_add_response_header(r, name, value) != MHD_YES)) {
        MHD_destroy_response(r);
        return MHD_NO;
    }
    ret = MHD_queue_response(conn, status, r);
    MHD_destroy_response(r);
    return ret;
}

enum MHD_Result wsg_web_answer(struct MHD_Connection *conn, unsigned status,
                               const char *type, const void *body, size_t len,
                               int is_static)
{
    return answer_with(conn, status, type, body, len, is_static, NULL, NULL);
}

enum MHD_Result wsg_web_json(struct MHD_Connection *conn, unsigned status,
                             const char *fmt, ...)
{
    static const char too_long[] = "{\"error\":\"the answer does not fit\"}";
    char buf[WSG_WEB_ANSWER_MAX];
    va_list ap;
    int n;

    va_start(ap, fmt);
    n = vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    /* Answered all the same: MHD_NO would close the connection without
     * a word. The handlers size what they put in; this is a bug's net. */
    if (n < 0 || (size_t)n >= sizeof buf)
        return wsg_web_answer(conn, MHD_HTTP_INTERNAL_SERVER_ERROR,
                              "application/json", too_long,
                              sizeof too_long - 1, 1);
    return wsg_web_answer(conn, status, "application/json", buf, (size_t)n, 0);
}

/* The length of the UTF-8 character at s (n bytes left): 1..4, or 0 when
 * s does not start one (a stray continuation byte, an overlong form, a
 * surrogate, past U+10FFFF, or cut short). */
static size_t utf8_len(const unsigned char *s, size_t n)
{
    unsigned char lo = 0x80, hi = 0xbf;
    size_t len, i;

    if (s[0] < 0x80)
        return 1;
    if (s[0] >= 0xc2 && s[0] <= 0xdf)
        len = 2;
    else if (s[0] >= 0xe0 && s[0] <= 0xef)
        len = 3;
    else if (s[0] >= 0xf0 && s[0] <= 0xf4)
        len = 4;
    else
        return 0;
    if (s[0] == 0xe0)
        lo = 0xa0;
    else if (s[0] == 0xed)
        hi = 0x9f;
    else if (s[0] == 0xf0)
        lo = 0x90;
    else if (s[0] == 0xf4)
        hi = 0x8f;
    if (n < len || s[1] < lo || s[1] > hi)
        return 0;
    for (i = 2; i < len; i++)
        if (s[i] < 0x80 || s[i] > 0xbf)
            return 0;
    return len;
}

size_t wsg_web_utf8_whole(const char *s, size_t n)
{
    const unsigned char *u = (const unsigned char *)s;
    size_t back, need;

    /* Back over continuation bytes (three at most) to the lead byte: cut
     * before it when its character needs more bytes than are there. */
    for (back = 1; back <= 3 && back <= n; back++) {
        if (u[n - back] < 0x80)
            return n;
        if (u[n - back] >= 0xc0) {
            need = u[n - back] >= 0xf0 ? 4 : u[n - back] >= 0xe0 ? 3 : 2;
            return need > back ? n - back : n;
        }
    }
    return n;
}

size_t wsg_web_escape(char *buf, size_t cap, const char *s, size_t len)
{
    static const char hex[] = "0123456789abcdef";
    const unsigned char *u = (const unsigned char *)s;
    size_t used = 0, i = 0;

    while (i < len) {
        unsigned char c = u[i];
        const char *from = s + i;
        char esc[7];
        size_t n, take;

        if (c == '"' || c == '\\') {
            esc[0] = '\\';
            esc[1] = (char)c;
            from = esc;
            n = 2;
            take = 1;
        } else if (c < 0x20 || c == 0x7f) {
            memcpy(esc, "\\u00", 4);
            esc[4] = hex[c >> 4];
            esc[5] = hex[c & 15];
            from = esc;
            n = 6;
            take = 1;
        } else if ((n = utf8_len(u + i, len - i)) != 0) {
            take = n; /* a character whole, never a part of one */
        } else {
            /* Not UTF-8 (a script's bytes, a cut name): JSON must be. */
            from = "\\ufffd";
            n = 6;
            take = 1;
        }
        if (used + n >= cap) {
            if (cap)
                buf[used] = '\0';
            return cap;
        }
        memcpy(buf + used, from, n);
        used += n;
        i += take;
    }
    if (cap)
        buf[used] = '\0';
    return used;
}

enum MHD_Result wsg_web_error(struct MHD_Connection *conn, unsigned status,
                              const char *msg)
{
    char esc[WSG_WEB_ANSWER_MAX - 16];

    wsg_web_escape(esc, sizeof esc, msg, strlen(msg));
    return wsg_web_json(conn, status, "{\"error\":\"%s\"}", esc);
}

static enum MHD_Result refuse_method(struct MHD_Connection *conn,
                                     unsigned methods)
{
    struct MHD_Response *r;
    enum MHD_Result ret;
    static const char body[] = "{\"error\":\"method not allowed\"}";
    char allow[40] = "";

    if (methods & WSG_WEB_GET)
        strcat(allow, ", GET, HEAD");
    if (methods & WSG_WEB_POST)
        strcat(allow, ", POST");
    if (methods & WSG_WEB_PUT)
        strcat(allow, ", PUT");
    if (methods & WSG_WEB_DELETE)
        strcat(allow, ", DELETE");
    r = MHD_create_response_from_buffer(sizeof body - 1, (void *)body,
                                        MHD_RESPMEM_PERSISTENT);
    if (!r)
        return MHD_NO;
    if (MHD_add_response_header(r, MHD_HTTP_HEADER_ALLOW, allow + 2) !=
            MHD_YES ||
        MHD_add_response_header(r, MHD_HTTP_HEADER_CONTENT_TYPE,
                                "application/json") != MHD_YES) {
        MHD_destroy_response(r);
        return MHD_NO;
    }
    ret = MHD_queue_response(conn, MHD_HTTP_METHOD_NOT_ALLOWED, r);
    MHD_destroy_response(r);
    return ret;
}

const char *wsg_web_field(const struct wsg_web_req *req, const char *name)
{
    size_t i;

    for (i = 0; i < req->nfields; i++)
        if (strcmp(req->fields[i].name, name) == 0)
            return req->fields[i].value;
    return MHD_lookup_connection_value(req->conn, MHD_GET_ARGUMENT_KIND, name);
}

void wsg_web_touch(struct wsg_web *web)
{
    wsg_sched_touch(web->sched, web->g);
}

void wsg_web_done(struct wsg_web *web)
{
    wsg_sched_check(web->sched, web->g);
}

/* ---- endpoints ---- */

static enum MHD_Result serve_state(struct wsg_web *web,
                                   struct wsg_web_req *req)
{
    char json[WSG_STATE_JSON_MAX];
    size_t len;

    /* As the control channel does: the gripper's time brought up to the
     * grid first, its deadline checked after. */
    wsg_web_touch(web);
    len =
        wsg_state_format(json, sizeof json, web->g, web->sched, WSG_STATE_ALL);
    wsg_web_done(web);
    /* A line, as the control channel's: `curl .../state.json` in a
     * terminal leaves the prompt on a line of its own. */
    if (len + 1 < sizeof json)
        json[len++] = '\n';
    return wsg_web_answer(req->conn, MHD_HTTP_OK, "application/json", json,
                          len, 0);
}

/* What the page needs to draw the gripper and name its flags: the
 * stroke, the forces, and every flag's name by bit (null where the
 * manual names none). */
static enum MHD_Result serve_info(struct wsg_web *web, struct wsg_web_req *req)
{
    const struct wsg_axis_config *cfg =
        wsg_axis_cfg(wsg_device_axis(&web->g->dev));
    char buf[WEB_INFO_MAX], key[32];
    size_t used;
    unsigned i;
    int n;

    n = snprintf(buf, sizeof buf,
                 "{\"type\":%u,\"serial\":%lu,\"firmware\":\"2.2.0\","
                 "\"emulator\":\"%s\",\"stroke\":%g,\"min_force\":%g,"
                 "\"nominal_force\":%g,\"overdrive_force\":%g,"
                 "\"max_speed\":%g,\"flag_names\":[",
                 (unsigned)cfg->type, (unsigned long)web->g->dev.info.serial,
                 WSG_VERSION, cfg->stroke, cfg->min_force, cfg->nom_force,
                 cfg->ovr_force, cfg->max_speed);
    if (n < 0 || (size_t)n >= sizeof buf)
        return MHD_NO;
    used = (size_t)n;
    for (i = 0; i < 32; i++) {
        if (wsg_system_flag_names[i]) {
            key[0] = '"';
            wsg_schema_key(wsg_system_flag_names[i], key + 1, sizeof key - 2);
            strcat(key, "\"");
        } else {
            strcpy(key, "null");
        }
        n = snprintf(buf + used, sizeof buf - used, "%s%s", i ? "," : "", key);
        if (n < 0 || (size_t)n >= sizeof buf - used)
            return MHD_NO;
        used += (size_t)n;
    }
    if (used + 3 > sizeof buf)
        return MHD_NO;
    memcpy(buf + used, "]}", 3);
    return wsg_web_answer(req->conn, MHD_HTTP_OK, "application/json", buf,
                          used + 2, 0);
}

/* Whether a and b are the same address (the port aside). */
static int same_peer(const struct sockaddr_storage *a,
                     const struct sockaddr_storage *b)
{
    struct sockaddr_in a4, b4;
    struct sockaddr_in6 a6, b6;

    if (a->ss_family != b->ss_family)
        return 0;
    if (a->ss_family == AF_INET) {
        memcpy(&a4, a, sizeof a4);
        memcpy(&b4, b, sizeof b4);
        return a4.sin_addr.s_addr == b4.sin_addr.s_addr;
    }
    if (a->ss_family == AF_INET6) {
        memcpy(&a6, a, sizeof a6);
        memcpy(&b6, b, sizeof b6);
        return memcmp(&a6.sin6_addr, &b6.sin6_addr, sizeof a6.sin6_addr) == 0;
    }
    return 0;
}

/* A new stream beyond the caps: 503, with when to try again. The page
 * (app.js) does: a browser's EventSource gives up on a 503. */
static enum MHD_Result refuse_stream(struct MHD_Connection *conn,
                                     const char *why)
{
    char body[WSG_WEB_ANSWER_MAX], retry[16];
    int n;

    n = snprintf(body, sizeof body, "{\"error\":\"%s\"}", why);
    if (n < 0 || (size_t)n >= sizeof body)
        return MHD_NO;
    snprintf(retry, sizeof retry, "%u", WSG_WEB_RETRY_AFTER_S);
    return answer_with(conn, MHD_HTTP_SERVICE_UNAVAILABLE, "application/json",
                       body, (size_t)n, 0, MHD_HTTP_HEADER_RETRY_AFTER, retry);
}

static enum MHD_Result serve_events(struct wsg_web *web,
                                    struct wsg_web_req *req)
{
    struct MHD_Connection *conn = req->conn;
    const union MHD_ConnectionInfo *ci;
    struct sockaddr_storage peer;
    const struct web_sub *other;
    const char *last;
    struct MHD_Response *r;
    struct web_sub *sub;
    enum MHD_Result ret;
    size_t mine = 0;

    /* Each stream holds a connection while its page is open: a few
     * clients must not take them all (a peer), nor all the memory. */
    memset(&peer, 0, sizeof peer);
    ci = MHD_get_connection_info(conn, MHD_CONNECTION_INFO_CLIENT_ADDRESS);
    if (ci && ci->client_addr)
        memcpy(&peer, ci->client_addr,
               ci->client_addr->sa_family == AF_INET6
                   ? sizeof(struct sockaddr_in6)
                   : sizeof(struct sockaddr_in));
    for (other = web->subs; other; other = other->next)
        mine += same_peer(&other->peer, &peer);
    if (web->nsubs >= WSG_WEB_STREAMS_MAX)
        return refuse_stream(conn, "too many event streams open: try again "
                                   "later");
    if (mine >= WSG_WEB_PEER_STREAMS_MAX)
        return refuse_stream(conn, "too many event streams open from this "
                                   "address: close a page, or try again "
                                   "later");
    sub = calloc(1, sizeof *sub);
    if (!sub)
        return MHD_NO;
    sub->web = web;
    sub->conn = conn;
    sub->peer = peer;
    sub->hup.fd = -1;
    r = MHD_create_response_from_callback(
        MHD_SIZE_UNKNOWN, WSG_WEB_LOG_EVENT_MAX, sub_read, sub, sub_free);
    if (!r) {
        free(sub);
        return MHD_NO;
    }
    sub->next = web->subs;
    if (web->subs)
        web->subs->prev = sub;
    web->subs = sub;
    if (web->nsubs++ == 0)
        wsg_web_world_watch(web, 1);
    /* The log as far back as it is kept: a page reloaded shows what
     * happened before; a stream reconnected goes on after the last line
     * it had. */
    sub->log_off = web->log_head > WSG_WEB_LOG_RING
                       ? web->log_head - WSG_WEB_LOG_RING
                       : 0;
    last = MHD_lookup_connection_value(conn, MHD_HEADER_KIND, "Last-Event-ID");
    if (last && *last) {
        char *end;
        unsigned long long off = strtoull(last, &end, 10);

        if (*end == '\0' && off <= web->log_head && off > sub->log_off)
            sub->log_off = off;
    }
    /* From here on sub_free, run when r goes, unlinks it. */
    if (MHD_add_response_header(r, MHD_HTTP_HEADER_CONTENT_TYPE,
                                "text/event-stream") != MHD_YES ||
        MHD_add_response_header(r, MHD_HTTP_HEADER_CACHE_CONTROL,
                                "no-store") != MHD_YES) {
        MHD_destroy_response(r);
        return MHD_NO;
    }
    /* It starts with the state as it is now: pushed if it changed while
     * no one was listening, else the newest event, which is current. */
    wsg_sched_touch(web->sched, web->g);
    web_check(web);
    wsg_sched_check(web->sched, web->g);
    ret = MHD_queue_response(conn, MHD_HTTP_OK, r);
    MHD_destroy_response(r);
    return ret;
}

/* STOP and ACK of the page's sidebar: what Stop (22h) and FAST STOP
 * acknowledge (24h) do, on the model, settled before the answer so that
 * a state read after it shows the effect. They are not commands of an
 * interface: the last command's failure flag (D12) is the interfaces'. */
static enum MHD_Result serve_action(struct wsg_web *web,
                                    struct wsg_web_req *req, int ack)
{
    struct wsg_axis *ax = wsg_device_axis(&web->g->dev);
    int fast_stop;

    wsg_web_touch(web);
    fast_stop = (wsg_device_flags(&web->g->dev) & WSG_SF_FAST_STOP) != 0;
    /* In the communication log as the interfaces' 22h and 24h are. */
    wsg_device_event(&web->g->dev, "web",
                     !ack        ? "stop"
                     : fast_stop ? "ack fast-stop cleared"
                                 : "ack nothing to clear");
    if (ack)
        wsg_axis_request_ack(ax);
    else
        wsg_axis_request_stop(ax);
    wsg_axis_settle(ax);
    wsg_web_done(web);
    return wsg_web_json(req->conn, MHD_HTTP_OK, "{\"status\":\"%s\"}",
                        wsg_status_name(WSG_E_SUCCESS));
}

static enum MHD_Result serve_stop(struct wsg_web *web, struct wsg_web_req *req)
{
    return serve_action(web, req, 0);
}

static enum MHD_Result serve_ack(struct wsg_web *web, struct wsg_web_req *req)
{
    return serve_action(web, req, 1);
}

/* The page's files: "/" is index.html. */
static enum MHD_Result serve_asset(struct wsg_web *web,
                                   struct wsg_web_req *req)
{
    const struct wsg_web_asset *a;
    const char *url = strcmp(req->url, "/") == 0 ? "/index.html" : req->url;

    (void)web;
    for (a = wsg_web_assets; a->path; a++)
        if (strcmp(a->path, url) == 0)
            return wsg_web_answer(req->conn, MHD_HTTP_OK, a->type, a->data,
                                  a->len, 1);
    return wsg_web_error(req->conn, MHD_HTTP_NOT_FOUND, "not found");
}

/* Every URL the server answers; the first match wins, and what no other
 * entry names is one of the page's files (the last entry). Only what a
 * route says it takes of a body is kept: a form where it reads one, an
 * upload's bytes; any other body is dropped unread by the handlers. */
static const struct wsg_web_route routes[] = {
    {.path = "/state.json", .methods = WSG_WEB_GET, .serve = serve_state},
    {.path = "/info.json", .methods = WSG_WEB_GET, .serve = serve_info},
    {.path = "/events", .methods = WSG_WEB_GET, .serve = serve_events},
    {.path = "/stop", .methods = WSG_WEB_POST, .serve = serve_stop},
    {.path = "/ack", .methods = WSG_WEB_POST, .serve = serve_ack},
    {.path = "/motion.json",
     .methods = WSG_WEB_POST,
     .form = WSG_WEB_POST,
     .serve = wsg_web_serve_motion_form},
    {.path = "/graspconf.json",
     .methods = WSG_WEB_POST,
     .form = WSG_WEB_POST,
     .serve = wsg_web_serve_graspconf},
    {.path = "/motion",
     .methods = WSG_WEB_POST,
     .form = WSG_WEB_POST,
     .serve = wsg_web_serve_motion},
    {.path = "/settings.json",
     .methods = WSG_WEB_GET | WSG_WEB_POST,
     .form = WSG_WEB_POST,
     .serve = wsg_web_serve_settings},
    {.path = "/scripts.json",
     .methods = WSG_WEB_GET,
     .serve = wsg_web_serve_scripts},
    {.path = "/scripts/",
     .methods = WSG_WEB_GET | WSG_WEB_PUT | WSG_WEB_DELETE,
     .raw = WSG_WEB_PUT,
     .body_max = WSG_WEB_UPLOAD_MAX,
     .serve = wsg_web_serve_script_file},
    {.path = "/script/",
     .methods = WSG_WEB_GET | WSG_WEB_POST,
     .form = WSG_WEB_POST,
     .serve = wsg_web_serve_script_run},
    {.path = "/control",
     .methods = WSG_WEB_POST,
     .form = WSG_WEB_POST,
     .serve = wsg_web_serve_control},
    {.path = "/", .methods = WSG_WEB_GET, .serve = serve_asset},
};

static const struct wsg_web_route *find_route(const char *url,
                                              const char **tail)
{
    size_t i, n;

    for (i = 0; i < sizeof routes / sizeof routes[0]; i++) {
        n = strlen(routes[i].path);
        if (routes[i].path[n - 1] == '/' ? strncmp(url, routes[i].path, n) == 0
                                         : strcmp(url, routes[i].path) == 0) {
            *tail = url + n;
            return &routes[i];
        }
    }
    return NULL; /* cannot happen: "/" takes every path */
}

static enum wsg_web_method method_of(const char *m)
{
    if (strcmp(m, MHD_HTTP_METHOD_GET) == 0 ||
        strcmp(m, MHD_HTTP_METHOD_HEAD) == 0)
        return WSG_WEB_GET;
    if (strcmp(m, MHD_HTTP_METHOD_POST) == 0)
        return WSG_WEB_POST;
    if (strcmp(m, MHD_HTTP_METHOD_PUT) == 0)
        return WSG_WEB_PUT;
    if (strcmp(m, MHD_HTTP_METHOD_DELETE) == 0)
        return WSG_WEB_DELETE;
    return 0;
}

/* The request's Host names this server (web_host.h): a site that points
 * its own name at the address (DNS rebinding) must not get its pages
 * into the origin of this one, which could then read and drive the
 * gripper. Whatever the address it listens on. */
static int foreign_host(const struct wsg_web *web, struct MHD_Connection *conn)
{
    const char *host = MHD_lookup_connection_value(conn, MHD_HEADER_KIND,
                                                   MHD_HTTP_HEADER_HOST);

    return !wsg_web_host_allowed(host, web->d->opt.web_hosts,
                                 web->d->opt.web.addr);
}

/* A request that changes something from another page than this server's
 * own (its Origin is not http:// and this request's Host) is refused: a
 * page anywhere must not stop the gripper through the browser of someone
 * who has this one open. Clients that are not browsers send no Origin. */
static int foreign_origin(const struct wsg_web *web,
                          struct MHD_Connection *conn)
{
    const char *origin, *host;

    origin = MHD_lookup_connection_value(conn, MHD_HEADER_KIND,
                                         MHD_HTTP_HEADER_ORIGIN);
    host = MHD_lookup_connection_value(conn, MHD_HEADER_KIND,
                                       MHD_HTTP_HEADER_HOST);
    return !wsg_web_origin_allowed(origin, host, web->d->opt.web_hosts,
                                   web->d->opt.web.addr);
}

static enum MHD_Result too_large(struct wsg_web_req *req)
{
    char msg[64];

    req->refused = 1;
    snprintf(msg, sizeof msg, "body larger than %zu bytes",
             req->route->body_max ? req->route->body_max : WSG_WEB_BODY_MAX);
    return wsg_web_error(req->conn, MHD_HTTP_CONTENT_TOO_LARGE, msg);
}

/* The first call for a request (its headers): find its route and refuse
 * what it must not do before any of its body is read. */
static enum MHD_Result on_headers(struct wsg_web *web, struct wsg_web_req *req)
{
    const char *clen;
    size_t max;

    if (foreign_host(web, req->conn)) {
        req->refused = 1;
        return wsg_web_error(req->conn, MHD_HTTP_MISDIRECTED_REQUEST,
                             "Host is not a name of this server: it answers "
                             "to localhost, 127.x.x.x, [::1], the address "
                             "it listens on and the names given with "
                             "--web-host");
    }
    if (!(req->route->methods & req->method)) {
        req->refused = 1;
        return refuse_method(req->conn, req->route->methods);
    }
    if (req->method != WSG_WEB_GET && foreign_origin(web, req->conn)) {
        req->refused = 1;
        return wsg_web_error(req->conn, MHD_HTTP_FORBIDDEN,
                             "foreign origin: a change is taken from this "
                             "server's own page (Origin http:// and its "
                             "Host) or from a client that sends no Origin");
    }
    if (req->bad_url) {
        req->refused = 1;
        return wsg_web_error(req->conn, MHD_HTTP_BAD_REQUEST,
                             "a NUL or control character in the URL");
    }
    max = req->route->body_max ? req->route->body_max : WSG_WEB_BODY_MAX;
    clen = MHD_lookup_connection_value(req->conn, MHD_HEADER_KIND,
                                       MHD_HTTP_HEADER_CONTENT_LENGTH);
    if (clen && strtoull(clen, NULL, 10) > max)
        return too_large(req);
    return MHD_YES;
}

/* A piece of the body, kept (up to the route's cap). */
static enum MHD_Result on_body(struct wsg_web_req *req, const char *data,
                               size_t n)
{
    size_t max =
        req->route->body_max ? req->route->body_max : WSG_WEB_BODY_MAX;
    char *p;

    if (req->refused || req->too_big)
        return MHD_YES;             /* the rest of a refused body: dropped */
    if (n > max - req->body_seen) { /* body_seen <= max: no wrap */
        /* A chunked body, whose size no header told: MHD takes an answer
         * only before a body or after all of it (one queued now is
         * refused, and the connection reset). So the rest is read and
         * dropped, and 413 answered at its end; the request's deadline
         * bounds how long that may take. */
        req->too_big = 1;
        free(req->body);
        req->body = NULL;
        req->body_len = req->body_cap = 0;
        return MHD_YES;
    }
    req->body_seen += n;
    /* A body the route does not take: not kept, never decoded. */
    if (!((req->route->form | req->route->raw) & req->method))
        return MHD_YES;
    if (req->body_len + n + 1 > req->body_cap) {
        size_t cap = req->body_cap ? req->body_cap * 2 : 1024;

        while (cap < req->body_len + n + 1)
            cap *= 2;
        p = realloc(req->body, cap);
        if (!p)
            return MHD_NO;
        req->body = p;
        req->body_cap = cap;
    }
    memcpy(req->body + req->body_len, data, n);
    req->body_len += n;
    req->body[req->body_len] = '\0';
    return MHD_YES;
}

/* The body of a route that takes a form: decoded when it is one (its
 * media type, exactly), refused when it is something else. NULL to go
 * on to the handler, else why it is refused, with its status. */
static const char *take_form(struct wsg_web_req *req, unsigned *status)
{
    const char *type;
    int r;

    /* No body: the fields, if any, are in the query. */
    if (!(req->route->form & req->method) || req->body_len == 0)
        return NULL;
    type = MHD_lookup_connection_value(req->conn, MHD_HEADER_KIND,
                                       MHD_HTTP_HEADER_CONTENT_TYPE);
    *status = MHD_HTTP_BAD_REQUEST;
    if (!wsg_web_media_is(type, MHD_HTTP_POST_ENCODING_FORM_URLENCODED)) {
        *status = MHD_HTTP_UNSUPPORTED_MEDIA_TYPE;
        return "the body must be a form: Content-Type: "
               "application/x-www-form-urlencoded";
    }
    r = wsg_web_form_decode(req);
    if (r == -EILSEQ)
        return "a NUL or control character in a form field";
    if (r < 0) {
        req->overfull = 1;
        return "too many form fields, or one too long";
    }
    return NULL;
}

/* MHD has read a request's first line: the request starts here, its URL
 * still as sent, before MHD decodes it (a "%00" cuts the decoded one
 * short, unseen). What it returns is the request's *req_cls. */
static void *on_uri(void *cls, const char *uri, struct MHD_Connection *conn)
{
    struct wsg_web_req *req = calloc(1, sizeof *req);

    (void)cls;
    if (!req)
        return NULL; /* on_request closes the connection */
    req->conn = conn;
    req->bad_url = wsg_web_url_bad(uri ? uri : "");
    return req;
}

/* MHD calls this once with the headers, then with each piece of the body,
 * then once more with none: the request is answered then. */
static enum MHD_Result on_request(void *cls, struct MHD_Connection *conn,
                                  const char *url, const char *method,
                                  const char *version, const char *upload,
                                  size_t *upload_size, void **req_cls)
{
    struct wsg_web *web = cls;
    struct wsg_web_req *req = *req_cls;
    enum MHD_Result ret;
    const char *why;
    unsigned status;
    size_t n;

    (void)version;
    if (!req)
        return MHD_NO; /* no memory for it (on_uri) */
    if (!req->route) {
        req->conn = conn;
        req->url = url;
        req->method = method_of(method);
        req->route = find_route(url, &req->tail);
        ret = on_headers(web, req);
        if (req->refused)
            conn_clock(web, conn, 0); /* answered */
        return ret;
    }
    if (*upload_size) {
        n = *upload_size;
        *upload_size = 0;
        return on_body(req, upload, n);
    }
    if (req->refused)
        return MHD_YES;
    /* All of it is here: answered from now on, no longer received. */
    conn_clock(web, conn, 0);
    if (req->too_big)
        return too_large(req);
    if (!req->body) {
        /* An empty body still reads as "". */
        req->body = calloc(1, 1);
        if (!req->body)
            return MHD_NO;
    }
    why = take_form(req, &status);
    if (why)
        return wsg_web_error(conn, status, why);
    return req->route->serve(web, req);
}

static void on_completed(void *cls, struct MHD_Connection *conn,
                         void **req_cls, enum MHD_RequestTerminationCode why)
{
    struct wsg_web_req *req = *req_cls;

    (void)why;
    /* Its answer is sent: the next request's clock starts. */
    conn_clock(cls, conn, mono_ns());
    if (req)
        free(req->body);
    free(req);
    *req_cls = NULL;
}

/* MHD's own messages (a client's malformed request, a failed send), on
 * stderr as the daemon's are. */
static void on_log(void *cls, const char *fmt, va_list ap)
{
    char msg[256];
    size_t n;

    (void)cls;
    vsnprintf(msg, sizeof msg, fmt, ap);
    n = strlen(msg);
    while (n > 0 && msg[n - 1] == '\n')
        msg[--n] = '\0';
    /* A page closed while its event stream was open: MHD cannot end the
     * stream on the gone socket. That is how every page leaves. */
    if (strstr(msg, "socket is no longer available"))
        return;
    fprintf(stderr, "wsgemu: web: %s\n", msg);
}

/* ---- the service ---- */

int wsg_web_describe(const struct wsg_web *web, char *buf, size_t len)
{
    int r = snprintf(buf, len, "%s", web->local);

    return r < 0 || (size_t)r >= len ? -ENOSPC : 0;
}

void wsg_web_close(struct wsg_web *web)
{
    struct web_sub *sub;
    int i;

    if (!web)
        return;
    if (web->hooked)
        wsg_reactor_forget(web->reactor, web_after, web);
    if (web->mhd) {
        /* MHD refuses to stop with a connection suspended, and a resumed
         * one leaves its list only in MHD_run: each stream is ended
         * (gone), resumed, and run to its close. */
        for (i = 0; i < WEB_RUN_ROUNDS && web->subs; i++) {
            for (sub = web->subs; sub; sub = sub->next) {
                sub->gone = 1;
                sub_resume(sub);
            }
            web->in_run = 1; /* no kick: this loop is the next run */
            MHD_run(web->mhd);
            web->in_run = 0;
        }
        MHD_stop_daemon(web->mhd);
    }
    /* MHD told of each connection's close as it stopped; were one left,
     * its clock goes with the server. */
    while (web->conns) {
        struct web_conn *c = web->conns;

        web->conns = c->next;
        free(c);
    }
    if (web->mhd_watch.fd >= 0)
        wsg_reactor_del(web->reactor, &web->mhd_watch);
    if (web->timer.fd >= 0) {
        wsg_reactor_del(web->reactor, &web->timer);
        close(web->timer.fd);
    }
    wsg_web_world_close(web);
    free(web);
}

int wsg_web_open(struct wsg_web **out, struct wsg_daemon *d, char *err,
                 size_t errlen)
{
    struct wsg_reactor *reactor = &d->reactor;
    const struct wsg_endpoint *ep = &d->opt.web;
    const union MHD_DaemonInfo *info;
    struct wsg_web *web;
    int fd = -1, mine, r;

    *out = NULL;
    web = calloc(1, sizeof *web);
    if (!web) {
        snprintf(err, errlen, "cannot serve the web page: %s",
                 strerror(ENOMEM));
        return -ENOMEM;
    }
    web->d = d;
    web->reactor = reactor;
    web->sched = &d->sched;
    web->g = &d->sched.grippers[0];
    web->mhd_watch.fd = -1;
    web->timer.fd = -1;
    r = wsg_web_world_open(web);
    if (r < 0) {
        snprintf(err, errlen, "cannot serve the web page: %s", strerror(-r));
        goto fail;
    }
    fd = wsg_transport_listen_tcp(ep, (int)WSG_WEB_CLIENTS_MAX, "web",
                                  web->local, sizeof web->local, err, errlen);
    if (fd < 0) {
        r = fd;
        goto fail;
    }
    /* MHD closes the socket it is given when it stops, and may or may not
     * when it fails to start: it gets a copy, this one is closed here
     * either way. */
    mine = fd;
    fd = fcntl(mine, F_DUPFD_CLOEXEC, 0);
    r = fd < 0 ? -errno : 0;
    close(mine);
    if (r < 0) {
        snprintf(err, errlen, "cannot serve the web page on %s: %s",
                 web->local, strerror(-r));
        goto fail;
    }
    /* External epoll: no thread, MHD_run from the reactor. Suspending and
     * resuming the event streams brings MHD's eventfd along. */
    web->mhd = MHD_start_daemon(
        MHD_USE_EPOLL | MHD_ALLOW_SUSPEND_RESUME | MHD_USE_ERROR_LOG, 0, NULL,
        NULL, on_request, web, MHD_OPTION_EXTERNAL_LOGGER, on_log, NULL,
        MHD_OPTION_LISTEN_SOCKET, fd, MHD_OPTION_URI_LOG_CALLBACK, on_uri,
        NULL, MHD_OPTION_CONNECTION_LIMIT, (unsigned)WSG_WEB_CLIENTS_MAX,
        MHD_OPTION_CONNECTION_TIMEOUT, (unsigned)WEB_IDLE_TIMEOUT_S,
        MHD_OPTION_NOTIFY_COMPLETED, on_completed, web,
        MHD_OPTION_NOTIFY_CONNECTION, on_connection, web,
        MHD_OPTION_PER_IP_CONNECTION_LIMIT, (unsigned)WSG_WEB_PEER_CLIENTS_MAX,
        MHD_OPTION_END);
    if (!web->mhd) {
        r = -EIO;
        snprintf(err, errlen,
                 "cannot serve the web page on %s: libmicrohttpd did not "
                 "start",
                 web->local);
        goto fail;
    }
    fd = -1; /* MHD's now */
    info = MHD_get_daemon_info(web->mhd, MHD_DAEMON_INFO_EPOLL_FD);
    if (!info) {
        r = -EIO;
        snprintf(err, errlen,
                 "cannot serve the web page on %s: no epoll descriptor",
                 web->local);
        goto fail;
    }
    wsg_watch_init(&web->mhd_watch, info->epoll_fd, on_mhd, web);
    r = wsg_reactor_add(reactor, &web->mhd_watch, EPOLLIN);
    if (r < 0) {
        web->mhd_watch.fd = -1;
        snprintf(err, errlen, "cannot serve the web page on %s: epoll: %s",
                 web->local, strerror(-r));
        goto fail;
    }
    r = timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
    if (r < 0) {
        r = -errno;
        snprintf(err, errlen, "cannot serve the web page on %s: timerfd: %s",
                 web->local, strerror(-r));
        goto fail;
    }
    wsg_watch_init(&web->timer, r, on_timer, web);
    r = wsg_reactor_add(reactor, &web->timer, EPOLLIN);
    if (r < 0) {
        close(web->timer.fd);
        web->timer.fd = -1;
        snprintf(err, errlen, "cannot serve the web page on %s: epoll: %s",
                 web->local, strerror(-r));
        goto fail;
    }
    r = wsg_reactor_after(reactor, web_after, web);
    if (r < 0) {
        snprintf(err, errlen, "cannot serve the web page on %s: %s",
                 web->local, strerror(-r));
        goto fail;
    }
    web->hooked = 1;
    *out = web;
    return 0;

fail:
    if (fd >= 0)
        close(fd);
    wsg_web_close(web);
    return r;
}
