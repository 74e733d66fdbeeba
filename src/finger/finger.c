/*
 * The finger interface (wsg/finger.h): each finger's kind, power, tare and
 * sensor values, and the UART and SPI of custom electronics.
 *
 * Everything that changes with time changes in wsg_fingers_update, from
 * the axis's simulated time: requests recorded by the commands and the
 * script are applied there, UART bytes arrive there one byte time apart
 * (ten bits a byte: 8N1), and the sensors take their values there from
 * what the model says each pad feels (wsg_axis_contact). The update runs
 * after every step and every settle, so a command answered after another
 * sees what the first one asked, and a run in lockstep is exact.
 */
#include "wsg/finger.h"

#include <math.h>
#include <string.h>

#include "wsg/proto.h"

static const char *const kind_names[WSG_FINGER_KINDS] = {
    "none", "generic", "fmf", "dsa", "device"};

const char *wsg_finger_kind_name(enum wsg_finger_kind k)
{
    return (unsigned)k < WSG_FINGER_KINDS ? kind_names[k] : "?";
}

int wsg_finger_kind_parse(const char *s)
{
    int k;

    for (k = 0; k < WSG_FINGER_KINDS; k++)
        if (strcmp(s, kind_names[k]) == 0)
            return k;
    return -1;
}

static void fifo_clear(struct wsg_finger_fifo *q)
{
    q->head = q->len = q->ready = 0;
    q->next_ns = q->free_ns = 0;
}

/* The interface and its wires back to nothing (a new kind). */
static void finger_unwire(struct wsg_finger *f)
{
    f->iface = WSG_FINGER_IFACE_NONE;
    f->baud = f->spi_hz = 0;
    f->spi_bits = f->spi_mode = 0;
    f->byte_ns = 0;
    fifo_clear(&f->tx);
    fifo_clear(&f->rx);
    f->overrun = 0;
}

void wsg_fingers_init(struct wsg_fingers *fs, enum wsg_finger_kind kind)
{
    int i;

    memset(fs, 0, sizeof *fs);
    for (i = 0; i < WSG_FINGER_COUNT; i++) {
        fs->f[i].kind = kind == WSG_FINGER_DEVICE ? WSG_FINGER_GENERIC : kind;
        fs->f[i].powered = 1;
        fs->f[i].req_kind = fs->f[i].req_power = -1;
    }
}

/* The electronics are there and may be called. */
static int finger_live(const struct wsg_finger *f)
{
    return f->kind == WSG_FINGER_DEVICE && f->link && f->powered && !f->fault;
}

/* A call into the electronics failed: the finger faults until its power
 * is cycled, and its wires go quiet. */
static void finger_failed(struct wsg_finger *f)
{
    f->fault = 1;
    fifo_clear(&f->tx);
    fifo_clear(&f->rx);
}

/* ---- the UART's wires ---- */

static size_t fifo_push(struct wsg_finger_fifo *q, uint64_t now,
                        uint64_t byte_ns, const uint8_t *p, size_t n)
{
    size_t room = WSG_FINGER_FIFO - q->len, k;
    uint64_t start = q->free_ns > now ? q->free_ns : now;

    if (n > room)
        n = room;
    if (n == 0)
        return 0;
    for (k = 0; k < n; k++)
        q->b[(q->head + q->len + k) % WSG_FINGER_FIFO] = p[k];
    if (q->len == q->ready)
        q->next_ns = start + byte_ns; /* the first byte in flight */
    q->len = (uint16_t)(q->len + n);
    q->free_ns = start + (uint64_t)n * byte_ns;
    return n;
}

/* Bytes in flight whose time has come are arrived. */
static void fifo_arrive(struct wsg_finger_fifo *q, uint64_t now,
                        uint64_t byte_ns)
{
    while (q->ready < q->len && q->next_ns <= now) {
        q->ready++;
        q->next_ns += byte_ns;
    }
}

static size_t fifo_take(struct wsg_finger_fifo *q, uint8_t *out, size_t n)
{
    size_t k;

    if (n > q->ready)
        n = q->ready;
    for (k = 0; k < n; k++)
        out[k] = q->b[(q->head + k) % WSG_FINGER_FIFO];
    q->head = (uint16_t)((q->head + n) % WSG_FINGER_FIFO);
    q->len = (uint16_t)(q->len - n);
    q->ready = (uint16_t)(q->ready - n);
    return n;
}

static void finger_wires(struct wsg_finger *f, int i, uint64_t now)
{
    uint8_t buf[WSG_FINGER_FIFO];
    size_t n;

    if (f->iface != WSG_FINGER_IFACE_UART)
        return;
    fifo_arrive(&f->tx, now, f->byte_ns);
    n = fifo_take(&f->tx, buf, sizeof buf);
    /* Without electronics to take them, the bytes are gone all the same. */
    if (n && finger_live(f) && f->link->uart &&
        f->link->uart(f->link_ctx, i, buf, n) < 0)
        finger_failed(f);
    fifo_arrive(&f->rx, now, f->byte_ns);
}

/* ---- the sensors ---- */

/* Length of the overlap of [a0, a1] and [b0, b1]. */
static double overlap(double a0, double a1, double b0, double b1)
{
    double lo = a0 > b0 ? a0 : b0, hi = a1 < b1 ? a1 : b1;

    return hi > lo ? hi - lo : 0.0;
}

/* The pad's cells under the patch: the force spread evenly over the part
 * of the patch that lies on the pad, each cell reading what its area
 * carries. Cell (c, r) is centred at x = (c - 2.5) * pitch, y = (r - 6.5)
 * * pitch from the pad's centre; index r * 6 + c. */
static void dsa_cells(struct wsg_finger *f)
{
    const struct wsg_contact *c = &f->contact;
    const double hw = WSG_DSA_COLS * WSG_DSA_PITCH_MM / 2.0;
    const double hh = WSG_DSA_ROWS * WSG_DSA_PITCH_MM / 2.0;
    double x0 = c->x - c->w / 2.0, x1 = c->x + c->w / 2.0;
    double y0 = c->y - c->h / 2.0, y1 = c->y + c->h / 2.0;
    double on_pad = overlap(x0, x1, -hw, hw) * overlap(y0, y1, -hh, hh);
    int r, k;

    memset(f->cells, 0, sizeof f->cells);
    if (!(c->force > 0.0) || !(on_pad > 0.0) || !isfinite(c->force))
        return;
    for (r = 0; r < WSG_DSA_ROWS; r++) {
        double cy0 = -hh + r * WSG_DSA_PITCH_MM;
        double oy = overlap(y0, y1, cy0, cy0 + WSG_DSA_PITCH_MM);

        if (oy <= 0.0)
            continue;
        for (k = 0; k < WSG_DSA_COLS; k++) {
            double cx0 = -hw + k * WSG_DSA_PITCH_MM;
            double a = oy * overlap(x0, x1, cx0, cx0 + WSG_DSA_PITCH_MM);
            double v = c->force * a / on_pad * WSG_DSA_PER_N;

            f->cells[r * WSG_DSA_COLS + k] =
                v >= WSG_DSA_MAX ? (uint16_t)WSG_DSA_MAX : (uint16_t)lround(v);
        }
    }
}

static void finger_sense(struct wsg_finger *f)
{
    f->fmf = 0.0f;
    if (f->kind == WSG_FINGER_FMF)
        f->fmf = (float)(f->contact.force - f->tare);
    else if (f->kind == WSG_FINGER_DSA)
        dsa_cells(f);
}

/* ---- the update ---- */

static void finger_power(struct wsg_finger *f, int i, int on)
{
    if (f->powered == on)
        return;
    f->powered = on;
    /* The electronics start again: what was on the wire is lost, and a
     * fault is gone with the power. */
    fifo_clear(&f->tx);
    fifo_clear(&f->rx);
    f->overrun = 0;
    f->fault = 0;
    if (f->kind == WSG_FINGER_DEVICE && f->link && f->link->power &&
        f->link->power(f->link_ctx, i, on) < 0)
        finger_failed(f);
}

void wsg_fingers_update(struct wsg_fingers *fs, const struct wsg_axis *ax)
{
    int i;

    fs->now_ns = wsg_axis_time(ax) * 1000u;
    for (i = 0; i < WSG_FINGER_COUNT; i++) {
        struct wsg_finger *f = &fs->f[i];

        if (f->req_kind >= 0) {
            f->kind = (enum wsg_finger_kind)f->req_kind;
            f->req_kind = -1;
            f->fault = 0;
            f->tare = 0.0;
            finger_unwire(f);
            if (f->kind != WSG_FINGER_DEVICE) {
                f->link = NULL;
                f->link_ctx = NULL;
                f->data_size = 0;
            } else if (f->link && f->powered && f->link->power &&
                       f->link->power(f->link_ctx, i, 1) < 0) {
                finger_failed(f);
            }
        }
        if (f->req_power >= 0) {
            finger_power(f, i, f->req_power);
            f->req_power = -1;
        }
        if (wsg_axis_contact(ax, i, &f->contact) != 0)
            memset(&f->contact, 0, sizeof f->contact);
        if (fs->req_tare && f->kind == WSG_FINGER_FMF)
            f->tare = f->contact.force;
        finger_wires(f, i, fs->now_ns);
        finger_sense(f);
    }
    fs->req_tare = 0;
}

int wsg_fingers_busy(const struct wsg_fingers *fs)
{
    int i;

    for (i = 0; i < WSG_FINGER_COUNT; i++)
        if (fs->f[i].tx.len > fs->f[i].tx.ready ||
            fs->f[i].rx.len > fs->f[i].rx.ready)
            return 1;
    return 0;
}

int wsg_fingers_fmf(const struct wsg_fingers *fs)
{
    return fs->f[0].kind == WSG_FINGER_FMF || fs->f[1].kind == WSG_FINGER_FMF;
}

int wsg_fingers_fault(const struct wsg_fingers *fs)
{
    return fs->f[0].fault || fs->f[1].fault;
}

void wsg_finger_request_kind(struct wsg_fingers *fs, int i,
                             enum wsg_finger_kind kind)
{
    fs->f[i].req_kind = (int)kind;
}

void wsg_finger_request_power(struct wsg_fingers *fs, int i, int on)
{
    fs->f[i].req_power = on ? 1 : 0;
}

void wsg_finger_request_tare(struct wsg_fingers *fs)
{
    fs->req_tare = 1;
}

void wsg_finger_attach(struct wsg_fingers *fs, int i,
                       const struct wsg_finger_link *link, void *ctx,
                       uint16_t data_size)
{
    struct wsg_finger *f = &fs->f[i];

    /* At once, not with the update: whoever detaches may free ctx now. */
    f->link = link;
    f->link_ctx = link ? ctx : NULL;
    f->data_size =
        data_size > WSG_FINGER_DATA_MAX ? WSG_FINGER_DATA_MAX : data_size;
    f->req_kind = link ? WSG_FINGER_DEVICE : WSG_FINGER_GENERIC;
}

/* ---- what the commands read ---- */

uint16_t wsg_finger_check(const struct wsg_fingers *fs, int i,
                          uint32_t ax_faults)
{
    const struct wsg_finger *f = &fs->f[i];

    if (f->kind == WSG_FINGER_NONE)
        return WSG_E_NO_SENSOR;
    if (!f->powered)
        return WSG_E_NOT_AVAILABLE;
    if (f->fault || (ax_faults & WSG_SF_FINGER_FAULT))
        return WSG_E_READ_ERROR;
    return WSG_E_SUCCESS;
}

enum wsg_finger_type wsg_finger_type(const struct wsg_fingers *fs, int i)
{
    switch (fs->f[i].kind) {
    case WSG_FINGER_FMF:
        return WSG_FINGER_TYPE_FMF;
    case WSG_FINGER_DSA:
        return WSG_FINGER_TYPE_DSA;
    case WSG_FINGER_GENERIC:
    case WSG_FINGER_DEVICE:
        return WSG_FINGER_TYPE_GENERIC;
    default:
        return WSG_FINGER_TYPE_NONE;
    }
}

uint16_t wsg_finger_size(const struct wsg_fingers *fs, int i)
{
    switch (fs->f[i].kind) {
    case WSG_FINGER_FMF:
        return 4;
    case WSG_FINGER_DSA:
        return 2 * WSG_DSA_CELLS;
    case WSG_FINGER_DEVICE:
        return fs->f[i].data_size;
    default:
        return 0;
    }
}

uint16_t wsg_finger_flags(const struct wsg_fingers *fs, int i,
                          uint32_t ax_faults)
{
    const struct wsg_finger *f = &fs->f[i];
    uint16_t fl = 0;

    if (f->kind == WSG_FINGER_NONE)
        return 0;
    if (f->powered)
        fl |= WSG_FF_POWERED;
    if (wsg_finger_check(fs, i, ax_faults) == WSG_E_SUCCESS &&
        wsg_finger_size(fs, i) > 0)
        fl |= WSG_FF_DATA;
    if (f->fault || (ax_faults & WSG_SF_FINGER_FAULT))
        fl |= WSG_FF_FAULT;
    if (f->contact.force > 0.0)
        fl |= WSG_FF_CONTACT;
    if (f->iface == WSG_FINGER_IFACE_UART)
        fl |= WSG_FF_UART;
    if (f->iface == WSG_FINGER_IFACE_SPI)
        fl |= WSG_FF_SPI;
    if (f->overrun)
        fl |= WSG_FF_OVERRUN;
    return fl;
}

uint16_t wsg_finger_data(struct wsg_fingers *fs, int i, uint32_t ax_faults,
                         uint8_t *out, size_t *n)
{
    struct wsg_finger *f = &fs->f[i];
    uint16_t st = wsg_finger_check(fs, i, ax_faults);
    size_t k;
    int got;

    *n = 0;
    if (st != WSG_E_SUCCESS)
        return st;
    switch (f->kind) {
    case WSG_FINGER_FMF:
        wsg_put_f32(out, f->fmf);
        *n = 4;
        break;
    case WSG_FINGER_DSA:
        for (k = 0; k < WSG_DSA_CELLS; k++)
            wsg_put_u16(out + 2 * k, f->cells[k]);
        *n = 2 * WSG_DSA_CELLS;
        break;
    case WSG_FINGER_DEVICE:
        if (!f->data_size)
            break;
        memset(out, 0, f->data_size);
        got = f->link && f->link->data
                  ? f->link->data(f->link_ctx, i, out, f->data_size)
                  : 0;
        if (got < 0) {
            finger_failed(f);
            return WSG_E_READ_ERROR;
        }
        *n = f->data_size; /* a short answer is padded with zeros */
        break;
    default:
        break;
    }
    return WSG_E_SUCCESS;
}

/* ---- custom electronics ---- */

int wsg_finger_set_uart(struct wsg_fingers *fs, int i, uint32_t baud)
{
    struct wsg_finger *f = &fs->f[i];

    if (baud < WSG_FINGER_BAUD_MIN || baud > WSG_FINGER_BAUD_MAX)
        return -22; /* -EINVAL, without errno.h in the core's headers */
    finger_unwire(f);
    f->iface = WSG_FINGER_IFACE_UART;
    f->baud = baud;
    /* Ten bits a byte (8N1), rounded to the nanosecond. */
    f->byte_ns = (10000000000ull + baud / 2) / baud;
    return 0;
}

int wsg_finger_set_spi(struct wsg_fingers *fs, int i, uint32_t hz,
                       uint8_t bits, uint8_t mode)
{
    struct wsg_finger *f = &fs->f[i];

    if (hz < WSG_FINGER_SPI_HZ_MIN || hz > WSG_FINGER_SPI_HZ_MAX ||
        bits != 8 || mode > 3)
        return -22;
    finger_unwire(f);
    f->iface = WSG_FINGER_IFACE_SPI;
    f->spi_hz = hz;
    f->spi_bits = bits;
    f->spi_mode = mode;
    return 0;
}

size_t wsg_finger_write(struct wsg_fingers *fs, int i, const uint8_t *p,
                        size_t n)
{
    struct wsg_finger *f = &fs->f[i];

    if (f->iface != WSG_FINGER_IFACE_UART || !f->powered || f->fault ||
        f->kind == WSG_FINGER_NONE)
        return 0;
    return fifo_push(&f->tx, fs->now_ns, f->byte_ns, p, n);
}

size_t wsg_finger_available(const struct wsg_fingers *fs, int i)
{
    return fs->f[i].rx.ready;
}

size_t wsg_finger_read(struct wsg_fingers *fs, int i, uint8_t *out, size_t n)
{
    return fifo_take(&fs->f[i].rx, out, n);
}

uint16_t wsg_finger_spi(struct wsg_fingers *fs, int i, const uint8_t *tx,
                        uint8_t *rx, size_t n)
{
    struct wsg_finger *f = &fs->f[i];
    uint16_t st = wsg_finger_check(fs, i, 0);

    if (st != WSG_E_SUCCESS)
        return st;
    if (f->iface != WSG_FINGER_IFACE_SPI || n > WSG_FINGER_SPI_MAX)
        return WSG_E_NOT_AVAILABLE;
    memset(rx, 0xFF, n);
    if (finger_live(f) && f->link->spi &&
        f->link->spi(f->link_ctx, i, tx, rx, n) < 0) {
        finger_failed(f);
        return WSG_E_READ_ERROR;
    }
    return WSG_E_SUCCESS;
}

size_t wsg_finger_device_send(struct wsg_fingers *fs, int i, const uint8_t *p,
                              size_t n)
{
    struct wsg_finger *f = &fs->f[i];
    size_t k;

    if (f->iface != WSG_FINGER_IFACE_UART || !f->powered || f->fault)
        return 0; /* nobody listens: the bytes go nowhere */
    k = fifo_push(&f->rx, fs->now_ns, f->byte_ns, p, n);
    if (k < n)
        f->overrun = 1;
    return k;
}
