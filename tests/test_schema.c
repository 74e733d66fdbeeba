/*
 * The protocol schema (wsg/schema.h) against itself and the field walker:
 * rows in ID order with unique symbols and names, every request layout
 * accepted by its own length rules, every reply within a reply's size,
 * field names in the one spelling (lower case, hyphens) with known units,
 * names for every enum and bit vector; then decoding, fitting, encoding and
 * formatting values as the log and wsgctl write them, and the control
 * channel's spelling of names.
 */
#include <string.h>

#include "check.h"
#include "wsg/proto.h"

#define ROW_ID_(id, ...) id,
static const uint8_t row_ids[] = {WSG_SCHEMA_COMMANDS(ROW_ID_)};
#define NROWS (sizeof row_ids / sizeof row_ids[0])

static int spelled_right(const char *s)
{
    if (!*s)
        return 0;
    for (; *s; s++)
        if (!((*s >= 'a' && *s <= 'z') || (*s >= '0' && *s <= '9') ||
              *s == '-'))
            return 0;
    return 1;
}

static int unit_known(const char *u)
{
    static const char *const units[] = {"",  "mm",   "mm/s", "mm/s2",
                                        "N", "degC", "ms"};
    size_t i;

    for (i = 0; i < sizeof units / sizeof units[0]; i++)
        if (!strcmp(u, units[i]))
            return 1;
    return 0;
}

static void check_layout(const struct wsg_layout *l)
{
    size_t i, j;

    CHECK(l->n <= WSG_FIELDS_MAX);
    CHECK(l->n == 0 || l->fields != NULL);
    for (i = 0; i < l->n; i++) {
        const struct wsg_field *f = &l->fields[i];
        int rest = f->type == WSG_FT_TEXT || f->type == WSG_FT_BYTES;

        CHECK(spelled_right(f->name));
        CHECK(unit_known(f->unit));
        /* Only the last field takes the rest of the payload. */
        CHECK(!rest || i + 1 == l->n);
        CHECK(!rest || f->max > 0);
        if (f->type == WSG_FT_ENUM8 || f->type == WSG_FT_BITS8 ||
            f->type == WSG_FT_BITS32)
            CHECK(f->names != NULL && f->nnames > 0);
        for (j = 0; j < i; j++)
            CHECK(strcmp(f->name, l->fields[j].name) != 0);
    }
}

static int layout_meets_rules(uint8_t id, const struct wsg_layout *l)
{
    size_t n;

    for (n = 0; n <= WSG_PAYLOAD_MAX; n++)
        if (wsg_layout_fits(l, n) && wsg_cmd_request_fits(id, n))
            return 1;
    return 0;
}

static void test_rows(void)
{
    size_t i, j;
    unsigned named = 0;

    for (i = 0; i < NROWS; i++) {
        const struct wsg_cmd_schema *c = &wsg_schema[row_ids[i]];

        /* In ID order: the fuzz corpus names IDs by their index. */
        CHECK(i == 0 || row_ids[i] > row_ids[i - 1]);
        REQUIRE(c->name != NULL);
        CHECK(c->min_len <= c->max_len && c->max_len <= WSG_PAYLOAD_MAX);
        /* Some request laid out as the schema says passes its rules. */
        CHECK(layout_meets_rules(row_ids[i], &c->request));
        CHECK(wsg_layout_size(&c->reply) <= WSG_REPLY_PARAMS_MAX);
        CHECK(!(c->flags & WSG_CMDF_STREAM) ||
              wsg_layout_size(&c->request) == 3);
        check_layout(&c->request);
        check_layout(&c->reply);
        for (j = 0; j < i; j++) {
            CHECK(strcmp(c->name, wsg_schema[row_ids[j]].name) != 0);
            CHECK(strcmp(c->symbol, wsg_schema[row_ids[j]].symbol) != 0);
        }
    }
    for (i = 0; i < 256; i++)
        named += wsg_schema[i].name != NULL;
    CHECK_EQ(named, NROWS);
    CHECK(wsg_cmd_name(0x90) == NULL && !wsg_cmd_request_fits(0x90, 0));
    CHECK(!strcmp(wsg_cmd_name(WSG_CMD_GET_WIDTH), "GetOpeningWidth"));
    CHECK(!strcmp(wsg_schema[WSG_CMD_GET_WIDTH].symbol, "GET_WIDTH"));
    /* Stream commands take FLAGS and PERIOD_MS, or nothing. */
    CHECK(wsg_cmd_request_fits(WSG_CMD_GET_WIDTH, 0));
    CHECK(wsg_cmd_request_fits(WSG_CMD_GET_WIDTH, 3));
    CHECK(!wsg_cmd_request_fits(WSG_CMD_GET_WIDTH, 2));
}

static void test_names(void)
{
    unsigned i, flags = 0;

    for (i = 0; i < 32; i++) {
        if (!wsg_system_flag_names[i])
            continue;
        CHECK(!strncmp(wsg_system_flag_names[i], "SF_", 3));
        flags |= 1u << i;
    }
    CHECK_EQ(flags, WSG_SF_ALL);
    CHECK_EQ(WSG_SF_FAST_STOP, 1u << 12);
    CHECK(wsg_system_flag_names[10] == NULL &&
          wsg_system_flag_names[21] == NULL);
    CHECK(!strcmp(wsg_system_flag_names[9], "SF_FORCECNTL_MODE"));
    CHECK_EQ(WSG_GS_COUNT, 8);
    CHECK(!strcmp(wsg_grasp_state_names[WSG_GS_HOLDING], "HOLDING"));
    CHECK(!strcmp(wsg_status_name(WSG_E_CMD_PENDING), "E_CMD_PENDING"));
    CHECK(!strcmp(wsg_status_name(31), "E_UNKNOWN"));
}

static void test_key(void)
{
    char k[32];

    wsg_schema_key("SF_FORCECNTL_MODE", k, sizeof k);
    CHECK(!strcmp(k, "forcecntl_mode"));
    wsg_schema_key("HOLDING", k, sizeof k);
    CHECK(!strcmp(k, "holding"));
    wsg_schema_key("no-part", k, sizeof k);
    CHECK(!strcmp(k, "no_part"));
    wsg_schema_key("grasp-state", k, 6);
    CHECK(!strcmp(k, "grasp"));
}

/* The first field of a reply, formatted in style st. */
static const char *fmt_reply(uint8_t id, const uint8_t *p, size_t n,
                             const struct wsg_value_style *st, int field)
{
    static char buf[512];
    struct wsg_value v[WSG_FIELDS_MAX];
    int k = wsg_layout_decode(&wsg_schema[id].reply, p, n, v);

    if (k <= field)
        return "(does not fit)";
    wsg_value_format(&v[field], st, buf, sizeof buf);
    return buf;
}

static void test_walker(void)
{
    static const struct wsg_value_style log = {3, "(", "|", ")", 0, 4};
    static const struct wsg_value_style human = {2, " (", " ", ")", 0, 0};
    static const struct wsg_value_style bare = {2, "", "", "", 1, 0};
    const uint8_t width[] = {0x00, 0x00, 0x5C, 0x42}; /* 55.0 */
    const uint8_t flags[] = {0x81, 0x14, 0x00, 0x00}; /* D0 D7 D10 D12 */
    const uint8_t gs[] = {4}, gs_bad[] = {9};
    const uint8_t info[] = {1, 1, 0x00, 0x22, 1, 0, 0, 0};
    const uint8_t temp[] = {0xC9, 0xFF}; /* -55 tenths */
    const uint8_t tag[] = {'a', '"', 0x01};
    const uint8_t loop[] = {1, 2, 3, 4, 5, 6};
    struct wsg_value v[WSG_FIELDS_MAX];
    double num[3] = {7, 2, 1};
    uint8_t out[8];

    CHECK(!strcmp(fmt_reply(WSG_CMD_GET_WIDTH, width, 4, &log, 0), "55.000"));
    CHECK(!strcmp(fmt_reply(WSG_CMD_GET_WIDTH, width, 4, &human, 0), "55.00"));
    CHECK(!strcmp(fmt_reply(WSG_CMD_GET_WIDTH, width, 3, &log, 0),
                  "(does not fit)"));
    CHECK(!strcmp(fmt_reply(WSG_CMD_GET_SYSTEM_STATE, flags, 4, &log, 0),
                  "0x00001481(SF_REFERENCED|SF_TARGET_POS_REACHED|D10|"
                  "SF_FAST_STOP)"));
    CHECK(!strcmp(fmt_reply(WSG_CMD_GET_SYSTEM_STATE, flags, 4, &bare, 0),
                  "0x00001481"));
    CHECK(!strcmp(fmt_reply(WSG_CMD_GET_GRASP_STATE, gs, 1, &human, 0),
                  "4 (HOLDING)"));
    CHECK(!strcmp(fmt_reply(WSG_CMD_GET_GRASP_STATE, gs, 1, &bare, 0), "4"));
    CHECK(
        !strcmp(fmt_reply(WSG_CMD_GET_GRASP_STATE, gs_bad, 1, &log, 0), "9"));
    CHECK(!strcmp(fmt_reply(WSG_CMD_GET_SYSTEM_INFO, info, 8, &log, 0),
                  "1(WSG 50)"));
    CHECK(!strcmp(fmt_reply(WSG_CMD_GET_SYSTEM_INFO, info, 8, &log, 2),
                  "2.2.0"));
    CHECK(!strcmp(fmt_reply(WSG_CMD_GET_TEMPERATURE, temp, 2, &human, 0),
                  "-5.5"));
    CHECK(!strcmp(fmt_reply(WSG_CMD_GET_DEVICE_TAG, tag, 3, &log, 0),
                  "\"a\\x22\\x01\""));
    CHECK(!strcmp(fmt_reply(WSG_CMD_GET_DEVICE_TAG, tag, 1, &bare, 0), "a"));
    CHECK(!strcmp(fmt_reply(WSG_CMD_LOOP, loop, 6, &log, 0),
                  "01 02 03 04 ...(6 bytes)"));
    CHECK(!strcmp(fmt_reply(WSG_CMD_LOOP, loop, 6, &human, 0),
                  "01 02 03 04 05 06"));

    /* Fitting: fixed layouts exactly, a tail up to its maximum. */
    CHECK(wsg_layout_fits(&wsg_schema[WSG_CMD_STOP].reply, 0));
    CHECK(!wsg_layout_fits(&wsg_schema[WSG_CMD_STOP].reply, 1));
    CHECK(wsg_layout_fits(&wsg_schema[WSG_CMD_GET_DEVICE_TAG].reply, 64));
    CHECK(!wsg_layout_fits(&wsg_schema[WSG_CMD_GET_DEVICE_TAG].reply, 65));
    CHECK_EQ(wsg_layout_size(&wsg_schema[WSG_CMD_GET_SYSTEM_LIMITS].reply),
             32);

    /* Numbers back onto the wire, and off it again. */
    CHECK_EQ(wsg_layout_encode(&wsg_schema[WSG_CMD_GET_GRASP_STATS].reply, num,
                               out),
             8);
    CHECK_EQ(wsg_get_u32(out), 7);
    CHECK_EQ(wsg_get_u16(out + 4), 2);
    CHECK_EQ(wsg_get_u16(out + 6), 1);
    CHECK_EQ(wsg_layout_decode(&wsg_schema[WSG_CMD_GET_GRASP_STATS].reply, out,
                               8, v),
             3);
    CHECK(!strcmp(v[1].field->name, "no-part") && v[1].num == 2.0);
    num[0] = -5.5;
    CHECK_EQ(wsg_layout_encode(&wsg_schema[WSG_CMD_GET_TEMPERATURE].reply, num,
                               out),
             2);
    CHECK_EQ(wsg_get_u16(out), 0xFFC9);
}

int main(void)
{
    test_rows();
    test_names();
    test_key();
    test_walker();
    TEST_EXIT();
}
