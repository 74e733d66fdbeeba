/*
 * The built-in plant's state, held inside the axis model's struct (so a
 * device holding the model by value holds its world too, at no
 * allocation): kinematic fingers, a part that yields as a linear spring,
 * and a rigid obstacle. The functions of wsg/axis.h that set the world
 * (wsg_axis_set_part, _set_obstacle, _set_part_patch) write it.
 */
#ifndef WSG_PLANT_BUILTIN_H
#define WSG_PLANT_BUILTIN_H

#include "wsg/plant.h"

struct wsg_plant_builtin {
    struct wsg_plant base;
    double stroke;
    int part;
    double part_width, part_stiffness;
    double patch_w, patch_h; /* mm, where the part touches each pad */
    int obstacle;            /* something rigid stands in the way */
    double obstacle_width;
};

void wsg_plant_builtin_init(struct wsg_plant_builtin *b, double stroke,
                            double part_stiffness);

#endif
