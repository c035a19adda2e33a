/*
 * scene_sphere_obj.h — a tessellated unit-radius sphere written as OBJ, for
 * test_scene.c and bench_scene.c: lat x lon quads (two triangles each,
 * counter-clockwise from outside), vertex normals = positions, and UVs that
 * reproduce the analytic sphere's mapping of docs/scene.md: u = phi,
 * v = theta in UV units (vt's v is written as 1 - theta, because assimp's
 * FlipUVs turns OBJ's bottom-left origin into 1 - v). The pole axis is +y,
 * phi = 0 along +x and phi = 90 deg along -z, as scene_basis gives for +y.
 * 2 * lat * lon triangles (those touching a pole have zero area).
 */
#ifndef SCENE_SPHERE_OBJ_H
#define SCENE_SPHERE_OBJ_H

#include <math.h>
#include <stdio.h>

static int write_sphere_obj(const char *path, int lat, int lon)
{
    FILE *f = fopen(path, "w");
    if (!f)
        return -1;
    for (int i = 0; i <= lat; i++) {
        double th = M_PI * i / lat;
        for (int j = 0; j <= lon; j++) {
            double ph = 2.0 * M_PI * j / lon;
            double x = sin(th) * cos(ph), y = cos(th), z = -sin(th) * sin(ph);
            fprintf(f, "v %.9g %.9g %.9g\nvn %.9g %.9g %.9g\nvt %.9g %.9g\n", x, y, z, x, y, z,
                    ph, 1.0 - th);
        }
    }
    for (int i = 0; i < lat; i++)
        for (int j = 0; j < lon; j++) {
            int a = i * (lon + 1) + j + 1, b = (i + 1) * (lon + 1) + j + 1;
            /* a = (i, j), b = (i + 1, j): theta grows southwards */
            fprintf(f, "f %d/%d/%d %d/%d/%d %d/%d/%d\n", a, a, a, b, b, b, b + 1, b + 1, b + 1);
            fprintf(f, "f %d/%d/%d %d/%d/%d %d/%d/%d\n", a, a, a, b + 1, b + 1, b + 1, a + 1,
                    a + 1, a + 1);
        }
    return fclose(f) == 0 ? 0 : -1;
}

#endif
