/*
 * mesh_io.h — private to src/scene/: the file access assimp gets for one
 * mesh (mesh_io.c). assimp opens the mesh and, on its own, the files the
 * mesh names (an OBJ's mtllib, a glTF's buffers); every one of them comes
 * through here, so that each is a regular file (a FIFO would block the
 * import forever) and each but the mesh itself lies in the mesh's folder
 * or below it (a downloaded glTF must not read ../../../etc/passwd as
 * vertex data). docs/scene.md, "Meshes".
 */
#ifndef BTF_SCENE_MESH_IO_H
#define BTF_SCENE_MESH_IO_H

#include "btfcar.h"

#include <assimp/cfileio.h>
#include <limits.h>

typedef struct scene_mesh_io {
    struct aiFileIO fs;     /* for aiImportFileEx; fs.UserData points here */
    const char *mesh;       /* the mesh file, as the scene names it */
    char folder[PATH_MAX];  /* its folder, resolved (no links, no ..) */
    btf_error refused;      /* the first file refused: "MESH: FILE: why"; code 0: none */
} scene_mesh_io;

/* Sets io up for the mesh file at path (kept, not copied): BTF_E_IO with
 * "FOLDER: cannot resolve: REASON" when its folder cannot be resolved. */
btf_status scene_mesh_io_init(scene_mesh_io *io, const char *path, btf_error *err);

#endif
