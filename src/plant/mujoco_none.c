/*
 * The MuJoCo plant's stand-in for a build without MuJoCo (-DWSG_MUJOCO=OFF,
 * libmujoco-dev missing, the static build): --physics mujoco is refused
 * with the reason, and the tests that need it skip.
 */
#include <errno.h>
#include <stdio.h>

#include "wsg/plant.h"

int wsg_plant_mujoco_available(void)
{
    return 0;
}

int wsg_plant_mujoco_open(struct wsg_plant **p,
                          const struct wsg_axis_config *cfg, const char *scene,
                          const char *left, const char *right, char *err,
                          size_t errlen)
{
    (void)p;
    (void)cfg;
    (void)scene;
    (void)left;
    (void)right;
    snprintf(err, errlen,
             "this build has no MuJoCo plant (a static build, as in the "
             "wheel and the container, or built without libmujoco-dev or "
             "with -DWSG_MUJOCO=OFF): use Debian's package or a source "
             "build");
    return -ENOTSUP;
}
