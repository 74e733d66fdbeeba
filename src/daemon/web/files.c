/*
 * A file replaced whole, for the web page's two writers: the config file
 * (settings.c) and a script uploaded to the script directory (scripts.c).
 * The new content goes to a temporary file beside it, is synced, and is
 * renamed over the old one, so that a reader (the next start, a running
 * script's require) sees the old file or the new one, never half of one.
 * A file replaced for another (the config file) keeps its owner and mode.
 */
#define _POSIX_C_SOURCE 200809L /* openat, unlinkat, renameat, fchown */

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <sys/stat.h>
#include <unistd.h>

#include "impl.h"

/* All of buf to fd: 0 or -errno. */
static int write_all(int fd, const char *buf, size_t len)
{
    ssize_t n;

    while (len) {
        n = write(fd, buf, len);
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0)
            return -errno;
        buf += (size_t)n;
        len -= (size_t)n;
    }
    return 0;
}

/* The new file takes like's owner and mode: its owner first (a change
 * of owner may clear set-ID bits), where the daemon may give it; -EPERM
 * where it may not, so that saving never hands a file to another owner. */
static int take_owner_and_mode(int fd, const struct stat *like)
{
    struct stat st;

    if (fstat(fd, &st) < 0)
        return -errno;
    if ((st.st_uid != like->st_uid || st.st_gid != like->st_gid) &&
        fchown(fd, like->st_uid, like->st_gid) < 0)
        return -errno;
    return fchmod(fd, like->st_mode & 07777) < 0 ? -errno : 0;
}

int wsg_web_replace_file(int dfd, const char *name, const char *tmp,
                         const void *buf, size_t len, const struct stat *like)
{
    const int flags = O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC;
    int fd, r;

    /* The daemon serves one request at a time: a temporary file already
     * there is what a crash left behind. Made for the owner alone until
     * it has like's owner and mode. */
    fd = openat(dfd, tmp, flags, like ? 0600 : 0644);
    if (fd < 0 && errno == EEXIST && unlinkat(dfd, tmp, 0) == 0)
        fd = openat(dfd, tmp, flags, like ? 0600 : 0644);
    if (fd < 0)
        return -errno;
    r = like ? take_owner_and_mode(fd, like) : 0;
    if (r == 0)
        r = write_all(fd, buf, len);
    if (r == 0 && fsync(fd) < 0)
        r = -errno;
    if (close(fd) < 0 && r == 0)
        r = -errno;
    if (r == 0 && renameat(dfd, tmp, dfd, name) < 0)
        r = -errno;
    if (r < 0)
        unlinkat(dfd, tmp, 0);
    return r;
}
