/*
 * Numbers as the documentation writes them (CAN IDs, command IDs, ports,
 * counts): decimal digits, or 0x (0X) and hex digits. strtoul with base 0
 * would read 010 as octal 8, refuse 08, and take blanks and signs, so the
 * daemon's options and wsgctl read them here. No I/O, no allocation.
 */
#include <errno.h>

#include "wsg/proto.h"

int wsg_parse_ulong(const char *s, unsigned long max, unsigned long *out)
{
    unsigned long v = 0, base = 10;

    if (s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
        base = 16;
        s += 2;
    }
    if (*s == '\0')
        return -EINVAL;
    for (; *s; s++) {
        unsigned long d;

        if (*s >= '0' && *s <= '9')
            d = (unsigned long)(*s - '0');
        else if (base == 16 && *s >= 'a' && *s <= 'f')
            d = (unsigned long)(*s - 'a' + 10);
        else if (base == 16 && *s >= 'A' && *s <= 'F')
            d = (unsigned long)(*s - 'A' + 10);
        else
            return -EINVAL;
        /* v * base + d > max, asked without overflowing */
        if (d > max || v > (max - d) / base)
            return -ERANGE;
        v = v * base + d;
    }
    *out = v;
    return 0;
}
