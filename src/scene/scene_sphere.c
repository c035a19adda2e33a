/*
 * scene_sphere.c — the material preview: one textured sphere filling the
 * frame under one directional light, the picture at the top of a report
 * (docs/report.md, "Preview") and the frame the sweep times (docs/report.md). A fixed scene
 * in code, so that every report and every sweep point renders the same.
 */
#include "scene/scene.h"
#include "core/core.h"

#include <math.h>
#include <string.h>

btf_status btf_scene_sphere(btf_dir light, double texture_scale, btf_scene *out, btf_error *err)
{
    if (!out)
        return btf__fail(err, BTF_E_ARG, "sphere scene: no output given");
    memset(out, 0, sizeof *out);
    if (!(light.theta >= 0.0 && light.theta <= 90.0) || !isfinite(light.phi))
        return btf__fail(err, BTF_E_ARG, "sphere scene: light (theta %g, phi %g): theta must be "
                         "in [0, 90] degrees and phi finite", light.theta, light.phi);
    if (!(texture_scale > 0.0 && texture_scale <= 1e6))
        return btf__fail(err, BTF_E_ARG, "sphere scene: texture scale %g: expected (0, 1e6]",
                         texture_scale);
    out->lights = btf__calloc(1, sizeof(btf_light), err);
    out->objects = btf__calloc(1, sizeof(btf_object), err);
    if (!out->lights || !out->objects) {
        btf_scene_free(out);
        return BTF_E_NOMEM;
    }
    /* The camera looks down -z at the sphere's equator; the light's
     * direction is given in the camera's frame as a measured direction is
     * in the sample's (theta from the axis towards the camera, phi from +x
     * counter-clockwise), so theta 0 lights the sphere head-on. */
    out->camera = (btf_camera){{0, 0, 3.4}, {0, 0, 0}, {0, 1, 0}, 38.0};
    double v[3];
    btf_dir_to_vec(light, v);
    out->n_lights = 1;
    out->lights[0].kind = BTF_LIGHT_DIRECTIONAL;
    memcpy(out->lights[0].direction, v, sizeof v);
    out->lights[0].rgb[0] = out->lights[0].rgb[1] = out->lights[0].rgb[2] = 1.0f;
    out->n_objects = 1;
    btf_object *o = &out->objects[0];
    o->kind = BTF_OBJECT_SPHERE;
    o->axis[1] = 1.0;
    o->radius = 1.0;
    o->texture_scale = texture_scale;
    out->background[0] = out->background[1] = out->background[2] = 0.04f;
    return BTF_OK;
}
