/*
 * Harness 9: the finger commands (60h..63h, 70h..73h) through the
 * dispatcher, in both addressing styles and with any payload, with the
 * fingers' kinds, power, faults and wires changed in between, on the fuzz
 * bench (fuzz_bench.h), whose invariants hold for every packet: each
 * request answered once, a known status, parameters that fit the schema's
 * reply layout only with E_SUCCESS.
 *
 * Input: one configuration byte (fuzz_bench_begin), then records of
 * [op][control][length][length bytes]. An op below 0xC0 is a finger
 * command: the eight IDs by its low three bits, the payload as given (no
 * payload, an index, index and on/off, anything longer); 0xC0..0xDF one of
 * the schema's other commands, the first byte its index in fuzz_ids.h and
 * the rest its payload, so the fingers get a grasp to feel; from 0xE0 a change
 * the commands do not reach, applied between chunks and settled as the control
 * channel settles it: a finger's kind (a device's electronics here a small C
 * link whose behaviour the bytes pick: answers short, long, failing), its
 * power, a tare, the part's contact patch, the finger's UART or SPI set up and
 * bytes written, read or moved over SPI as a script would. After every record
 * both fingers are checked against what docs/fingers.md says: 60h's type and
 * size for the kind, 61h's flags within the known bits and consistent with the
 * state, 63h's data as long as 60h's size (or an error saying why), a DSA
 * cell within 0..3895, the UART's queues within their bounds.
 */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "fuzz_bench.h"
#include "fuzz_check.h"
#include "fuzz_ids.h"
#include "wsg/device.h"
#include "wsg/finger.h"
#include "wsg/proto.h"

#ifndef FUZZ_ENTRY
#define FUZZ_ENTRY LLVMFuzzerTestOneInput
#endif

int FUZZ_ENTRY(const uint8_t *data, size_t size);

static const uint8_t fuzz_finger_ids[8] = {0x60, 0x61, 0x62, 0x63,
                                           0x70, 0x71, 0x72, 0x73};

/* The test electronics: behaviour bits per finger, set with the kind.
 * Bit 0: data() fails; bit 1: SPI fails; bit 2: UART bytes fail; bit 3:
 * power-on fails; bit 4: echo the UART's bytes back; bit 5: answer data
 * short. Each call checks it runs within its bounds. */
static uint8_t fuzz_link_mode[WSG_FINGER_COUNT];
static struct wsg_fingers *fuzz_link_fs;

static int fl_power(void *ctx, int i, int on)
{
    (void)ctx;
    FUZZ_CHECK(i == 0 || i == 1);
    return on && (fuzz_link_mode[i] & 8u) ? -1 : 0;
}

static int fl_uart(void *ctx, int i, const uint8_t *p, size_t n)
{
    (void)ctx;
    FUZZ_CHECK(i == 0 || i == 1);
    FUZZ_CHECK(n > 0 && n <= WSG_FINGER_FIFO);
    if (fuzz_link_mode[i] & 4u)
        return -1;
    if (fuzz_link_mode[i] & 16u) /* the link may send from the update */
        wsg_finger_device_send(fuzz_link_fs, i, p, n);
    return 0;
}

static int fl_spi(void *ctx, int i, const uint8_t *tx, uint8_t *rx, size_t n)
{
    size_t k;

    (void)ctx;
    FUZZ_CHECK(i == 0 || i == 1);
    FUZZ_CHECK(n <= WSG_FINGER_SPI_MAX);
    if (fuzz_link_mode[i] & 2u)
        return -1;
    for (k = 0; k < n; k++)
        rx[k] = (uint8_t)(tx[k] ^ 0x5Au);
    return 0;
}

static int fl_data(void *ctx, int i, uint8_t *out, size_t cap)
{
    size_t k, n;

    (void)ctx;
    FUZZ_CHECK(i == 0 || i == 1);
    FUZZ_CHECK(cap <= WSG_FINGER_DATA_MAX);
    if (fuzz_link_mode[i] & 1u)
        return -1;
    n = fuzz_link_mode[i] & 32u ? cap / 2 : cap;
    for (k = 0; k < n; k++)
        out[k] = (uint8_t)k;
    return (int)n;
}

static const struct wsg_finger_link fuzz_link = {fl_power, fl_uart, fl_spi,
                                                 fl_data};

static uint32_t fuzz_faults(struct wsg_device *d)
{
    return wsg_axis_faults(wsg_device_axis(d));
}

/* Both fingers as docs/fingers.md describes them. */
static void fuzz_check_fingers(struct wsg_device *d)
{
    uint8_t buf[WSG_FINGER_DATA_MAX];
    int i, k;

    for (i = 0; i < WSG_FINGER_COUNT; i++) {
        const struct wsg_finger *f = &d->fingers.f[i];
        uint16_t fl = wsg_finger_flags(&d->fingers, i, fuzz_faults(d));
        uint16_t size = wsg_finger_size(&d->fingers, i);
        uint16_t st;
        size_t n = 12345;

        FUZZ_CHECK((unsigned)f->kind < WSG_FINGER_KINDS);
        FUZZ_CHECK((fl & ~0x7Fu) == 0);
        FUZZ_CHECK(size <= WSG_FINGER_DATA_MAX);
        FUZZ_CHECK(!(fl & WSG_FF_POWERED) == !f->powered ||
                   f->kind == WSG_FINGER_NONE);
        FUZZ_CHECK(!((fl & WSG_FF_UART) && (fl & WSG_FF_SPI)));
        switch (f->kind) {
        case WSG_FINGER_NONE:
            FUZZ_CHECK(fl == 0 && size == 0);
            FUZZ_CHECK(wsg_finger_type(&d->fingers, i) ==
                       WSG_FINGER_TYPE_NONE);
            break;
        case WSG_FINGER_FMF:
            FUZZ_CHECK(size == 4);
            break;
        case WSG_FINGER_DSA:
            FUZZ_CHECK(size == 2 * WSG_DSA_CELLS);
            for (k = 0; k < WSG_DSA_CELLS; k++)
                FUZZ_CHECK(f->cells[k] <= WSG_DSA_MAX);
            break;
        default:
            FUZZ_CHECK(wsg_finger_type(&d->fingers, i) ==
                       WSG_FINGER_TYPE_GENERIC);
            break;
        }
        /* The UART's queues. */
        FUZZ_CHECK(f->tx.len <= WSG_FINGER_FIFO && f->tx.ready <= f->tx.len);
        FUZZ_CHECK(f->rx.len <= WSG_FINGER_FIFO && f->rx.ready <= f->rx.len);
        FUZZ_CHECK(f->tx.head < WSG_FINGER_FIFO &&
                   f->rx.head < WSG_FINGER_FIFO);
        /* 63h: D1 says whether it answers with data, and with how much. */
        st = wsg_finger_data(&d->fingers, i, fuzz_faults(d), buf, &n);
        if (st == WSG_E_SUCCESS)
            FUZZ_CHECK(n == size);
        else
            FUZZ_CHECK(n == 0 &&
                       (st == WSG_E_NO_SENSOR || st == WSG_E_NOT_AVAILABLE ||
                        st == WSG_E_READ_ERROR));
        FUZZ_CHECK(!(fl & WSG_FF_DATA) || st == WSG_E_SUCCESS ||
                   f->kind == WSG_FINGER_DEVICE);
    }
    /* D17 from a finger's electronics. */
    FUZZ_CHECK(!wsg_fingers_fault(&d->fingers) ||
               (wsg_device_flags(d) & WSG_SF_FINGER_FAULT));
}

/* A change the commands do not reach: op 0xE0..0xFF, its bytes p. */
static void fuzz_finger_event(struct wsg_device *d, unsigned op,
                              const uint8_t *p, size_t len)
{
    uint8_t b0 = len > 0 ? p[0] : 0, b1 = len > 1 ? p[1] : 0;
    uint8_t rx[WSG_FINGER_SPI_MAX + 8];
    int i = b0 & 1;
    size_t n;

    switch (op & 7u) {
    case 0: /* a kind; 4 and up: a device whose behaviour is b1 */
        if ((b0 >> 1) % 6 >= WSG_FINGER_DEVICE) {
            fuzz_link_mode[i] = b1;
            wsg_finger_attach(&d->fingers, i, &fuzz_link, NULL,
                              (uint16_t)(len > 2 ? p[2] * 2u : 0));
        } else {
            wsg_finger_request_kind(&d->fingers, i,
                                    (enum wsg_finger_kind)((b0 >> 1) % 6));
        }
        break;
    case 1:
        wsg_finger_request_power(&d->fingers, i, (b0 >> 1) & 1);
        break;
    case 2:
        wsg_finger_request_tare(&d->fingers);
        break;
    case 3: /* the contact patch, up to 51 x 51 mm (0: the default) */
        wsg_axis_set_part_patch(wsg_device_axis(d), b0 / 5.0, b1 / 5.0);
        break;
    case 4: /* a UART at any rate, valid or not */
        wsg_finger_set_uart(&d->fingers, i,
                            len > 3 ? wsg_get_u32(p) >> (p[3] & 7u) : b1);
        break;
    case 5: /* an SPI: clock, bits, mode as given */
        wsg_finger_set_spi(&d->fingers, i,
                           len > 3 ? wsg_get_u32(p) : 1000000u * b1,
                           len > 4 ? p[4] : 8, len > 5 ? p[5] : 0);
        break;
    case 6: /* bytes written, as finger.write */
        n = wsg_finger_write(&d->fingers, i, p, len);
        FUZZ_CHECK(n <= len);
        break;
    case 7: /* bytes read, or one SPI transfer */
        if (b0 & 2u) {
            n = len > WSG_FINGER_SPI_MAX + 8 ? WSG_FINGER_SPI_MAX + 8 : len;
            wsg_finger_spi(&d->fingers, i, p, rx, n);
        } else {
            n = wsg_finger_read(&d->fingers, i, rx, b1);
            FUZZ_CHECK(n <= b1);
        }
        break;
    }
    wsg_device_settle(d);
}

int FUZZ_ENTRY(const uint8_t *data, size_t size)
{
    uint8_t pkt[WSG_HEADER_LEN + WSG_PAYLOAD_MAX + WSG_CRC_LEN];
    struct wsg_device *d;
    size_t i = 1;

    if (size < 1)
        return 0;
    fuzz_bench_begin(data[0]);
    d = fuzz_bench_device();
    fuzz_link_fs = &d->fingers;
    memset(fuzz_link_mode, 0, sizeof fuzz_link_mode);
    while (i + 3 <= size) {
        unsigned op = data[i];
        uint8_t ctl = data[i + 1];
        size_t len = data[i + 2], n;

        i += 3;
        if (len > size - i)
            len = size - i;
        if (op >= 0xE0) {
            fuzz_finger_event(d, op, data + i, len);
            /* the bench steps as the control byte says, with no bytes */
            fuzz_bench_chunk((uint8_t)(ctl & 0x0Fu), NULL, 0);
        } else if (op >= 0xC0) {
            /* another command: its index in fuzz_ids first */
            n = len ? wsg_frame_encode(pkt, sizeof pkt,
                                       fuzz_ids[data[i] % FUZZ_NIDS],
                                       data + i + 1, len - 1)
                    : 0;
            if (n)
                fuzz_bench_chunk(ctl, pkt, n);
        } else {
            n = wsg_frame_encode(pkt, sizeof pkt, fuzz_finger_ids[op & 7u],
                                 data + i, len);
            if (n)
                fuzz_bench_chunk(ctl, pkt, n);
        }
        i += len;
        fuzz_check_fingers(d);
    }
    fuzz_bench_end();
    fuzz_check_fingers(d);
    /* A device's link must not outlive this input. */
    wsg_finger_attach(&d->fingers, 0, NULL, NULL, 0);
    wsg_finger_attach(&d->fingers, 1, NULL, NULL, 0);
    return 0;
}
