/*
 * The script's finger library: finger.type, data, count and power for
 * the fingers fitted, and the pass-through to custom finger electronics
 * (finger.interface, write, read, bytes_available, spi), all through the
 * finger interface (wsg/finger.h) of the script's gripper.
 *
 * A request (power) is settled at once, as the other libraries' are, so
 * the next call sees it. Bytes written go on the wire from the gripper's
 * time now and reach the finger in the steps their baud rate gives them;
 * reads take what has arrived by the last step, never waiting: a script
 * polls finger.bytes_available and sleeps, as the public scripts do. The
 * byte work is spent from the script's slice.
 *
 * Written to the part of the C API that Lua 5.2 and 5.4 share.
 */
#include <lauxlib.h>
#include <string.h>

#include "fdev.h"
#include "script_impl.h"
#include "wsg/finger.h"

static struct wsg_fingers *fingers_of(lua_State *L)
{
    return &wsg_script_of(L)->dev->fingers;
}

static int finger_index(lua_State *L)
{
    lua_Number i = luaL_checknumber(L, 1);

    luaL_argcheck(L, i == 0 || i == 1, 1, "a finger is 0 or 1");
    return (int)i;
}

/* nil and why, as Lua's io functions fail. */
static int finger_fail(lua_State *L, int i, const char *why)
{
    lua_pushnil(L);
    lua_pushfstring(L, "finger %d: %s", i, why);
    return 2;
}

static int finger_type(lua_State *L)
{
    struct wsg_fingers *fs = fingers_of(L);
    int i = finger_index(L);
    enum wsg_finger_kind k = fs->f[i].kind;

    /* Custom electronics sit on a generic finger. */
    lua_pushstring(L, wsg_finger_kind_name(
                          k == WSG_FINGER_DEVICE ? WSG_FINGER_GENERIC : k));
    return 1;
}

/* An FMF's force in N (tared), a DSA pad's 84 cells as a table (row by
 * row), a device's 63h data as a string; nil for a finger without data,
 * without power or faulted. */
static int finger_data(lua_State *L)
{
    struct wsg_script *h = wsg_script_of(L);
    struct wsg_fingers *fs = fingers_of(L);
    int i = finger_index(L), k;
    uint8_t buf[WSG_FINGER_DATA_MAX];
    size_t n;

    if (wsg_finger_data(fs, i, wsg_axis_faults(wsg_device_axis(h->dev)), buf,
                        &n) != WSG_E_SUCCESS ||
        n == 0) {
        lua_pushnil(L);
        return 1;
    }
    switch (fs->f[i].kind) {
    case WSG_FINGER_FMF:
        lua_pushnumber(L, fs->f[i].fmf);
        break;
    case WSG_FINGER_DSA:
        lua_createtable(L, WSG_DSA_CELLS, 0);
        for (k = 0; k < WSG_DSA_CELLS; k++) {
            lua_pushinteger(L, fs->f[i].cells[k]);
            lua_rawseti(L, -2, k + 1);
        }
        break;
    default:
        lua_pushlstring(L, (const char *)buf, n);
        break;
    }
    return 1;
}

static int finger_count(lua_State *L)
{
    lua_pushinteger(L, WSG_FINGER_COUNT);
    return 1;
}

/* finger.power(i [, on]): switch it (settled now); its power. */
static int finger_power(lua_State *L)
{
    struct wsg_script *h = wsg_script_of(L);
    struct wsg_fingers *fs = fingers_of(L);
    int i = finger_index(L);

    if (!lua_isnoneornil(L, 2) && fs->f[i].kind != WSG_FINGER_NONE) {
        wsg_finger_request_power(fs, i, lua_toboolean(L, 2));
        wsg_device_settle(h->dev);
    }
    lua_pushboolean(L, fs->f[i].powered);
    return 1;
}

static lua_Number opt_number(lua_State *L, int arg, lua_Number def)
{
    return lua_isnoneornil(L, arg) ? def : luaL_checknumber(L, arg);
}

/* finger.interface(i, "uart", baud) or (i, "spi", hz [, bits [, mode]]):
 * true, or nil and why. */
static int finger_interface(lua_State *L)
{
    struct wsg_fingers *fs = fingers_of(L);
    int i = finger_index(L);
    const char *what = luaL_checkstring(L, 2);
    lua_Number a = luaL_checknumber(L, 3);
    int r;

    if (fs->f[i].kind == WSG_FINGER_NONE)
        return finger_fail(L, i, "no finger fitted");
    if (strcmp(what, "uart") == 0) {
        r = a >= WSG_FINGER_BAUD_MIN && a <= WSG_FINGER_BAUD_MAX
                ? wsg_finger_set_uart(fs, i, (uint32_t)a)
                : -1;
        if (r < 0)
            return finger_fail(L, i, "baud rate out of 300..4000000");
    } else if (strcmp(what, "spi") == 0) {
        lua_Number bits = opt_number(L, 4, 8), mode = opt_number(L, 5, 0);

        r = a >= WSG_FINGER_SPI_HZ_MIN && a <= WSG_FINGER_SPI_HZ_MAX &&
                    bits == 8 &&
                    (mode == 0 || mode == 1 || mode == 2 || mode == 3)
                ? wsg_finger_set_spi(fs, i, (uint32_t)a, 8, (uint8_t)mode)
                : -1;
        if (r < 0)
            return finger_fail(L, i,
                               "SPI wants 1000..50000000 Hz, 8 bits, mode "
                               "0..3");
    } else {
        return luaL_argerror(L, 2, "\"uart\" or \"spi\"");
    }
    lua_pushboolean(L, 1);
    return 1;
}

/* Bytes from a string or a table of numbers 0..255, at most cap (fdev.h:
 * the device models take theirs so as well). */
size_t wsg_script_bytes(lua_State *L, int arg, uint8_t *out, size_t cap)
{
    size_t n, k;

    if (lua_type(L, arg) == LUA_TSTRING) {
        const char *s = lua_tolstring(L, arg, &n);

        if (n > cap)
            n = cap;
        memcpy(out, s, n);
        return n;
    }
    luaL_checktype(L, arg, LUA_TTABLE);
    n = lua_rawlen(L, arg);
    if (n > cap)
        n = cap;
    for (k = 0; k < n; k++) {
        lua_Number v;

        lua_rawgeti(L, arg, (int)k + 1);
        v = lua_tonumber(L, -1);
        lua_pop(L, 1);
        if (!(v >= 0 && v <= 255) || v != (lua_Number)(int)v)
            return (size_t)luaL_error(L, "byte %d is not a number 0..255",
                                      (int)k + 1);
        out[k] = (uint8_t)v;
    }
    return n;
}

/* finger.write(i, string or table): the bytes taken (what the UART's
 * buffer holds), or nil and why. */
static int finger_write(lua_State *L)
{
    struct wsg_fingers *fs = fingers_of(L);
    int i = finger_index(L);
    uint8_t buf[WSG_FINGER_FIFO];
    size_t n;

    if (fs->f[i].iface != WSG_FINGER_IFACE_UART)
        return finger_fail(L, i, "no UART set up (finger.interface)");
    if (!fs->f[i].powered)
        return finger_fail(L, i, "no power");
    n = wsg_script_bytes(L, 2, buf, sizeof buf);
    wsg_script_spend(wsg_script_of(L), L, (uint32_t)n);
    lua_pushinteger(L, (lua_Integer)wsg_finger_write(fs, i, buf, n));
    return 1;
}

static int finger_available(lua_State *L)
{
    lua_pushinteger(
        L, (lua_Integer)wsg_finger_available(fingers_of(L), finger_index(L)));
    return 1;
}

/* finger.read(i [, n]): a table of up to n of the bytes arrived (all of
 * them without n); empty when none. */
static int finger_read(lua_State *L)
{
    struct wsg_fingers *fs = fingers_of(L);
    int i = finger_index(L);
    lua_Number want = opt_number(L, 2, WSG_FINGER_FIFO);
    uint8_t buf[WSG_FINGER_FIFO];
    size_t n, k;

    luaL_argcheck(L, want >= 0, 2, "a count of bytes");
    n = want < WSG_FINGER_FIFO ? (size_t)want : WSG_FINGER_FIFO;
    n = wsg_finger_read(fs, i, buf, n);
    wsg_script_spend(wsg_script_of(L), L, (uint32_t)n);
    lua_createtable(L, (int)n, 0);
    for (k = 0; k < n; k++) {
        lua_pushinteger(L, buf[k]);
        lua_rawseti(L, -2, (int)k + 1);
    }
    return 1;
}

/* finger.spi(i, table): one transfer, the bytes clocked in as a table;
 * nil and why when it cannot happen. */
static int finger_spi(lua_State *L)
{
    struct wsg_script *h = wsg_script_of(L);
    struct wsg_fingers *fs = fingers_of(L);
    int i = finger_index(L);
    uint8_t tx[WSG_FINGER_SPI_MAX], rx[WSG_FINGER_SPI_MAX];
    size_t n, k;
    uint16_t st;

    luaL_checktype(L, 2, LUA_TTABLE);
    luaL_argcheck(L, lua_rawlen(L, 2) <= WSG_FINGER_SPI_MAX, 2,
                  "at most 256 bytes a transfer");
    n = wsg_script_bytes(L, 2, tx, sizeof tx);
    wsg_script_spend(h, L, (uint32_t)n);
    st = wsg_finger_spi(fs, i, tx, rx, n);
    if (st == WSG_E_NOT_AVAILABLE)
        return finger_fail(L, i,
                           fs->f[i].powered
                               ? "no SPI set up (finger.interface)"
                               : "no power");
    if (st != WSG_E_SUCCESS)
        return finger_fail(L, i, wsg_status_name(st));
    lua_createtable(L, (int)n, 0);
    for (k = 0; k < n; k++) {
        lua_pushinteger(L, rx[k]);
        lua_rawseti(L, -2, (int)k + 1);
    }
    return 1;
}

static const luaL_Reg finger_lib[] = {{"type", finger_type},
                                      {"data", finger_data},
                                      {"count", finger_count},
                                      {"power", finger_power},
                                      {"interface", finger_interface},
                                      {"write", finger_write},
                                      {"read", finger_read},
                                      {"bytes_available", finger_available},
                                      {"spi", finger_spi},
                                      {NULL, NULL}};

void wsg_script_open_finger(lua_State *L)
{
    luaL_newlib(L, finger_lib);
    lua_setglobal(L, "finger");
}
