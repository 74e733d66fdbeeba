/*
 * The web page's files, built into the program: CMake turns each file of
 * web/ into a byte array at build time (cmake/embed.cmake writes
 * web_assets.c in the build tree), so the daemon serves them with nothing
 * to find on disk and nothing fetched.
 */
#ifndef WSG_DAEMON_WEB_ASSETS_H
#define WSG_DAEMON_WEB_ASSETS_H

#include <stddef.h>

struct wsg_web_asset {
    const char *path; /* "/index.html" */
    const char *type; /* its Content-Type */
    const unsigned char *data;
    size_t len;
};

/* Every file, ended by one whose path is NULL. */
extern const struct wsg_web_asset wsg_web_assets[];

#endif
