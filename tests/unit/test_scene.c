/*
 * test_scene.c — scenes and ray casting (src/scene/, docs/scene.md): every
 * example loads; every kind of bad file is one error naming the file and
 * the key; the traced G-buffer agrees with the analytic projections (the
 * sphere's disk area, a head-on plane's linear uv, a two-triangle mesh
 * against the plane of the same size, a 100k-triangle sphere against the
 * analytic sphere); frames are orthonormal and right-handed with N towards
 * the eye everywhere; the extremes (eye inside, grazing rays, the poles,
 * 1x1 frames, huge and tiny scenes, degenerate and mirrored UVs) stay
 * finite; the thread count does not change a byte; assimp prints nothing.
 */
#include "testutil.h"
#include "scene/scene.h"
#include "scene_sphere_obj.h"

#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* ---------------------------------------------------------------- helpers */

static const char *write_text(const char *name, const char *text)
{
    const char *path = tu_fmt("%s/%s", tu_dir, name);
    tu_write_file(path, text, strlen(text));
    return path;
}

/* A scene around one object, camera on +z looking at the origin. */
static btf_scene one_object(btf_object ob, double cam_z, double fov, btf_object *store,
                            btf_light *light)
{
    *store = ob;
    *light = (btf_light){.kind = BTF_LIGHT_DIRECTIONAL, .direction = {0, 0, 1},
                         .rgb = {1, 1, 1}};
    btf_scene s = {.camera = {.position = {0, 0, cam_z}, .target = {0, 0, 0},
                              .up = {0, 1, 0}, .fov_deg = fov},
                   .n_lights = 1, .lights = light, .n_objects = 1, .objects = store};
    return s;
}

static btf_object sphere(double r)
{
    return (btf_object){.kind = BTF_OBJECT_SPHERE, .axis = {0, 1, 0}, .radius = r,
                        .texture_scale = 1.0};
}

/* Every float of the G-buffer is finite; every hit's frame orthonormal and
 * right-handed (det +1), its N towards the eye; the view vector unit. */
static void assert_gbuffer_sane(const btf_gbuffer *g)
{
    size_t n = (size_t)g->width * (size_t)g->height;
    for (size_t p = 0; p < n; p++) {
        for (int i = 0; i < 2; i++)
            assert_true(isfinite(g->uv[2 * p + i]));
        for (int i = 0; i < 9; i++)
            assert_true(isfinite(g->frame[9 * p + i]));
        for (int i = 0; i < 3; i++)
            assert_true(isfinite(g->position[3 * p + i]) && isfinite(g->view[3 * p + i]));
        const float *v = g->view + 3 * p;
        assert_true(fabs(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] - 1.0) < 1e-5);
        if (g->object[p] < 0)
            continue;
        double f[9];
        for (int i = 0; i < 9; i++)
            f[i] = g->frame[9 * p + i];
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++) {
                double d = v3_dot(f + 3 * a, f + 3 * b);
                assert_true(fabs(d - (a == b)) < 1e-5);
            }
        double c[3];
        v3_cross(f, f + 3, c);
        assert_true(fabs(v3_dot(c, f + 6) - 1.0) < 1e-5); /* det(T, B, N) = +1 */
        double vv[3] = {v[0], v[1], v[2]};
        assert_true(v3_dot(f + 6, vv) >= -1e-6);          /* N faces the eye */
    }
}

static int count_hits(const btf_gbuffer *g)
{
    int n = 0;
    for (int p = 0; p < g->width * g->height; p++)
        n += g->object[p] >= 0;
    return n;
}

/* ---------------------------------------------------------------- loading */

static void examples_load(void **state)
{
    (void)state;
    const char *files[] = {"examples/sphere.json", "examples/cylinder.json",
                           "examples/plane.json", "examples/mesh.json",
                           "examples/mesh_gltf.json"};
    const int kinds[] = {BTF_OBJECT_SPHERE, BTF_OBJECT_CYLINDER, BTF_OBJECT_PLANE,
                         BTF_OBJECT_MESH, BTF_OBJECT_MESH};
    for (int i = 0; i < 5; i++) {
        btf_scene s;
        btf_error err = {0};
        TU_OK(btf_scene_load(files[i], &s, &err), &err);
        assert_int_equal(s.n_objects, 1);
        assert_int_equal(s.objects[0].kind, kinds[i]);
        assert_true(s.n_lights >= 1);
        for (int l = 0; l < s.n_lights; l++)
            if (s.lights[l].kind == BTF_LIGHT_DIRECTIONAL)
                assert_true(fabs(v3_len(s.lights[l].direction) - 1.0) < 1e-12);
        TU_OK(btf_scene_check(&s, &err), &err);
        btf_gbuffer g;
        TU_OK(btf__scene_trace(&s, 64, 48, 0, &g, &err), &err);
        assert_true(count_hits(&g) > 64 * 48 / 20); /* every example shows its object */
        assert_gbuffer_sane(&g);
        btf__gbuffer_free(&g);
        btf_scene_free(&s);
    }
    /* Defaults: up +y, fov 45 where the file leaves them out; intensity
     * given as one number is grey. */
    btf_scene s;
    btf_error err = {0};
    TU_OK(btf_scene_load("examples/cylinder.json", &s, &err), &err);
    assert_true(s.camera.up[1] == 1.0 && s.camera.fov_deg == 35.0);
    assert_true(s.lights[0].rgb[0] == 1.0f && s.lights[0].rgb[2] == 1.0f);
    assert_true(s.objects[0].rotation_deg == 30.0);
    btf_scene_free(&s);
}

/* OBJ (v up, bottom-left origin) and glTF (top-left origin) give the same
 * UVs after loading: the top-left corner of the square is (0, 0). */
static void obj_and_gltf_uvs_agree(void **state)
{
    (void)state;
    btf_scene a, b;
    btf_error err = {0};
    TU_OK(btf_scene_load("examples/mesh.json", &a, &err), &err);
    TU_OK(btf_scene_load("examples/mesh_gltf.json", &b, &err), &err);
    const btf_mesh *ma = &a.objects[0].mesh, *mb = &b.objects[0].mesh;
    assert_int_equal(ma->n_triangles, 2);
    assert_int_equal(mb->n_triangles, 2);
    assert_non_null(ma->normals);
    for (const btf_mesh *m = ma; m; m = m == ma ? mb : NULL)
        for (int v = 0; v < m->n_vertices; v++) {
            float x = m->positions[3 * v], y = m->positions[3 * v + 1];
            /* u = x + 0.5 along the columns, v = 0.5 - y down the rows */
            assert_true(fabsf(m->uvs[2 * v] - (x + 0.5f)) < 1e-6f);
            assert_true(fabsf(m->uvs[2 * v + 1] - (0.5f - y)) < 1e-6f);
        }
    btf_scene_free(&a);
    btf_scene_free(&b);
}

/* assimp prints nothing: stderr is captured around good and bad loads. */
static void assimp_is_silent(void **state)
{
    (void)state;
    const char *log = tu_fmt("%s/stderr.txt", tu_dir);
    write_text("broken.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3 4 5\nvt x y\n#");
    const char *scene = write_text("broken.json",
        "{\"camera\": {\"position\": [0,0,3], \"target\": [0,0,0]},"
        " \"lights\": [{\"type\": \"directional\", \"direction\": [0,0,1]}],"
        " \"objects\": [{\"type\": \"mesh\", \"file\": \"broken.obj\"}]}");
    fflush(stderr);
    int saved = dup(2);
    int fd = open(log, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    assert_true(saved >= 0 && fd >= 0);
    dup2(fd, 2);
    btf_scene s;
    btf_error err = {0};
    int rc_good = btf_scene_load("examples/mesh_gltf.json", &s, &err);
    btf_scene_free(&s);
    int rc_bad = btf_scene_load(scene, &s, &err);
    fflush(stderr);
    dup2(saved, 2);
    close(saved);
    close(fd);
    assert_int_equal(rc_good, 0);
    assert_int_not_equal(rc_bad, 0);
    assert_non_null(strstr(err.msg, "objects[0].file"));
    struct stat st;
    assert_int_equal(stat(log, &st), 0);
    assert_int_equal((int)st.st_size, 0);
}

typedef struct bad_case {
    const char *name;     /* file name under tu_dir */
    const char *text;     /* its content */
    const char *key;      /* expected in the message */
    const char *problem;  /* expected in the message */
} bad_case;

#define CAM "\"camera\": {\"position\": [0,0,3], \"target\": [0,0,0]}"
#define LIGHT "\"lights\": [{\"type\": \"directional\", \"direction\": [0,0,1]}]"
#define SPH "{\"type\": \"sphere\", \"radius\": 1}"

static void bad_files(void **state)
{
    (void)state;
    write_text("nouv.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n");
    write_text("notamesh.obj", "this is not a mesh\n\x01\x02\x03");
    const bad_case cases[] = {
        {"typo_top.json", "{" CAM ", " LIGHT ", \"objects\": [], \"lites\": []}", "lites",
         "unknown key"},
        {"typo_obj.json", "{" CAM ", " LIGHT ", \"objects\": [{\"type\": \"sphere\", \"radus\": 1}]}",
         "objects[0].radus", "unknown key"},
        {"key_other_type.json", "{" CAM ", " LIGHT ", \"objects\": [" SPH ", {\"type\": \"plane\", "
         "\"size\": 1, \"radius\": 2}]}", "objects[1].radius", "unknown key"},
        {"twice.json", "{" CAM ", " LIGHT ", \"objects\": [{\"type\": \"sphere\", \"radius\": 1, "
         "\"radius\": 2}]}", "objects[0].radius", "given twice"},
        {"type_radius.json", "{" CAM ", " LIGHT ", \"objects\": [{\"type\": \"sphere\", "
         "\"radius\": \"1\"}]}", "objects[0].radius", "expected a number, got a string"},
        {"type_lights.json", "{" CAM ", \"lights\": {}, \"objects\": []}", "lights",
         "expected an array"},
        {"type_vec.json", "{\"camera\": {\"position\": [0,0], \"target\": [0,0,0]}, " LIGHT
         ", \"objects\": []}", "camera.position", "array of 3 numbers"},
        {"type_elem.json", "{\"camera\": {\"position\": [0,true,3], \"target\": [0,0,0]}, " LIGHT
         ", \"objects\": []}", "camera.position[1]", "got a boolean"},
        {"top_array.json", "[1, 2]", "(top level)", "expected an object"},
        {"no_camera.json", "{" LIGHT ", \"objects\": []}", "camera", "missing"},
        {"no_position.json", "{\"camera\": {\"target\": [0,0,0]}, " LIGHT ", \"objects\": []}",
         "camera.position", "missing"},
        {"no_radius.json", "{" CAM ", " LIGHT ", \"objects\": [{\"type\": \"sphere\"}]}",
         "objects[0].radius", "missing"},
        {"no_type.json", "{" CAM ", " LIGHT ", \"objects\": [{\"radius\": 1}]}",
         "objects[0].type", "missing"},
        {"no_file.json", "{" CAM ", " LIGHT ", \"objects\": [{\"type\": \"mesh\"}]}",
         "objects[0].file", "missing"},
        {"no_lights.json", "{" CAM ", \"lights\": [], \"objects\": []}", "lights",
         "at least one light"},
        {"bad_type.json", "{" CAM ", " LIGHT ", \"objects\": [{\"type\": \"cube\"}]}",
         "objects[0].type", "not an object type"},
        {"bad_light.json", "{" CAM ", \"lights\": [{\"type\": \"spot\"}], \"objects\": []}",
         "lights[0].type", "not a light type"},
        {"inf.json", "{" CAM ", " LIGHT ", \"objects\": [{\"type\": \"sphere\", \"radius\": 1e999}]}",
         "objects[0].radius", "not a finite number"},
        {"neg_radius.json", "{" CAM ", " LIGHT ", \"objects\": [{\"type\": \"sphere\", \"radius\": -1}]}",
         "objects[0].radius", "out of range"},
        {"zero_radius.json", "{" CAM ", " LIGHT ", \"objects\": [" SPH ", {\"type\": \"cylinder\", "
         "\"radius\": 0, \"height\": 1}]}", "objects[1].radius", "out of range"},
        {"huge_center.json", "{" CAM ", " LIGHT ", \"objects\": [{\"type\": \"sphere\", \"radius\": 1, "
         "\"center\": [0, 1e300, 0]}]}", "objects[0].center", "beyond"},
        {"zero_scale.json", "{" CAM ", " LIGHT ", \"objects\": [{\"type\": \"plane\", \"size\": 1, "
         "\"texture_scale\": 0}]}", "objects[0].texture_scale", "out of range"},
        {"neg_light.json", "{" CAM ", \"lights\": [{\"type\": \"point\", \"position\": [0,0,1], "
         "\"intensity\": [1, -1, 1]}], \"objects\": []}", "lights[0].intensity", "not in [0,"},
        {"fov180.json", "{\"camera\": {\"position\": [0,0,3], \"target\": [0,0,0], \"fov\": 180}, "
         LIGHT ", \"objects\": []}", "camera.fov", "not in (0, 180)"},
        {"fov0.json", "{\"camera\": {\"position\": [0,0,3], \"target\": [0,0,0], \"fov\": 0}, "
         LIGHT ", \"objects\": []}", "camera.fov", "not in (0, 180)"},
        {"cam_same.json", "{\"camera\": {\"position\": [1,2,3], \"target\": [1,2,3]}, " LIGHT
         ", \"objects\": []}", "camera.target", "equals camera.position"},
        {"cam_up.json", "{\"camera\": {\"position\": [0,0,3], \"target\": [0,0,0], \"up\": [0,0,-2]}, "
         LIGHT ", \"objects\": []}", "camera.up", "parallel to the view direction"},
        {"cam_up0.json", "{\"camera\": {\"position\": [0,0,3], \"target\": [0,0,0], \"up\": [0,0,0]}, "
         LIGHT ", \"objects\": []}", "camera.up", "zero-length"},
        {"light_zero.json", "{" CAM ", \"lights\": [{\"type\": \"directional\", \"direction\": [0,0,0]}], "
         "\"objects\": []}", "lights[0].direction", "zero-length"},
        {"axis_zero.json", "{" CAM ", " LIGHT ", \"objects\": [{\"type\": \"cylinder\", \"radius\": 1, "
         "\"height\": 1, \"axis\": [0,0,0]}]}", "objects[0].axis", "zero-length"},
        {"mesh_missing.json", "{" CAM ", " LIGHT ", \"objects\": [{\"type\": \"mesh\", "
         "\"file\": \"nothere.obj\"}]}", "objects[0].file", "No such file"},
        {"mesh_nouv.json", "{" CAM ", " LIGHT ", \"objects\": [{\"type\": \"mesh\", "
         "\"file\": \"nouv.obj\"}]}", "objects[0].file", "no texture coordinates"},
        {"mesh_garbage.json", "{" CAM ", " LIGHT ", \"objects\": [" SPH ", {\"type\": \"mesh\", "
         "\"file\": \"notamesh.obj\"}]}", "objects[1].file", "not a mesh"},
        {"syntax.json", "{\n  \"camera\": {,\n}", "line 2, column", "invalid JSON"},
        {"truncated.json", "{\"camera\": {\"position\": [0,0", "unexpected end", "invalid JSON"},
        {"trailing.json", "{" CAM ", " LIGHT ", \"objects\": []} x", "line 1", "invalid JSON"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const char *path = write_text(cases[i].name, cases[i].text);
        char file[512];
        snprintf(file, sizeof file, "%s", path);
        btf_scene s;
        btf_error err = {0};
        int rc = btf_scene_load(file, &s, &err);
        if (rc == 0 || !strstr(err.msg, file) || !strstr(err.msg, cases[i].key) ||
            !strstr(err.msg, cases[i].problem))
            print_error("%s: rc %d, message \"%s\"; wanted \"%s\" and \"%s\"\n", cases[i].name,
                        rc, err.msg, cases[i].key, cases[i].problem);
        assert_int_not_equal(rc, 0);
        assert_non_null(strstr(err.msg, file));
        assert_non_null(strstr(err.msg, cases[i].key));
        assert_non_null(strstr(err.msg, cases[i].problem));
        assert_null(strchr(err.msg, '\n'));
        assert_int_equal(s.n_objects, 0); /* freed on failure */
        assert_null(s.objects);
    }
    /* A huge file is refused unread; a missing one names itself. */
    const char *huge = tu_fmt("%s/huge.json", tu_dir);
    size_t n = SCENE_MAX_FILE_BYTES + 16;
    char *big = malloc(n);
    assert_non_null(big);
    memset(big, ' ', n);
    big[0] = '{', big[n - 1] = '}';
    tu_write_file(huge, big, n);
    free(big);
    btf_scene s;
    btf_error err = {0};
    assert_int_not_equal(btf_scene_load(huge, &s, &err), 0);
    assert_non_null(strstr(err.msg, huge));
    assert_non_null(strstr(err.msg, "larger than"));
    assert_int_not_equal(btf_scene_load(tu_fmt("%s/absent.json", tu_dir), &s, &err), 0);
    assert_non_null(strstr(err.msg, "absent.json"));
}

/* btf_scene_check on scenes built in memory: the same key names. */
static void check_in_memory(void **state)
{
    (void)state;
    btf_object ob;
    btf_light l;
    btf_error err = {0};
    btf_scene s = one_object(sphere(1.0), 4.0, 40.0, &ob, &l);
    TU_OK(btf_scene_check(&s, &err), &err);
    ob.radius = 0.0;
    assert_int_equal(btf_scene_check(&s, &err), BTF_E_DATA);
    assert_non_null(strstr(err.msg, "scene: objects[0].radius"));
    ob.radius = 1.0, ob.axis[1] = 2.0;
    assert_int_equal(btf_scene_check(&s, &err), BTF_E_DATA);
    assert_non_null(strstr(err.msg, "objects[0].axis: not a unit vector"));
    ob.axis[1] = 1.0, ob.texture_scale = NAN;
    assert_int_equal(btf_scene_check(&s, &err), BTF_E_DATA);
    assert_non_null(strstr(err.msg, "objects[0].texture_scale"));
    ob.texture_scale = 1.0, l.rgb[1] = INFINITY;
    assert_int_equal(btf_scene_check(&s, &err), BTF_E_DATA);
    assert_non_null(strstr(err.msg, "lights[0].intensity"));
    l.rgb[1] = 1.0f, s.camera.fov_deg = NAN;
    assert_int_equal(btf_scene_check(&s, &err), BTF_E_DATA);
    assert_non_null(strstr(err.msg, "camera.fov"));
    s.camera.fov_deg = 40.0;
    /* A mesh index beyond its vertices. */
    float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0}, uv[6] = {0, 0, 1, 0, 0, 1};
    uint32_t idx[3] = {0, 1, 3};
    ob = (btf_object){.kind = BTF_OBJECT_MESH, .texture_scale = 1.0,
                      .mesh = {.n_vertices = 3, .n_triangles = 1, .positions = pos, .uvs = uv,
                               .indices = idx}};
    assert_int_equal(btf_scene_check(&s, &err), BTF_E_DATA);
    assert_non_null(strstr(err.msg, "objects[0].file: index 2 is 3"));
    btf_gbuffer g;
    assert_int_equal(btf__scene_trace(&s, 8, 8, 1, &g, &err), BTF_E_DATA);
    assert_null(g.object);
    idx[2] = 2;
    TU_OK(btf__scene_trace(&s, 8, 8, 1, &g, &err), &err);
    btf__gbuffer_free(&g);
    assert_int_equal(btf__scene_trace(&s, 0, 8, 1, &g, &err), BTF_E_ARG);
    assert_int_equal(btf_scene_check(NULL, &err), BTF_E_ARG);
    btf__gbuffer_free(NULL);
    btf_scene_free(NULL);
}

/* ---------------------------------------------------------------- tracing */

/* The analytic mapping of docs/scene.md for a sphere with axis +y at the
 * origin: phi from +x towards -z, theta from +y. */
static void sphere_uv(const float p[3], double r, double scale, double *u, double *v)
{
    double n[3] = {p[0] / r, p[1] / r, p[2] / r};
    double phi = atan2(-n[2], n[0]);
    if (phi < 0.0)
        phi += 2.0 * M_PI;
    double c = n[1] > 1.0 ? 1.0 : n[1] < -1.0 ? -1.0 : n[1];
    *u = r * phi * scale;
    *v = r * acos(c) * scale;
}

static void sphere_trace(void **state)
{
    (void)state;
    const int W = 256, H = 256;
    const double R = 1.0, D = 4.0, FOV = 40.0, SCALE = 50.0;
    btf_object ob;
    btf_light l;
    btf_object sp = sphere(R);
    sp.texture_scale = SCALE;
    btf_scene s = one_object(sp, D, FOV, &ob, &l);
    btf_gbuffer g;
    btf_error err = {0};
    TU_OK(btf__scene_trace(&s, W, H, 0, &g, &err), &err);
    assert_gbuffer_sane(&g);
    /* The projected disk: angular radius asin(R / D), radius in pixels
     * tan(asin(R/D)) / tan(fov/2) * H/2. */
    double rpx = tan(asin(R / D)) / tan(0.5 * FOV * M_PI / 180.0) * 0.5 * H;
    double area = M_PI * rpx * rpx;
    int hits = count_hits(&g);
    print_message("sphere: %d hits, analytic disk %.1f (%.3f %%)\n", hits, area,
                  100.0 * (hits - area) / area);
    assert_true(fabs(hits - area) / area < 0.01);
    double max_sil = 0.0, centre_nv = 0.0, max_uv_err = 0.0;
    int seam_or_pole = 0, jumps = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            size_t p = (size_t)y * W + x;
            if (g.object[p] < 0)
                continue;
            const float *pos = g.position + 3 * p, *f = g.frame + 9 * p, *v = g.view + 3 * p;
            double len = sqrt(pos[0] * pos[0] + pos[1] * pos[1] + pos[2] * pos[2]);
            assert_true(fabs(len - R) < 1e-5);
            for (int i = 0; i < 3; i++)
                assert_true(fabs(f[6 + i] - pos[i] / R) < 1e-5); /* outward normal */
            double nv = f[6] * v[0] + f[7] * v[1] + f[8] * v[2];
            if (x == W / 2 && y == H / 2)
                centre_nv = nv;
            int edge = 0;
            for (int k = 0; k < 4; k++) {
                int xx = x + (k == 0) - (k == 1), yy = y + (k == 2) - (k == 3);
                if (xx < 0 || yy < 0 || xx >= W || yy >= H || g.object[(size_t)yy * W + xx] < 0)
                    edge = 1;
            }
            if (edge && nv > max_sil)
                max_sil = nv;
            /* uv: the documented mapping, and T along increasing u
             * (a x n), B towards the pole. */
            double u, vv;
            sphere_uv(pos, R, SCALE, &u, &vv);
            double du = fabs(u - g.uv[2 * p]), dv = fabs(vv - g.uv[2 * p + 1]);
            if (du > M_PI * R * SCALE)
                du = fabs(du - 2.0 * M_PI * R * SCALE); /* the seam */
            max_uv_err = fmax(max_uv_err, fmax(du, dv));
            double axn[3] = {pos[2], 0.0, -pos[0]};
            if (fabs(pos[1]) < 0.9 * R) {
                v3_normalize(axn);
                double t[3] = {f[0], f[1], f[2]};
                assert_true(v3_dot(t, axn) > 0.9999);
                assert_true(f[4] > 0.0); /* B has a +y component: up towards the pole */
            }
            /* Continuity: a right neighbour's u differs by little, except
             * across the seam (phi = 0, the +x meridian) or near a pole;
             * towards the silhouette a pixel spans much of the surface. */
            if (x + 1 < W && g.object[p + 1] >= 0 && nv > 0.3) {
                double step = fabs(g.uv[2 * (p + 1)] - g.uv[2 * p]);
                double stepv = fabs(g.uv[2 * (p + 1) + 1] - g.uv[2 * p + 1]);
                if (fabs(pos[1]) > 0.95 * R || step > 0.9 * 2.0 * M_PI * R * SCALE)
                    seam_or_pole++;
                else if (step > 0.1 * R * SCALE || stepv > 0.1 * R * SCALE)
                    jumps++;
            }
        }
    print_message("sphere: silhouette max N.V %.3f, centre N.V %.6f, uv error %.2e texels, "
                  "%d pole/seam steps\n", max_sil, centre_nv, max_uv_err, seam_or_pole);
    assert_true(max_sil < 0.25);
    assert_true(centre_nv > 0.9999);
    assert_true(max_uv_err < 1e-3 * SCALE);
    assert_int_equal(jumps, 0);
    /* The same bytes on 1 and 2 threads. */
    btf_gbuffer g1;
    TU_OK(btf__scene_trace(&s, W, H, 1, &g1, &err), &err);
    assert_memory_equal(g.frame, g1.frame, sizeof(float) * 9 * W * H);
    assert_memory_equal(g.uv, g1.uv, sizeof(float) * 2 * W * H);
    assert_memory_equal(g.object, g1.object, sizeof(int32_t) * W * H);
    btf__gbuffer_free(&g1);
    btf__gbuffer_free(&g);
}

/* A plane seen head-on: uv linear in the pixel position, the frame the
 * world axes; from behind, u negated and the frame turned about B. */
static void plane_head_on(void **state)
{
    (void)state;
    const int W = 64, H = 64;
    const double SCALE = 10.0, FOV = 60.0, D = 3.0;
    btf_object ob;
    btf_light l;
    btf_object pl = {.kind = BTF_OBJECT_PLANE, .axis = {0, 0, 1}, .size = 2.0,
                     .texture_scale = SCALE};
    btf_scene s = one_object(pl, D, FOV, &ob, &l);
    btf_gbuffer g;
    btf_error err = {0};
    TU_OK(btf__scene_trace(&s, W, H, 0, &g, &err), &err);
    assert_gbuffer_sane(&g);
    double px = 2.0 * D * tan(0.5 * FOV * M_PI / 180.0) / W; /* world units per pixel */
    int hits = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            size_t p = (size_t)y * W + x;
            double wx = (x + 0.5 - 0.5 * W) * px, wy = (0.5 * H - y - 0.5) * px;
            int inside = fabs(wx) <= 1.0 && fabs(wy) <= 1.0;
            assert_int_equal(g.object[p] >= 0, inside);
            if (!inside)
                continue;
            hits++;
            assert_true(fabs(g.uv[2 * p] - (wx + 1.0) * SCALE) < 1e-4);
            assert_true(fabs(g.uv[2 * p + 1] - (1.0 - wy) * SCALE) < 1e-4);
            const float want[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
            for (int i = 0; i < 9; i++)
                assert_true(fabsf(g.frame[9 * p + i] - want[i]) < 1e-6f);
        }
    assert_true(hits > 0);
    btf__gbuffer_free(&g);
    /* From behind (the eye on -z): u = -(the front's u), T = -x, N = -z. */
    s.camera.position[2] = -D;
    TU_OK(btf__scene_trace(&s, W, H, 0, &g, &err), &err);
    assert_gbuffer_sane(&g);
    for (int p = 0; p < W * H; p++) {
        if (g.object[p] < 0)
            continue;
        double wx = g.position[3 * p];
        assert_true(fabs(g.uv[2 * p] + (wx + 1.0) * SCALE) < 1e-4);
        assert_true(fabsf(g.frame[9 * p] + 1.0f) < 1e-6f && fabsf(g.frame[9 * p + 8] + 1.0f) < 1e-6f);
    }
    btf__gbuffer_free(&g);
}

/* The two-triangle square mesh against the analytic plane of the same
 * size, also with a material rotation: the same hits, uv and frame. */
static void mesh_square_matches_plane(void **state)
{
    (void)state;
    const int W = 96, H = 80;
    btf_scene ms;
    btf_error err = {0};
    TU_OK(btf_scene_load("examples/mesh.json", &ms, &err), &err);
    for (int rot = 0; rot <= 30; rot += 30) {
        btf_object *mo = &ms.objects[0];
        mo->texture_scale = 100.0, mo->rotation_deg = rot;
        btf_object pl = {.kind = BTF_OBJECT_PLANE, .axis = {0, 0, 1}, .size = 1.0,
                         .texture_scale = 100.0, .rotation_deg = rot};
        btf_scene ps = ms;
        ps.objects = &pl;
        /* An oblique view. */
        double eye[3] = {0.7, -0.4, 1.6};
        memcpy(ms.camera.position, eye, sizeof eye);
        memcpy(ps.camera.position, eye, sizeof eye);
        btf_gbuffer gm, gp;
        TU_OK(btf__scene_trace(&ms, W, H, 0, &gm, &err), &err);
        TU_OK(btf__scene_trace(&ps, W, H, 0, &gp, &err), &err);
        assert_gbuffer_sane(&gm);
        int both = 0, differ = 0;
        for (int p = 0; p < W * H; p++) {
            if ((gm.object[p] >= 0) != (gp.object[p] >= 0)) {
                differ++;
                continue;
            }
            if (gm.object[p] < 0)
                continue;
            both++;
            /* The plane's uv is relative to its corner, the mesh's to the
             * file's origin (the same corner): rotation turns both about
             * their own origin, so compare their differences to a pixel. */
            for (int i = 0; i < 9; i++)
                assert_true(fabsf(gm.frame[9 * p + i] - gp.frame[9 * p + i]) < 1e-5f);
            for (int i = 0; i < 3; i++)
                assert_true(fabsf(gm.position[3 * p + i] - gp.position[3 * p + i]) < 1e-5f);
            if (rot == 0) {
                assert_true(fabsf(gm.uv[2 * p] - gp.uv[2 * p]) < 1e-3f);
                assert_true(fabsf(gm.uv[2 * p + 1] - gp.uv[2 * p + 1]) < 1e-3f);
            }
        }
        if (rot != 0) {
            /* uv offsets differ by a constant (the centre of rotation). */
            int p0 = -1;
            for (int p = 0; p < W * H && p0 < 0; p++)
                if (gm.object[p] >= 0 && gp.object[p] >= 0)
                    p0 = p;
            for (int p = 0; p < W * H; p++)
                if (gm.object[p] >= 0 && gp.object[p] >= 0)
                    for (int i = 0; i < 2; i++) {
                        double dm = gm.uv[2 * p + i] - gm.uv[2 * p0 + i];
                        double dp = gp.uv[2 * p + i] - gp.uv[2 * p0 + i];
                        assert_true(fabs(dm - dp) < 2e-3);
                    }
        }
        print_message("mesh square vs plane (rotation %d): %d common hits, %d differ\n", rot,
                      both, differ);
        assert_true(both > W * H / 8);
        assert_true(differ <= 2);
        btf__gbuffer_free(&gm);
        btf__gbuffer_free(&gp);
    }
    btf_scene_free(&ms);
}

/* A tessellated sphere of >= 100k triangles, as OBJ: loads, traces, and
 * agrees with the analytic sphere on hits, normals, positions and uv. */
static void big_mesh_matches_sphere(void **state)
{
    (void)state;
    const char *obj = tu_fmt("%s/sphere.obj", tu_dir);
    assert_int_equal(write_sphere_obj(obj, 224, 256), 0);
    const char *json = write_text("big.json",
        "{\"camera\": {\"position\": [0, 0.8, 4], \"target\": [0, 0, 0], \"fov\": 40},"
        " \"lights\": [{\"type\": \"directional\", \"direction\": [0, 0, 1]}],"
        " \"objects\": [{\"type\": \"mesh\", \"file\": \"sphere.obj\", \"texture_scale\": 50}]}");
    btf_scene ms;
    btf_error err = {0};
    double t0 = tu_now();
    TU_OK(btf_scene_load(json, &ms, &err), &err);
    double t_load = tu_now() - t0;
    assert_true(ms.objects[0].mesh.n_triangles >= 100000);
    const int W = 256, H = 256;
    btf_gbuffer gm, gs;
    t0 = tu_now();
    TU_OK(btf__scene_trace(&ms, W, H, 0, &gm, &err), &err);
    double t_trace = tu_now() - t0;
    assert_gbuffer_sane(&gm);
    btf_object sp = sphere(1.0);
    sp.texture_scale = 50.0;
    btf_scene ss = ms;
    ss.objects = &sp;
    TU_OK(btf__scene_trace(&ss, W, H, 0, &gs, &err), &err);
    int agree = 0, differ = 0, uv_ok = 0, both = 0;
    double max_n = 0.0;
    for (int p = 0; p < W * H; p++) {
        int a = gm.object[p] >= 0, b = gs.object[p] >= 0;
        if (a != b) {
            differ++;
            continue;
        }
        agree++;
        if (!a)
            continue;
        both++;
        double dn = 0.0;
        for (int i = 0; i < 3; i++)
            dn = fmax(dn, fabs(gm.frame[9 * p + 6 + i] - gs.frame[9 * p + 6 + i]));
        max_n = fmax(max_n, dn);
        /* The facets lie within the sagitta of the sphere (R (2 pi /
         * 256)^2 / 8 = 7.5e-5 between meridians; twice that as margin);
         * along a grazing ray the offset grows as 1 / (N . V). */
        const float *nv3 = gs.frame + 9 * p + 6, *v3 = gs.view + 3 * p;
        double nv = nv3[0] * v3[0] + nv3[1] * v3[1] + nv3[2] * v3[2];
        for (int i = 0; i < 3; i++)
            assert_true(fabs(gm.position[3 * p + i] - gs.position[3 * p + i]) <
                        1e-4 + 1.5e-4 / fmax(nv, 1e-3));
        double du = fabs(gm.uv[2 * p] - gs.uv[2 * p]), dv = fabs(gm.uv[2 * p + 1] - gs.uv[2 * p + 1]);
        uv_ok += du < 0.05 * 50 && dv < 0.05 * 50;
    }
    print_message("100k mesh: %d triangles, load %.3f s, trace %dx%d %.3f s (%.2f Mrays/s), "
                  "%d of %d pixels agree, max normal diff %.2e, uv agree on %d of %d\n",
                  ms.objects[0].mesh.n_triangles, t_load, W, H, t_trace,
                  W * H / t_trace * 1e-6, agree, W * H, max_n, uv_ok, both);
    assert_true(differ <= W * H / 1000);
    assert_true(max_n < 5e-3);
    assert_true(uv_ok >= both * 99 / 100);
    btf__gbuffer_free(&gm);
    btf__gbuffer_free(&gs);
    btf_scene_free(&ms);
}

static void eye_inside_sphere(void **state)
{
    (void)state;
    btf_object ob;
    btf_light l;
    btf_scene s = one_object(sphere(2.0), 0.5, 90.0, &ob, &l);
    btf_gbuffer g;
    btf_error err = {0};
    TU_OK(btf__scene_trace(&s, 48, 32, 0, &g, &err), &err);
    assert_gbuffer_sane(&g);
    assert_int_equal(count_hits(&g), 48 * 32);
    for (int p = 0; p < 48 * 32; p++)
        for (int i = 0; i < 3; i++) /* N inward: towards the eye */
            assert_true(fabsf(g.frame[9 * p + 6 + i] + g.position[3 * p + i] / 2.0f) < 1e-5f);
    btf__gbuffer_free(&g);
    /* Inside an open cylinder, looking along its axis: the wall all around,
     * the open far end background. */
    btf_object cy = {.kind = BTF_OBJECT_CYLINDER, .axis = {0, 0, 1}, .radius = 1.0,
                     .height = 4.0, .texture_scale = 3.0};
    s = one_object(cy, 1.0, 90.0, &ob, &l);
    TU_OK(btf__scene_trace(&s, 33, 33, 0, &g, &err), &err);
    assert_gbuffer_sane(&g);
    assert_true(g.object[16 * 33 + 16] < 0); /* down the tube's axis */
    assert_true(g.object[0] == 0);           /* a corner sees the wall */
    btf__gbuffer_free(&g);
}

/* Rays that graze, run along an axis or parallel to a plane, and hits at
 * the poles: finite, orthonormal frames. */
static void grazing_and_poles(void **state)
{
    (void)state;
    btf_object sp = sphere(1.0), cy = {.kind = BTF_OBJECT_CYLINDER, .axis = {0, 1, 0},
                                       .radius = 1.0, .height = 2.0, .texture_scale = 1.0};
    btf_object pl = {.kind = BTF_OBJECT_PLANE, .axis = {0, 1, 0}, .size = 2.0,
                     .texture_scale = 1.0};
    scene_hit h;
    /* Tangent to the sphere at (0, 1, 0): the discriminant is exactly 0. */
    double o1[3] = {0, 1, -5}, d1[3] = {0, 0, 1};
    assert_int_equal(scene_hit_sphere(&sp, o1, d1, INFINITY, &h), 1);
    assert_true(fabs(h.t - 5.0) < 1e-9);
    for (int i = 0; i < 9; i++)
        assert_true(isfinite(h.frame[i]) && isfinite(h.uv[i % 2]));
    double n[3] = {h.frame[6], h.frame[7], h.frame[8]};
    assert_true(fabs(v3_dot(n, d1)) < 1e-6); /* N perpendicular to the view */
    /* Straight down onto the north pole, and up onto the south pole. */
    for (int k = 0; k < 2; k++) {
        double o[3] = {0, k ? -5 : 5, 0}, d[3] = {0, k ? 1 : -1, 0};
        assert_int_equal(scene_hit_sphere(&sp, o, d, INFINITY, &h), 1);
        double f[9];
        memcpy(f, h.frame, sizeof f);
        double c[3];
        v3_cross(f, f + 3, c);
        assert_true(fabs(v3_dot(c, f + 6) - 1.0) < 1e-9);
        assert_true(fabs(f[7] - (k ? -1.0 : 1.0)) < 1e-12);
        assert_true(isfinite(h.uv[0]) && isfinite(h.uv[1]));
    }
    /* Along the cylinder's axis (inside and on the wall), parallel to the
     * plane (in it, above it): no hit. */
    double o2[3] = {0, -5, 0}, o3[3] = {1, -5, 0}, d2[3] = {0, 1, 0};
    assert_int_equal(scene_hit_cylinder(&cy, o2, d2, INFINITY, &h), 0);
    assert_int_equal(scene_hit_cylinder(&cy, o3, d2, INFINITY, &h), 0);
    double o4[3] = {-5, 0, 0}, o5[3] = {-5, 1e-9, 0}, d4[3] = {1, 0, 0};
    assert_int_equal(scene_hit_plane(&pl, o4, d4, INFINITY, &h), 0);
    assert_int_equal(scene_hit_plane(&pl, o5, d4, INFINITY, &h), 0);
    /* Tangent to the cylinder's wall. */
    double o6[3] = {1, 0, -5}, d6[3] = {0, 0, 1};
    if (scene_hit_cylinder(&cy, o6, d6, INFINITY, &h))
        for (int i = 0; i < 9; i++)
            assert_true(isfinite(h.frame[i]));
    /* A whole frame of grazing views: the camera in the plane's plane. */
    btf_object ob;
    btf_light l;
    btf_scene s = one_object(pl, 3.0, 60.0, &ob, &l);
    btf_gbuffer g;
    btf_error err = {0};
    TU_OK(btf__scene_trace(&s, 31, 31, 0, &g, &err), &err);
    assert_gbuffer_sane(&g);
    assert_int_equal(count_hits(&g), 0); /* edge-on: zero area */
    btf__gbuffer_free(&g);
}

/* 1x1 frames, huge and tiny scenes, a fov near 180: finite. */
static void extremes(void **state)
{
    (void)state;
    btf_object ob;
    btf_light l;
    btf_gbuffer g;
    btf_error err = {0};
    btf_scene s = one_object(sphere(1.0), 4.0, 40.0, &ob, &l);
    TU_OK(btf__scene_trace(&s, 1, 1, 0, &g, &err), &err);
    assert_int_equal(g.object[0], 0); /* the centre ray hits the sphere's front */
    assert_true(fabsf(g.frame[8] - 1.0f) < 1e-6f && fabsf(g.position[2] - 1.0f) < 1e-6f);
    btf__gbuffer_free(&g);
    const double radii[] = {1e-6, 1e5};
    const double dists[] = {4e-6, 9e5};
    for (int k = 0; k < 2; k++) {
        btf_object sp = sphere(radii[k]);
        sp.texture_scale = 1e6;
        s = one_object(sp, dists[k], 179.0, &ob, &l);
        /* Odd sides: the centre pixel's ray is the view direction. */
        TU_OK(btf__scene_trace(&s, 41, 31, 0, &g, &err), &err);
        assert_gbuffer_sane(&g);
        assert_true(g.object[15 * 41 + 20] == 0);
        btf__gbuffer_free(&g);
    }
    s = one_object(sphere(1.0), 4.0, 1e-4, &ob, &l);
    TU_OK(btf__scene_trace(&s, 17, 1, 0, &g, &err), &err);
    assert_gbuffer_sane(&g);
    assert_int_equal(count_hits(&g), 17);
    btf__gbuffer_free(&g);
    /* No objects at all: background everywhere. */
    s.n_objects = 0;
    TU_OK(btf__scene_trace(&s, 5, 3, 0, &g, &err), &err);
    assert_gbuffer_sane(&g);
    assert_int_equal(count_hits(&g), 0);
    btf__gbuffer_free(&g);
}

/* Degenerate UVs (all one point) give some orthonormal frame around N;
 * a mirrored UV layout has u negated, the frame still right-handed. */
static void degenerate_and_mirrored_uvs(void **state)
{
    (void)state;
    float pos[12] = {-0.5f, -0.5f, 0, 0.5f, -0.5f, 0, 0.5f, 0.5f, 0, -0.5f, 0.5f, 0};
    float same[8] = {0.3f, 0.3f, 0.3f, 0.3f, 0.3f, 0.3f, 0.3f, 0.3f};
    float mirror[8] = {1, 1, 0, 1, 0, 0, 1, 0}; /* u = 0.5 - x: mirrored */
    uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    for (int k = 0; k < 2; k++) {
        btf_object mo = {.kind = BTF_OBJECT_MESH, .texture_scale = 10.0,
                         .mesh = {.n_vertices = 4, .n_triangles = 2, .positions = pos,
                                  .uvs = k ? mirror : same, .indices = idx}};
        btf_object ob;
        btf_light l;
        btf_scene s = one_object(mo, 2.0, 45.0, &ob, &l);
        btf_gbuffer g;
        btf_error err = {0};
        TU_OK(btf__scene_trace(&s, 32, 32, 0, &g, &err), &err);
        assert_gbuffer_sane(&g);
        assert_true(count_hits(&g) > 100);
        for (int p = 0; p < 32 * 32; p++) {
            if (g.object[p] < 0)
                continue;
            assert_true(fabsf(g.frame[9 * p + 8] - 1.0f) < 1e-6f); /* N = +z, the eye's side */
            if (k) {
                /* u negated: -(10 (0.5 - x)), T = +x (u increases to the right). */
                float x = g.position[3 * p];
                assert_true(fabsf(g.uv[2 * p] + 10.0f * (0.5f - x)) < 1e-4f);
                assert_true(fabsf(g.frame[9 * p] - 1.0f) < 1e-6f);
            }
        }
        btf__gbuffer_free(&g);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(examples_load),
        cmocka_unit_test(obj_and_gltf_uvs_agree),
        cmocka_unit_test(assimp_is_silent),
        cmocka_unit_test(bad_files),
        cmocka_unit_test(check_in_memory),
        cmocka_unit_test(sphere_trace),
        cmocka_unit_test(plane_head_on),
        cmocka_unit_test(mesh_square_matches_plane),
        cmocka_unit_test(big_mesh_matches_sphere),
        cmocka_unit_test(eye_inside_sphere),
        cmocka_unit_test(grazing_and_poles),
        cmocka_unit_test(extremes),
        cmocka_unit_test(degenerate_and_mirrored_uvs),
    };
    return cmocka_run_group_tests(tests, tu_setup_dir, tu_teardown_dir);
}
