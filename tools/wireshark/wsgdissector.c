/*
 * wsgdissector TEMPLATE OUT: writes the Wireshark Lua dissector (wsg.lua)
 * from the protocol schema. It copies TEMPLATE (tools/wireshark/wsg.lua.in,
 * the dissector's code) and puts in place of its line "--@SCHEMA@" the
 * schema as Lua tables: every command of wsg_schema[] with its symbol,
 * name, length rules and request and reply fields (name, type, unit, the
 * names of values or bits, the most bytes of a text), the status codes,
 * the system state flags and the checksum table. Nothing here names a
 * command: a row added to include/wsg/schema.h is in the next build's
 * dissector.
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "wsg/proto.h"

/* A schema name as a Lua string: they are plain ASCII; anything else is a
 * broken schema, refused rather than escaped. Returns 0 or -1. */
static int str(FILE *o, const char *s)
{
    const char *p;

    for (p = s; *p; p++)
        if (*p < 0x20 || *p > 0x7E || *p == '"' || *p == '\\') {
            fprintf(stderr, "wsgdissector: bad name \"%s\"\n", s);
            return -1;
        }
    fprintf(o, "\"%s\"", s);
    return 0;
}

static int layout(FILE *o, const struct wsg_layout *l)
{
    unsigned i, j;

    fputs("{", o);
    for (i = 0; i < l->n; i++) {
        const struct wsg_field *f = &l->fields[i];
        const char *t = wsg_field_type_name(f->type);

        if (!t) {
            fprintf(stderr, "wsgdissector: field %s: unknown type %u\n",
                    f->name, f->type);
            return -1;
        }
        fputs("\n      { name = ", o);
        if (str(o, f->name) < 0)
            return -1;
        fprintf(o, ", type = \"%s\", unit = ", t);
        if (str(o, f->unit) < 0)
            return -1;
        fprintf(o, ", max = %u", (unsigned)f->max);
        if (f->names) {
            fputs(", names = {", o);
            for (j = 0; j < f->nnames; j++) {
                if (!f->names[j])
                    continue;
                fprintf(o, " [%u] = ", j);
                if (str(o, f->names[j]) < 0)
                    return -1;
                fputs(",", o);
            }
            fputs(" }", o);
        }
        fputs(" },", o);
    }
    fputs(" }", o);
    return 0;
}

static int schema(FILE *o)
{
    unsigned i;

    fputs("-- GENERATED from include/wsg/schema.h by wsgdissector.\n"
          "local SCHEMA = {}\n",
          o);
    fputs("SCHEMA.statuses = {", o);
    for (i = 0; i < 256; i++) {
        const char *n = wsg_status_name(i);

        if (strcmp(n, "E_UNKNOWN") == 0)
            continue;
        fprintf(o, "\n  [%u] = ", i);
        if (str(o, n) < 0)
            return -1;
        fputs(",", o);
    }
    fputs("\n}\nSCHEMA.system_flags = {", o);
    for (i = 0; i < 32; i++) {
        if (!wsg_system_flag_names[i])
            continue;
        fprintf(o, "\n  [%u] = ", i);
        if (str(o, wsg_system_flag_names[i]) < 0)
            return -1;
        fputs(",", o);
    }
    fprintf(o, "\n}\nSCHEMA.crc_init = 0x%04X\nSCHEMA.crc_table = {",
            (unsigned)WSG_CRC_INIT);
    for (i = 0; i < 256; i++) {
        uint8_t b = (uint8_t)i;

        /* The table's entry i is the CRC of byte i from 0. */
        fprintf(o, "%s[%u] = 0x%04X,", i % 6 ? " " : "\n  ", i,
                (unsigned)wsg_crc_update(0, &b, 1));
    }
    fputs("\n}\nSCHEMA.commands = {", o);
    for (i = 0; i < 256; i++) {
        const struct wsg_cmd_schema *c = &wsg_schema[i];

        if (!c->name)
            continue;
        fprintf(o, "\n  [0x%02X] = {\n    symbol = ", i);
        if (str(o, c->symbol) < 0)
            return -1;
        fputs(", name = ", o);
        if (str(o, c->name) < 0)
            return -1;
        fprintf(o, ",\n    min_len = %u, max_len = %u, flags = %u,",
                (unsigned)c->min_len, (unsigned)c->max_len,
                (unsigned)c->flags);
        fputs("\n    request = ", o);
        if (layout(o, &c->request) < 0)
            return -1;
        fputs(",\n    reply = ", o);
        if (layout(o, &c->reply) < 0)
            return -1;
        fputs(",\n  },", o);
    }
    fputs("\n}\n-- End of the generated tables.\n", o);
    return 0;
}

int main(int argc, char **argv)
{
    FILE *in = NULL, *out = NULL;
    char line[4096];
    int found = 0, rc = 1;

    if (argc != 3) {
        fprintf(stderr, "usage: wsgdissector TEMPLATE OUT\n");
        return 2;
    }
    in = fopen(argv[1], "r");
    if (!in) {
        fprintf(stderr, "wsgdissector: %s: %s\n", argv[1], strerror(errno));
        goto out;
    }
    out = fopen(argv[2], "w");
    if (!out) {
        fprintf(stderr, "wsgdissector: %s: %s\n", argv[2], strerror(errno));
        goto out;
    }
    while (fgets(line, sizeof line, in)) {
        if (strcmp(line, "--@SCHEMA@\n") == 0) {
            if (schema(out) < 0)
                goto out;
            found = 1;
        } else {
            fputs(line, out);
        }
    }
    if (ferror(in) || !found) {
        fprintf(stderr, "wsgdissector: %s: %s\n", argv[1],
                found ? "read error" : "no line --@SCHEMA@");
        goto out;
    }
    rc = 0;
out:
    if (in)
        fclose(in);
    if (out && fclose(out) != 0) {
        fprintf(stderr, "wsgdissector: %s: write error\n", argv[2]);
        rc = 1;
    }
    if (rc && argc == 3)
        remove(argv[2]);
    return rc;
}
