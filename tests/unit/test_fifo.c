/* test_fifo.c — only regular files are read: a FIFO given as any input (a
 * model, an image, a scene, a dataset's image, a manifest, a file a mesh
 * names) is refused at once with one line naming it, where opening it used to
 * wait for a writer forever; and a mesh reads no file outside its folder (a
 * glTF buffer of ../../etc/passwd). Every command runs under `timeout 10`: a
 * hang is exit 124, not the error exit 1. */
#include "testutil.h"
#include "core/core.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static char *dir;

/* A tiny UBO2003 dataset: one view, two lights, flat in one folder. */
static const char *const UBO_NAMES[2] = {"00000 tl000 pl000 tv000 pv000.jpg",
                                         "00001 tl015 pl000 tv000 pv000.jpg"};

static void make_fifo(const char *path)
{
    int rc = mkfifo(path, 0600);
    if (rc != 0)
        print_error("mkfifo %s: %s\n", path, strerror(errno));
    assert_int_equal(rc, 0);
}

static void write_text(const char *path, const char *text)
{
    tu_write_file(path, text, strlen(text));
}

/* A texture (tex.png, tex.jpg), its model (m.btfcar), the dataset folder
 * ds/ whose second image is a FIFO, and FIFOs for every other input. */
static int setup(void **state)
{
    (void)state;
    dir = tu_tmpdir();
    btf_image img = {0};
    btf_error e = {0};
    tu_material_image("leather", 64, 1, (btf_dir){0, 0}, (btf_dir){0, 0}, &img);
    int rc = btf_image_write_png(tu_fmt("%s/tex.png", dir), &img, &e) ||
             btf_mkdirs(tu_fmt("%s/ds", dir), &e) ||
             btf_image_write_jpeg(tu_fmt("%s/ds/%s", dir, UBO_NAMES[0]), &img, 90, &e);
    btf_image_free(&img);
    if (rc) {
        print_error("setup: %s\n", e.msg);
        return -1;
    }
    if (tu_run(tu_fmt("%s texture-fit -q %s/tex.png -o %s/m.btfcar", tu_cli(), dir, dir), NULL))
        return -1;
    static const char *const fifos[] = {"f.btfcar", "f.png", "f.exr", "f.json", "f.tsv",
                                        "f.mtl", "f.bin", NULL};
    for (int i = 0; fifos[i]; i++)
        if (mkfifo(tu_fmt("%s/%s", dir, fifos[i]), 0600) != 0)
            return -1;
    return mkfifo(tu_fmt("%s/ds/%s", dir, UBO_NAMES[1]), 0600) != 0 ? -1 : 0;
}

static int teardown(void **state)
{
    (void)state;
    tu_rmtree(dir);
    free(dir);
    return 0;
}

/* `btfcar ARGS` (in dir) under timeout 10 s exits 1, not 124, with one line
 * that holds what (the file and why). */
static void expect_refused(const char *args, const char *what)
{
    char *err = NULL;
    int st = tu_run(tu_fmt("cd %s && timeout 10 %s %s", dir, tu_cli(), args), &err);
    if (st != 1 || !strstr(err, what))
        print_error("btfcar %s: exit %d%s; stderr: %s\n", args, st,
                    st == 124 ? " (hung: killed by timeout)" : "", err);
    assert_int_equal(st, 1);
    assert_non_null(strstr(err, what));
    char *nl = strchr(err, '\n');
    assert_true(nl && nl[1] == '\0');
    free(err);
}

static void fifo_model(void **state)
{
    (void)state;
    expect_refused("info f.btfcar", "f.btfcar: not a regular file");
    expect_refused("synthesise f.btfcar --size 16x16 -o out", "f.btfcar: not a regular file");
    expect_refused("render f.btfcar --view 0,0 --light 0,0 -o r.png",
                   "f.btfcar: not a regular file");
    expect_refused("report ds f.btfcar -o rep", "f.btfcar: not a regular file");
}

static void fifo_image(void **state)
{
    (void)state;
    expect_refused("texture-fit f.png -o t.btfcar", "f.png: not a regular file");
    expect_refused("texture-fit f.exr -o t.btfcar", "f.exr: not a regular file");
    expect_refused("compare tex.png f.png", "f.png: not a regular file");
    expect_refused("compare f.png tex.png", "f.png: not a regular file");
}

static void fifo_scene(void **state)
{
    (void)state;
    expect_refused("render m.btfcar --scene f.json -o r.png", "f.json: not a regular file");
}

/* A dataset's image, read through the folder, a manifest, and --beside. */
static void fifo_dataset(void **state)
{
    (void)state;
    const char *img = tu_fmt("ds/%s: not a regular file", UBO_NAMES[1]);
    char *what = strdup(img);
    expect_refused("info ds", what);
    /* --beside needs a model with directions (render refuses a single
     * texture before reading the dataset): a tiny generated material's */
    assert_int_equal(tu_run(tu_fmt("cd %s && %s generate -q --material leather --size 16 gen && "
                                   "%s analyse -q gen -o b.btfcar --subspaces 2 --levels 1 "
                                   "--no-range", dir, tu_cli(), tu_cli()), NULL), 0);
    expect_refused("render b.btfcar --view 0,0 --light 15,0 --beside ds -o r.png", what);
    free(what);
    expect_refused("info f.tsv", "f.tsv: not a regular file");
    write_text(tu_fmt("%s/list.tsv", dir), "path\ttheta_l\tphi_l\ttheta_v\tphi_v\n"
                                            "tex.png\t0\t0\t0\t0\nf.png\t15\t0\t0\t0\n");
    expect_refused("info list.tsv", "f.png: not a regular file");
}

/* A scene whose one object is the mesh file (relative to the scene). */
static void write_mesh_scene(const char *scene, const char *mesh)
{
    write_text(tu_fmt("%s/%s", dir, scene),
               tu_fmt("{\"camera\": {\"position\": [0, 0, 4], \"target\": [0, 0, 0]}, "
                      "\"lights\": [{\"type\": \"directional\", \"direction\": [1, 1, 1]}], "
                      "\"objects\": [{\"type\": \"mesh\", \"file\": \"%s\"}]}",
                      mesh));
}

/* One triangle with UVs, after the line head (an mtllib or nothing). */
static void write_obj(const char *name, const char *head)
{
    write_text(tu_fmt("%s/%s", dir, name),
               tu_fmt("%sv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n",
                      head));
}

/* One triangle (positions, then UVs) in the buffer at uri. */
static void write_gltf(const char *name, const char *uri)
{
    write_text(tu_fmt("%s/%s", dir, name),
               tu_fmt("{\"asset\": {\"version\": \"2.0\"}, \"scene\": 0, \"scenes\": [{\"nodes\": "
                      "[0]}], \"nodes\": [{\"mesh\": 0}], \"meshes\": [{\"primitives\": "
                      "[{\"attributes\": {\"POSITION\": 0, \"TEXCOORD_0\": 1}}]}], "
                      "\"buffers\": [{\"byteLength\": 60, \"uri\": \"%s\"}], "
                      "\"bufferViews\": [{\"buffer\": 0, \"byteLength\": 36}, "
                      "{\"buffer\": 0, \"byteOffset\": 36, \"byteLength\": 24}], "
                      "\"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, "
                      "\"count\": 3, \"type\": \"VEC3\", \"min\": [0, 0, 0], "
                      "\"max\": [1, 1, 0]}, {\"bufferView\": 1, \"componentType\": 5126, "
                      "\"count\": 3, \"type\": \"VEC2\"}]}",
                      uri));
}

/* Files assimp opens on its own: an OBJ's material library, a glTF buffer. */
static void fifo_mesh_files(void **state)
{
    (void)state;
    write_obj("fifo.obj", "mtllib f.mtl\n");
    write_mesh_scene("obj.json", "fifo.obj");
    expect_refused("render m.btfcar --scene obj.json -o r.png",
                   "obj.json: objects[0].file: fifo.obj: f.mtl: not a regular file");
    write_gltf("fifo.gltf", "f.bin");
    write_mesh_scene("gltf.json", "fifo.gltf");
    expect_refused("render m.btfcar --scene gltf.json -o r.png",
                   "gltf.json: objects[0].file: fifo.gltf: f.bin: not a regular file");
    make_fifo(tu_fmt("%s/f.obj", dir));
    write_mesh_scene("mesh.json", "f.obj");
    expect_refused("render m.btfcar --scene mesh.json -o r.png",
                   "mesh.json: objects[0].file: f.obj: not a regular file");
}

/* A mesh in sub/ naming a file above it: refused, though it exists. A
 * missing material library stays what it was: the mesh loads without it. */
static void mesh_confined_to_its_folder(void **state)
{
    (void)state;
    assert_int_equal(btf_mkdirs(tu_fmt("%s/sub", dir), NULL), 0);
    write_text(tu_fmt("%s/outside.mtl", dir), "newmtl x\nKd 1 1 1\n");
    write_obj("sub/up.obj", "mtllib ../outside.mtl\n");
    write_mesh_scene("up.json", "sub/up.obj");
    expect_refused("render m.btfcar --scene up.json -o r.png",
                   "up.json: objects[0].file: sub/up.obj: sub/../outside.mtl: outside the "
                   "mesh's folder");
    write_gltf("sub/passwd.gltf", "../../../../../../../../etc/passwd");
    write_mesh_scene("passwd.json", "sub/passwd.gltf");
    expect_refused("render m.btfcar --scene passwd.json -o r.png",
                   "passwd.json: objects[0].file: sub/passwd.gltf: "
                   "sub/../../../../../../../../etc/passwd: outside the mesh's folder");
    /* Beside the mesh, below it, or missing: loads. */
    write_text(tu_fmt("%s/sub/in.mtl", dir), "newmtl x\nKd 1 1 1\n");
    write_obj("sub/in.obj", "mtllib in.mtl\n");
    write_obj("sub/missing.obj", "mtllib nothere.mtl\n");
    btf_scene s;
    btf_error e = {0};
    for (int i = 0; i < 2; i++) {
        write_mesh_scene("ok.json", i ? "sub/missing.obj" : "sub/in.obj");
        TU_OK(btf_scene_load(tu_fmt("%s/ok.json", dir), &s, &e), &e);
        assert_int_equal(s.objects[0].mesh.n_triangles, 1);
        btf_scene_free(&s);
    }
}

/* The helper itself: a regular file's size; a FIFO, a device and a folder
 * refused with errno EINVAL and the message; a missing file ENOENT. */
static void open_regular(void **state)
{
    (void)state;
    btf_error e = {0};
    uint64_t size = 0;
    int fd = btf__open_regular(tu_fmt("%s/tex.png", dir), &size, &e);
    assert_true(fd >= 0);
    struct stat st;
    assert_int_equal(fstat(fd, &st), 0);
    assert_int_equal(size, (uint64_t)st.st_size);
    close(fd);
    const char *bad[] = {tu_fmt("%s/f.png", dir), "/dev/null", dir};
    for (int i = 0; i < 3; i++) {
        e = (btf_error){0};
        assert_int_equal(btf__open_regular(bad[i], NULL, &e), -1);
        assert_int_equal(errno, EINVAL);
        assert_int_equal(e.code, BTF_E_IO);
        assert_string_equal(e.msg, tu_fmt("%s: not a regular file", bad[i]));
    }
    assert_int_equal(btf__open_regular(tu_fmt("%s/nothere", dir), NULL, NULL), -1);
    assert_int_equal(errno, ENOENT);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(open_regular),
        cmocka_unit_test(fifo_model),
        cmocka_unit_test(fifo_image),
        cmocka_unit_test(fifo_scene),
        cmocka_unit_test(fifo_dataset),
        cmocka_unit_test(fifo_mesh_files),
        cmocka_unit_test(mesh_confined_to_its_folder),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
