/*
 * Replays fuzz inputs without libFuzzer: every file named on the command
 * line, or every regular file in a directory named there, goes through
 * every harness (each accepts any bytes). Built by every compiler, so the
 * seed corpus and every crash-regression input run in each ctest; a
 * violated invariant aborts, which fails the test.
 */
#define _POSIX_C_SOURCE 200809L

#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

int fuzz_frames_one(const uint8_t *data, size_t size);
int fuzz_commands_one(const uint8_t *data, size_t size);
int fuzz_config_one(const uint8_t *data, size_t size);
int fuzz_control_one(const uint8_t *data, size_t size);
int fuzz_script_one(const uint8_t *data, size_t size);
int fuzz_gcl_one(const uint8_t *data, size_t size);
int fuzz_sse_one(const uint8_t *data, size_t size);
int fuzz_match_one(const uint8_t *data, size_t size);
int fuzz_fingers_one(const uint8_t *data, size_t size);
int fuzz_fdev_one(const uint8_t *data, size_t size);

/* Largest input replayed; libFuzzer's default -max_len is 4096. */
#define REPLAY_MAX (1u << 20)

static int replay_file(const char *path)
{
    static uint8_t buf[REPLAY_MAX];
    FILE *f = fopen(path, "rb");
    size_t n;

    if (!f) {
        perror(path);
        return -1;
    }
    n = fread(buf, 1, sizeof buf, f);
    fclose(f);
    fuzz_frames_one(buf, n);
    fuzz_commands_one(buf, n);
    fuzz_config_one(buf, n);
    fuzz_control_one(buf, n);
    fuzz_script_one(buf, n);
    fuzz_gcl_one(buf, n);
    fuzz_sse_one(buf, n);
    fuzz_match_one(buf, n);
    fuzz_fingers_one(buf, n);
    fuzz_fdev_one(buf, n);
    return 0;
}

/* Files in directory order; the order does not matter, each input starts
 * from a fresh gripper. */
static int replay_dir(const char *dir, unsigned *count)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    int rc = 0;

    if (!d) {
        perror(dir);
        return -1;
    }
    while ((e = readdir(d)) != NULL) {
        char path[4096];
        struct stat st;

        if (e->d_name[0] == '.')
            continue; /* ., .. and hidden files such as .gitkeep */
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        if (stat(path, &st) != 0 || !S_ISREG(st.st_mode))
            continue;
        if (replay_file(path) != 0)
            rc = -1;
        (*count)++;
    }
    closedir(d);
    return rc;
}

int main(int argc, char **argv)
{
    unsigned count = 0;
    int i, rc = 0;

    for (i = 1; i < argc; i++) {
        struct stat st;

        if (stat(argv[i], &st) != 0) {
            perror(argv[i]);
            rc = 1;
        } else if (S_ISDIR(st.st_mode)) {
            if (replay_dir(argv[i], &count) != 0)
                rc = 1;
        } else {
            if (replay_file(argv[i]) != 0)
                rc = 1;
            count++;
        }
    }
    printf("replayed %u inputs through every harness\n", count);
    /* An empty corpus means the paths are wrong, not that all is well. */
    return rc || count == 0 ? 1 : 0;
}
