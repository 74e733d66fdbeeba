/*
 * What the parts of the web page's server share (private to src/daemon/web):
 * the server's state, a request as its handler sees it (its body read in
 * full, its form fields), the answers, and each part's handlers, which
 * server.c's route table names. server.c runs libmicrohttpd and the event
 * stream; forms.c the motion and grasping forms; settings.c the settings;
 * scripts.c the script directory and the script host; world.c the
 * communication log and the control channel's scenario commands.
 */
#ifndef WSG_DAEMON_WEB_IMPL_H
#define WSG_DAEMON_WEB_IMPL_H

#include <microhttpd.h>
#include <stddef.h>
#include <stdint.h>

#include "control.h"
#include "daemon.h"
#include "state.h"
#include "web.h"

/* "event: state\ndata: " and the blank line that ends an event. */
#define WSG_WEB_EVENT_MAX (WSG_STATE_JSON_MAX + 32u)
/* Form fields a request may carry, and their longest name and value. */
#define WSG_WEB_FIELDS_MAX 32u
#define WSG_WEB_NAME_MAX   32u
#define WSG_WEB_VALUE_MAX  256u
/* A short JSON answer ({"error":"..."} and the like). */
#define WSG_WEB_ANSWER_MAX 2048u
/* The communication log's newest lines, kept for the event stream: a
 * client that falls further behind skips what it missed. */
#define WSG_WEB_LOG_RING (256u * 1024u)
/* The largest "log" event: as many whole lines as fit. */
#define WSG_WEB_LOG_EVENT_MAX (16u * 1024u)

struct web_sub;
struct web_conn;

struct wsg_web {
    struct wsg_daemon *d;
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
     * change waits to be pushed at push_due, a request's deadline passes
     * at conn_due; the timer is armed for the earliest (armed). */
    uint64_t mhd_due;
    uint64_t push_due;
    uint64_t conn_due; /* the first request's deadline (server.c) */
    uint64_t armed;
    /* The connections, each with the time its request started. */
    struct web_conn *conns;
    /* The event stream: its subscribers, and the newest event. */
    struct web_sub *subs;
    size_t nsubs;
    uint64_t seq;    /* the newest event's number; 0: none yet */
    uint64_t pushed; /* when it was made */
    size_t key_len;
    char key[WSG_STATE_JSON_MAX]; /* its state without the time */
    size_t event_len;
    char event[WSG_WEB_EVENT_MAX];
    /* The communication log while someone watches (world.c feeds it):
     * log_head bytes were ever written, the last WSG_WEB_LOG_RING of
     * them are in log_ring at log_head % WSG_WEB_LOG_RING; log_pushed of
     * them were offered to the streams. */
    char *log_ring;
    uint64_t log_head;
    uint64_t log_pushed;
    /* The control channel's commands, run for the page (world.c). */
    struct wsg_ctl *ctl;
    struct wsg_ctl_session ctl_session;
    char ctl_answer[WSG_WEB_ANSWER_MAX];
    size_t ctl_answer_len;
    /* The startup script the page set (settings.c): the options point
     * here once it has, as they point at argv or their own buffer. */
    char script_path[WSG_WEB_VALUE_MAX];
};

enum wsg_web_method {
    WSG_WEB_GET = 1u << 0, /* HEAD too */
    WSG_WEB_POST = 1u << 1,
    WSG_WEB_PUT = 1u << 2,
    WSG_WEB_DELETE = 1u << 3
};

struct wsg_web_field {
    char name[WSG_WEB_NAME_MAX];
    char value[WSG_WEB_VALUE_MAX];
};

/* A request as its handler sees it: its body in full (NUL-terminated,
 * body_len bytes), and for a form (application/x-www-form-urlencoded)
 * its fields, decoded. */
struct wsg_web_req {
    struct MHD_Connection *conn;
    const char *url;
    const char *tail; /* of a route that is a prefix: the URL after it */
    enum wsg_web_method method;
    const struct wsg_web_route *route;
    char *body;
    size_t body_len;
    size_t body_cap;
    int refused; /* answered already (a body too large) */
    int too_big; /* a chunked body past the cap: dropped, 413 at its end */
    int bad_url; /* its URL decodes to a control character: 400 */
    size_t body_seen; /* bytes of body received, kept or not */
    int overfull;     /* a field too long, or too many */
    size_t nfields;
    struct wsg_web_field fields[WSG_WEB_FIELDS_MAX];
};

typedef enum MHD_Result (*wsg_web_serve_fn)(struct wsg_web *web,
                                            struct wsg_web_req *req);

/* One entry of server.c's route table. */
struct wsg_web_route {
    const char *path; /* the URL; ending in '/': every URL under it */
    unsigned methods; /* enum wsg_web_method bits */
    /* The methods whose body is a form, decoded into the fields; those
     * whose body is kept as it is (an upload). Any other body is read
     * (up to the cap) and dropped, never decoded. */
    unsigned form;
    unsigned raw;
    size_t body_max; /* the largest body it takes; 0: the default */
    wsg_web_serve_fn serve;
};

/* ---- answers (server.c) ---- */

/* body (len bytes) with its Content-Type; copied unless static. */
enum MHD_Result wsg_web_answer(struct MHD_Connection *conn, unsigned status,
                               const char *type, const void *body, size_t len,
                               int is_static);
/* A JSON answer from a format. */
enum MHD_Result wsg_web_json(struct MHD_Connection *conn, unsigned status,
                             const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
/* {"error":"<msg>"} with status, msg escaped as a JSON string. */
enum MHD_Result wsg_web_error(struct MHD_Connection *conn, unsigned status,
                              const char *msg);
/* A field of the request's form (or its query string); NULL if absent. */
const char *wsg_web_field(const struct wsg_web_req *req, const char *name);
/* s as a JSON string body (no quotes) into buf; returns its length, or
 * cap when it does not fit (buf then holds a cut that is still valid:
 * whole escapes and whole characters). Bytes that are not UTF-8 become
 * U+FFFD, so the answer is UTF-8 whatever s holds. */
size_t wsg_web_escape(char *buf, size_t cap, const char *s, size_t len);
/* n, or less so that s's first bytes end with a whole UTF-8 character
 * (not in the middle of one; bytes that are not UTF-8 count as whole). */
size_t wsg_web_utf8_whole(const char *s, size_t n);
/* Bring the gripper's time up to date before acting on it, and have it
 * rescheduled after (as the control channel does). */
void wsg_web_touch(struct wsg_web *web);
void wsg_web_done(struct wsg_web *web);

/* ---- what a request carries (request.c) ---- */

/* 1 when the Content-Type value is the media type type: the same name
 * (case aside), then nothing or its parameters (";charset=UTF-8"). */
int wsg_web_media_is(const char *value, const char *type);
/* 1 when the URL (path and query, as sent: before percent-decoding)
 * holds a NUL or a control character, raw or percent-encoded. */
int wsg_web_url_bad(const char *uri);
/* req's body, a url-encoded form, into req's fields: 0; -E2BIG for too
 * many fields or one too long, -EILSEQ for a NUL or control character in
 * a name or a value. */
int wsg_web_form_decode(struct wsg_web_req *req);

/* ---- files (files.c) ---- */

/* Replace the file name (relative to dfd, or AT_FDCWD) with len bytes of
 * buf, through the temporary file tmp beside it: written, synced and
 * renamed over it; links are not followed. like: the file whose owner
 * and mode the new one takes (-EPERM when the owner cannot be given), or
 * NULL for the daemon's user and 0644 less the umask. 0 or -errno
 * (nothing is replaced). */
struct stat;
int wsg_web_replace_file(int dfd, const char *name, const char *tmp,
                         const void *buf, size_t len, const struct stat *like);

/* ---- the parts' handlers ---- */

/* forms.c: the motion and grasping forms, and the page's motion buttons. */
enum MHD_Result wsg_web_serve_motion_form(struct wsg_web *web,
                                          struct wsg_web_req *req);
enum MHD_Result wsg_web_serve_graspconf(struct wsg_web *web,
                                        struct wsg_web_req *req);
enum MHD_Result wsg_web_serve_motion(struct wsg_web *web,
                                     struct wsg_web_req *req);
/* settings.c */
enum MHD_Result wsg_web_serve_settings(struct wsg_web *web,
                                       struct wsg_web_req *req);
/* Check the settings fields (the config file's keys, as POST
 * /settings.json takes them) and, all of them good, save them to the
 * config file (save) and apply them to every gripper. 0; -EINVAL for a
 * bad field or no config file to save to, another -errno when saving
 * failed; then nothing changed and err says why. */
int wsg_web_settings_apply(struct wsg_web *web,
                           const struct wsg_web_field *fields, size_t n,
                           int save, char *err, size_t errcap);
/* scripts.c */
enum MHD_Result wsg_web_serve_scripts(struct wsg_web *web,
                                      struct wsg_web_req *req);
enum MHD_Result wsg_web_serve_script_file(struct wsg_web *web,
                                          struct wsg_web_req *req);
enum MHD_Result wsg_web_serve_script_run(struct wsg_web *web,
                                         struct wsg_web_req *req);
/* Run name, a script of the script directory (a plain NAME.lua, as the
 * file manager takes it), on h: checked and opened in one step, run from
 * that descriptor. 0, or the HTTP status of the refusal with the reason
 * in why (400 a bad name, 404, 403 a link or not a file, 409 no script
 * directory or one runs already, 422 it does not compile or failed as it
 * started). The caller brings the gripper's time up to date around it. */
unsigned wsg_web_script_start(struct wsg_web *web, struct wsg_script *h,
                              const char *name, char *why, size_t cap);
/* world.c: the control channel's commands and the communication log. */
int wsg_web_world_open(struct wsg_web *web);
void wsg_web_world_close(struct wsg_web *web);
/* The first stream opened (on 1) or the last closed (0): the log is fed
 * only while someone watches. */
void wsg_web_world_watch(struct wsg_web *web, int on);
/* A log line (with its newline) into the ring; pushed by the next
 * check. */
void wsg_web_log_line(struct wsg_web *web, const char *line, size_t len);
enum MHD_Result wsg_web_serve_control(struct wsg_web *web,
                                      struct wsg_web_req *req);

#endif
