/*
 * files.c — safe output: temporary files and folders beside the target,
 * created exclusively (O_EXCL | O_NOFOLLOW, never through a planted
 * symlink), fsync'd and renamed into place; output folders written as a
 * whole (a temporary sibling folder renamed at the end); the list of live
 * temporaries that a signal handler removes; stale temporaries of dead
 * processes; output paths checked before work; whole-file reads with a size
 * bound, folders and paths (docs/design.md, "Writes are atomic").
 *
 * The one piece of mutable state of the library is here: the table of live
 * temporaries (tmp_live below), so that btf_remove_temporaries, called from
 * a SIGINT/SIGTERM handler, can remove them. Each slot is claimed and
 * released atomically by the thread that created the temporary.
 */
#include "core/core.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

/* Every temporary name ends in TMP_TAG IDENTITY-PID-N: IDENTITY names the
 * PID namespace on this boot of this host (tmp_identity), so that only a
 * process of the same namespace judges whether PID is dead. */
#define TMP_TAG ".btfcar-tmp-"
#define IDENTITY_LEN (BTF_TMP_IDENTITY_SIZE - 1)
#define TMP_SLOTS 64
#define TMP_TRIES 1000

/* SLOT_COMMIT: a folder being moved into place; the signal cleanup waits
 * for it (the committing thread blocks the signals, another thread may take
 * them). */
enum { SLOT_FREE, SLOT_BUSY, SLOT_FILE, SLOT_DIR, SLOT_COMMIT };
static struct {
    _Atomic int state;
    char path[4096];
    size_t top; /* a folder's: the length of the topmost folder its writer
                   created above it (removed again when empty), or 0 */
} tmp_live[TMP_SLOTS];

/* Records a temporary just created; -1 when the table is full (then only
 * the signal cleanup misses it). */
static int live_add(const char *path, int kind, size_t top)
{
    if (strlen(path) >= sizeof tmp_live[0].path)
        return -1;
    for (int i = 0; i < TMP_SLOTS; i++) {
        int expect = SLOT_FREE;
        if (atomic_compare_exchange_strong(&tmp_live[i].state, &expect, SLOT_BUSY)) {
            strcpy(tmp_live[i].path, path);
            tmp_live[i].top = top;
            atomic_store(&tmp_live[i].state, kind);
            return i;
        }
    }
    return -1;
}

static void live_set(const char *path, int kind)
{
    for (int i = 0; i < TMP_SLOTS; i++) {
        int s = atomic_load(&tmp_live[i].state);
        if (s >= SLOT_FILE && !strcmp(tmp_live[i].path, path)) {
            atomic_store(&tmp_live[i].state, kind);
            return;
        }
    }
}

static void live_drop(const char *path)
{
    live_set(path, SLOT_FREE);
}

/* Removes a tree with system calls only (async-signal-safe): openat,
 * getdents64, unlinkat. */
struct linux_dirent64 {
    unsigned long long d_ino;
    long long d_off;
    unsigned short d_reclen;
    unsigned char d_type;
    char d_name[];
};

static void sig_rmtree_at(int parent, const char *name, int depth)
{
    if (unlinkat(parent, name, 0) == 0 || depth > 16)
        return;
    int fd = openat(parent, name, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
    if (fd < 0)
        return;
    char buf[2048] __attribute__((aligned(8)));
    for (int pass = 0; pass < 64; pass++) {
        int removed = 0;
        long n;
        lseek(fd, 0, SEEK_SET);
        while ((n = syscall(SYS_getdents64, fd, buf, sizeof buf)) > 0) {
            for (long off = 0; off < n;) {
                struct linux_dirent64 *e = (struct linux_dirent64 *)(buf + off);
                off += e->d_reclen;
                if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
                    continue;
                sig_rmtree_at(fd, e->d_name, depth + 1);
                removed = 1;
            }
        }
        if (!removed)
            break;
    }
    close(fd);
    unlinkat(parent, name, AT_REMOVEDIR);
}

/* rmdir of the folders above a temporary folder, innermost first, down to
 * length top, while they are empty (async-signal-safe: a local copy, rmdir). */
static void sig_rmdir_up(const char *path, size_t top)
{
    char p[4096];
    size_t n = strlen(path);
    if (!top || n >= sizeof p)
        return;
    memcpy(p, path, n + 1);
    for (;;) {
        while (n > 0 && p[n - 1] != '/') /* drop the last component */
            n--;
        while (n > 1 && p[n - 1] == '/')
            n--;
        p[n] = '\0';
        if (n < top || n == 0 || rmdir(p) != 0)
            return;
    }
}

void btf_remove_temporaries(void)
{
    for (int i = 0; i < TMP_SLOTS; i++) {
        int s = atomic_load(&tmp_live[i].state);
        if (s == SLOT_FILE)
            unlink(tmp_live[i].path);
        else if (s == SLOT_DIR) {
            sig_rmtree_at(AT_FDCWD, tmp_live[i].path, 0);
            sig_rmdir_up(tmp_live[i].path, tmp_live[i].top);
        }
        /* A set being moved into place: wait (at most 10 s) for the move. */
        for (int t = 0; t < 10000 && atomic_load(&tmp_live[i].state) == SLOT_COMMIT; t++)
            nanosleep(&(struct timespec){0, 1000000}, NULL);
    }
}

/* FNV-1a: a short stable digest, not a secret. */
static uint64_t fnv1a(uint64_t h, const char *s, size_t n)
{
    for (size_t i = 0; i < n; i++)
        h = (h ^ (unsigned char)s[i]) * 1099511628211ull;
    return h;
}

/* Appends the first line of a small system file to the digest (nothing when
 * it cannot be read: the identity then rests on the rest). */
static uint64_t digest_file(uint64_t h, const char *path)
{
    char buf[256];
    int fd = open(path, O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    if (fd < 0)
        return fnv1a(h, "-", 1);
    ssize_t r = read(fd, buf, sizeof buf);
    close(fd);
    return fnv1a(h, buf, r > 0 ? (size_t)r : 0);
}

/* A PID means a process only within one PID namespace of one boot of one
 * host: two hosts sharing a folder over NFS, or a container sharing it by a
 * bind mount, see other processes under the same numbers. The
 * identity digests the host name, the boot id and the PID namespace. It is
 * read again each time, not cached: a child forked into a new namespace
 * must not inherit its parent's. */
void btf__tmp_identity(char out[BTF_TMP_IDENTITY_SIZE])
{
    uint64_t h = 14695981039346656037ull;
    char buf[256] = "";
    if (gethostname(buf, sizeof buf - 1) == 0)
        h = fnv1a(h, buf, strlen(buf));
    h = digest_file(h, "/proc/sys/kernel/random/boot_id");
    ssize_t r = readlink("/proc/self/ns/pid", buf, sizeof buf - 1);
    h = fnv1a(h, buf, r > 0 ? (size_t)r : 0);
    snprintf(out, BTF_TMP_IDENTITY_SIZE, "%016llx", (unsigned long long)h);
}

/* PATH.btfcar-tmp-IDENTITY-PID-N, N from a counter shared by all threads. */
static int tmp_name(const char *path, char *tmp, size_t n, btf_error *err)
{
    static _Atomic unsigned long counter;
    unsigned long c = ++counter;
    char id[BTF_TMP_IDENTITY_SIZE];
    btf__tmp_identity(id);
    int k = snprintf(tmp, n, "%s" TMP_TAG "%s-%ld-%lu", path, id, (long)getpid(), c);
    if (k < 0 || (size_t)k >= n)
        return btf__fail(err, BTF_E_ARG, "%s: path too long", path);
    return BTF_OK;
}

int btf__tmp_create(const char *path, char *tmp, size_t n, int *fd, btf_error *err)
{
    *fd = -1;
    for (int t = 0; t < TMP_TRIES; t++) {
        int rc = tmp_name(path, tmp, n, err);
        if (rc)
            return rc;
        /* O_EXCL: an existing name, a symlink too, is never opened. */
        int f = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
        if (f >= 0) {
            live_add(tmp, SLOT_FILE, 0);
            *fd = f;
            return BTF_OK;
        }
        if (errno != EEXIST)
            return btf__fail(err, BTF_E_IO, "%s: cannot create: %s", path, strerror(errno));
    }
    return btf__fail(err, BTF_E_IO, "%s: cannot create a temporary file: %d names taken", path,
                     TMP_TRIES);
}

int btf__commit_file(const char *tmp, const char *path, btf_error *err)
{
    if (rename(tmp, path) != 0) {
        int e = errno;
        btf__abort_file(tmp);
        return btf__fail(err, BTF_E_IO, "%s: cannot rename into place: %s", path, strerror(e));
    }
    live_drop(tmp);
    return BTF_OK;
}

void btf__abort_file(const char *tmp)
{
    remove(tmp);
    live_drop(tmp);
}

btf_status btf_write_file_atomic(const char *path, const void *data, size_t n, btf_error *err)
{
    char tmp[4096];
    int fd;
    int rc = btf__tmp_create(path, tmp, sizeof tmp, &fd, err);
    if (rc)
        return rc;
    const unsigned char *p = data;
    size_t left = n;
    int e = 0;
    while (left > 0) {
        ssize_t w = write(fd, p, left);
        if (w < 0 && errno == EINTR)
            continue;
        if (w <= 0) {
            e = w < 0 ? errno : ENOSPC;
            break;
        }
        p += w;
        left -= (size_t)w;
    }
    if (!e && fsync(fd) != 0)
        e = errno;
    if (close(fd) != 0 && !e)
        e = errno;
    if (e) {
        btf__abort_file(tmp);
        return btf__fail(err, BTF_E_IO, "%s: write failed: %s", path, strerror(e));
    }
    return btf__commit_file(tmp, path, err);
}

/* -1 with the message of what failed on fd (closed here), errno kept. */
static int open_failed(int fd, btf_error *err, const char *fmt, const char *path)
{
    int e = errno;
    if (fd >= 0)
        close(fd);
    btf__fail(err, BTF_E_IO, fmt, path, strerror(e));
    errno = e;
    return -1;
}

int btf__open_regular(const char *path, uint64_t *size, btf_error *err)
{
    /* O_NONBLOCK: opening a FIFO for reading otherwise waits for a writer,
     * forever; O_NOCTTY: a terminal never becomes the controlling one. */
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
    if (fd < 0)
        return open_failed(-1, err, "%s: cannot open: %s", path);
    struct stat st;
    if (fstat(fd, &st) != 0)
        return open_failed(fd, err, "%s: cannot stat: %s", path);
    /* A FIFO, a socket or a device has no end to read to (/dev/zero) or
     * none at all yet (a FIFO without a writer); a folder no bytes. */
    if (!S_ISREG(st.st_mode)) {
        close(fd);
        btf__fail(err, BTF_E_IO, "%s: not a regular file", path);
        errno = EINVAL;
        return -1;
    }
    /* Blocking again, as readers expect (for a regular file the flag means
     * nothing on most systems, but a network file system may honour it). */
    int fl = fcntl(fd, F_GETFL);
    if (fl < 0 || fcntl(fd, F_SETFL, fl & ~O_NONBLOCK) != 0)
        return open_failed(fd, err, "%s: cannot clear O_NONBLOCK: %s", path);
    if (size)
        *size = (uint64_t)st.st_size;
    return fd;
}

int btf__read_file(const char *path, size_t max_bytes, unsigned char **data,
                   size_t *n, btf_error *err)
{
    *data = NULL;
    *n = 0;
    int fd = btf__open_regular(path, NULL, err);
    if (fd < 0)
        return BTF_E_IO;
    FILE *f = fdopen(fd, "rb");
    if (!f) {
        close(fd);
        return btf__fail(err, BTF_E_NOMEM, "%s: out of memory", path);
    }
    size_t cap = 1 << 16, len = 0;
    unsigned char *buf = malloc(cap);
    if (!buf) {
        fclose(f);
        return btf__fail(err, BTF_E_NOMEM, "%s: out of memory", path);
    }
    for (;;) {
        if (len == cap) {
            if (cap >= max_bytes) {
                free(buf);
                fclose(f);
                return btf__fail(err, BTF_E_FORMAT, "%s: larger than %zu bytes", path, max_bytes);
            }
            size_t ncap = cap * 2 > max_bytes ? max_bytes : cap * 2;
            unsigned char *nb = realloc(buf, ncap);
            if (!nb) {
                free(buf);
                fclose(f);
                return btf__fail(err, BTF_E_NOMEM, "%s: out of memory", path);
            }
            buf = nb;
            cap = ncap;
        }
        size_t r = fread(buf + len, 1, cap - len, f);
        len += r;
        if (r == 0)
            break;
    }
    int bad = ferror(f);
    fclose(f);
    if (bad) {
        free(buf);
        return btf__fail(err, BTF_E_IO, "%s: read error", path);
    }
    *data = buf;
    *n = len;
    return BTF_OK;
}

btf_status btf_mkdirs(const char *path, btf_error *err)
{
    char buf[4096];
    size_t len = strlen(path);
    if (len == 0 || len >= sizeof buf)
        return btf__fail(err, BTF_E_ARG, "'%s': bad folder name", path);
    memcpy(buf, path, len + 1);
    for (size_t i = 1; i <= len; i++) {
        if (buf[i] == '/' || buf[i] == '\0') {
            char c = buf[i];
            buf[i] = '\0';
            if (mkdir(buf, 0777) != 0 && errno != EEXIST)
                return btf__fail(err, BTF_E_IO, "%s: cannot create folder: %s", buf, strerror(errno));
            buf[i] = c;
        }
    }
    struct stat st;
    if (stat(path, &st) != 0 || !S_ISDIR(st.st_mode))
        return btf__fail(err, BTF_E_IO, "%s: exists and is not a folder", path);
    return BTF_OK;
}

int btf__path_join(char *out, size_t n, const char *dir, const char *name, btf_error *err)
{
    size_t dl = strlen(dir);
    int slash = dl > 0 && dir[dl - 1] != '/';
    int k = snprintf(out, n, "%s%s%s", dir, slash ? "/" : "", name);
    if (k < 0 || (size_t)k >= n)
        return btf__fail(err, BTF_E_ARG, "%s/%s: path too long", dir, name);
    return BTF_OK;
}

void btf__remove_tree(const char *path)
{
    DIR *d = opendir(path);
    if (d) {
        struct dirent *e;
        while ((e = readdir(d))) {
            if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
                continue;
            char sub[4096];
            snprintf(sub, sizeof sub, "%s/%s", path, e->d_name);
            struct stat st;
            if (lstat(sub, &st) == 0 && S_ISDIR(st.st_mode))
                btf__remove_tree(sub);
            else
                remove(sub);
        }
        closedir(d);
    }
    rmdir(path);
}

/* ---- Output folders written as a whole ---- */

struct btf_output_dir {
    char given[4096];   /* the folder as the caller named it, no trailing slash */
    char dir[4096];     /* the final folder (a link followed), no trailing slash */
    char tmp[4096];     /* DIR.btfcar-tmp-ID-PID-N beside it */
    char created[4096]; /* the topmost missing ancestor begin created, or "" */
};

/* path without trailing slashes into out. */
static int strip_slashes(const char *path, char *out, size_t n, btf_error *err)
{
    size_t len = strlen(path);
    while (len > 1 && path[len - 1] == '/')
        len--;
    if (len == 0 || len >= n)
        return btf__fail(err, BTF_E_ARG, "'%s': bad path", path);
    memcpy(out, path, len);
    out[len] = '\0';
    return BTF_OK;
}

/* The folder that holds path ("." for a bare name). */
static void parent_of(const char *path, char *out, size_t n)
{
    const char *s = strrchr(path, '/');
    if (!s)
        snprintf(out, n, ".");
    else if (s == path)
        snprintf(out, n, "/");
    else
        snprintf(out, n, "%.*s", (int)(s - path), path);
}

/* Removes the folders begin created above the temporary folder, innermost
 * first, as long as they are empty. */
static void undo_ancestors(const btf_output_dir *d)
{
    sig_rmdir_up(d->dir, strlen(d->created)); /* the signal handler's walk too */
}

/* An output folder given as a symlink to a folder is written into the
 * folder it names: the set is assembled beside the real
 * folder, so that the final renames stay within one file system and never
 * replace the link. A link to anything else is left for the checks. */
static btf_status follow_folder_link(char *dir, size_t n, btf_error *err)
{
    struct stat st;
    if (lstat(dir, &st) != 0 || !S_ISLNK(st.st_mode) || stat(dir, &st) != 0 ||
        !S_ISDIR(st.st_mode))
        return BTF_OK;
    char *real = realpath(dir, NULL);
    if (!real)
        return btf__fail(err, BTF_E_IO, "%s: cannot follow the link: %s", dir, strerror(errno));
    int fits = strlen(real) < n;
    if (fits)
        strcpy(dir, real);
    free(real);
    return fits ? BTF_OK : btf__fail(err, BTF_E_ARG, "%s: the folder it links to has too long a "
                                     "path", dir);
}

btf_status btf_output_dir_begin(const char *dir, btf_output_dir **out, btf_error *err)
{
    if (!out)
        return btf__fail(err, BTF_E_ARG, "btf_output_dir_begin: NULL output pointer");
    *out = NULL;
    if (!dir)
        return btf__fail(err, BTF_E_ARG, "btf_output_dir_begin: no folder");
    btf_output_dir *d = calloc(1, sizeof *d);
    if (!d)
        return btf__fail(err, BTF_E_NOMEM, "%s: out of memory", dir);
    btf_status rc = strip_slashes(dir, d->dir, sizeof d->dir, err);
    memcpy(d->given, d->dir, sizeof d->given);
    if (!rc)
        rc = follow_folder_link(d->dir, sizeof d->dir, err);
    char parent[4096];
    parent_of(d->dir, parent, sizeof parent);
    struct stat st;
    if (!rc && stat(parent, &st) != 0) {
        /* The first missing ancestor, to be removed again on failure. */
        for (size_t i = 1; i <= strlen(parent); i++)
            if (parent[i] == '/' || parent[i] == '\0') {
                snprintf(d->created, sizeof d->created, "%.*s", (int)i, parent);
                if (stat(d->created, &st) != 0)
                    break;
            }
        rc = btf_mkdirs(parent, err);
        if (rc)
            undo_ancestors(d);
    }
    for (int t = 0; !rc; t++) {
        if ((rc = tmp_name(d->dir, d->tmp, sizeof d->tmp, err)))
            break;
        if (mkdir(d->tmp, 0777) == 0) {
            live_add(d->tmp, SLOT_DIR, strlen(d->created));
            *out = d;
            return BTF_OK;
        }
        if (errno != EEXIST || t == TMP_TRIES)
            rc = btf__fail(err, BTF_E_IO, "%s: cannot create a folder beside it: %s", d->dir,
                           strerror(errno));
    }
    undo_ancestors(d);
    free(d);
    return rc;
}

const char *btf_output_dir_path(const btf_output_dir *d)
{
    return d ? d->tmp : NULL;
}

/* Moves every entry of the temporary folder into the existing folder: a
 * first pass checks that no new file would land on a folder, so that a
 * refusal moves nothing. */
static btf_status move_entries(const btf_output_dir *d, btf_error *err)
{
    btf_status rc = BTF_OK;
    for (int pass = 0; pass < 2 && !rc; pass++) {
        DIR *dh = opendir(d->tmp);
        if (!dh)
            return btf__fail(err, BTF_E_IO, "%s: %s", d->dir, strerror(errno));
        struct dirent *e;
        while (!rc && (e = readdir(dh))) {
            if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
                continue;
            char from[8192], to[8192];
            snprintf(from, sizeof from, "%s/%s", d->tmp, e->d_name);
            snprintf(to, sizeof to, "%s/%s", d->dir, e->d_name);
            struct stat a, b;
            if (pass == 0 && lstat(from, &a) == 0 && lstat(to, &b) == 0 &&
                (S_ISDIR(a.st_mode) || S_ISDIR(b.st_mode)))
                rc = btf__fail(err, BTF_E_IO, "%s: exists and is %s; nothing moved into %s", to,
                               S_ISDIR(b.st_mode) ? "a folder" : "a file", d->dir);
            else if (pass == 1 && rename(from, to) != 0)
                rc = btf__fail(err, BTF_E_IO, "%s: cannot move into place: %s", to,
                               strerror(errno));
        }
        closedir(dh);
    }
    return rc;
}

/* Writers into one existing folder take turns: an exclusive
 * flock on the folder itself, held while a set moves in, so that two runs
 * never interleave their files (the later set lands whole over the
 * earlier). The lock is taken on the folder the path names now: a folder
 * replaced while we waited (an empty one renamed over) is locked afresh.
 * Returns the locked descriptor, or -1 when the folder does not exist (a
 * missing folder is created by one atomic rename, no lock needed). */
static int lock_folder(const char *dir)
{
    for (int tries = 0; tries < 100; tries++) {
        int fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC | O_NOFOLLOW);
        if (fd < 0)
            return -1;
        int r;
        while ((r = flock(fd, LOCK_EX)) != 0 && errno == EINTR)
            ;
        struct stat a, b;
        if (r == 0 && fstat(fd, &a) == 0 && stat(dir, &b) == 0 && a.st_dev == b.st_dev &&
            a.st_ino == b.st_ino)
            return fd;
        close(fd);
        if (r != 0)
            return -1; /* no locks here (e.g. a file system without them) */
    }
    return -1;
}

btf_status btf_output_dir_commit(btf_output_dir *d, btf_error *err)
{
    if (!d)
        return btf__fail(err, BTF_E_ARG, "btf_output_dir_commit: NULL");
    /* Wait for another writer of the folder first, interruptibly. */
    int lock = lock_folder(d->dir);
    /* No interrupt between the renames: the set moves as a whole. */
    sigset_t block, old;
    sigemptyset(&block);
    sigaddset(&block, SIGINT);
    sigaddset(&block, SIGTERM);
    sigaddset(&block, SIGHUP);
    pthread_sigmask(SIG_BLOCK, &block, &old);
    live_set(d->tmp, SLOT_COMMIT);
    btf_status rc = BTF_OK;
    /* A missing or empty folder is replaced in one rename. */
    if (rename(d->tmp, d->dir) != 0) {
        struct stat st;
        if ((errno == ENOTEMPTY || errno == EEXIST) && stat(d->dir, &st) == 0 &&
            S_ISDIR(st.st_mode)) {
            if (lock < 0) /* made meanwhile by another writer */
                lock = lock_folder(d->dir);
            rc = move_entries(d, err);
        } else
            rc = btf__fail(err, BTF_E_IO, "%s: cannot move the output into place: %s", d->dir,
                           strerror(errno));
        btf__remove_tree(d->tmp);
    }
    live_drop(d->tmp);
    if (rc)
        undo_ancestors(d);
    if (lock >= 0)
        close(lock); /* the turn passes on */
    pthread_sigmask(SIG_SETMASK, &old, NULL);
    free(d);
    return rc;
}

/* The message of an error met while the set was written names the
 * temporary folder (the writers were given its path): the user named the
 * output, so every occurrence of the one becomes the other. */
static void name_output(const btf_output_dir *d, btf_error *err)
{
    if (!err)
        return;
    char out[sizeof err->msg];
    size_t n = 0, lt = strlen(d->tmp), lg = strlen(d->given);
    const char *s = err->msg;
    while (*s && n + 1 < sizeof out) {
        if (lt && !strncmp(s, d->tmp, lt) && n + lg < sizeof out) {
            memcpy(out + n, d->given, lg);
            n += lg;
            s += lt;
        } else {
            out[n++] = *s++;
        }
    }
    out[n] = '\0';
    memcpy(err->msg, out, n + 1);
}

void btf_output_dir_fail(btf_output_dir *d, btf_error *err)
{
    if (!d)
        return;
    name_output(d, err);
    btf_output_dir_abort(d);
}

void btf_output_dir_abort(btf_output_dir *d)
{
    if (!d)
        return;
    btf__remove_tree(d->tmp);
    live_drop(d->tmp);
    undo_ancestors(d);
    free(d);
}

/* ---- Checks before work, stale temporaries ---- */

/* Creates and removes a temporary file in folder: proof that it takes files. */
static btf_status probe_folder(const char *path, const char *folder, btf_error *err)
{
    char name[4096], tmp[4096];
    int fd;
    btf_error e = {0};
    snprintf(name, sizeof name, "%s/.btfcar-probe", folder);
    if (btf__tmp_create(name, tmp, sizeof tmp, &fd, &e) != 0) {
        const char *why = strstr(e.msg, ": cannot create: ");
        return btf__fail(err, BTF_E_IO, "%s: cannot write in folder %s%s", path, folder,
                         why ? why + 15 : "");
    }
    close(fd);
    btf__abort_file(tmp);
    return BTF_OK;
}

btf_status btf_output_check(const char *path, btf_output_kind kind, btf_error *err)
{
    if (!path || !*path)
        return btf__fail(err, BTF_E_ARG, "no output path given");
    if (kind != BTF_OUTPUT_FILE && kind != BTF_OUTPUT_FOLDER)
        return btf__fail(err, BTF_E_ARG, "%s: unknown output kind %d", path, (int)kind);
    char p[4096], parent[4096];
    btf_status rc = strip_slashes(path, p, sizeof p, err);
    if (rc)
        return rc;
    size_t len = strlen(path);
    if (kind == BTF_OUTPUT_FILE && path[len - 1] == '/')
        return btf__fail(err, BTF_E_ARG, "%s: names a folder; expected a file name", path);
    struct stat st;
    int exists = stat(p, &st) == 0;
    if (!exists && errno != ENOENT)
        return btf__fail(err, BTF_E_IO, "%s: %s", path, strerror(errno));
    if (exists && kind == BTF_OUTPUT_FILE && S_ISDIR(st.st_mode))
        return btf__fail(err, BTF_E_ARG, "%s: is a folder; expected a file name", path);
    if (exists && kind == BTF_OUTPUT_FILE && !S_ISREG(st.st_mode))
        return btf__fail(err, BTF_E_ARG, "%s: exists and is not a regular file", path);
    if (exists && kind == BTF_OUTPUT_FOLDER && !S_ISDIR(st.st_mode))
        return btf__fail(err, BTF_E_ARG, "%s: exists and is not a folder", path);
    parent_of(p, parent, sizeof parent);
    /* A folder output may create missing folders above it (removed again
     * on failure); a file goes into an existing folder. */
    while (stat(parent, &st) != 0) {
        if (errno == ENOENT && kind == BTF_OUTPUT_FILE)
            return btf__fail(err, BTF_E_IO, "%s: folder %s does not exist", path, parent);
        if (errno != ENOENT)
            return btf__fail(err, BTF_E_IO, "%s: folder %s: %s", path, parent, strerror(errno));
        char up[4096];
        parent_of(parent, up, sizeof up);
        if (!strcmp(up, parent))
            return btf__fail(err, BTF_E_IO, "%s: folder %s: %s", path, parent, strerror(errno));
        snprintf(parent, sizeof parent, "%s", up);
    }
    if (!S_ISDIR(st.st_mode))
        return btf__fail(err, BTF_E_ARG, "%s: %s is not a folder", path, parent);
    rc = probe_folder(path, parent, err);
    if (!rc && exists && kind == BTF_OUTPUT_FOLDER)
        rc = probe_folder(path, p, err);
    return rc;
}

int btf_remove_stale_temporaries(const char *folder)
{
    DIR *dh = opendir(folder && *folder ? folder : ".");
    if (!dh)
        return 0;
    int removed = 0;
    char ours[BTF_TMP_IDENTITY_SIZE];
    btf__tmp_identity(ours);
    struct dirent *e;
    while ((e = readdir(dh))) {
        const char *t = strstr(e->d_name, TMP_TAG), *next;
        while (t && (next = strstr(t + 1, TMP_TAG)))
            t = next;
        if (!t)
            continue;
        char *end;
        const char *id = t + strlen(TMP_TAG), *num = id + IDENTITY_LEN + 1;
        /* Another namespace's or host's (or a name without an identity):
         * its PID says nothing here, so it is never judged dead. */
        if (strlen(id) <= IDENTITY_LEN || strncmp(id, ours, IDENTITY_LEN) ||
            id[IDENTITY_LEN] != '-')
            continue;
        if (*num < '0' || *num > '9')
            continue;
        long pid = strtol(num, &end, 10);
        if (*end != '-' || end[1] < '0' || end[1] > '9')
            continue;
        strtoul(end + 1, &end, 10);
        if (*end || pid <= 0 || pid == (long)getpid())
            continue;
        char sub[8192];
        struct stat st;
        snprintf(sub, sizeof sub, "%s/%s", folder && *folder ? folder : ".", e->d_name);
        if (lstat(sub, &st) != 0 || st.st_uid != getuid())
            continue;
        if (kill((pid_t)pid, 0) == 0 || errno != ESRCH)
            continue; /* alive, or not ours to judge */
        if (S_ISDIR(st.st_mode))
            btf__remove_tree(sub);
        else
            unlink(sub);
        removed++;
    }
    closedir(dh);
    return removed;
}
