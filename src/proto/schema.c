/*
 * The schema's tables (wsg_schema[] by command ID, the names of statuses,
 * system state flags and grasping states), all made from the lists in
 * wsg/schema.h, and the field walker: whether a payload fits a layout, its
 * fields taken apart into values, numbers put back on the wire, and a value
 * written as text. The log, wsgctl and the fuzzers print and check payloads
 * with these, so none of them knows a layout of its own.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "wsg/proto.h"

#define WSG_STATUS_NAME_(v, name) [v] = #name,
static const char *const wsg_status_names[] = {
    WSG_SCHEMA_STATUSES(WSG_STATUS_NAME_)};

#define WSG_SF_NAME_(bit, name) [bit] = #name,
const char *const wsg_system_flag_names[32] = {
    WSG_SCHEMA_SYSTEM_FLAGS(WSG_SF_NAME_)};

#define WSG_GS_NAME_(v, name) [v] = #name,
const char *const wsg_grasp_state_names[WSG_GS_COUNT] = {
    WSG_SCHEMA_GRASP_STATES(WSG_GS_NAME_)};

#define WSG_SCHEMA_ROW_(id, sym, handler, name, min, max, flags, req, rep)    \
    [id] = {name, #sym, min, max, flags, req, rep},
const struct wsg_cmd_schema wsg_schema[256] = {
    WSG_SCHEMA_COMMANDS(WSG_SCHEMA_ROW_)};

const char *wsg_status_name(unsigned status)
{
    if (status >= sizeof wsg_status_names / sizeof wsg_status_names[0] ||
        !wsg_status_names[status])
        return "E_UNKNOWN";
    return wsg_status_names[status];
}

const char *wsg_cmd_name(uint8_t id)
{
    return wsg_schema[id].name;
}

int wsg_cmd_request_fits(uint8_t id, size_t len)
{
    const struct wsg_cmd_schema *c = &wsg_schema[id];

    return c->name && wsg_schema_len_ok(c->min_len, c->max_len, c->flags, len);
}

void wsg_schema_key(const char *name, char *buf, size_t cap)
{
    size_t i = 0;

    if (cap == 0)
        return;
    if (strncmp(name, "SF_", 3) == 0)
        name += 3;
    for (; *name && i + 1 < cap; name++) {
        char c = *name;

        buf[i++] = c == '-' ? '_' : c >= 'A' && c <= 'Z' ? (char)(c + 32) : c;
    }
    buf[i] = '\0';
}

/* Bytes on the wire of a fixed-size field; 0 for TEXT and BYTES. */
static size_t wsg_field_size(const struct wsg_field *f)
{
    switch (f->type) {
    case WSG_FT_U8:
    case WSG_FT_ENUM8:
    case WSG_FT_BITS8:
        return 1;
    case WSG_FT_U16:
    case WSG_FT_I16_TENTHS:
    case WSG_FT_VERSION:
    case WSG_FT_BITS16:
        return 2;
    case WSG_FT_U32:
    case WSG_FT_F32:
    case WSG_FT_BITS32:
        return 4;
    default:
        return 0;
    }
}

const char *wsg_field_type_name(unsigned type)
{
    static const char *const names[] = {[WSG_FT_U8] = "u8",
                                        [WSG_FT_U16] = "u16",
                                        [WSG_FT_U32] = "u32",
                                        [WSG_FT_F32] = "f32",
                                        [WSG_FT_I16_TENTHS] = "i16_tenths",
                                        [WSG_FT_VERSION] = "version",
                                        [WSG_FT_ENUM8] = "enum8",
                                        [WSG_FT_BITS8] = "bits8",
                                        [WSG_FT_BITS16] = "bits16",
                                        [WSG_FT_BITS32] = "bits32",
                                        [WSG_FT_TEXT] = "text",
                                        [WSG_FT_BYTES] = "bytes"};

    return type < sizeof names / sizeof names[0] ? names[type] : NULL;
}

static int wsg_field_rest(const struct wsg_field *f)
{
    return f->type == WSG_FT_TEXT || f->type == WSG_FT_BYTES;
}

size_t wsg_layout_size(const struct wsg_layout *l)
{
    size_t n = 0, i;

    for (i = 0; i < l->n; i++)
        n += wsg_field_size(&l->fields[i]);
    return n;
}

int wsg_layout_fits(const struct wsg_layout *l, size_t n)
{
    size_t fixed = wsg_layout_size(l);

    if (l->n && wsg_field_rest(&l->fields[l->n - 1]))
        return n >= fixed && n - fixed <= l->fields[l->n - 1].max;
    return n == fixed;
}

/* An integer of size 1, 2 or 4 bytes off the wire, and onto it. */
static uint32_t wsg_get_uint(const uint8_t *p, size_t size)
{
    return size == 1 ? p[0] : size == 2 ? wsg_get_u16(p) : wsg_get_u32(p);
}

static void wsg_put_uint(uint8_t *p, size_t size, uint32_t v)
{
    if (size == 1)
        p[0] = (uint8_t)v;
    else if (size == 2)
        wsg_put_u16(p, (uint16_t)v);
    else
        wsg_put_u32(p, v);
}

int wsg_layout_decode(const struct wsg_layout *l, const uint8_t *p, size_t n,
                      struct wsg_value *out)
{
    size_t i, off = 0;

    if (!wsg_layout_fits(l, n))
        return -1;
    for (i = 0; i < l->n; i++) {
        const struct wsg_field *f = &l->fields[i];
        struct wsg_value *v = &out[i];
        size_t size = wsg_field_size(f);

        memset(v, 0, sizeof *v);
        v->field = f;
        if (size == 0) { /* TEXT, BYTES: the rest */
            v->data = p + off;
            v->len = n - off;
            continue;
        }
        v->raw = wsg_get_uint(p + off, size);
        if (f->type == WSG_FT_F32)
            v->num = wsg_get_f32(p + off);
        else if (f->type == WSG_FT_I16_TENTHS)
            v->num = (int16_t)v->raw / 10.0;
        else
            v->num = v->raw;
        off += size;
    }
    return (int)l->n;
}

size_t wsg_layout_encode(const struct wsg_layout *l, const double *num,
                         uint8_t *out)
{
    size_t i, off = 0;

    for (i = 0; i < l->n; i++) {
        const struct wsg_field *f = &l->fields[i];
        size_t size = wsg_field_size(f);

        if (f->type == WSG_FT_F32)
            wsg_put_f32(out + off, (float)num[i]);
        else if (f->type == WSG_FT_I16_TENTHS)
            wsg_put_u16(out + off, (uint16_t)(int16_t)lround(num[i] * 10.0));
        else if (size)
            wsg_put_uint(out + off, size, (uint32_t)num[i]);
        off += size;
    }
    return off;
}

/* snprintf that appends at *n and never runs past cap. */
static void wsg_put(char *buf, size_t cap, size_t *n, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

static void wsg_put(char *buf, size_t cap, size_t *n, const char *fmt, ...)
{
    va_list ap;
    int r;

    if (*n + 1 >= cap)
        return;
    va_start(ap, fmt);
    r = vsnprintf(buf + *n, cap - *n, fmt, ap);
    va_end(ap);
    if (r > 0)
        *n += (size_t)r < cap - *n ? (size_t)r : cap - *n - 1;
}

static const char wsg_hex_digit[] = "0123456789ABCDEF";

static const char *wsg_field_value_name(const struct wsg_field *f, unsigned v)
{
    return f->names && v < f->nnames ? f->names[v] : NULL;
}

/* "(relative|stop-on-block)" after a BITS value; nothing when none is
 * set. */
static void wsg_put_bits(const struct wsg_value *v,
                         const struct wsg_value_style *st, char *buf,
                         size_t cap, size_t *n)
{
    unsigned bit, bits = 8 * (unsigned)wsg_field_size(v->field);
    int first = 1;

    for (bit = 0; bit < bits; bit++) {
        const char *name;

        if (!(v->raw & (1ul << bit)))
            continue;
        wsg_put(buf, cap, n, "%s", first ? st->open : st->sep);
        first = 0;
        name = wsg_field_value_name(v->field, bit);
        if (name)
            wsg_put(buf, cap, n, "%s", name);
        else
            wsg_put(buf, cap, n, "D%u", bit);
    }
    if (!first)
        wsg_put(buf, cap, n, "%s", st->close);
}

size_t wsg_value_format(const struct wsg_value *v,
                        const struct wsg_value_style *st, char *buf,
                        size_t cap)
{
    const struct wsg_field *f = v->field;
    size_t n = 0, i;

    if (cap == 0)
        return 0;
    buf[0] = '\0';
    switch (f->type) {
    case WSG_FT_F32:
        wsg_put(buf, cap, &n, "%.*f", st->decimals, v->num);
        break;
    case WSG_FT_I16_TENTHS:
        wsg_put(buf, cap, &n, "%.1f", v->num);
        break;
    case WSG_FT_VERSION:
        wsg_put(buf, cap, &n, "%u.%u.%u", (unsigned)(v->raw >> 12),
                (unsigned)(v->raw >> 8) & 15u, (unsigned)(v->raw >> 4) & 15u);
        break;
    case WSG_FT_ENUM8: {
        const char *name = wsg_field_value_name(f, v->raw);

        wsg_put(buf, cap, &n, "%lu", (unsigned long)v->raw);
        if (name && !st->bare)
            wsg_put(buf, cap, &n, "%s%s%s", st->open, name, st->close);
        break;
    }
    case WSG_FT_BITS8:
    case WSG_FT_BITS16:
    case WSG_FT_BITS32:
        wsg_put(buf, cap, &n, "0x%0*lX", 2 * (int)wsg_field_size(f),
                (unsigned long)v->raw);
        if (!st->bare)
            wsg_put_bits(v, st, buf, cap, &n);
        break;
    case WSG_FT_TEXT:
        if (st->bare) {
            wsg_put(buf, cap, &n, "%.*s", (int)v->len, (const char *)v->data);
            break;
        }
        wsg_put(buf, cap, &n, "\"");
        for (i = 0; i < v->len; i++)
            wsg_put(buf, cap, &n,
                    v->data[i] >= 0x20 && v->data[i] < 0x7F &&
                            v->data[i] != '"'
                        ? "%c"
                        : "\\x%02X",
                    v->data[i]);
        wsg_put(buf, cap, &n, "\"");
        break;
    case WSG_FT_BYTES:
        /* By hand: a log of Loop packets is all hex, and printf per byte
         * would cost the emulator throughput. */
        for (i = 0;
             i < v->len && (!st->max_hex || i < st->max_hex) && n + 4 <= cap;
             i++) {
            if (i)
                buf[n++] = ' ';
            buf[n++] = wsg_hex_digit[v->data[i] >> 4];
            buf[n++] = wsg_hex_digit[v->data[i] & 15u];
        }
        buf[n] = '\0';
        if (i < v->len)
            wsg_put(buf, cap, &n, " ...(%zu bytes)", v->len);
        break;
    default: /* U8, U16, U32 */
        wsg_put(buf, cap, &n, "%lu", (unsigned long)v->raw);
        break;
    }
    return n;
}
