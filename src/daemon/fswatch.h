/*
 * File watches for the whole process on one inotify instance, itself one
 * watch of the reactor: the kernel allows few inotify instances per user
 * (128 by default), and a fleet has a pty each. An event on a watched path
 * is delivered as EPOLLIN to the watch registered for it (w->fd is not
 * used).
 */
#ifndef WSG_DAEMON_FSWATCH_H
#define WSG_DAEMON_FSWATCH_H

#include <stddef.h>
#include <stdint.h>

#include "reactor.h"

struct wsg_fswatch {
    struct wsg_reactor *reactor;
    struct wsg_watch watch; /* the inotify descriptor, -1 until first use */
    struct wsg_watch **tab; /* tab[wd]: where that descriptor's events go */
    size_t ntab;
};

void wsg_fswatch_init(struct wsg_fswatch *f, struct wsg_reactor *r);
void wsg_fswatch_fini(struct wsg_fswatch *f);
/* Watch path for the inotify events in mask. Returns the watch descriptor
 * or -errno. */
int wsg_fswatch_add(struct wsg_fswatch *f, const char *path, uint32_t mask,
                    struct wsg_watch *w);
void wsg_fswatch_del(struct wsg_fswatch *f, int wd);

#endif
