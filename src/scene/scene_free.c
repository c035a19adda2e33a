/*
 * scene_free.c — releases what btf_scene_load (or a program, with malloc)
 * put into a scene: the light and object arrays and every mesh.
 */
#include "scene/scene.h"

#include <stdlib.h>
#include <string.h>

void btf_scene_free(btf_scene *s)
{
    if (!s)
        return;
    for (int i = 0; i < s->n_objects && s->objects; i++)
        if (s->objects[i].kind == BTF_OBJECT_MESH)
            scene_mesh_free(&s->objects[i].mesh);
    free(s->objects);
    free(s->lights);
    memset(s, 0, sizeof *s);
}
