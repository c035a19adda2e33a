/*
 * mesh_io.c — assimp's file access for one mesh (mesh_io.h): every open
 * goes through btf__open_regular, and a file other than the mesh itself
 * must resolve (realpath: links and .. followed) to the mesh's folder or
 * below. A refusal is kept in io->refused and fails the load after assimp
 * returns: assimp treats a file it cannot open as absent, and an OBJ
 * whose material library is absent still loads, so the refusal would
 * otherwise go unseen. A file that does not exist stays assimp's matter
 * (an OBJ without its .mtl loads, as it always did).
 */
#include "scene/mesh_io.h"
#include "core/core.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <unistd.h>

/* One open file: the aiFile assimp sees first, so that the one pointer
 * serves as both. */
typedef struct mesh_file {
    struct aiFile f;
    FILE *fp;
    size_t size;
} mesh_file;

static size_t file_read(struct aiFile *f, char *buf, size_t size, size_t count)
{
    return fread(buf, size, count, ((mesh_file *)f)->fp);
}

/* Import only: nothing is ever written. */
static size_t file_write(struct aiFile *f, const char *buf, size_t size, size_t count)
{
    (void)f, (void)buf, (void)size, (void)count;
    return 0;
}

static size_t file_tell(struct aiFile *f)
{
    off_t at = ftello(((mesh_file *)f)->fp);
    return at < 0 ? 0 : (size_t)at;
}

static size_t file_size(struct aiFile *f)
{
    return ((mesh_file *)f)->size;
}

/* assimp passes a backwards offset as a wrapped size_t, as its own stream
 * does (it casts to long for fseek); the cast back recovers it. */
static enum aiReturn file_seek(struct aiFile *f, size_t offset, enum aiOrigin origin)
{
    int whence = origin == aiOrigin_SET ? SEEK_SET : origin == aiOrigin_CUR ? SEEK_CUR : SEEK_END;
    return fseeko(((mesh_file *)f)->fp, (off_t)(int64_t)offset, whence) == 0 ? aiReturn_SUCCESS
                                                                              : aiReturn_FAILURE;
}

static void file_flush(struct aiFile *f)
{
    (void)f;
}

/* Keeps the first refusal, the one the user has to act on, as "MESH: FILE:
 * why" (just "MESH: why" for the mesh itself). */
static struct aiFile *refuse(scene_mesh_io *io, const char *path, const btf_error *e)
{
    if (!io->refused.code) {
        io->refused = *e;
        if (strcmp(path, io->mesh) != 0)
            btf__fail(&io->refused, e->code, "%s: %s", io->mesh, e->msg);
    }
    return NULL;
}

/* 1 when path lies in the mesh's folder or below; else the refusal is
 * kept. A path that does not resolve (a missing file) passes: the open
 * that follows fails and says why. */
static int inside_folder(scene_mesh_io *io, const char *path)
{
    char real[PATH_MAX];
    if (!realpath(path, real))
        return 1;
    size_t n = strlen(io->folder);
    int below = strncmp(real, io->folder, n) == 0 && (real[n] == '/' || real[n] == '\0');
    if (below || strcmp(io->folder, "/") == 0)
        return 1;
    btf_error e = {0};
    btf__fail(&e, BTF_E_IO, "%s: outside the mesh's folder %s (a mesh may read only files "
              "beside it or below)", path, io->folder);
    refuse(io, path, &e);
    return 0;
}

static struct aiFile *io_open(struct aiFileIO *fs, const char *path, const char *mode)
{
    scene_mesh_io *io = (scene_mesh_io *)fs->UserData;
    if (!path || !mode || strpbrk(mode, "wa+"))
        return NULL; /* reading only */
    if (strcmp(path, io->mesh) != 0 && !inside_folder(io, path))
        return NULL;
    btf_error e = {0};
    uint64_t size;
    int fd = btf__open_regular(path, &size, &e);
    if (fd < 0) /* missing: assimp's matter, as before (an OBJ loads without its .mtl) */
        return errno == ENOENT || errno == ENOTDIR ? NULL : refuse(io, path, &e);
    mesh_file *m = calloc(1, sizeof *m);
    FILE *fp = m ? fdopen(fd, "rb") : NULL;
    if (!fp) {
        free(m);
        close(fd);
        btf__fail(&e, BTF_E_NOMEM, "%s: out of memory", path);
        return refuse(io, path, &e);
    }
    m->fp = fp;
    m->size = (size_t)size;
    m->f = (struct aiFile){.ReadProc = file_read, .WriteProc = file_write,
                           .TellProc = file_tell, .FileSizeProc = file_size,
                           .SeekProc = file_seek, .FlushProc = file_flush,
                           .UserData = (aiUserData)m};
    return &m->f;
}

static void io_close(struct aiFileIO *fs, struct aiFile *f)
{
    (void)fs;
    if (!f)
        return;
    fclose(((mesh_file *)f)->fp);
    free(f);
}

btf_status scene_mesh_io_init(scene_mesh_io *io, const char *path, btf_error *err)
{
    memset(io, 0, sizeof *io);
    io->mesh = path;
    io->fs = (struct aiFileIO){.OpenProc = io_open, .CloseProc = io_close,
                               .UserData = (aiUserData)io};
    const char *slash = strrchr(path, '/');
    char dir[PATH_MAX];
    size_t n = slash ? (size_t)(slash - path) : 1;
    if (n >= sizeof dir)
        return btf__fail(err, BTF_E_ARG, "%s: path too long", path);
    if (!slash)
        memcpy(dir, ".", 2);
    else if (n == 0)
        memcpy(dir, "/", 2);
    else
        memcpy(dir, path, n), dir[n] = '\0';
    if (!realpath(dir, io->folder))
        return btf__fail(err, BTF_E_IO, "%s: cannot resolve: %s", dir, strerror(errno));
    return BTF_OK;
}
