/*
 * The web page in a build without libmicrohttpd (CMakeLists.txt picks this
 * file then): --web is still an option, so a config file that names it
 * reads the same everywhere, but opening the server says why it cannot.
 */
#include "web.h"

#include <errno.h>
#include <stdio.h>

int wsg_web_open(struct wsg_web **out, struct wsg_daemon *d, char *err,
                 size_t errlen)
{
    (void)d;
    *out = NULL;
    snprintf(err, errlen,
             "--web: this wsgemu was built without libmicrohttpd "
             "(install libmicrohttpd-dev and build again)");
    return -ENOTSUP;
}

int wsg_web_describe(const struct wsg_web *web, char *buf, size_t len)
{
    (void)web;
    if (len)
        buf[0] = '\0';
    return -ENOTSUP;
}

void wsg_web_close(struct wsg_web *web)
{
    (void)web;
}
