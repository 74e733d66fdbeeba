/*
 * options_list: the daemon's settings table (src/daemon/options.c), one
 * setting a line: its name, then "key" when it is also a config-file key
 * and "not" when it is the negation of another setting (--no-crc).
 * options_docs.sh checks the documents that list the options against it,
 * so an option added to the table and missing from them fails a test.
 */
#include "options.h"

#include <stdio.h>

int main(void)
{
    size_t n, i;
    const struct wsg_setting *s = wsg_options_settings(&n);

    for (i = 0; i < n; i++)
        printf("%s%s%s\n", s[i].name, s[i].cli_only ? "" : " key",
               s[i].type == WSG_SETTING_NOT ? " not" : "");
    return 0;
}
