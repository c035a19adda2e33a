/* common.c — what every command shares (declared in cli.h): error and usage
 * messages, number and size parsing, the progress bar, byte counts as text. */
#include "cli.h"
#include "core/describe.h"

#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

int cli_error(const cli_ctx *c, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, "btfcar %s: ", c->cmd);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
    return 1;
}

int cli_check_output(const cli_ctx *c, const char *path, btf_output_kind kind)
{
    btf_error err = {0};
    if (btf_output_check(path, kind, &err) != 0)
        return cli_lib_error(c, &err);
    char parent[4096];
    snprintf(parent, sizeof parent, "%s", path);
    size_t len = strlen(parent);
    while (len > 1 && parent[len - 1] == '/')
        parent[--len] = '\0';
    char *slash = strrchr(parent, '/');
    if (!slash)
        snprintf(parent, sizeof parent, ".");
    else
        slash[slash == parent] = '\0'; /* "/x" keeps "/" */
    btf_remove_stale_temporaries(parent);
    if (kind == BTF_OUTPUT_FOLDER)
        btf_remove_stale_temporaries(path);
    return 0;
}

static void on_signal(int sig)
{
    btf_remove_temporaries();
    _exit(128 + sig);
}

void cli_install_signal_cleanup(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigfillset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGHUP, &sa, NULL);
    /* Past `ulimit -f` a write fails with EFBIG instead of killing the
     * process: the writer then reports it in one line and removes its
     * temporary, as for a full disk. */
    signal(SIGXFSZ, SIG_IGN);
}

int cli_set_error(btf_error *err, int code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err->msg, sizeof err->msg, fmt, ap);
    va_end(ap);
    err->code = code;
    return code;
}

int cli_lib_error(const cli_ctx *c, const btf_error *err)
{
    cli_progress_done();
    return cli_error(c, "%s", err->msg[0] ? err->msg : btf_status_name(err->code));
}

int cli_usage_error(const cli_ctx *c, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, "btfcar %s: ", c->cmd);
    vfprintf(stderr, fmt, ap);
    fprintf(stderr, " (see 'btfcar %s --help')\n", c->cmd);
    va_end(ap);
    return 2;
}

int cli_plain_number(const char *s, int allow_minus)
{
    if (allow_minus && *s == '-')
        s++;
    return (*s >= '0' && *s <= '9') || (*s == '.' && s[1] >= '0' && s[1] <= '9');
}

int cli_parse_int(const char *s, long lo, long hi, long *out)
{
    char *end;
    if (!cli_plain_number(s, 1) || *s == '.' || (*s == '-' && s[1] == '.'))
        return -1;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (end == s || *end || errno || v < lo || v > hi)
        return -1;
    *out = v;
    return 0;
}

int cli_parse_u64(const char *s, uint64_t *out)
{
    char *end;
    errno = 0;
    if (!cli_plain_number(s, 0) || *s == '.')
        return -1;
    unsigned long long v = strtoull(s, &end, 10); /* "010" is ten, not eight */
    if (end == s || *end || errno)
        return -1;
    *out = (uint64_t)v;
    return 0;
}

int cli_parse_size(const char *s, int *w, int *h)
{
    char buf[64];
    const char *x = strchr(s, 'x');
    if (!x || (size_t)(x - s) >= sizeof buf)
        return -1;
    memcpy(buf, s, (size_t)(x - s));
    buf[x - s] = '\0';
    long a, b;
    if (cli_parse_int(buf, 1, 1L << 30, &a) || cli_parse_int(x + 1, 1, 1L << 30, &b))
        return -1;
    *w = (int)a;
    *h = (int)b;
    return 0;
}

static int progress_drawn;

void cli_progress(void *user, double fraction, const char *what)
{
    (void)user;
    int width = 30, fill = (int)(fraction * width + 0.5);
    if (fill > width)
        fill = width;
    fprintf(stderr, "\r%-22s [", what);
    for (int i = 0; i < width; i++)
        fputc(i < fill ? '#' : '.', stderr);
    fprintf(stderr, "] %3d%%", (int)(fraction * 100.0 + 0.5));
    fflush(stderr);
    progress_drawn = 1;
}

btf_progress_fn cli_progress_fn(const cli_ctx *c)
{
    return (!c->quiet && isatty(2)) ? cli_progress : NULL;
}

void cli_progress_done(void)
{
    if (progress_drawn)
        fputc('\n', stderr);
    progress_drawn = 0;
}

void cli_format_bytes(uint64_t bytes, char *buf, size_t n)
{
    const char *unit[] = {"B", "KB", "MB", "GB", "TB"};
    double v = (double)bytes;
    int u = 0;
    while (v >= 1000.0 && u < 4) {
        v /= 1000.0;
        u++;
    }
    if (u == 0)
        snprintf(buf, n, "%" PRIu64 " B", bytes);
    else
        snprintf(buf, n, "%.1f %s (%" PRIu64 " bytes)", v, unit[u], bytes);
}

double cli_now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

int cli_utf8_length(const char *s)
{
    return txt_utf8_length(s);
}

char *cli_utf8_copy(const char *s)
{
    /* Each bad byte becomes the 3 bytes of U+FFFD at most. */
    char *out = malloc(3 * strlen(s) + 1), *o = out;
    if (!out)
        return NULL;
    while (*s) {
        int n = cli_utf8_length(s);
        if (n == 0) {
            memcpy(o, "\xEF\xBF\xBD", 3);
            o += 3;
            s++;
        } else {
            memcpy(o, s, (size_t)n);
            o += n;
            s += n;
        }
    }
    *o = '\0';
    return out;
}

int cli_parse_decimal(const char *s, int allow_minus, double *out)
{
    char *end;
    /* The plain start rules out spaces, signs, "inf" and "nan"; an 'x'
     * after it would make strtod read "0x10" as hexadecimal. */
    if (!cli_plain_number(s, allow_minus) || strpbrk(s, "xX"))
        return -1;
    errno = 0;
    double v = strtod(s, &end);
    /* strtod flags ERANGE for subnormal results too ("1e-320"): a finite
     * value is kept, only an overflow to infinity is refused. */
    if (end == s || *end || !isfinite(v))
        return -1;
    *out = v;
    return 0;
}

int cli_parse_pair(const char *s, double *a, double *b)
{
    char buf[64];
    const char *comma = strchr(s, ',');
    if (!comma || (size_t)(comma - s) >= sizeof buf)
        return -1;
    memcpy(buf, s, (size_t)(comma - s));
    buf[comma - s] = '\0';
    if (cli_parse_decimal(buf, 0, a) != 0 || cli_parse_decimal(comma + 1, 0, b) != 0)
        return -1;
    return 0;
}

int cli_parse_dir(const char *s, btf_dir *d, char *why, size_t n)
{
    double theta, phi;
    snprintf(why, n, "THETA,PHI in degrees, theta 0..90, phi 0..360");
    if (cli_parse_pair(s, &theta, &phi) != 0 || !(theta >= 0.0 && theta <= 90.0) ||
        !(phi >= 0.0 && phi <= 360.0))
        return -1;
    d->theta = theta;
    d->phi = phi >= 360.0 ? 0.0 : phi;
    return 0;
}

int cli_parse_dir_arg(const char *s, void *dest, char *why, size_t n)
{
    cli_dir_arg *d = dest;
    if (cli_parse_dir(s, &d->dir, why, n) != 0)
        return -1;
    d->given = 1;
    return 0;
}

/* BTF_VK_DEVICE and BTF_VK_VALIDATION into o (*index -1 when unset). */
static int env_gpu_opts(btf_gpu_opts *o, int *index, btf_error *err)
{
    const char *d = getenv("BTF_VK_DEVICE"), *v = getenv("BTF_VK_VALIDATION");
    *index = -1;
    if (d && *d) {
        long n = 0;
        for (const char *c = d; *c; c++) {
            if (*c < '0' || *c > '9' || n > 100000)
                return cli_set_error(err, BTF_E_ARG, "BTF_VK_DEVICE='%s': expected a device "
                                     "index (see btfcar info --devices)", d);
            n = n * 10 + (*c - '0');
        }
        *index = (int)n;
    }
    if (v && *v && strcmp(v, "0") && strcmp(v, "1"))
        return cli_set_error(err, BTF_E_ARG, "BTF_VK_VALIDATION='%s': expected 0 or 1", v);
    o->validation = v && !strcmp(v, "1");
    return 0;
}

btf_gpu *cli_open_gpu(const char *backend, int device, btf_error *err)
{
    return cli_open_gpu_for(backend, device, 0, err);
}

/* auto without a named device: the library's rule over the device list
 * (btf_gpu_auto_device); -1 (the CPU) with the reason in err. */
static int auto_device(uint64_t image_bytes, btf_error *err)
{
    btf_gpu_device *list;
    int n;
    if (btf_gpu_list_devices(&list, &n, err))
        return -1;
    int pick = btf_gpu_auto_device(list, n, image_bytes);
    free(list);
    if (pick < 0)
        cli_set_error(err, BTF_E_UNSUPPORTED, "no real GPU whose memory budget holds %.1f MiB "
                      "images (btfcar info --devices)", image_bytes / 1048576.0);
    return pick;
}

btf_gpu *cli_open_gpu_for(const char *backend, int device, uint64_t image_bytes, btf_error *err)
{
    if (!strcmp(backend, "cpu"))
        return NULL;
    /* A named device is as explicit as --backend gpu: its errors are errors. */
    int explicit_gpu = !strcmp(backend, "gpu") || device >= 0;
    btf_gpu_opts o = btf_gpu_defaults();
    int env_device;
    btf_gpu *g = NULL;
    int rc = env_gpu_opts(&o, &env_device, err), from_env = device < 0 && env_device >= 0;
    if (from_env)
        device = env_device;
    if (rc == 0 && !explicit_gpu && !from_env && (device = auto_device(image_bytes, err)) < 0)
        return NULL;
    o.use_device = device >= 0;
    o.device = device < 0 ? 0 : device;
    o.allow_cpu = explicit_gpu;
    if (rc == 0 && btf_gpu_open(&o, &g, err) != 0 && from_env) {
        char msg[sizeof err->msg];
        snprintf(msg, sizeof msg, "BTF_VK_DEVICE=%d: %s", device, err->msg);
        snprintf(err->msg, sizeof err->msg, "%s", msg);
    }
    return g;
}

int cli_has_suffix(const char *s, const char *suffix)
{
    size_t a = strlen(s), b = strlen(suffix);
    return a >= b && !strcasecmp(s + a - b, suffix);
}

size_t cli_read_head(const char *path, unsigned char *buf, size_t n)
{
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
    if (fd < 0)
        return 0;
    struct stat st;
    ssize_t r = fstat(fd, &st) == 0 && S_ISREG(st.st_mode) ? read(fd, buf, n) : 0;
    close(fd);
    return r > 0 ? (size_t)r : 0;
}

btf_status cli_write_image(const char *path, const btf_image *img, btf_error *err)
{
    if (cli_has_suffix(path, ".exr"))
        return btf_image_write_exr_opts(path, img, NULL, NULL, err);
    return btf_image_write_png(path, img, err);
}
