/*
 * Harness 10: finger devices (src/script/fdev.c), the device models that
 * play custom finger electronics: a model's Lua and the bytes a gripper's
 * script sends it over UART and SPI. Whatever the model does and whatever
 * it is sent, the harness must not crash, its memory stays within the cap
 * it was given, no call into it runs unbounded (libFuzzer's -timeout
 * catches a model that holds on), and the finger interface stays
 * consistent: a failing model is a finger fault, cleared by a power cycle.
 *
 * Input: a configuration byte. Bit 0 set: the model's source is the input
 * from byte 1 to the first NUL (any text: the compiler and the sandbox see
 * it), the records follow the NUL. Bit 0 clear: the model is fdev_model
 * below, which does what the bytes it receives say (echo, send more than
 * the wire holds, loop forever, loop inside pcall, allocate past its cap,
 * inside pcall too, raise, send bad bytes, build long strings with
 * string.rep, set finalizers, recurse, call its API, answer 63h and SPI
 * with strings, numbers, tables, nothing), and the records follow byte 1,
 * whose value is its DATA_SIZE. Bits 1-2: the finger (0 or 1) and whether
 * the other finger has the same model.
 *
 * Records: [op][length][bytes]. op & 7: 0 set up the UART (baud from the
 * bytes), 1 write the bytes over it (finger.write), 2 one SPI transfer of
 * the bytes, 3 step the gripper (the first byte's count of 1 ms steps,
 * times 8), 4 power off, or on, 5 read 63h, 6 read the bytes arrived, 7 set
 * up the SPI. At most FDEV_RECORDS records are run, so that an input of
 * calls each at its instruction bound stays within libFuzzer's timeout.
 */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fdev.h"
#include "fuzz_check.h"
#include "wsg/device.h"
#include "wsg/finger.h"

#ifndef FUZZ_ENTRY
#define FUZZ_ENTRY LLVMFuzzerTestOneInput
#endif

int FUZZ_ENTRY(const uint8_t *data, size_t size);

/* Records run per input, and the memory each model may use (a quarter of
 * the default, to keep the harness fast; the bound is the same code). */
#define FDEV_RECORDS 48
#define FDEV_MEMORY  (256u << 10)

/* A device model that does what the bytes it is sent ask for. */
static const char fdev_model[] =
    "local answer = 'ok'\n"
    "local function op(b, rest)\n"
    "  local k = b % 16\n"
    "  if k == 0 then dev.send(rest)\n"
    "  elseif k == 1 then dev.send(string.rep('x', b * 40))\n"
    "  elseif k == 2 then while true do end\n"
    "  elseif k == 3 then\n"
    "    while true do pcall(function() while true do end end) end\n"
    "  elseif k == 4 then local t = {} for i = 1, 1e9 do t[i] = i end\n"
    "  elseif k == 5 then\n"
    "    while true do pcall(function() local t = {} "
    "for i = 1, 1e9 do t[i] = tostring(i) end end) end\n"
    "  elseif k == 6 then error('the electronics failed')\n"
    "  elseif k == 7 then dev.send({256}) \n"
    "  elseif k == 8 then local s = string.rep('', 2 ^ 31 - 1) "
    "s = string.rep('', 1e9, '') answer = s\n"
    "  elseif k == 9 then setmetatable({}, {__gc = function() "
    "while true do end end})\n"
    "  elseif k == 10 then local function f(n) return 1 + f(n + 1) end f(1)\n"
    "  elseif k == 11 then\n"
    "    local f, x, y, w, h = dev.contact()\n"
    "    answer = string.format('%g %g %g %g %g %g %d %d', f, x, y, w, h,\n"
    "      dev.time(), dev.finger(), dev.baud())\n"
    "  elseif k == 12 then answer = nil\n"
    "  elseif k == 13 then answer = {1, 2, 3}\n"
    "  elseif k == 14 then answer = string.rep(rest, 300)\n"
    "  else answer = b * 1000 end\n"
    "end\n"
    "function on_uart(bytes)\n"
    "  for i = 1, #bytes do op(bytes:byte(i), bytes:sub(i + 1)) end\n"
    "end\n"
    "function on_spi(tx)\n"
    "  if #tx > 0 then op(tx:byte(1), tx:sub(2)) end\n"
    "  return answer\n"
    "end\n"
    "function data() return answer end\n"
    "function on_power(on) answer = 'powered' end\n";

/* The finger interface's side of things, as docs/fingers.md says. */
static void fdev_check(struct wsg_device *d, struct wsg_fdev *const m[2])
{
    int i;

    for (i = 0; i < WSG_FINGER_COUNT; i++) {
        const struct wsg_finger *f = &d->fingers.f[i];

        if (m[i])
            FUZZ_CHECK(wsg_fdev_memory(m[i]) <= FDEV_MEMORY);
        FUZZ_CHECK(f->tx.len <= WSG_FINGER_FIFO && f->tx.ready <= f->tx.len);
        FUZZ_CHECK(f->rx.len <= WSG_FINGER_FIFO && f->rx.ready <= f->rx.len);
        /* A fault shows in D17. */
        FUZZ_CHECK(!f->fault || (wsg_device_flags(d) & WSG_SF_FINGER_FAULT));
    }
}

int FUZZ_ENTRY(const uint8_t *data, size_t size)
{
    static struct wsg_device dev; /* large: not on the stack */
    struct wsg_axis_config c;
    struct wsg_fdev *m[2] = {NULL, NULL};
    const char *src = fdev_model;
    size_t srclen = sizeof fdev_model - 1, i, records = 0;
    char err[256], sized[sizeof fdev_model + 64];
    uint8_t buf[WSG_FINGER_DATA_MAX];
    int fi, k;

    if (size < 2)
        return 0;
    fi = (data[0] >> 1) & 1;
    if (data[0] & 1u) {
        const uint8_t *nul = memchr(data + 1, 0, size - 1);

        src = (const char *)data + 1;
        srclen = nul ? (size_t)(nul - (data + 1)) : size - 1;
        i = 1 + srclen + (nul ? 1 : 0);
    } else {
        snprintf(sized, sizeof sized, "DATA_SIZE = %u\n%s", (unsigned)data[1],
                 fdev_model);
        src = sized;
        srclen = strlen(sized);
        i = 2;
    }
    FUZZ_CHECK(wsg_axis_config_init(&c, "wsg50") == 0);
    wsg_device_init(&dev, &c);
    for (k = 0; k < 2; k++) {
        if (k != fi && !((data[0] >> 2) & 1u))
            continue;
        if (wsg_fdev_open(&m[k], &dev.fingers, k, NULL, src, srclen, "fuzz",
                          FDEV_MEMORY, err, sizeof err) != 0) {
            FUZZ_CHECK(m[k] == NULL && memchr(err, 0, sizeof err));
            continue;
        }
        /* Bounded while it is compiled and its body run, then closed
         * until the finger's power starts it. */
        FUZZ_CHECK(wsg_fdev_memory(m[k]) == 0);
    }
    wsg_device_settle(&dev);
    fdev_check(&dev, m);

    while (i + 2 <= size && records++ < FDEV_RECORDS) {
        unsigned op = data[i];
        size_t len = data[i + 1], n;
        const uint8_t *p = data + i + 2;
        uint32_t ax_faults = wsg_axis_faults(wsg_device_axis(&dev));

        if (len > size - i - 2)
            len = size - i - 2;
        i += 2 + len;
        switch (op & 7u) {
        case 0:
            wsg_finger_set_uart(&dev.fingers, fi,
                                len >= 4 ? wsg_get_u32(p) : 115200u);
            break;
        case 1:
            n = wsg_finger_write(&dev.fingers, fi, p, len);
            FUZZ_CHECK(n <= len);
            break;
        case 2:
            if (len <= WSG_FINGER_SPI_MAX)
                wsg_finger_spi(&dev.fingers, fi, p, buf, len);
            break;
        case 3:
            for (n = (len ? p[0] : 1) * 8u; n > 0; n--)
                wsg_device_step(&dev);
            break;
        case 4:
            wsg_finger_request_power(&dev.fingers, fi, (op >> 3) & 1u);
            break;
        case 5:
            wsg_finger_data(&dev.fingers, fi, ax_faults, buf, &n);
            FUZZ_CHECK(n <= WSG_FINGER_DATA_MAX);
            FUZZ_CHECK(n == 0 || n == wsg_finger_size(&dev.fingers, fi));
            break;
        case 6:
            n = wsg_finger_read(&dev.fingers, fi, buf, len ? p[0] : 64u);
            break;
        case 7:
            wsg_finger_set_spi(&dev.fingers, fi,
                               len >= 4 ? wsg_get_u32(p) : 1000000u, 8,
                               (uint8_t)(op >> 3 & 3u));
            break;
        }
        wsg_device_settle(&dev);
        fdev_check(&dev, m);
        if ((op >> 5) == 7) /* the records go to the other finger */
            fi ^= 1;
    }
    wsg_fdev_close(m[0]);
    wsg_fdev_close(m[1]);
    return 0;
}
