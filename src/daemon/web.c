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

#include "web.h"

#include <errno.h>
#include <fcntl.h>
#include <microhttpd.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

#include "gripper.h"
#include "state.h"
#include "web_assets.h"
#include "wsg/schema.h"

#define NS_PER_S  1000000000ull
#define NS_PER_MS 1000000ull
/* "event: state\ndata: " and the blank line that ends an event. */
#define WEB_EVENT_MAX (WSG_STATE_JSON_MAX + 32u)
/* An HTTP connection that sends nothing is closed after this; a browser
 * keeps one open after loading the page. A suspended event stream does
 * not time out (MHD stops its clock while suspended). */
#define WEB_IDLE_TIMEOUT_S 60u
/* MHD_run rounds in a row while resumes come in during them (a new
 * stream's first event): one more does it, the rest only bound the loop;
 * past them the timer runs MHD at once. Closing uses as many to let the
 * resumed streams end. */
#define WEB_RUN_ROUNDS 4
#define WEB_INFO_MAX   1536u

struct web_sub;

struct wsg_web {
    struct wsg_reactor *reactor;
    struct wsg_sched *sched;
    struct wsg_gripper *g; /* the gripper the page shows: the first */
    struct MHD_Daemon *mhd;
    struct wsg_watch mhd_watch; /* MHD's epoll descriptor; fd -1: none */
    struct wsg_watch timer;     /* timerfd; fd -1: none */
    int hooked;                 /* the after-batch hook is added */
    int in_run;                 /* inside MHD_run */
    int kicked;                 /* a connection resumed: MHD must run */
    char local[WSG_ADDR_LEN];
    /* CLOCK_MONOTONIC deadlines, 0 for none: MHD wants to run by mhd_due
     * (a connection's timeout, or work it left for the next round), a
     * change waits to be pushed at push_due; the timer is armed for the
     * earlier one (armed). */
    uint64_t mhd_due;
    uint64_t push_due;
    uint64_t armed;
    /* The event stream: its subscribers, and the newest event. */
    struct web_sub *subs;
    size_t nsubs;
    uint64_t seq;    /* the newest event's number; 0: none yet */
    uint64_t pushed; /* when it was made */
    size_t key_len;
    char key[WSG_STATE_JSON_MAX]; /* its state without the time */
    size_t event_len;
    char event[WEB_EVENT_MAX];
};

/* One client of /events. It sends its own copy of an event, so a newer
 * one can be made while it is half sent; a slow client skips to the
 * newest, never queues. */
struct web_sub {
    struct wsg_web *web;
    struct MHD_Connection *conn;
    struct wsg_watch hup; /* its socket while suspended; fd -1: not */
    int suspended;
    int gone;     /* hung up: end the stream */
    uint64_t seq; /* the event it has (or is sending) */
    size_t len, off;
    char buf[WEB_EVENT_MAX];
    struct web_sub *prev, *next;
};

/* What a request carries from one call of the handler to the next. */
struct web_req {
    size_t body; /* bytes of body received */
    int refused; /* answered already (a body too large) */
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
        if (sub->seq == web->seq) {
            /* Returning 0 has MHD ask again at its next run: suspended,
             * it does not run for this connection until resumed. */
            sub_suspend(sub);
            return 0;
        }
        memcpy(sub->buf, web->event, web->event_len);
        sub->len = web->event_len;
        sub->off = 0;
        sub->seq = web->seq;
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
}

/* A new event from the gripper's state now (key: it without its time),
 * and every stream that waits for one resumed. */
static void web_push(struct wsg_web *web, const char *key, size_t key_len,
                     uint64_t now)
{
    char json[WSG_STATE_JSON_MAX];
    struct web_sub *sub;
    int n;

    wsg_state_format(json, sizeof json, web->g, web->sched, WSG_STATE_ALL);
    n = snprintf(web->event, sizeof web->event, "event: state\ndata: %s\n\n",
                 json);
    if (n < 0 || (size_t)n >= sizeof web->event)
        return; /* cannot happen: the room is the state's and the frame's */
    memcpy(web->key, key, key_len);
    web->key_len = key_len;
    web->event_len = (size_t)n;
    web->seq++;
    web->pushed = now;
    for (sub = web->subs; sub; sub = sub->next)
        sub_resume(sub);
    web_kick(web);
}

/* Push the state if it changed, or have it pushed when the last push is
 * WSG_WEB_PUSH_MIN_NS old. */
static void web_check(struct wsg_web *web)
{
    char key[WSG_STATE_JSON_MAX];
    size_t len;
    uint64_t now;

    if (!web->nsubs || web->push_due)
        return;
    len = wsg_state_format(key, sizeof key, web->g, web->sched,
                           WSG_STATE_NO_TIME);
    if (web->seq && len == web->key_len && memcmp(key, web->key, len) == 0)
        return;
    now = mono_ns();
    if (web->seq && now - web->pushed < WSG_WEB_PUSH_MIN_NS) {
        web->push_due = web->pushed + WSG_WEB_PUSH_MIN_NS;
        web_arm(web);
        return;
    }
    web_push(web, key, len, now);
}

/* After each batch of the reactor's events. */
static void web_after(void *ctx)
{
    web_check(ctx);
}

/* ---- answers ---- */

static enum MHD_Result answer(struct MHD_Connection *conn, unsigned status,
                              const char *type, const void *body, size_t len,
                              enum MHD_ResponseMemoryMode mode,
                              const char *cache)
{
    struct MHD_Response *r;
    enum MHD_Result ret;

    /* MHD_RESPMEM_PERSISTENT does not write to body: the cast only
     * meets the old prototype. */
    r = MHD_create_response_from_buffer(len, (void *)(uintptr_t)body, mode);
    if (!r)
        return MHD_NO;
    if (MHD_add_response_header(r, MHD_HTTP_HEADER_CONTENT_TYPE, type) !=
            MHD_YES ||
        MHD_add_response_header(r, MHD_HTTP_HEADER_CACHE_CONTROL, cache) !=
            MHD_YES ||
        MHD_add_response_header(r, "X-Content-Type-Options", "nosniff") !=
            MHD_YES) {
        MHD_destroy_response(r);
        return MHD_NO;
    }
    ret = MHD_queue_response(conn, status, r);
    MHD_destroy_response(r);
    return ret;
}

/* A short JSON answer: {"error":"..."} and the like. */
static enum MHD_Result answer_json(struct MHD_Connection *conn,
                                   unsigned status, const char *fmt, ...)
{
    char buf[WEB_INFO_MAX];
    va_list ap;
    int n;

    va_start(ap, fmt);
    n = vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    if (n < 0 || (size_t)n >= sizeof buf)
        return MHD_NO;
    return answer(conn, status, "application/json", buf, (size_t)n,
                  MHD_RESPMEM_MUST_COPY, "no-store");
}

static enum MHD_Result refuse_method(struct MHD_Connection *conn,
                                     const char *allow)
{
    struct MHD_Response *r;
    enum MHD_Result ret;
    static const char body[] = "{\"error\":\"method not allowed\"}";

    r = MHD_create_response_from_buffer(sizeof body - 1, (void *)body,
                                        MHD_RESPMEM_PERSISTENT);
    if (!r)
        return MHD_NO;
    if (MHD_add_response_header(r, MHD_HTTP_HEADER_ALLOW, allow) != MHD_YES ||
        MHD_add_response_header(r, MHD_HTTP_HEADER_CONTENT_TYPE,
                                "application/json") != MHD_YES) {
        MHD_destroy_response(r);
        return MHD_NO;
    }
    ret = MHD_queue_response(conn, MHD_HTTP_METHOD_NOT_ALLOWED, r);
    MHD_destroy_response(r);
    return ret;
}

/* ---- endpoints ---- */

static enum MHD_Result serve_state(struct wsg_web *web,
                                   struct MHD_Connection *conn)
{
    char json[WSG_STATE_JSON_MAX];
    size_t len;

    /* As the control channel does: the gripper's time brought up to the
     * grid first, its deadline checked after. */
    wsg_sched_touch(web->sched, web->g);
    len =
        wsg_state_format(json, sizeof json, web->g, web->sched, WSG_STATE_ALL);
    wsg_sched_check(web->sched, web->g);
    return answer(conn, MHD_HTTP_OK, "application/json", json, len,
                  MHD_RESPMEM_MUST_COPY, "no-store");
}

/* What the page needs to draw the gripper and name its flags: the
 * stroke, the forces, and every flag's name by bit (null where the
 * manual names none). */
static enum MHD_Result serve_info(struct wsg_web *web,
                                  struct MHD_Connection *conn)
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
    return answer(conn, MHD_HTTP_OK, "application/json", buf, used + 2,
                  MHD_RESPMEM_MUST_COPY, "no-store");
}

static enum MHD_Result serve_events(struct wsg_web *web,
                                    struct MHD_Connection *conn)
{
    struct MHD_Response *r;
    struct web_sub *sub;
    enum MHD_Result ret;

    sub = calloc(1, sizeof *sub);
    if (!sub)
        return MHD_NO;
    sub->web = web;
    sub->conn = conn;
    sub->hup.fd = -1;
    r = MHD_create_response_from_callback(MHD_SIZE_UNKNOWN, WEB_EVENT_MAX,
                                          sub_read, sub, sub_free);
    if (!r) {
        free(sub);
        return MHD_NO;
    }
    sub->next = web->subs;
    if (web->subs)
        web->subs->prev = sub;
    web->subs = sub;
    web->nsubs++;
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
                                    struct MHD_Connection *conn, int ack)
{
    struct wsg_axis *ax = wsg_device_axis(&web->g->dev);

    wsg_sched_touch(web->sched, web->g);
    if (ack)
        wsg_axis_request_ack(ax);
    else
        wsg_axis_request_stop(ax);
    wsg_axis_settle(ax);
    wsg_sched_check(web->sched, web->g);
    return answer_json(conn, MHD_HTTP_OK, "{\"status\":\"%s\"}",
                       wsg_status_name(WSG_E_SUCCESS));
}

static const struct wsg_web_asset *find_asset(const char *url)
{
    const struct wsg_web_asset *a;

    if (strcmp(url, "/") == 0)
        url = "/index.html";
    for (a = wsg_web_assets; a->path; a++)
        if (strcmp(a->path, url) == 0)
            return a;
    return NULL;
}

/* A POST from another site's page (its Origin is not this server) is
 * refused: a page anywhere must not stop the gripper through the
 * browser of someone who has this one open. Clients that are not
 * browsers send no Origin. */
static int foreign_origin(struct MHD_Connection *conn)
{
    const char *origin, *host;

    origin = MHD_lookup_connection_value(conn, MHD_HEADER_KIND,
                                         MHD_HTTP_HEADER_ORIGIN);
    if (!origin)
        return 0;
    host = MHD_lookup_connection_value(conn, MHD_HEADER_KIND,
                                       MHD_HTTP_HEADER_HOST);
    return !host || strncmp(origin, "http://", 7) != 0 ||
           strcmp(origin + 7, host) != 0;
}

static enum MHD_Result route(struct wsg_web *web, struct MHD_Connection *conn,
                             const char *url, const char *method)
{
    int get = strcmp(method, MHD_HTTP_METHOD_GET) == 0 ||
              strcmp(method, MHD_HTTP_METHOD_HEAD) == 0;
    int post = strcmp(method, MHD_HTTP_METHOD_POST) == 0;
    const struct wsg_web_asset *a;

    if (strcmp(url, "/state.json") == 0)
        return get ? serve_state(web, conn) : refuse_method(conn, "GET, HEAD");
    if (strcmp(url, "/info.json") == 0)
        return get ? serve_info(web, conn) : refuse_method(conn, "GET, HEAD");
    if (strcmp(url, "/events") == 0)
        return strcmp(method, MHD_HTTP_METHOD_GET) == 0
                   ? serve_events(web, conn)
                   : refuse_method(conn, "GET");
    if (strcmp(url, "/stop") == 0 || strcmp(url, "/ack") == 0) {
        if (!post)
            return refuse_method(conn, "POST");
        if (foreign_origin(conn))
            return answer_json(conn, MHD_HTTP_FORBIDDEN,
                               "{\"error\":\"foreign origin\"}");
        return serve_action(web, conn, url[1] == 'a');
    }
    a = find_asset(url);
    if (a)
        return get ? answer(conn, MHD_HTTP_OK, a->type, a->data, a->len,
                            MHD_RESPMEM_PERSISTENT, "no-cache")
                   : refuse_method(conn, "GET, HEAD");
    return answer_json(conn, MHD_HTTP_NOT_FOUND, "{\"error\":\"not found\"}");
}

/* MHD calls this once with the headers, then with each piece of the body,
 * then once more with none: the request is answered then. A body longer
 * than WSG_WEB_BODY_MAX is refused as soon as that is known. */
static enum MHD_Result on_request(void *cls, struct MHD_Connection *conn,
                                  const char *url, const char *method,
                                  const char *version, const char *upload,
                                  size_t *upload_size, void **req_cls)
{
    struct wsg_web *web = cls;
    struct web_req *req = *req_cls;
    const char *clen;

    (void)version;
    (void)upload;
    if (!req) {
        req = calloc(1, sizeof *req);
        if (!req)
            return MHD_NO;
        *req_cls = req;
        clen = MHD_lookup_connection_value(conn, MHD_HEADER_KIND,
                                           MHD_HTTP_HEADER_CONTENT_LENGTH);
        if (clen && strtoull(clen, NULL, 10) > WSG_WEB_BODY_MAX) {
            req->refused = 1;
            return answer_json(conn, MHD_HTTP_CONTENT_TOO_LARGE,
                               "{\"error\":\"body larger than %u bytes\"}",
                               WSG_WEB_BODY_MAX);
        }
        return MHD_YES;
    }
    if (*upload_size) {
        req->body += *upload_size;
        *upload_size = 0;
        if (req->body > WSG_WEB_BODY_MAX && !req->refused) {
            req->refused = 1;
            return answer_json(conn, MHD_HTTP_CONTENT_TOO_LARGE,
                               "{\"error\":\"body larger than %u bytes\"}",
                               WSG_WEB_BODY_MAX);
        }
        return MHD_YES;
    }
    if (req->refused)
        return MHD_YES;
    return route(web, conn, url, method);
}

static void on_completed(void *cls, struct MHD_Connection *conn,
                         void **req_cls, enum MHD_RequestTerminationCode why)
{
    (void)cls;
    (void)conn;
    (void)why;
    free(*req_cls);
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
    if (web->mhd_watch.fd >= 0)
        wsg_reactor_del(web->reactor, &web->mhd_watch);
    if (web->timer.fd >= 0) {
        wsg_reactor_del(web->reactor, &web->timer);
        close(web->timer.fd);
    }
    free(web);
}

int wsg_web_open(struct wsg_web **out, struct wsg_reactor *reactor,
                 struct wsg_sched *sched, const struct wsg_endpoint *ep,
                 char *err, size_t errlen)
{
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
    web->reactor = reactor;
    web->sched = sched;
    web->g = &sched->grippers[0];
    web->mhd_watch.fd = -1;
    web->timer.fd = -1;
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
        MHD_OPTION_LISTEN_SOCKET, fd, MHD_OPTION_CONNECTION_LIMIT,
        (unsigned)WSG_WEB_CLIENTS_MAX, MHD_OPTION_CONNECTION_TIMEOUT,
        (unsigned)WEB_IDLE_TIMEOUT_S, MHD_OPTION_NOTIFY_COMPLETED,
        on_completed, NULL, MHD_OPTION_END);
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
