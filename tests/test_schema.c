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
        CHECK(wsg_field_type_name(f->type) != NULL);
        if (f->type == WSG_FT_ENUM8 || f->type == WSG_FT_BITS8 ||
            f->type == WSG_FT_BITS16 || f->type == WSG_FT_BITS32)
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

static const struct wsg_value_style log_style = {3, "(", "|", ")", 0, 4};
static const struct wsg_value_style human = {2, " (", " ", ")", 0, 0};
static const struct wsg_value_style bare = {2, "", "", "", 1, 0};

/* A reply's parameters, which field of them, and how it reads. */
static const struct {
    uint8_t id;
    const char *params;
    size_t len;
    const struct wsg_value_style *style;
    int field;
    const char *text;
} formats[] = {
    {WSG_CMD_GET_WIDTH, "\x00\x00\x5C\x42", 4, &log_style, 0, "55.000"},
    {WSG_CMD_GET_WIDTH, "\x00\x00\x5C\x42", 4, &human, 0, "55.00"},
    {WSG_CMD_GET_WIDTH, "\x00\x00\x5C", 3, &log_style, 0, NULL},
    /* D0, D7, D10 (reserved), D12 */
    {WSG_CMD_GET_SYSTEM_STATE, "\x81\x14\x00\x00", 4, &log_style, 0,
     "0x00001481(SF_REFERENCED|SF_TARGET_POS_REACHED|D10|SF_FAST_STOP)"},
    {WSG_CMD_GET_SYSTEM_STATE, "\x81\x14\x00\x00", 4, &bare, 0, "0x00001481"},
    {WSG_CMD_GET_GRASP_STATE, "\x04", 1, &human, 0, "4 (HOLDING)"},
    {WSG_CMD_GET_GRASP_STATE, "\x04", 1, &bare, 0, "4"},
    {WSG_CMD_GET_GRASP_STATE, "\x09", 1, &log_style, 0, "9"},
    {WSG_CMD_GET_SYSTEM_INFO, "\x01\x01\x00\x22\x01\x00\x00\x00", 8,
     &log_style, 0, "1(WSG 50)"},
    {WSG_CMD_GET_SYSTEM_INFO, "\x01\x01\x00\x22\x01\x00\x00\x00", 8,
     &log_style, 2, "2.2.0"},
    {WSG_CMD_GET_TEMPERATURE, "\xC9\xFF", 2, &human, 0, "-5.5"},
    {WSG_CMD_GET_DEVICE_TAG, "a\"\x01", 3, &log_style, 0, "\"a\\x22\\x01\""},
    {WSG_CMD_GET_DEVICE_TAG, "a", 1, &bare, 0, "a"},
    {WSG_CMD_LOOP, "\x01\x02\x03\x04\x05\x06", 6, &log_style, 0,
     "01 02 03 04 ...(6 bytes)"},
    {WSG_CMD_LOOP, "\x01\x02\x03\x04\x05\x06", 6, &human, 0,
     "01 02 03 04 05 06"},
};

static void test_format(void)
{
    size_t i;

    for (i = 0; i < sizeof formats / sizeof formats[0]; i++) {
        struct wsg_value v[WSG_FIELDS_MAX];
        char buf[512];
        int k = wsg_layout_decode(&wsg_schema[formats[i].id].reply,
                                  (const uint8_t *)formats[i].params,
                                  formats[i].len, v);

        if (!formats[i].text) {
            CHECK_EQ(k, -1); /* does not fit */
            continue;
        }
        REQUIRE(k > formats[i].field);
        wsg_value_format(&v[formats[i].field], formats[i].style, buf,
                         sizeof buf);
        if (strcmp(buf, formats[i].text) != 0)
            fprintf(stderr, "case %zu: \"%s\", not \"%s\"\n", i, buf,
                    formats[i].text);
        CHECK(!strcmp(buf, formats[i].text));
    }
}

static void test_walker(void)
{
    struct wsg_value v[WSG_FIELDS_MAX];
    double num[3] = {7, 2, 1};
    uint8_t out[8];

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
    test_format();
    test_walker();
    TEST_EXIT();
}
