/*
 * The control channel (--control [ADDR:]PORT): a line protocol on a TCP
 * port of its own, for tests and people with nc, that changes the world
 * around the gripper (a part, an obstacle, faults), controls simulated time
 * and reports the model's state. It has no sessions and speaks no gripper
 * protocol: it is a service of the daemon on the reactor, acting on the
 * grippers through the scheduler (which brings a gripper's time up to date
 * before a command and reschedules it after).
 *
 * One command per line, each answered with one line: "ok ..." or
 * "error <reason>". The commands are listed in README.md; control.c parses
 * and runs them.
 */
#ifndef WSG_DAEMON_CONTROL_H
#define WSG_DAEMON_CONTROL_H

#include <stddef.h>

#include "reactor.h"
#include "sched.h"
#include "transport.h"

/* Longest command line, without its newline; longer ones are answered with
 * an error and discarded up to their newline. */
#define WSG_CTL_LINE_MAX 256u
/* Control clients at once; one more is told so and closed. */
#define WSG_CTL_CLIENTS_MAX 16u

struct wsg_ctl;
struct wsg_script;

/* One client's side of the conversation: the line it is sending, the
 * gripper its commands act on (`gripper N`), and where its answers go:
 * answer gets each answer line, newline included. The owner sets closed
 * when the client is gone; its further lines are then not run. */
struct wsg_ctl_session {
    unsigned gripper;
    int overlong; /* discarding the rest of a too long line */
    int closed;
    size_t len;
    char line[WSG_CTL_LINE_MAX + 1];
    void (*answer)(void *ctx, const char *line, size_t len);
    void *ctx;
    /* `script run FILE` for this session, in place of running any file
     * the daemon can read: the web page's, kept to its script directory.
     * NULL: any file. 0, or -1 with the reason in err. */
    int (*script_run)(void *ctx, struct wsg_script *h, const char *file,
                      char *err, size_t errcap);
};

/* A control channel on the scheduler's grippers that serves no socket
 * (tests, fuzzing): sessions are fed with wsg_control_input. 0 or
 * -ENOMEM. */
int wsg_control_new(struct wsg_ctl **out, struct wsg_reactor *reactor,
                    struct wsg_sched *sched);
void wsg_control_session_init(struct wsg_ctl_session *s,
                              void (*answer)(void *ctx, const char *line,
                                             size_t len),
                              void *ctx);
/* Bytes a client sent: every complete line is run and answered, one
 * answer per line, in order. */
void wsg_control_input(struct wsg_ctl *ctl, struct wsg_ctl_session *s,
                       const char *data, size_t n);
/* A control channel listening on ep. On failure put a one-line reason in
 * err and return -errno (*out NULL). */
int wsg_control_open(struct wsg_ctl **out, struct wsg_reactor *reactor,
                     struct wsg_sched *sched, const struct wsg_endpoint *ep,
                     char *err, size_t errlen);
struct wsg_capture;
/* Let `capture start FILE|stop` act on cap (without it the command is
 * refused: the web page's channel). */
void wsg_control_set_capture(struct wsg_ctl *ctl, struct wsg_capture *cap);
/* The address it listens on, for the ready line. */
int wsg_control_describe(const struct wsg_ctl *ctl, char *buf, size_t len);
/* Close every client and the socket (if any); safe on NULL. */
void wsg_control_close(struct wsg_ctl *ctl);

#endif
