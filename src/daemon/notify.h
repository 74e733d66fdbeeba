/*
 * The service manager's readiness protocol (sd_notify(3)): systemd starts a
 * Type=notify service with $NOTIFY_SOCKET naming a datagram socket, and
 * waits for "READY=1" on it before it counts the service as started.
 */
#ifndef WSG_NOTIFY_H
#define WSG_NOTIFY_H

/* Send msg ("KEY=value" lines, e.g. "READY=1\nSTATUS=...") as one datagram
 * to the socket $NOTIFY_SOCKET names: a path, or an abstract name when it
 * starts with '@'. Returns 0 when sent or when $NOTIFY_SOCKET is unset or
 * empty (not started by a service manager), else -errno (-EAFNOSUPPORT for
 * a name that is neither, -ENAMETOOLONG for one too long). */
int wsg_notify(const char *msg);

#endif
