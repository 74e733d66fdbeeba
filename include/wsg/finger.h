/*
 * The finger interface: the two fingers a gripper carries, as its firmware
 * sees them. Each finger has a kind (none, generic, a force measurement
 * finger, a DSA tactile pad, or a generic finger whose own electronics a
 * device model plays), a power switch, a tare for force measurement, and
 * for custom electronics a UART or SPI link.
 *
 * The sensors read the model only through wsg_axis_contact: a force
 * measurement finger's value is the force on its pad minus its tare; a DSA
 * pad spreads that force over the cells under the part's contact patch.
 *
 * State changes only in wsg_fingers_update, which the device calls in its
 * step and in its settle (a step of zero length) after every command:
 * handlers and scripts record requests (a kind, power, a tare, bytes to
 * send) and the update applies them, moves UART bytes along the wire at
 * the time the baud rate gives each byte (simulated, in nanoseconds), and
 * takes the sensors' values for the step. No clock is read here, nothing
 * is allocated: everything lives in struct wsg_fingers.
 *
 * The numbers the command set does not make public are this emulator's
 * choice (docs/fingers.md): 60h's type byte (WSG_FINGER_TYPE_*) and 61h's
 * flags (WSG_FF_*).
 */
#ifndef WSG_FINGER_H
#define WSG_FINGER_H

#include <stddef.h>
#include <stdint.h>

#include "wsg/axis.h"
#include "wsg/schema.h"

#define WSG_FINGER_COUNT 2
/* A DSA pad: 6 columns by 14 rows at 3.4 mm, row-major, each 0..3895. */
#define WSG_DSA_COLS     6
#define WSG_DSA_ROWS     14
#define WSG_DSA_CELLS    (WSG_DSA_COLS * WSG_DSA_ROWS)
#define WSG_DSA_PITCH_MM 3.4
#define WSG_DSA_MAX      3895u
/* What a cell reads per newton on its area (3895 at 10 N), saturating. */
#define WSG_DSA_PER_N 389.5
/* The most data one finger's 63h carries (a device model's may be up to
 * this; a DSA frame is 168 bytes). */
#define WSG_FINGER_DATA_MAX WSG_PAYLOAD_MAX
/* Bytes each direction of a finger's UART holds: in flight plus, towards
 * the gripper, received and not yet read. */
#define WSG_FINGER_FIFO 2048u
/* UART bit rates a script may choose, and SPI clocks. */
#define WSG_FINGER_BAUD_MIN   300u
#define WSG_FINGER_BAUD_MAX   4000000u
#define WSG_FINGER_SPI_HZ_MIN 1000u
#define WSG_FINGER_SPI_HZ_MAX 50000000u
/* The most bytes one SPI transfer moves. */
#define WSG_FINGER_SPI_MAX 256u

enum wsg_finger_kind {
    WSG_FINGER_NONE,
    WSG_FINGER_GENERIC,
    WSG_FINGER_FMF,
    WSG_FINGER_DSA,
    WSG_FINGER_DEVICE, /* generic, with a device model's electronics */
    WSG_FINGER_KINDS
};

/* 60h's type byte. A finger with custom electronics is a generic finger
 * to the gripper. */
enum wsg_finger_type {
    WSG_FINGER_TYPE_NONE = 0,
    WSG_FINGER_TYPE_GENERIC = 1,
    WSG_FINGER_TYPE_FMF = 2,
    WSG_FINGER_TYPE_DSA = 3
};

/* 61h's flags. */
#define WSG_FF_POWERED 0x0001u /* the finger has power */
#define WSG_FF_DATA    0x0002u /* 63h answers with data now */
#define WSG_FF_FAULT   0x0004u /* the finger's electronics failed */
#define WSG_FF_CONTACT 0x0008u /* something presses on the pad */
#define WSG_FF_UART    0x0010u /* its UART is set up */
#define WSG_FF_SPI     0x0020u /* its SPI is set up */
#define WSG_FF_OVERRUN 0x0040u /* bytes towards the gripper were lost */

enum wsg_finger_iface {
    WSG_FINGER_IFACE_NONE,
    WSG_FINGER_IFACE_UART,
    WSG_FINGER_IFACE_SPI
};

/* The electronics of a device finger: a device model (the script host's
 * finger devices) or a test's. Called from within wsg_fingers_update, or
 * from wsg_finger_spi and wsg_finger_data: none may call back into the
 * update. Each returns 0, or < 0 when the electronics failed, which sets
 * the finger's fault until its power is cycled. */
struct wsg_finger_link {
    /* Power switched (on 1 or 0); also at attach while powered. */
    int (*power)(void *ctx, int finger, int on);
    /* Bytes that reached the finger over its UART in this step. */
    int (*uart)(void *ctx, int finger, const uint8_t *p, size_t n);
    /* One SPI transfer: rx gets n bytes for the n of tx. */
    int (*spi)(void *ctx, int finger, const uint8_t *tx, uint8_t *rx,
               size_t n);
    /* 63h's data, at most cap bytes: its length (< 0: failed). */
    int (*data)(void *ctx, int finger, uint8_t *out, size_t cap);
};

/* One direction of a UART: bytes on their way and, towards the gripper,
 * arrived ones (the first `ready`), as a ring. */
struct wsg_finger_fifo {
    uint8_t b[WSG_FINGER_FIFO];
    uint16_t head, len, ready;
    uint64_t next_ns; /* when the first byte in flight arrives */
    uint64_t free_ns; /* when the line is free for the next byte */
};

struct wsg_finger {
    enum wsg_finger_kind kind;
    int powered;
    int fault; /* the electronics failed; a power cycle clears it */
    int overrun;
    double tare; /* N, subtracted from an FMF's force */
    struct wsg_contact contact;
    float fmf; /* the FMF's value for 63h */
    uint16_t cells[WSG_DSA_CELLS];
    /* Custom electronics: the link set up by the script, and the device. */
    enum wsg_finger_iface iface;
    uint32_t baud, spi_hz;
    uint8_t spi_bits, spi_mode;
    uint64_t byte_ns;
    struct wsg_finger_fifo tx; /* gripper -> finger */
    struct wsg_finger_fifo rx; /* finger -> gripper */
    uint16_t data_size;        /* a device's 63h size */
    const struct wsg_finger_link *link;
    void *link_ctx;
    /* Requests, applied by the next update: -1 none. */
    int req_kind, req_power;
};

struct wsg_fingers {
    struct wsg_finger f[WSG_FINGER_COUNT];
    uint64_t now_ns; /* simulated time of the last update */
    int req_tare;
};

/* Both fingers of kind, powered. */
void wsg_fingers_init(struct wsg_fingers *fs, enum wsg_finger_kind kind);
/* Apply the requests, move the UARTs to the axis's time and take the
 * sensors' values from its contact. */
void wsg_fingers_update(struct wsg_fingers *fs, const struct wsg_axis *ax);
/* Bytes on a wire: the update must run every step until they arrive. */
int wsg_fingers_busy(const struct wsg_fingers *fs);
/* Some finger measures force (Tare, FORCECNTL_MODE). */
int wsg_fingers_fmf(const struct wsg_fingers *fs);
/* A finger's electronics failed (D17 SF_FINGER_FAULT). */
int wsg_fingers_fault(const struct wsg_fingers *fs);

/* Requests (i 0 or 1, checked by the caller). A new kind takes effect
 * with the next update: the link and the interface are dropped, power and
 * tare kept. */
void wsg_finger_request_kind(struct wsg_fingers *fs, int i,
                             enum wsg_finger_kind kind);
void wsg_finger_request_power(struct wsg_fingers *fs, int i, int on);
void wsg_finger_request_tare(struct wsg_fingers *fs);
/* Attach a device's electronics to finger i (its kind becomes device
 * with the next update); data_size is 60h's size of its data. link NULL
 * detaches. */
void wsg_finger_attach(struct wsg_fingers *fs, int i,
                       const struct wsg_finger_link *link, void *ctx,
                       uint16_t data_size);

/* The commands' view. wsg_finger_check: E_SUCCESS, E_NO_SENSOR (no
 * finger), E_NOT_AVAILABLE (no power), or E_READ_ERROR (a fault; ax_faults
 * the axis's injected faults, whose SF_FINGER_FAULT counts for both). */
uint16_t wsg_finger_check(const struct wsg_fingers *fs, int i,
                          uint32_t ax_faults);
enum wsg_finger_type wsg_finger_type(const struct wsg_fingers *fs, int i);
/* 60h's size: the bytes 63h carries for this finger's kind. */
uint16_t wsg_finger_size(const struct wsg_fingers *fs, int i);
uint16_t wsg_finger_flags(const struct wsg_fingers *fs, int i,
                          uint32_t ax_faults);
/* 63h: check, then the data into out (WSG_FINGER_DATA_MAX), *n its
 * length. A device's data comes from its link now. */
uint16_t wsg_finger_data(struct wsg_fingers *fs, int i, uint32_t ax_faults,
                         uint8_t *out, size_t *n);
/* "none", "generic", "fmf", "dsa", "device"; and back (-1: unknown). */
const char *wsg_finger_kind_name(enum wsg_finger_kind k);
int wsg_finger_kind_parse(const char *s);

/* The custom electronics' wire. Set up finger i's UART at baud (0 or
 * -EINVAL out of range) or its SPI. */
int wsg_finger_set_uart(struct wsg_fingers *fs, int i, uint32_t baud);
int wsg_finger_set_spi(struct wsg_fingers *fs, int i, uint32_t hz,
                       uint8_t bits, uint8_t mode);
/* Queue bytes for the finger: the count taken (what fits). They leave one
 * byte time after another from now, and reach the finger in the update
 * of the step in which each arrives. */
size_t wsg_finger_write(struct wsg_fingers *fs, int i, const uint8_t *p,
                        size_t n);
/* Bytes that arrived from the finger and are not read yet; take up to n. */
size_t wsg_finger_available(const struct wsg_fingers *fs, int i);
size_t wsg_finger_read(struct wsg_fingers *fs, int i, uint8_t *out, size_t n);
/* One SPI transfer (n <= WSG_FINGER_SPI_MAX): E_SUCCESS with rx filled,
 * E_NOT_AVAILABLE without power or SPI set up, E_READ_ERROR on a fault.
 * A finger without electronics answers 0xFF (an idle MISO line). */
uint16_t wsg_finger_spi(struct wsg_fingers *fs, int i, const uint8_t *tx,
                        uint8_t *rx, size_t n);
/* For the device's electronics: bytes it sends towards the gripper, put
 * on the wire from the time of the update they are sent in. Those that do
 * not fit are lost (WSG_FF_OVERRUN). Returns the count taken. */
size_t wsg_finger_device_send(struct wsg_fingers *fs, int i, const uint8_t *p,
                              size_t n);

#endif
