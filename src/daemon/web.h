/*
 * The gripper's web page (--web [ADDR:]PORT): an HTTP server on a TCP port
 * of its own that serves a live view of the gripper, its state as JSON,
 * the state pushed as Server-Sent Events whenever it changes, and the
 * sidebar's STOP and ACK. Like the control channel it is a service of the
 * daemon on the reactor: GNU libmicrohttpd does the HTTP, driven by the
 * reactor (its epoll descriptor is one watch, its timeouts one timerfd),
 * with no thread of its own; it acts on the gripper through the scheduler
 * as the control channel does.
 *
 * Built without libmicrohttpd (web_none.c), opening one fails with a
 * message and -ENOTSUP.
 */
#ifndef WSG_DAEMON_WEB_H
#define WSG_DAEMON_WEB_H

#include <stddef.h>

#include "reactor.h"
#include "sched.h"
#include "transport.h"

/* Connections served at once (the page, its event stream, requests);
 * a further one is refused by the HTTP server. */
#define WSG_WEB_CLIENTS_MAX 256u
/* Connections from one address at once: one client cannot take every
 * slot. A further one is closed at once, without an answer. */
#define WSG_WEB_PEER_CLIENTS_MAX 64u
/* Event streams (GET /events) at once, in all and from one address: a
 * stream holds its connection for as long as its page is open. A further
 * one is refused, 503 with a Retry-After of WSG_WEB_RETRY_AFTER_S. */
#define WSG_WEB_STREAMS_MAX      64u
#define WSG_WEB_PEER_STREAMS_MAX 16u
#define WSG_WEB_RETRY_AFTER_S    10u
/* A request's head and body must have come within this many seconds of
 * its connection's opening, or of the previous answer on it; else the
 * connection is closed. A client sending a byte now and then (slowloris)
 * cannot hold a slot for longer; nor can one that keeps a connection
 * open and idle. An answer being sent (an event stream) has no such
 * limit. */
#define WSG_WEB_REQUEST_S 10u
/* The shortest time between two state events: the page is redrawn at up
 * to 20 Hz while something changes. */
#define WSG_WEB_PUSH_MIN_NS 50000000ull
/* A request body larger than this is refused (413) before more of it is
 * read. */
#define WSG_WEB_BODY_MAX 4096u
/* A script uploaded to the script directory may be this large. */
#define WSG_WEB_UPLOAD_MAX (256u * 1024u)

struct wsg_web;
struct wsg_daemon;

/* A web server on the daemon's --web endpoint showing its first gripper.
 * On failure put a one-line reason in err and return -errno (*out
 * NULL). */
int wsg_web_open(struct wsg_web **out, struct wsg_daemon *d, char *err,
                 size_t errlen);
/* The address it listens on, for the ready line. */
int wsg_web_describe(const struct wsg_web *web, char *buf, size_t len);
/* Close every connection and the socket; safe on NULL. */
void wsg_web_close(struct wsg_web *web);

#endif
