/* test_output.c — safe output (src/core/files.c; docs/design.md, "Writes are
 * atomic"): planted symlinks at the temporary names, output folders as a
 * whole, stale temporaries, output paths checked before work, and SIGINT /
 * SIGTERM in the middle of `btfcar synthesise`. */
#include "testutil.h"
#include "core/core.h"

#include <dirent.h>
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

/* Entries of a folder other than . and .. */
static int count_entries(const char *path)
{
    DIR *d = opendir(path);
    if (!d)
        return -1;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)))
        n += strcmp(e->d_name, ".") && strcmp(e->d_name, "..");
    closedir(d);
    return n;
}

static int has_tmp_entry(const char *path)
{
    DIR *d = opendir(path);
    if (!d)
        return 0;
    int found = 0;
    struct dirent *e;
    while ((e = readdir(d)))
        found |= strstr(e->d_name, ".btfcar-tmp-") != NULL;
    closedir(d);
    return found;
}

static int count_lines(const char *s)
{
    int n = 0;
    for (; *s; s++)
        n += *s == '\n';
    return n;
}

static void read_back(const char *path, char *buf, size_t n)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    size_t r = fread(buf, 1, n - 1, f);
    buf[r] = '\0';
    fclose(f);
}

/* Symlinks at the next temporary names of this process (the counter is
 * shared by every writer, so the first 400 cover this program), pointing
 * at target. */
static void plant(const char *path, const char *target)
{
    char id[BTF_TMP_IDENTITY_SIZE];
    btf__tmp_identity(id);
    for (int k = 1; k <= 400; k++) {
        const char *name = tu_fmt("%s.btfcar-tmp-%s-%ld-%d", path, id, (long)getpid(), k);
        assert_int_equal(symlink(target, name), 0);
    }
}

static void unplant(const char *path)
{
    char id[BTF_TMP_IDENTITY_SIZE];
    btf__tmp_identity(id);
    for (int k = 1; k <= 400; k++)
        unlink(tu_fmt("%s.btfcar-tmp-%s-%ld-%d", path, id, (long)getpid(), k));
}

static void planted_symlinks_are_skipped(void **state)
{
    (void)state;
    char victim[4096], path[4096], buf[64];
    btf_error e = {0};
    snprintf(victim, sizeof victim, "%s/victim", tu_dir);
    tu_write_file(victim, "keep", 4);
    struct stat st;
    /* btf_write_file_atomic (model files, PNG, JPEG, tables). */
    snprintf(path, sizeof path, "%s/out.bin", tu_dir);
    plant(path, victim);
    TU_OK(btf_write_file_atomic(path, "new", 3, &e), &e);
    read_back(victim, buf, sizeof buf);
    assert_string_equal(buf, "keep");
    assert_int_equal(lstat(path, &st), 0);
    assert_true(S_ISREG(st.st_mode));
    read_back(path, buf, sizeof buf);
    assert_string_equal(buf, "new");
    unplant(path);
    /* The EXR writer's temporary file. */
    snprintf(path, sizeof path, "%s/out.exr", tu_dir);
    plant(path, victim);
    btf_image img;
    TU_OK(btf_image_alloc(&img, 4, 4, 3, &e), &e);
    TU_OK(btf_image_write_exr_opts(path, &img, NULL, NULL, &e), &e);
    btf_image_free(&img);
    read_back(victim, buf, sizeof buf);
    assert_string_equal(buf, "keep");
    assert_int_equal(lstat(path, &st), 0);
    assert_true(S_ISREG(st.st_mode));
    unplant(path);
    /* An output folder's temporary sibling: a planted link to another folder. */
    char other[4096];
    snprintf(other, sizeof other, "%s/other", tu_dir);
    assert_int_equal(mkdir(other, 0777), 0);
    snprintf(path, sizeof path, "%s/set", tu_dir);
    plant(path, other);
    btf_output_dir *od;
    TU_OK(btf_output_dir_begin(path, &od, &e), &e);
    tu_write_file(tu_fmt("%s/a.txt", btf_output_dir_path(od)), "a", 1);
    TU_OK(btf_output_dir_commit(od, &e), &e);
    assert_int_equal(count_entries(other), 0);
    assert_int_equal(lstat(path, &st), 0);
    assert_true(S_ISDIR(st.st_mode));
    assert_int_equal(count_entries(path), 1);
    unplant(path);
}

static void output_folders_are_whole(void **state)
{
    (void)state;
    btf_error e = {0};
    char *root = tu_tmpdir();
    btf_output_dir *od;
    /* Aborted: neither the folder, nor its temporary, nor the folders above. */
    TU_OK(btf_output_dir_begin(tu_fmt("%s/a/b/c", root), &od, &e), &e);
    tu_write_file(tu_fmt("%s/x.txt", btf_output_dir_path(od)), "x", 1);
    btf_output_dir_abort(od);
    assert_int_equal(count_entries(root), 0);
    /* Committed into a missing folder: one rename. */
    TU_OK(btf_output_dir_begin(tu_fmt("%s/new/", root), &od, &e), &e);
    tu_write_file(tu_fmt("%s/x.txt", btf_output_dir_path(od)), "x", 1);
    assert_int_equal(access(tu_fmt("%s/new", root), F_OK), -1); /* not before commit */
    TU_OK(btf_output_dir_commit(od, &e), &e);
    assert_int_equal(count_entries(tu_fmt("%s/new", root)), 1);
    /* Into an existing folder: new names replace, other files stay. */
    tu_write_file(tu_fmt("%s/new/keep.txt", root), "k", 1);
    TU_OK(btf_output_dir_begin(tu_fmt("%s/new", root), &od, &e), &e);
    tu_write_file(tu_fmt("%s/x.txt", btf_output_dir_path(od)), "y", 1);
    tu_write_file(tu_fmt("%s/z.txt", btf_output_dir_path(od)), "z", 1);
    TU_OK(btf_output_dir_commit(od, &e), &e);
    assert_int_equal(count_entries(tu_fmt("%s/new", root)), 3);
    char buf[8];
    read_back(tu_fmt("%s/new/x.txt", root), buf, sizeof buf);
    assert_string_equal(buf, "y");
    /* A new file that would land on a folder: refused, nothing moved. */
    assert_int_equal(mkdir(tu_fmt("%s/new/d.txt", root), 0777), 0);
    TU_OK(btf_output_dir_begin(tu_fmt("%s/new", root), &od, &e), &e);
    tu_write_file(tu_fmt("%s/w.txt", btf_output_dir_path(od)), "w", 1);
    tu_write_file(tu_fmt("%s/d.txt", btf_output_dir_path(od)), "d", 1);
    assert_int_not_equal(btf_output_dir_commit(od, &e), 0);
    assert_non_null(strstr(e.msg, "d.txt"));
    assert_int_equal(count_entries(tu_fmt("%s/new", root)), 4);
    assert_int_equal(access(tu_fmt("%s/new/w.txt", root), F_OK), -1);
    assert_int_equal(count_entries(root), 1); /* no temporary left */
    tu_rmtree(root);
    free(root);
}

static void stale_temporaries(void **state)
{
    (void)state;
    char *root = tu_tmpdir();
    pid_t child = fork();
    if (child == 0)
        _exit(0);
    assert_true(child > 0);
    waitpid(child, NULL, 0); /* a pid that no longer runs */
    long dead = (long)child;
    char id[BTF_TMP_IDENTITY_SIZE];
    btf__tmp_identity(id);
    tu_write_file(tu_fmt("%s/a.exr.btfcar-tmp-%s-%ld-1", root, id, dead), "x", 1);
    assert_int_equal(mkdir(tu_fmt("%s/set.btfcar-tmp-%s-%ld-2", root, id, dead), 0777), 0);
    tu_write_file(tu_fmt("%s/set.btfcar-tmp-%s-%ld-2/in.exr", root, id, dead), "x", 1);
    /* Kept: this live process's, pid 1's (alive), names not of the pattern,
     * the dead pid under another host's or namespace's identity and under
     * none (a name from before the identity): not proven dead. */
    tu_write_file(tu_fmt("%s/b.btfcar-tmp-%s-%ld-1", root, id, (long)getpid()), "x", 1);
    tu_write_file(tu_fmt("%s/c.btfcar-tmp-%s-1-1", root, id), "x", 1);
    tu_write_file(tu_fmt("%s/d.btfcar-tmp-%s-%ld-x", root, id, dead), "x", 1);
    tu_write_file(tu_fmt("%s/e.btfcar-tmp-%s-%ld", root, id, dead), "x", 1);
    tu_write_file(tu_fmt("%s/f.btfcar-tmp-0123456789abcdef-%ld-1", root, dead), "x", 1);
    tu_write_file(tu_fmt("%s/g.btfcar-tmp-%ld-1", root, dead), "x", 1);
    tu_write_file(tu_fmt("%s/plain.txt", root), "x", 1);
    assert_int_equal(btf_remove_stale_temporaries(root), 2);
    assert_int_equal(count_entries(root), 7);
    assert_int_equal(access(tu_fmt("%s/a.exr.btfcar-tmp-%s-%ld-1", root, id, dead), F_OK), -1);
    /* A btfcar run removes the stale ones beside its output. */
    tu_write_file(tu_fmt("%s/m.btfcar.btfcar-tmp-%s-%ld-7", root, id, dead), "x", 1);
    char *err = NULL;
    assert_int_equal(tu_run(tu_fmt("%s texture-fit -q %s/nothing.png -o %s/m.btfcar", tu_cli(),
                                   root, root), &err), 1);
    free(err);
    assert_int_equal(access(tu_fmt("%s/m.btfcar.btfcar-tmp-%s-%ld-7", root, id, dead), F_OK),
                     -1);
    assert_int_equal(count_entries(root), 7);
    tu_rmtree(root);
    free(root);
}

/* Output paths are checked before any work: one line naming the path, exit
 * 1, nothing created. The inputs do not exist: the output error comes first. */
static void outputs_checked_first(void **state)
{
    (void)state;
    char *root = tu_tmpdir();
    tu_write_file(tu_fmt("%s/file", root), "x", 1);
    assert_int_equal(mkdir(tu_fmt("%s/dir", root), 0777), 0);
    const char *in = tu_fmt("%s/no-such-input", root);
    char input[4096];
    snprintf(input, sizeof input, "%s", in);
    struct { const char *args, *path; } cases[] = {
        {"analyse %s -o %s", "%s/missing-dir/m.btfcar"},
        {"analyse %s -o %s", "/proc/x"},
        {"analyse %s -o %s", "%s/dir"},
        {"analyse %s -o %s", "%s/file/m.btfcar"},
        {"analyse %s --stage segment -o %s", "%s/file"},
        {"texture-fit %s -o %s", "%s/dir"},
        {"texture-fit %s -o %s", "%s/missing-dir/m.btfcar"},
        {"synthesise %s --size 8x8 -o %s", "%s/file"},
        {"synthesise %s --size 8x8 -o %s", "/proc/x"},
        {"photostereo %s -o %s", "%s/file"},
        {"generate --material wood --size 4 %s", "%s/file"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        char path[4096], cmd[8192];
        snprintf(path, sizeof path, cases[i].path, root);
        if (!strncmp(cases[i].args, "generate", 8))
            snprintf(cmd, sizeof cmd, cases[i].args, path);
        else
            snprintf(cmd, sizeof cmd, cases[i].args, input, path);
        char *err = NULL;
        int rc = tu_run(tu_fmt("%s %s", tu_cli(), cmd), &err);
        if (rc != 1 || !strstr(err, path))
            print_error("%s: exit %d, %s\n", cmd, rc, err ? err : "");
        assert_int_equal(rc, 1);
        assert_non_null(strstr(err, path));
        assert_null(strstr(err, "no-such-input"));
        assert_true(strchr(err, '\n') == err + strlen(err) - 1); /* one line */
        free(err);
        assert_int_equal(count_entries(root), 2); /* nothing created */
    }
    if (geteuid() != 0) { /* root writes into read-only folders */
        chmod(tu_fmt("%s/dir", root), 0555);
        char *err = NULL;
        assert_int_equal(tu_run(tu_fmt("%s analyse %s -o %s/dir/m.btfcar", tu_cli(), input, root),
                                &err), 1);
        assert_non_null(strstr(err, "cannot write"));
        free(err);
        chmod(tu_fmt("%s/dir", root), 0755);
    }
    tu_rmtree(root);
    free(root);
}

/* btfcar synthesise of a large image, interrupted once its temporary file
 * exists: exit 128 + signal, nothing of the run left. */
/* sub: "" or folders (ending in '/') that do not exist yet, created by the
 * run above its output: the signal removes them too (they used to be left). */
static void interrupt_one(const char *model, int sig, const char *sub)
{
    char *root = tu_tmpdir();
    char out[4096], where[4096];
    snprintf(out, sizeof out, "%s/%sout", root, sub);
    snprintf(where, sizeof where, "%s/%s", root, sub);
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        if (!freopen("/dev/null", "w", stdout) || !freopen("/dev/null", "w", stderr))
            _exit(126);
        execl(tu_cli(), tu_cli(), "synthesise", "-q", model, "--size", "8192x8192",
              "--backend", "cpu", "-o", out, (char *)NULL);
        _exit(127);
    }
    /* Until the EXR's temporary file has bytes in it (at most 60 s). */
    int seen = 0;
    for (int i = 0; i < 6000 && !seen; i++) {
        DIR *d = opendir(where);
        struct dirent *e;
        while (d && (e = readdir(d)))
            if (strstr(e->d_name, ".btfcar-tmp-")) {
                char tmp[8192];
                snprintf(tmp, sizeof tmp, "%s/%s", where, e->d_name);
                seen = has_tmp_entry(tmp);
            }
        if (d)
            closedir(d);
        nanosleep(&(struct timespec){0, 10000000}, NULL);
    }
    assert_true(seen);
    nanosleep(&(struct timespec){0, 100000000}, NULL); /* mid-write */
    assert_int_equal(kill(pid, sig), 0);
    int status;
    assert_int_equal(waitpid(pid, &status, 0), pid);
    assert_true(WIFEXITED(status));
    assert_int_equal(WEXITSTATUS(status), 128 + sig);
    assert_int_equal(count_entries(root), 0);
    tu_rmtree(root);
    free(root);
}

static void interrupted_synthesis_leaves_nothing(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image img;
    tu_material_image("wood", 32, 3, (btf_dir){0, 0}, (btf_dir){30, 0}, &img);
    char png[4096], model[4096];
    snprintf(png, sizeof png, "%s/int.png", tu_dir);
    snprintf(model, sizeof model, "%s/int.btfcar", tu_dir);
    TU_OK(btf_image_write_png(png, &img, &e), &e);
    btf_image_free(&img);
    assert_int_equal(tu_run(tu_fmt("%s texture-fit -q %s -o %s --levels 1", tu_cli(), png, model),
                            NULL), 0);
    interrupt_one(model, SIGINT, "");
    interrupt_one(model, SIGTERM, "");
    interrupt_one(model, SIGINT, "new1/new2/");
    /* A failing --preview (its name taken by a folder in OUTDIR) leaves no
     * EXR either, and no temporary. */
    char out[4096];
    snprintf(out, sizeof out, "%s/pv", tu_dir);
    assert_int_equal(mkdir(out, 0777), 0);
    assert_int_equal(mkdir(tu_fmt("%s/subspace_00.png", out), 0777), 0);
    char *err = NULL;
    assert_int_equal(tu_run(tu_fmt("%s synthesise -q %s --size 16x16 --preview -o %s", tu_cli(),
                                   model, out), &err), 1);
    assert_non_null(strstr(err, "subspace_00.png"));
    free(err);
    assert_int_equal(count_entries(out), 1);
    assert_false(has_tmp_entry(tu_dir));
}

/* The same with several images (btfcar synthesise writes each on a thread
 * of its own while the next is synthesised): the first image's failure
 * stops the run, whatever image the synthesis was on; nothing is left. */
static void failed_write_of_a_batch_leaves_nothing(void **state)
{
    (void)state;
    char ds[4096], model[4096], out[4096];
    snprintf(ds, sizeof ds, "%s/bds", tu_dir);
    snprintf(model, sizeof model, "%s/b.btfcar", tu_dir);
    assert_int_equal(tu_run(tu_fmt("%s generate -q --material fabric --size 32 --seed 2 %s",
                                   tu_cli(), ds), NULL), 0);
    assert_int_equal(tu_run(tu_fmt("%s analyse -q %s -o %s --subspaces 4 --levels 1 --no-range",
                                   tu_cli(), ds, model), NULL), 0);
    for (int bad = 0; bad < 4; bad += 3) { /* the first image fails, or the last */
        snprintf(out, sizeof out, "%s/bpv%d", tu_dir, bad);
        assert_int_equal(mkdir(out, 0777), 0);
        assert_int_equal(mkdir(tu_fmt("%s/subspace_%02d.png", out, bad), 0777), 0);
        char *err = NULL;
        assert_int_equal(tu_run(tu_fmt("%s synthesise -q %s --size 64x48 --preview "
                                       "--backend cpu -o %s", tu_cli(), model, out), &err), 1);
        assert_non_null(strstr(err, tu_fmt("subspace_%02d.png", bad)));
        free(err);
        assert_int_equal(count_entries(out), 1);
        assert_false(has_tmp_entry(tu_dir));
    }
    /* a write that fails on the writer thread (files limited to 50 KiB:
     * the first image's EXR already fails) while the next image is being
     * synthesised: the run stops naming that file, nothing is left */
    snprintf(out, sizeof out, "%s/bfs", tu_dir);
    char *err = NULL;
    /* (no `trap '' XFSZ`: btfcar ignores SIGXFSZ itself, so
     * the write fails with EFBIG and the run reports it in one line) */
    assert_int_equal(tu_run(tu_fmt("(ulimit -f 100; exec %s synthesise -q %s "
                                   "--size 256x256 --backend cpu -o %s)", tu_cli(), model, out),
                            &err), 1);
    print_message("%s", err);
    /* the file as the user will look for it: under the output, not under
     * the temporary folder */
    assert_non_null(strstr(err, tu_fmt("%s/subspace_00.exr", out)));
    assert_null(strstr(err, ".btfcar-tmp-"));
    assert_null(strstr(err, "b.btfcar:")); /* the output's error, not the model's */
    free(err);
    assert_int_equal(access(out, F_OK), -1);
    assert_false(has_tmp_entry(tu_dir));
    /* one file past the limit: a model (its temporary file) */
    char m2[4096];
    snprintf(m2, sizeof m2, "%s/big.btfcar", tu_dir);
    err = NULL;
    assert_int_equal(tu_run(tu_fmt("(ulimit -f 8; exec %s analyse -q %s -o %s --subspaces 4 "
                                   "--levels 1)", tu_cli(), ds, m2), &err), 1);
    print_message("%s", err);
    assert_non_null(strstr(err, "big.btfcar"));
    assert_non_null(strstr(err, "too large"));
    assert_int_equal(count_lines(err), 1);
    free(err);
    assert_int_equal(access(m2, F_OK), -1);
    assert_false(has_tmp_entry(tu_dir));
}

/* An output folder given as a symlink to a folder: every command that
 * writes a set fills the folder it names and leaves the link a link
 * (before, the work was done and the final rename failed with
 * "Not a directory"). */
static void symlinked_output_folders(void **state)
{
    (void)state;
    char *root = tu_tmpdir();
    const char *ds = tu_fmt("%s/ds", root);
    const char *model = tu_fmt("%s/m.btfcar", root);
    const char *cmds[] = {
        "%s generate -q --material leather --size 32 --seed 3 %s",
        "%s synthesise -q " /* the model, made below */ "%s --size 16x16 --backend cpu -o %s",
        "%s photostereo -q %s -o %s",
        "%s analyse -q %s --stage segment --subspaces 2 -o %s",
        "%s report -q %s %s -o %s --views 2 --lights 2",
    };
    for (int i = 0; i < 5; i++) {
        char real[4096], link[4096];
        snprintf(real, sizeof real, "%s/real%d", root, i);
        snprintf(link, sizeof link, "%s/link%d", root, i);
        assert_int_equal(mkdir(real, 0777), 0);
        assert_int_equal(symlink(real, link), 0);
        const char *cmd = i == 0   ? tu_fmt(cmds[0], tu_cli(), link)
                          : i == 1 ? tu_fmt(cmds[1], tu_cli(), model, link)
                          : i == 4 ? tu_fmt(cmds[4], tu_cli(), ds, model, link)
                                   : tu_fmt(cmds[i], tu_cli(), ds, link);
        char *err = NULL;
        int rc = tu_run(cmd, &err);
        if (rc)
            print_message("%s: %s", cmd, err ? err : "");
        free(err);
        assert_int_equal(rc, 0);
        struct stat st;
        assert_int_equal(lstat(link, &st), 0);
        assert_true(S_ISLNK(st.st_mode));
        assert_true(count_entries(real) > 0);
        assert_false(has_tmp_entry(root));
        if (i == 0) { /* the generated dataset and its model serve the others */
            assert_int_equal(rename(real, ds), 0);
            assert_int_equal(mkdir(real, 0777), 0);
            assert_int_equal(tu_run(tu_fmt("%s analyse -q %s -o %s --subspaces 2 --levels 1",
                                           tu_cli(), ds, model), NULL), 0);
        }
    }
    tu_rmtree(root);
    free(root);
}

/* Holder mode, run by other_namespace_temporaries_are_kept inside a new PID
 * namespace: a temporary beside DIR/held, its name written to DIR/ready,
 * kept until DIR/stop appears (at most 60 s), then removed. */
static int hold_temporary(const char *dir)
{
    char path[4096], tmp[4096], ready[4096], stop[4096];
    int fd;
    btf_error e = {0};
    snprintf(path, sizeof path, "%s/held", dir);
    snprintf(ready, sizeof ready, "%s/ready", dir);
    snprintf(stop, sizeof stop, "%s/stop", dir);
    if (btf__tmp_create(path, tmp, sizeof tmp, &fd, &e) != 0)
        return 1;
    close(fd);
    if (btf_write_file_atomic(ready, tmp, strlen(tmp), &e) != 0)
        return 1;
    for (int i = 0; i < 6000 && access(stop, F_OK) != 0; i++)
        usleep(10000);
    btf__abort_file(tmp);
    return 0;
}

/* A temporary of a live process in another PID namespace (a container
 * sharing the folder), whose PID no process of ours has: kept, although
 * kill(PID, 0) says ESRCH here: a temporary's name carries the identity of
 * the host's boot and PID namespace, and only a temporary of this identity
 * whose PID is gone is stale. Needs root and unshare(1). */
static void other_namespace_temporaries_are_kept(void **state)
{
    (void)state;
    if (geteuid() != 0 ||
        system("unshare --pid --fork --mount-proc true >/dev/null 2>&1") != 0) {
        print_message("skipped: a PID namespace needs root and unshare(1)\n");
        skip();
    }
    char *root = tu_tmpdir();
    char self[4096];
    ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
    assert_true(n > 0);
    self[n] = '\0';
    long pid = 0; /* a PID no process of this namespace has */
    for (long p = 31001; p < 90000 && !pid; p += 97)
        if (kill((pid_t)p, 0) != 0 && errno == ESRCH)
            pid = p;
    assert_true(pid > 0);
    pid_t child = fork();
    if (child == 0) {
        char cmd[8192];
        snprintf(cmd, sizeof cmd,
                 /* not exec: the shell is PID 1 there; its child gets the PID */
                 "echo %ld > /proc/sys/kernel/ns_last_pid && '%s' --hold-temporary '%s'; "
                 "exit $?",
                 pid - 1, self, root);
        execlp("unshare", "unshare", "--pid", "--fork", "--mount-proc", "sh", "-c", cmd,
               (char *)NULL);
        _exit(127);
    }
    char ready[4096], tmp[4096] = "";
    snprintf(ready, sizeof ready, "%s/ready", root);
    for (int i = 0; i < 2000 && access(ready, F_OK) != 0; i++)
        usleep(10000);
    read_back(ready, tmp, sizeof tmp);
    assert_non_null(strstr(tmp, tu_fmt("-%ld-", pid))); /* the PID it was given */
    assert_true(kill((pid_t)pid, 0) != 0 && errno == ESRCH); /* "dead" seen from here */
    assert_int_equal(btf_remove_stale_temporaries(root), 0);
    assert_int_equal(access(tmp, F_OK), 0);
    tu_write_file(tu_fmt("%s/stop", root), "", 0);
    int status = 0;
    assert_int_equal(waitpid(child, &status, 0), child);
    assert_true(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    assert_int_equal(access(tmp, F_OK), -1); /* its owner removed it */
    tu_rmtree(root);
    free(root);
}

int main(int argc, char **argv)
{
    if (argc == 3 && !strcmp(argv[1], "--hold-temporary"))
        return hold_temporary(argv[2]);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(other_namespace_temporaries_are_kept),
        cmocka_unit_test(planted_symlinks_are_skipped),
        cmocka_unit_test(output_folders_are_whole),
        cmocka_unit_test(stale_temporaries),
        cmocka_unit_test(outputs_checked_first),
        cmocka_unit_test(interrupted_synthesis_leaves_nothing),
        cmocka_unit_test(failed_write_of_a_batch_leaves_nothing),
        cmocka_unit_test(symlinked_output_folders),
    };
    return cmocka_run_group_tests_name("output", tests, tu_setup_dir, tu_teardown_dir);
}
