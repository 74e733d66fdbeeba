/*
 * wsgctl --json: one JSON object per command on stdout, for scripts. A
 * command's values are gathered while it runs (jout_*: the fields of
 * print_values, the channel's answers, the echo of a loop) and the object
 * is written once it has ended, with "error" and "exit" when it failed.
 * The reason of a failure is the last thing wsgctl said on stderr
 * (err_last), which still goes to stderr as well.
 */
#include "wsgctl.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/* Append to the object's fields; what does not fit is cut, and said so
 * once at the end (jout_print). */
void jout_add(struct jout *j, const char *fmt, ...)
{
    va_list ap;
    int n;

    if (j->cut || j->len >= sizeof j->body) {
        j->cut = 1;
        return;
    }
    va_start(ap, fmt);
    n = vsnprintf(j->body + j->len, sizeof j->body - j->len, fmt, ap);
    va_end(ap);
    if (n < 0 || (size_t)n >= sizeof j->body - j->len) {
        j->body[j->len] = '\0'; /* no half a value */
        j->cut = 1;
        return;
    }
    j->len += (size_t)n;
}

/* s[0..n) as a JSON string, quoted, into f. */
void json_write_str(FILE *f, const char *s, size_t n)
{
    fputc('"', f);
    for (size_t i = 0; i < n; i++) {
        unsigned char ch = (unsigned char)s[i];

        if (ch == '"' || ch == '\\')
            fprintf(f, "\\%c", ch);
        else if (ch == '\n')
            fputs("\\n", f);
        else if (ch == '\t')
            fputs("\\t", f);
        else if (ch == '\r')
            fputs("\\r", f);
        else if (ch < 0x20 || ch == 0x7F)
            fprintf(f, "\\u%04x", ch);
        else
            fputc(ch, f);
    }
    fputc('"', f);
}

/* ,"key":"s" with s escaped; all of it or, when it does not fit,
 * nothing (and "cut"). */
void jout_str(struct jout *j, const char *key, const char *s, size_t n)
{
    size_t start = j->len;
    int was_cut = j->cut;

    j->cut = 0;
    jout_add(j, ",\"%s\":\"", key);
    for (size_t i = 0; i < n && !j->cut; i++) {
        unsigned char ch = (unsigned char)s[i];

        if (ch == '"' || ch == '\\')
            jout_add(j, "\\%c", ch);
        else if (ch == '\n')
            jout_add(j, "\\n");
        else if (ch == '\t')
            jout_add(j, "\\t");
        else if (ch == '\r')
            jout_add(j, "\\r");
        else if (ch < 0x20 || ch == 0x7F)
            jout_add(j, "\\u%04x", ch);
        else
            jout_add(j, "%c", ch);
    }
    jout_add(j, "\"");
    if (j->cut) {
        j->len = start;
        j->body[start] = '\0';
    }
    j->cut |= was_cut;
}

/* One value of a reply layout under the control channel's spelling of its
 * name ("grasp_state"): numbers as numbers, the names of an enumeration
 * and of the set bits beside them ("grasp_state_name", "flags_names"),
 * text as a string. */
void jout_value(struct jout *j, const struct wsg_value *v)
{
    static const struct wsg_value_style named = {2, " ", " ", "", 0, 0};
    static const struct wsg_value_style bare = {2, "", "", "", 1, 0};
    char key[40], buf[4 * WSG_REPLY_PARAMS_MAX + 64], name[48];
    const char *p;

    wsg_schema_key(v->field->name, key, sizeof key);
    switch (v->field->type) {
    case WSG_FT_F32:
    case WSG_FT_I16_TENTHS:
        jout_add(j, ",\"%s\":%.6g", key, v->num);
        break;
    case WSG_FT_U8:
    case WSG_FT_U16:
    case WSG_FT_U32:
        jout_add(j, ",\"%s\":%lu", key, (unsigned long)v->raw);
        break;
    case WSG_FT_ENUM8:
        jout_add(j, ",\"%s\":%lu", key, (unsigned long)v->raw);
        wsg_value_format(v, &named, buf, sizeof buf);
        p = strchr(buf, ' ');
        snprintf(name, sizeof name, "%s_name", key);
        if (p)
            jout_str(j, name, p + 1, strlen(p + 1));
        break;
    case WSG_FT_BITS8:
    case WSG_FT_BITS16:
    case WSG_FT_BITS32:
        jout_add(j, ",\"%s\":%lu,\"%s_names\":[", key, (unsigned long)v->raw,
                 key);
        wsg_value_format(v, &named, buf, sizeof buf);
        p = strchr(buf, ' ');
        for (int first = 1; p && *p;) {
            size_t n;

            p++;
            n = strcspn(p, " ");
            if (n)
                jout_add(j, "%s\"%.*s\"", first ? "" : ",", (int)n, p);
            first = 0;
            p += n;
        }
        jout_add(j, "]");
        break;
    case WSG_FT_VERSION:
    case WSG_FT_TEXT:
    case WSG_FT_BYTES:
        wsg_value_format(v, &bare, buf, sizeof buf);
        jout_str(j, key, buf, strlen(buf));
        break;
    }
}

/* The object for the command that ran: its name, the gripper's status
 * when it answered one, the fields gathered, and for a failure the reason
 * wsgctl gave and the exit status. */
void jout_print(const struct jout *j, const char *command, int rc,
                const char *error)
{
    fputs("{\"command\":", stdout);
    json_write_str(stdout, command, strlen(command));
    if (j->has_status)
        printf(",\"status\":\"%s\"", wsg_status_name(j->status));
    else if (rc == EXIT_OK && j->gripper)
        fputs(",\"status\":\"E_SUCCESS\"", stdout);
    fputs(j->body, stdout);
    if (j->cut)
        fputs(",\"cut\":true", stdout);
    if (rc != EXIT_OK) {
        fputs(",\"error\":", stdout);
        json_write_str(stdout, error, strlen(error));
        printf(",\"exit\":%d", rc);
    }
    fputs("}\n", stdout);
    fflush(stdout);
}
