/*
 * The gripper's state as JSON (state.h). Numbers are printed at the
 * precision a viewer can use (micrometres, mN, hundredths of a degree),
 * so a change below it is no change: the web page's pushes compare these
 * texts, not the model's doubles.
 */
#include "state.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "script.h"
#include "wsg/plant.h"
#include "wsg/schema.h"

/* The script's name and error are cut to these many bytes of JSON: the
 * whole error is in the control channel's `script status` and the log;
 * the state must stay one control channel line. */
#define STATE_SCRIPT_NAME_MAX  80u
#define STATE_SCRIPT_ERROR_MAX 320u

/* Appends to buf at *used; what does not fit is cut, never overrun. */
static void append(char *buf, size_t cap, size_t *used, const char *fmt, ...)
{
    va_list ap;
    int n;

    if (*used + 1 >= cap)
        return;
    va_start(ap, fmt);
    n = vsnprintf(buf + *used, cap - *used, fmt, ap);
    va_end(ap);
    if (n > 0)
        *used += (size_t)n < cap - *used ? (size_t)n : cap - *used - 1;
}

/* s as a JSON string, quotes included, of at most max bytes: cut where
 * the next character's escape would not fit. Control bytes are escaped,
 * other bytes go as they are (a script's error is UTF-8 or what it
 * made). */
static void append_string(char *buf, size_t cap, size_t *used, const char *s,
                          size_t max)
{
    size_t start = *used;

    append(buf, cap, used, "\"");
    for (; *s; s++) {
        unsigned char ch = (unsigned char)*s;
        char esc[8];

        if (ch == '"' || ch == '\\')
            snprintf(esc, sizeof esc, "\\%c", ch);
        else if (ch == '\n')
            snprintf(esc, sizeof esc, "\\n");
        else if (ch < 0x20 || ch == 0x7F)
            snprintf(esc, sizeof esc, "\\u%04x", ch);
        else
            snprintf(esc, sizeof esc, "%c", ch);
        if (*used - start + strlen(esc) + 1 > max)
            break;
        append(buf, cap, used, "%s", esc);
    }
    append(buf, cap, used, "\"");
}

/* The script host's part: which script ran last, whether it runs, and
 * why it failed (D20 is in the flags). */
static void append_script(char *buf, size_t cap, size_t *used,
                          const struct wsg_gripper *g)
{
    struct wsg_script_status st;
    const char *name;

    if (!g->script) {
        append(buf, cap, used,
               "\"script\":{\"name\":null,\"running\":false,"
               "\"error\":null},");
        return;
    }
    wsg_script_status(g->script, &st);
    append(buf, cap, used, "\"script\":{\"name\":");
    if (st.file) {
        /* Its file name: the page knows the directory. */
        name = strrchr(st.file, '/');
        append_string(buf, cap, used, name ? name + 1 : st.file,
                      STATE_SCRIPT_NAME_MAX);
    } else {
        append(buf, cap, used, "null");
    }
    append(buf, cap, used,
           ",\"running\":%s,\"error\":", st.running ? "true" : "false");
    if (st.error)
        append_string(buf, cap, used, st.error, STATE_SCRIPT_ERROR_MAX);
    else
        append(buf, cap, used, "null");
    append(buf, cap, used, "},");
}

/* Each finger: its kind, power, fault, and what its pad feels (N). The
 * DSA cells are the control channel's `finger I cells`, which the page
 * asks for when this state changes: 84 numbers a finger would crowd this
 * line. */
static void append_fingers(char *buf, size_t cap, size_t *used,
                           const struct wsg_device *d)
{
    uint32_t faults = wsg_axis_faults(wsg_device_axis_const(d));
    int i;

    append(buf, cap, used, "\"fingers\":[");
    for (i = 0; i < WSG_FINGER_COUNT; i++) {
        const struct wsg_finger *f = &d->fingers.f[i];

        append(buf, cap, used,
               "%s{\"kind\":\"%s\",\"powered\":%s,\"fault\":%s,"
               "\"force\":%.3f}",
               i ? "," : "", wsg_finger_kind_name(f->kind),
               f->powered ? "true" : "false",
               (wsg_finger_flags(&d->fingers, i, faults) & WSG_FF_FAULT)
                   ? "true"
                   : "false",
               f->contact.force);
    }
    append(buf, cap, used, "],");
}

/* The object a physics plant holds between the fingers, for the page to
 * draw: its shape, sizes (mm), mass, friction and where it is now (mm, the
 * scene's frame); null when there is none or the plant has no objects. A
 * position that is not a number (a scene gone unstable) reads null. */
static void append_object(char *buf, size_t cap, size_t *used,
                          const struct wsg_gripper *g)
{
    static const char *const kinds[] = {"none", "box", "cylinder", "sphere"};
    struct wsg_object o;

    if (!g->plant || !g->plant->ops->object(g->plant, &o) ||
        (unsigned)o.kind >= sizeof kinds / sizeof kinds[0]) {
        append(buf, cap, used, "\"object\":null,");
        return;
    }
    append(buf, cap, used,
           "\"object\":{\"kind\":\"%s\",\"size\":[%g,%g,%g],\"mass\":%g,"
           "\"friction\":%g,\"pos\":",
           kinds[o.kind], o.size[0], o.size[1], o.size[2], o.mass, o.friction);
    if (isfinite(o.pos[0]) && isfinite(o.pos[1]) && isfinite(o.pos[2]) &&
        fabs(o.pos[0]) < 1e6 && fabs(o.pos[1]) < 1e6 && fabs(o.pos[2]) < 1e6)
        append(buf, cap, used, "[%.2f,%.2f,%.2f]},", o.pos[0], o.pos[1],
               o.pos[2]);
    else
        append(buf, cap, used, "null},");
}

void wsg_state_format_time(char *buf, size_t len, uint64_t us)
{
    char frac[8];
    int digits = 6;

    snprintf(frac, sizeof frac, "%06u", (unsigned)(us % 1000000u));
    while (digits > 3 && frac[digits - 1] == '0')
        digits--;
    frac[digits] = '\0';
    snprintf(buf, len, "%llu.%s", (unsigned long long)(us / 1000000u), frac);
}

size_t wsg_state_format(char *buf, size_t cap, const struct wsg_gripper *g,
                        const struct wsg_sched *s, enum wsg_state_parts parts)
{
    const struct wsg_device *d = &g->dev;
    const struct wsg_axis *ax = wsg_device_axis_const(d);
    uint32_t flags = wsg_device_flags(d);
    unsigned gs = (unsigned)wsg_axis_grasp_state(ax);
    struct wsg_grasp_stats stats = wsg_axis_stats(ax);
    char t[32], key[32], gs_key[32];
    double part_width, stiffness;
    size_t used = 0;
    unsigned i;
    int first = 1;

    if (cap == 0)
        return 0;
    buf[0] = '\0';
    append(buf, cap, &used,
           "{\"width\":%.3f,\"speed\":%.3f,\"force\":%.3f,"
           "\"temperature\":%.2f,\"flags\":%lu,\"flag_names\":[",
           wsg_axis_width(ax), wsg_axis_speed(ax), wsg_axis_force(ax),
           wsg_axis_temperature(ax), (unsigned long)flags);
    /* The manual's names in the channel's spelling ("fast_stop"). */
    for (i = 0; i < 32; i++) {
        if (!(flags & (1u << i)) || !wsg_system_flag_names[i])
            continue;
        wsg_schema_key(wsg_system_flag_names[i], key, sizeof key);
        append(buf, cap, &used, "%s\"%s\"", first ? "" : ",", key);
        first = 0;
    }
    if (gs < WSG_GS_COUNT)
        wsg_schema_key(wsg_grasp_state_names[gs], gs_key, sizeof gs_key);
    else
        strcpy(gs_key, "unknown");
    append(buf, cap, &used,
           "],\"grasp_state\":%u,\"grasp_state_name\":\"%s\","
           "\"stats\":{\"total\":%lu,\"no_part\":%u,\"lost_part\":%u},",
           gs, gs_key, (unsigned long)stats.total, (unsigned)stats.no_part,
           (unsigned)stats.lost_part);
    if (parts != WSG_STATE_NO_TIME) {
        wsg_state_format_time(t, sizeof t, wsg_axis_time(ax));
        append(buf, cap, &used, "\"time\":%s,", t);
    }
    append(
        buf, cap, &used,
        "\"paused\":%s,\"scale\":%g,\"delayed\":%lu,\"delay_dropped\":%llu,",
        s->paused ? "true" : "false", s->scale,
        (unsigned long)wsg_gripper_delayed(g),
        (unsigned long long)wsg_gripper_delay_dropped(g));
    append_script(buf, cap, &used, g);
    append_fingers(buf, cap, &used, d);
    append_object(buf, cap, &used, g);
    /* The world's part and obstacle too: the web page draws them
     * between the fingers. */
    if (wsg_axis_part(ax, &part_width, &stiffness))
        append(buf, cap, &used, "\"part\":{\"width\":%.3f,\"stiffness\":%g},",
               part_width, stiffness);
    else
        append(buf, cap, &used, "\"part\":null,");
    if (wsg_axis_obstacle(ax, &part_width))
        append(buf, cap, &used, "\"obstacle\":%.3f}", part_width);
    else
        append(buf, cap, &used, "\"obstacle\":null}");
    return used;
}
