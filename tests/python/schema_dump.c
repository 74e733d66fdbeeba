/*
 * schema_dump: the protocol schema (wsg/schema.h) as one JSON object on
 * stdout, for check_schema.py, which holds the Python package's tables
 * against it: the status codes, the system state flags by bit, the
 * grasping states, and per command its ID, symbol, name, length rules,
 * flags and request and reply fields (name, type, unit, names of values or
 * bits, the most bytes of a text).
 */
#include <stdio.h>
#include <stdlib.h>

#include "wsg/proto.h"

/* Schema names are plain ASCII without quotes or backslashes; anything
 * else would be a broken schema, and is refused rather than escaped. */
static void str(const char *s)
{
    const char *p;

    for (p = s; *p; p++)
        if (*p < 0x20 || *p > 0x7E || *p == '"' || *p == '\\') {
            fprintf(stderr, "schema_dump: bad name \"%s\"\n", s);
            exit(1);
        }
    printf("\"%s\"", s);
}

static const char *type_name(uint8_t t)
{
    const char *name = wsg_field_type_name(t);

    if (!name) {
        fprintf(stderr, "schema_dump: unknown field type %u\n", t);
        exit(1);
    }
    return name;
}

static void layout(const struct wsg_layout *l)
{
    unsigned i, j;

    putchar('[');
    for (i = 0; i < l->n; i++) {
        const struct wsg_field *f = &l->fields[i];

        printf("%s{\"name\":", i ? "," : "");
        str(f->name);
        printf(",\"type\":\"%s\",\"unit\":", type_name(f->type));
        str(f->unit);
        printf(",\"max\":%u,\"names\":[", (unsigned)f->max);
        for (j = 0; f->names && j < f->nnames; j++) {
            if (j)
                putchar(',');
            if (f->names[j])
                str(f->names[j]);
            else
                printf("null");
        }
        printf("]}");
    }
    putchar(']');
}

static void cmd_flags(uint8_t flags)
{
    static const struct {
        uint8_t bit;
        const char *name;
    } names[] = {
        {WSG_CMDF_MOTION, "motion"},     {WSG_CMDF_HOMED, "homed"},
        {WSG_CMDF_ASYNC, "async"},       {WSG_CMDF_NO_PARAM, "no_param"},
        {WSG_CMDF_EMPTY_OK, "empty_ok"}, {WSG_CMDF_STREAM, "stream"}};
    unsigned i, first = 1, known = 0;

    putchar('[');
    for (i = 0; i < sizeof names / sizeof names[0]; i++) {
        known |= names[i].bit;
        if (flags & names[i].bit) {
            printf("%s\"%s\"", first ? "" : ",", names[i].name);
            first = 0;
        }
    }
    putchar(']');
    if (flags & ~known) {
        fprintf(stderr, "schema_dump: unknown command flags 0x%02X\n", flags);
        exit(1);
    }
}

/* "NAME":VALUE of a list whose first value is 0. */
#define MEMBER_(v, name) printf("%s\"" #name "\":%d", v ? "," : "", v);

int main(void)
{
    unsigned id, bit, first = 1;

    printf("{\"statuses\":{");
    WSG_SCHEMA_STATUSES(MEMBER_)
    printf("},\"system_flags\":{");
    for (bit = 0; bit < 32; bit++) {
        if (!wsg_system_flag_names[bit])
            continue;
        printf("%s", first ? "" : ",");
        str(wsg_system_flag_names[bit]);
        printf(":%u", bit);
        first = 0;
    }
    printf("},\"grasp_states\":{");
    WSG_SCHEMA_GRASP_STATES(MEMBER_)
    printf("},\"commands\":[");
    first = 1;
    for (id = 0; id < 256; id++) {
        const struct wsg_cmd_schema *c = &wsg_schema[id];

        if (!c->name)
            continue;
        printf("%s{\"id\":%u,\"symbol\":", first ? "" : ",", id);
        str(c->symbol);
        printf(",\"name\":");
        str(c->name);
        printf(",\"min_len\":%u,\"max_len\":%u,\"flags\":",
               (unsigned)c->min_len, (unsigned)c->max_len);
        cmd_flags(c->flags);
        printf(",\"request\":");
        layout(&c->request);
        printf(",\"reply\":");
        layout(&c->reply);
        putchar('}');
        first = 0;
    }
    printf("]}\n");
    return ferror(stdout) ? 1 : 0;
}
