/*
 * sd_notify(3) without libsystemd: the protocol is one datagram on an
 * AF_UNIX socket, and the static build (the container image) cannot link
 * libsystemd, which Debian ships only as a shared library. The
 * credentials systemd checks (that the sender is the service's process)
 * are the kernel's, attached to every datagram; nothing to send for them.
 */
#define _GNU_SOURCE /* SOCK_CLOEXEC, MSG_NOSIGNAL */

#include "notify.h"

#include <errno.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

int wsg_notify(const char *msg)
{
    const char *name = getenv("NOTIFY_SOCKET");
    struct sockaddr_un sa;
    size_t len, mlen = strlen(msg);
    ssize_t n;
    int fd, r = 0;

    if (!name || !name[0])
        return 0;
    /* systemd also names vsock addresses ("vsock:..."), for a service in a
     * VM; this emulator is not run as one. */
    if (name[0] != '/' && name[0] != '@')
        return -EAFNOSUPPORT;
    len = strlen(name);
    if (len >= sizeof sa.sun_path)
        return -ENAMETOOLONG;
    memset(&sa, 0, sizeof sa);
    sa.sun_family = AF_UNIX;
    memcpy(sa.sun_path, name, len);
    /* An abstract name: a leading NUL instead of '@', and its length is
     * the address's (no terminating NUL). A path's length includes it. */
    if (name[0] == '@')
        sa.sun_path[0] = '\0';
    else
        len++;

    fd = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (fd < 0)
        return -errno;
    n = sendto(fd, msg, mlen, MSG_NOSIGNAL, (struct sockaddr *)&sa,
               (socklen_t)(offsetof(struct sockaddr_un, sun_path) + len));
    if (n < 0)
        r = -errno;
    else if ((size_t)n != mlen)
        r = -EMSGSIZE; /* a datagram goes whole or not at all */
    close(fd);
    return r;
}
