/*
 * fuzz_scene.c — libFuzzer target for the JSON scene files `btfcar render
 * --scene` reads (src/scene/scene_json.c through cJSON: keys, types,
 * numbers, the camera and object checks). The input is written to a
 * temporary file, since the loader resolves mesh paths beside the scene: a
 * fuzzed "file" names a mesh that does not exist (or the input itself, which
 * assimp must refuse cleanly). Every outcome is a clean load or one error
 * line; a loaded scene is traced at 4 x 3 and every G-buffer value must be
 * finite. `make fuzz` builds and runs it (seeds in
 * tests/fuzz/corpus/fuzz_scene/).
 */
#include "btfcar.h"
#include "scene/gbuffer.h"
#include "fuzzutil.h"

#include <math.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fuzz_input_path("json");
    fuzz_write_input(path, data, size);
    btf_scene s;
    btf_error e = {0};
    int rc = btf_scene_load(path, &s, &e);
    if (rc > 0 || (rc < 0 && (e.code != rc || strchr(e.msg, '\n'))))
        abort();
    if (rc < 0)
        return 0;
    btf_gbuffer g;
    rc = btf__scene_trace(&s, 4, 3, 1, &g, &e);
    if (rc == 0) {
        for (int p = 0; p < 12; p++) {
            for (int k = 0; k < 9; k++)
                if (!isfinite(g.frame[9 * p + k]))
                    abort();
            for (int k = 0; k < 3; k++)
                if (!isfinite(g.view[3 * p + k]) || !isfinite(g.position[3 * p + k]))
                    abort();
            if (!isfinite(g.uv[2 * p]) || !isfinite(g.uv[2 * p + 1]))
                abort();
        }
        btf__gbuffer_free(&g);
    } else if (strchr(e.msg, '\n')) {
        abort();
    }
    btf_scene_free(&s);
    return 0;
}
