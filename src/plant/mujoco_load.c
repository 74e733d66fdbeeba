/*
 * The MuJoCo plant as the daemon gets it: a module (plants/mujoco.so, built
 * from mujoco.c) opened when --physics mujoco asks for it, and only then.
 * Linked in, libmujoco brings libstdc++ and MuJoCo's own libraries into
 * every emulator, some 2 MiB resident that the built-in plant never uses
 * (an idle daemon at 4.7 MiB instead of 2.6). The module is looked for
 * beside the program (the build tree) and then in the program's prefix
 * (WSG_PLANT_RELDIR, relative to its directory: /usr/bin/wsgemu finds
 * /usr/lib/wsgemu/plants/mujoco.so); never through a search path, so the
 * module is the one built with the program, and its version must be the
 * program's. Tests and fuzz harnesses link mujoco.c in instead.
 */
#define _POSIX_C_SOURCE 200809L /* readlink */

#include <dlfcn.h>
#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "wsg/plant.h"

#ifndef WSG_PLANT_RELDIR
#define WSG_PLANT_RELDIR "../lib/wsgemu/plants"
#endif
#define WSG_PLANT_MODULE   "mujoco.so"
#define WSG_PLANT_PATH_MAX 4096

typedef int (*wsg_plant_open_fn)(struct wsg_plant **,
                                 const struct wsg_axis_config *, const char *,
                                 const char *, const char *, char *, size_t);

static void *module;
static wsg_plant_open_fn module_open;

/* The program's directory into dir (with its slash): 0 or -errno. */
static int program_dir(char *dir, size_t n)
{
    ssize_t len = readlink("/proc/self/exe", dir, n - 1);
    char *slash;

    if (len < 0)
        return -errno;
    if ((size_t)len >= n - 1)
        return -ENAMETOOLONG;
    dir[len] = '\0';
    slash = strrchr(dir, '/');
    if (!slash)
        return -ENOENT;
    slash[1] = '\0';
    return 0;
}

/* Open the module once: 0, or -errno with the reason in err. */
static int load(char *err, size_t errlen)
{
    /* Room for the directory and the longest tail after it. */
    char dir[WSG_PLANT_PATH_MAX], path[2][WSG_PLANT_PATH_MAX + 64];
    const char *version;
    int r, i;

    if (module)
        return 0;
    r = program_dir(dir, sizeof dir);
    if (r < 0) {
        snprintf(err, errlen, "cannot find the program's directory (%s)",
                 strerror(-r));
        return r;
    }
    snprintf(path[0], sizeof path[0], "%splants/" WSG_PLANT_MODULE, dir);
    snprintf(path[1], sizeof path[1],
             "%s" WSG_PLANT_RELDIR "/" WSG_PLANT_MODULE, dir);
    for (i = 0; i < 2 && access(path[i], F_OK) != 0; i++)
        ;
    if (i == 2) {
        snprintf(err, errlen,
                 "the MuJoCo plant is not installed (no %s or %s; Debian's "
                 "package has it, a source build needs libmujoco-dev)",
                 path[0], path[1]);
        return -ENOENT;
    }
    /* RTLD_LOCAL: MuJoCo's symbols stay the module's. RTLD_NOW: a missing
     * library is told now, not at the first step. */
    module = dlopen(path[i], RTLD_NOW | RTLD_LOCAL);
    if (!module) {
        snprintf(err, errlen, "cannot load %s: %s", path[i], dlerror());
        return -ENOEXEC;
    }
    version = dlsym(module, "wsg_plant_mujoco_version");
    *(void **)&module_open = dlsym(module, "wsg_plant_mujoco_open");
    if (!version || !module_open || strcmp(version, WSG_VERSION) != 0) {
        snprintf(err, errlen, "%s is not this wsgemu's (version %s) plant",
                 path[i], WSG_VERSION);
        dlclose(module);
        module = NULL;
        module_open = NULL;
        return -ENOEXEC;
    }
    return 0;
}

int wsg_plant_mujoco_available(void)
{
    char err[64];

    return load(err, sizeof err) == 0;
}

int wsg_plant_mujoco_open(struct wsg_plant **p,
                          const struct wsg_axis_config *cfg, const char *scene,
                          const char *left, const char *right, char *err,
                          size_t errlen)
{
    int r = load(err, errlen);

    if (r < 0)
        return r;
    return module_open(p, cfg, scene, left, right, err, errlen);
}
