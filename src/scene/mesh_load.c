/*
 * mesh_load.c — a triangle mesh from OBJ, glTF or any format assimp reads
 * (docs/scene.md, "Meshes"), through assimp's C API: triangulated, node
 * transforms applied, every triangle mesh of the file joined into one.
 * UV channel 0 is required; aiProcess_FlipUVs turns assimp's bottom-left
 * origin (OBJ's vt as written; glTF's top-left origin is flipped to it by
 * the importer) into this project's top-left origin, v down the rows.
 * assimp logs nothing unless a log stream is attached, and none is. It
 * opens files only through mesh_io.c: regular files, in the mesh's folder.
 */
#include "scene/scene.h"
#include "scene/mesh_io.h"
#include "core/core.h"

#include <assimp/cimport.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

void scene_mesh_free(btf_mesh *m)
{
    if (!m)
        return;
    BTF_FREE_ALL(m->positions, m->normals, m->uvs, m->indices);
    memset(m, 0, sizeof *m);
}

static int is_triangles(const struct aiMesh *am)
{
    return am->mNumVertices > 0 && (am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE);
}

/* Counts what the joined mesh needs; fails on a mesh without UVs. */
static btf_status count_meshes(const struct aiScene *sc, const char *name, const char *key,
                               const char *path, long long *nv, long long *nt,
                               int *all_normals, btf_error *err)
{
    *nv = 0, *nt = 0, *all_normals = 1;
    for (unsigned i = 0; i < sc->mNumMeshes; i++) {
        const struct aiMesh *am = sc->mMeshes[i];
        if (!is_triangles(am))
            continue; /* points and lines (SortByPType split them off) */
        if (!am->mTextureCoords[0])
            return btf__fail(err, BTF_E_DATA, "%s: %s: %s: mesh %u has no texture coordinates "
                             "(UVs are required)", name, key, path, i);
        if (!am->mNormals)
            *all_normals = 0;
        *nv += am->mNumVertices;
        for (unsigned f = 0; f < am->mNumFaces; f++)
            *nt += am->mFaces[f].mNumIndices == 3;
    }
    if (*nt == 0)
        return btf__fail(err, BTF_E_DATA, "%s: %s: %s: no triangles", name, key, path);
    if (*nt > SCENE_MAX_TRIANGLES || *nv > (long long)UINT32_MAX / 2)
        return btf__fail(err, BTF_E_UNSUPPORTED, "%s: %s: %s: %lld triangles (at most %d)",
                         name, key, path, *nt, SCENE_MAX_TRIANGLES);
    return BTF_OK;
}

static void copy_meshes(const struct aiScene *sc, btf_mesh *m)
{
    size_t v0 = 0, t = 0;
    for (unsigned i = 0; i < sc->mNumMeshes; i++) {
        const struct aiMesh *am = sc->mMeshes[i];
        if (!is_triangles(am))
            continue;
        for (unsigned v = 0; v < am->mNumVertices; v++) {
            size_t o = v0 + v;
            m->positions[3 * o + 0] = am->mVertices[v].x;
            m->positions[3 * o + 1] = am->mVertices[v].y;
            m->positions[3 * o + 2] = am->mVertices[v].z;
            m->uvs[2 * o + 0] = am->mTextureCoords[0][v].x;
            m->uvs[2 * o + 1] = am->mTextureCoords[0][v].y;
            if (m->normals) {
                m->normals[3 * o + 0] = am->mNormals[v].x;
                m->normals[3 * o + 1] = am->mNormals[v].y;
                m->normals[3 * o + 2] = am->mNormals[v].z;
            }
        }
        for (unsigned f = 0; f < am->mNumFaces; f++) {
            const struct aiFace *fc = &am->mFaces[f];
            if (fc->mNumIndices != 3)
                continue;
            for (int k = 0; k < 3; k++)
                m->indices[3 * t + k] = (uint32_t)(v0 + fc->mIndices[k]);
            t++;
        }
        v0 += am->mNumVertices;
    }
}

/* Prefixes err's message (which names the file) with the scene's name and
 * key, as every message of a mesh starts. */
static btf_status name_key(btf_error *err, const char *name, const char *key)
{
    char m[sizeof err->msg];
    memcpy(m, err->msg, sizeof m);
    return btf__fail(err, err->code, "%s: %s: %s", name, key, m);
}

btf_status scene_mesh_load(const char *path, const char *name, const char *key, btf_mesh *out,
                           btf_error *err)
{
    memset(out, 0, sizeof *out);
    uint64_t size;
    int fd = btf__open_regular(path, &size, err);
    if (fd < 0)
        return name_key(err, name, key);
    close(fd);
    if (size > (uint64_t)SCENE_MAX_MESH_BYTES)
        return btf__fail(err, BTF_E_UNSUPPORTED, "%s: %s: %s: %llu bytes (at most %lld)", name,
                         key, path, (unsigned long long)size, SCENE_MAX_MESH_BYTES);
    scene_mesh_io io;
    if (scene_mesh_io_init(&io, path, err))
        return name_key(err, name, key);
    const struct aiScene *sc = aiImportFileEx(
        path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_SortByPType |
                  aiProcess_PreTransformVertices | aiProcess_FlipUVs |
                  aiProcess_ValidateDataStructure, &io.fs);
    if (io.refused.code) { /* a file refused fails the mesh, whatever assimp made of it */
        if (sc)
            aiReleaseImport(sc);
        *err = io.refused;
        return name_key(err, name, key);
    }
    if (!sc) {
        const char *why = aiGetErrorString();
        return btf__fail(err, BTF_E_FORMAT, "%s: %s: %s: not a mesh assimp reads (%s)", name,
                         key, path, why && *why ? why : "no reason given");
    }
    long long nv, nt;
    int all_normals;
    btf_status rc = count_meshes(sc, name, key, path, &nv, &nt, &all_normals, err);
    if (rc == BTF_OK) {
        out->n_vertices = (int)nv;
        out->n_triangles = (int)nt;
        out->positions = btf__alloc((size_t)nv * 3, sizeof(float), err);
        out->uvs = btf__alloc((size_t)nv * 2, sizeof(float), err);
        out->indices = btf__alloc((size_t)nt * 3, sizeof(uint32_t), err);
        /* Normals only where every part has them: else face normals. */
        out->normals = all_normals ? btf__alloc((size_t)nv * 3, sizeof(float), err) : NULL;
        if (!out->positions || !out->uvs || !out->indices || (all_normals && !out->normals))
            rc = btf__fail(err, BTF_E_NOMEM, "%s: %s: %s: out of memory for %lld triangles",
                           name, key, path, nt);
        else
            copy_meshes(sc, out);
    }
    aiReleaseImport(sc);
    if (rc != BTF_OK)
        scene_mesh_free(out);
    return rc;
}
