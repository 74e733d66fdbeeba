/*
 * What the command-line tools share for the emulator's control channel:
 * reading a number out of its one-line JSON answers ("state", "stats").
 * Header-only and apart from the client library (wsgclient.h), which
 * moves lines without reading them.
 */
#ifndef WSG_TOOLS_CTLJSON_H
#define WSG_TOOLS_CTLJSON_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The number after "key": in a JSON line (the channel's keys are unique,
 * nested ones too). 0 or -1. */
static inline int wsg_json_num(const char *json, const char *key, double *v)
{
    char pat[32];
    const char *p;
    char *end;

    snprintf(pat, sizeof pat, "\"%s\":", key);
    p = strstr(json, pat);
    if (!p)
        return -1;
    *v = strtod(p + strlen(pat), &end);
    return end == p + strlen(pat) ? -1 : 0;
}

#endif
