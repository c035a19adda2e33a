/*
 * check-page.c — opens an HTML page in headless Chromium (Debian's
 * /usr/bin/chromium) and fails when the page does not load cleanly; takes a
 * screenshot. The browser test of `btfcar report` and anyone who
 * wants to see a page as a reader would.
 *
 *   build/check-page [--size WxH] [--timeout S] PAGE.html [SCREENSHOT.png]
 *
 * Exit status: 0 the page is clean (and the screenshot was written);
 * 1 the page has problems, one line each on stderr; 2 usage error;
 * 3 the browser could not be run, crashed or timed out (no verdict).
 *
 * How: Chromium is driven over the DevTools protocol on a pipe
 * (--remote-debugging-pipe: commands in on fd 3, answers and events out on
 * fd 4, each a JSON text ended by a NUL byte), so the verdict comes from the
 * browser's own events, not from its log lines:
 *  - Page.navigate's errorText: the page itself did not load;
 *  - Runtime.consoleAPICalled of type error, warning or assert, and
 *    Runtime.exceptionThrown (an uncaught script error);
 *  - Log.entryAdded of level error or warning (what the browser itself
 *    reports to the console: a resource that failed to load, a blocked
 *    request, a deprecation);
 *  - Network.loadingFailed: any resource (image, style sheet, font, frame)
 *    that failed, a missing file included; the network is switched off
 *    (Network.emulateNetworkConditions offline), so a page that reaches for
 *    the network fails too;
 *  - after the load event, every <img> (PNG, SVG, any format) must be
 *    complete with naturalWidth > 0: this catches a file that is there but
 *    does not decode (a broken PNG, an SVG that is not well-formed XML),
 *    which raises no console message. Lazy images are made eager first.
 * The screenshot is Page.captureScreenshot of the viewport (--size,
 * default 1280x900) as PNG.
 *
 * The browser runs with a fresh --user-data-dir in a temporary folder
 * (removed at the end), --headless --disable-gpu, --no-sandbox (needed as
 * root, as CI runs), no first-run, extensions, sync or background
 * networking; stdin is /dev/null and its own log goes to a file that is
 * shown only when it fails to start. A deadline (--timeout, default 30 s,
 * for the whole run) kills its process group, so a test can never hang.
 * $BTF_CHROMIUM names another browser binary (default /usr/bin/chromium).
 *
 * Not part of the library: a tool, built as build/check-page by `make`.
 */
#ifndef _DEFAULT_SOURCE
#define _DEFAULT_SOURCE
#endif
#define _XOPEN_SOURCE 700 /* nftw */
#include <cjson/cJSON.h>

#include <errno.h>
#include <fcntl.h>
#include <ftw.h>
#include <limits.h>
#include <poll.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

enum { ST_OK = 0, ST_PROBLEMS = 1, ST_USAGE = 2, ST_BROWSER = 3 };

typedef struct req_url {
    char *id, *url;
} req_url;

typedef struct cdp {
    int wfd, rfd;
    pid_t pid;
    double deadline;
    int next_id;
    char *session;          /* the page's session id */
    char *buf;              /* bytes read and not yet split */
    size_t len, cap;
    int loaded;             /* Page.loadEventFired seen */
    int problems;
    int crashed;
    req_url *reqs;          /* request id -> URL, for loadingFailed */
    int nreqs, capreqs;
} cdp;

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + (double)t.tv_nsec * 1e-9;
}

static void problem(cdp *c, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("check-page: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
    c->problems++;
}

static int write_all(int fd, const char *p, size_t n)
{
    while (n > 0) {
        ssize_t w = write(fd, p, n);
        if (w < 0 && errno == EINTR)
            continue;
        if (w <= 0)
            return -1;
        p += w;
        n -= (size_t)w;
    }
    return 0;
}

/* Sends {"id":N,"method":M,"params":P[,"sessionId":S]}\0; returns N or -1. */
static int send_cmd(cdp *c, const char *method, cJSON *params, int to_page)
{
    cJSON *m = cJSON_CreateObject();
    int id = ++c->next_id;
    cJSON_AddNumberToObject(m, "id", id);
    cJSON_AddStringToObject(m, "method", method);
    cJSON_AddItemToObject(m, "params", params ? params : cJSON_CreateObject());
    if (to_page && c->session)
        cJSON_AddStringToObject(m, "sessionId", c->session);
    char *text = cJSON_PrintUnformatted(m);
    cJSON_Delete(m);
    if (!text)
        return -1;
    int rc = write_all(c->wfd, text, strlen(text) + 1); /* with the NUL */
    free(text);
    return rc ? -1 : id;
}

static const char *str_at(const cJSON *o, const char *name)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, name);
    return cJSON_IsString(v) ? v->valuestring : NULL;
}

static const char *nz(const char *s)
{
    return s ? s : "";
}

/* The text of a console call: its arguments' values or descriptions. */
static void console_text(const cJSON *args, char *out, size_t n)
{
    out[0] = '\0';
    const cJSON *a;
    size_t len = 0;
    cJSON_ArrayForEach(a, args) {
        const char *s = str_at(a, "value");
        char num[64];
        if (!s)
            s = str_at(a, "description");
        if (!s && cJSON_IsNumber(cJSON_GetObjectItemCaseSensitive(a, "value"))) {
            snprintf(num, sizeof num, "%g", cJSON_GetObjectItemCaseSensitive(a, "value")->valuedouble);
            s = num;
        }
        if (!s)
            s = nz(str_at(a, "type"));
        int w = snprintf(out + len, n - len, "%s%s", len ? " " : "", s);
        if (w < 0 || (size_t)w >= n - len)
            break;
        len += (size_t)w;
    }
}

static void remember_request(cdp *c, const char *id, const char *url)
{
    if (!id || !url)
        return;
    if (c->nreqs == c->capreqs) {
        int cap = c->capreqs ? 2 * c->capreqs : 64;
        req_url *r = realloc(c->reqs, (size_t)cap * sizeof *r);
        if (!r)
            return;
        c->reqs = r;
        c->capreqs = cap;
    }
    c->reqs[c->nreqs].id = strdup(id);
    c->reqs[c->nreqs].url = strdup(url);
    c->nreqs++;
}

static const char *request_url(const cdp *c, const char *id)
{
    for (int i = c->nreqs - 1; id && i >= 0; i--)
        if (c->reqs[i].id && !strcmp(c->reqs[i].id, id))
            return c->reqs[i].url;
    return "(unknown URL)";
}

static void on_event(cdp *c, const char *method, const cJSON *p)
{
    if (!strcmp(method, "Page.loadEventFired")) {
        c->loaded = 1;
    } else if (!strcmp(method, "Runtime.consoleAPICalled")) {
        const char *type = nz(str_at(p, "type"));
        if (!strcmp(type, "error") || !strcmp(type, "warning") || !strcmp(type, "assert")) {
            char text[1024];
            console_text(cJSON_GetObjectItemCaseSensitive(p, "args"), text, sizeof text);
            problem(c, "console %s: %s", type, text);
        }
    } else if (!strcmp(method, "Runtime.exceptionThrown")) {
        const cJSON *d = cJSON_GetObjectItemCaseSensitive(p, "exceptionDetails");
        const cJSON *ex = cJSON_GetObjectItemCaseSensitive(d, "exception");
        const char *desc = str_at(ex, "description");
        problem(c, "uncaught exception: %s (%s:%d)", desc ? desc : nz(str_at(d, "text")),
                nz(str_at(d, "url")),
                cJSON_GetObjectItemCaseSensitive(d, "lineNumber")
                    ? cJSON_GetObjectItemCaseSensitive(d, "lineNumber")->valueint + 1 : 0);
    } else if (!strcmp(method, "Log.entryAdded")) {
        const cJSON *e = cJSON_GetObjectItemCaseSensitive(p, "entry");
        const char *level = nz(str_at(e, "level"));
        if (!strcmp(level, "error") || !strcmp(level, "warning"))
            problem(c, "console %s (%s): %s%s%s", level, nz(str_at(e, "source")),
                    nz(str_at(e, "text")), str_at(e, "url") ? " " : "", nz(str_at(e, "url")));
    } else if (!strcmp(method, "Network.requestWillBeSent")) {
        const cJSON *r = cJSON_GetObjectItemCaseSensitive(p, "request");
        remember_request(c, str_at(p, "requestId"), str_at(r, "url"));
    } else if (!strcmp(method, "Network.loadingFailed")) {
        const cJSON *canceled = cJSON_GetObjectItemCaseSensitive(p, "canceled");
        if (!cJSON_IsTrue(canceled))
            problem(c, "failed to load %s: %s", request_url(c, str_at(p, "requestId")),
                    nz(str_at(p, "errorText")));
    } else if (!strcmp(method, "Inspector.targetCrashed") || !strcmp(method, "Target.targetCrashed")) {
        c->crashed = 1;
    }
}

/* Reads and dispatches messages until the answer to id arrives (returned,
 * the caller deletes it), or, with id 0, until `until` (seconds, monotonic).
 * NULL on timeout, a closed pipe or a crash. */
static cJSON *pump(cdp *c, int id, double until)
{
    for (;;) {
        char *nul;
        while (c->len && (nul = memchr(c->buf, '\0', c->len))) {
            size_t n = (size_t)(nul - c->buf) + 1;
            cJSON *m = cJSON_Parse(c->buf);
            memmove(c->buf, c->buf + n, c->len - n);
            c->len -= n;
            if (!m)
                continue;
            const cJSON *mid = cJSON_GetObjectItemCaseSensitive(m, "id");
            const char *method = str_at(m, "method");
            if (cJSON_IsNumber(mid) && id && mid->valueint == id)
                return m;
            if (method)
                on_event(c, method, cJSON_GetObjectItemCaseSensitive(m, "params"));
            cJSON_Delete(m);
        }
        if (c->crashed)
            return NULL;
        double end = id ? c->deadline : (until < c->deadline ? until : c->deadline);
        double left = end - now();
        if (left <= 0)
            return NULL;
        struct pollfd pf = {.fd = c->rfd, .events = POLLIN};
        int r = poll(&pf, 1, (int)(left * 1000) + 1);
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0)
            continue; /* the loop re-checks the time */
        if (c->cap - c->len < 65536) {
            size_t cap = c->cap ? 2 * c->cap : 1 << 20;
            char *b = realloc(c->buf, cap);
            if (!b)
                return NULL;
            c->buf = b;
            c->cap = cap;
        }
        ssize_t got = read(c->rfd, c->buf + c->len, c->cap - c->len - 1);
        if (got < 0 && errno == EINTR)
            continue;
        if (got <= 0)
            return NULL; /* the browser closed the pipe */
        c->len += (size_t)got;
    }
}

/* A command and its answer's "result" (the whole answer in *whole, which
 * the caller deletes); NULL with a message on an error answer or none. */
static const cJSON *call(cdp *c, const char *method, cJSON *params, int to_page, cJSON **whole)
{
    *whole = NULL;
    int id = send_cmd(c, method, params, to_page);
    if (id < 0) {
        fprintf(stderr, "check-page: cannot send %s to the browser\n", method);
        return NULL;
    }
    cJSON *m = pump(c, id, 0);
    if (!m) {
        fprintf(stderr, "check-page: no answer to %s from the browser (%s)\n", method,
                c->crashed ? "the page crashed" : now() >= c->deadline ? "timed out" : "pipe closed");
        return NULL;
    }
    *whole = m;
    const cJSON *e = cJSON_GetObjectItemCaseSensitive(m, "error");
    if (e) {
        fprintf(stderr, "check-page: %s failed: %s\n", method, nz(str_at(e, "message")));
        return NULL;
    }
    return cJSON_GetObjectItemCaseSensitive(m, "result");
}

/* A command whose answer is only checked for success. */
static int call_ok(cdp *c, const char *method, cJSON *params)
{
    cJSON *m;
    int ok = call(c, method, params, 1, &m) != NULL;
    cJSON_Delete(m);
    return ok;
}

static int b64val(int ch)
{
    if (ch >= 'A' && ch <= 'Z')
        return ch - 'A';
    if (ch >= 'a' && ch <= 'z')
        return ch - 'a' + 26;
    if (ch >= '0' && ch <= '9')
        return ch - '0' + 52;
    if (ch == '+')
        return 62;
    if (ch == '/')
        return 63;
    return -1;
}

/* Decodes base64 into a new buffer; *n its length. */
static unsigned char *b64decode(const char *s, size_t *n)
{
    size_t len = strlen(s);
    unsigned char *out = malloc(len / 4 * 3 + 3);
    if (!out)
        return NULL;
    unsigned acc = 0;
    int bits = 0;
    size_t k = 0;
    for (size_t i = 0; i < len; i++) {
        int v = b64val((unsigned char)s[i]);
        if (v < 0)
            continue; /* '=' and line breaks */
        acc = (acc << 6) | (unsigned)v;
        bits += 6;
        if (bits >= 8) {
            bits -= 8;
            out[k++] = (unsigned char)(acc >> bits);
            acc &= (1u << bits) - 1;
        }
    }
    *n = k;
    return out;
}

/* Writes the file through a temporary beside it, renamed into place. */
static int write_file(const char *path, const unsigned char *data, size_t n)
{
    char tmp[PATH_MAX];
    if (snprintf(tmp, sizeof tmp, "%s.check-page-tmp-%ld", path, (long)getpid()) >= (int)sizeof tmp)
        return -1;
    int fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
    if (fd < 0)
        return -1;
    int bad = write_all(fd, (const char *)data, n) || fsync(fd);
    bad |= close(fd) != 0;
    if (bad || rename(tmp, path) != 0) {
        unlink(tmp);
        return -1;
    }
    return 0;
}

static int rm_entry(const char *path, const struct stat *st, int flag, struct FTW *ftw)
{
    (void)st, (void)flag, (void)ftw;
    remove(path);
    return 0;
}

/* file:///abs/path with every byte outside [A-Za-z0-9/._~-] percent-encoded. */
static char *file_url(const char *path)
{
    char *abs = realpath(path, NULL);
    if (!abs)
        return NULL;
    size_t n = strlen(abs);
    char *u = malloc(8 + 3 * n + 1);
    if (!u) {
        free(abs);
        return NULL;
    }
    char *p = u + sprintf(u, "file://");
    for (size_t i = 0; i < n; i++) {
        unsigned char ch = (unsigned char)abs[i];
        if ((ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || (ch >= '0' && ch <= '9') ||
            strchr("/._~-", ch))
            *p++ = (char)ch;
        else
            p += sprintf(p, "%%%02X", ch);
    }
    *p = '\0';
    free(abs);
    return u;
}

/* The images' check, run in the page after its load event: every <img>
 * complete with a natural width (lazy ones made eager and awaited first).
 * Its value: a JSON text {"images": N, "bad": [src...]}. */
static const char IMAGE_CHECK[] =
    "(async () => {"
    "  const imgs = Array.from(document.images);"
    "  for (const i of imgs) if (i.loading === 'lazy') i.loading = 'eager';"
    "  await Promise.all(imgs.map(i => i.complete ? null :"
    "    new Promise(r => { i.addEventListener('load', r); i.addEventListener('error', r); })));"
    "  const bad = imgs.filter(i => !(i.complete && i.naturalWidth > 0))"
    "                  .map(i => i.getAttribute('src') || i.currentSrc || '(no src)');"
    "  return JSON.stringify({images: imgs.length, bad: bad, ready: document.readyState});"
    "})()";

static void usage(void)
{
    fputs("usage: check-page [--size WxH] [--timeout S] PAGE.html [SCREENSHOT.png]\n"
          "  Opens PAGE.html in headless Chromium ($BTF_CHROMIUM, default /usr/bin/chromium);\n"
          "  exit 0 clean, 1 problems (listed), 2 usage, 3 browser failure or timeout.\n",
          stderr);
}

int main(int argc, char **argv)
{
    int width = 1280, height = 900;
    double timeout = 30;
    const char *page = NULL, *shot = NULL;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--size") && i + 1 < argc) {
            if (sscanf(argv[++i], "%dx%d", &width, &height) != 2 || width < 16 || height < 16 ||
                width > 8192 || height > 8192) {
                fprintf(stderr, "check-page: --size %s: expected WxH, 16..8192 each\n", argv[i]);
                return ST_USAGE;
            }
        } else if (!strcmp(argv[i], "--timeout") && i + 1 < argc) {
            timeout = atof(argv[++i]);
            if (!(timeout > 0 && timeout <= 600)) {
                fprintf(stderr, "check-page: --timeout %s: expected seconds in (0, 600]\n", argv[i]);
                return ST_USAGE;
            }
        } else if (!strcmp(argv[i], "-h") || !strcmp(argv[i], "--help")) {
            usage();
            return ST_OK;
        } else if (argv[i][0] == '-' && argv[i][1]) {
            usage();
            return ST_USAGE;
        } else if (!page) {
            page = argv[i];
        } else if (!shot) {
            shot = argv[i];
        } else {
            usage();
            return ST_USAGE;
        }
    }
    if (!page) {
        usage();
        return ST_USAGE;
    }
    struct stat st;
    if (stat(page, &st) != 0 || !S_ISREG(st.st_mode)) {
        fprintf(stderr, "check-page: %s: the page is not a readable file\n", page);
        return ST_PROBLEMS;
    }
    const char *browser = getenv("BTF_CHROMIUM");
    if (!browser || !*browser)
        browser = "/usr/bin/chromium";
    if (access(browser, X_OK) != 0) {
        fprintf(stderr, "check-page: %s: no browser there (Debian's chromium; `make deps` installs it)\n",
                browser);
        return ST_BROWSER;
    }
    char *url = file_url(page);
    if (!url) {
        fprintf(stderr, "check-page: %s: %s\n", page, strerror(errno));
        return ST_PROBLEMS;
    }

    const char *tmpbase = getenv("TMPDIR");
    char dir[PATH_MAX], profile[PATH_MAX + 64], logpath[PATH_MAX + 64];
    snprintf(dir, sizeof dir, "%s/btfcar-check-page-XXXXXX", tmpbase && *tmpbase ? tmpbase : "/tmp");
    if (!mkdtemp(dir)) {
        fprintf(stderr, "check-page: cannot make a temporary folder %s: %s\n", dir, strerror(errno));
        free(url);
        return ST_BROWSER;
    }
    snprintf(profile, sizeof profile, "--user-data-dir=%s/profile", dir);
    snprintf(logpath, sizeof logpath, "%s/chromium.log", dir);

    int to_browser[2], from_browser[2];
    if (pipe(to_browser) || pipe(from_browser)) {
        fprintf(stderr, "check-page: pipe: %s\n", strerror(errno));
        free(url);
        return ST_BROWSER;
    }
    signal(SIGPIPE, SIG_IGN);
    pid_t pid = fork();
    if (pid < 0) {
        fprintf(stderr, "check-page: fork: %s\n", strerror(errno));
        free(url);
        return ST_BROWSER;
    }
    if (pid == 0) {
        setpgid(0, 0);
        int in = open("/dev/null", O_RDONLY), log = open(logpath, O_WRONLY | O_CREAT | O_TRUNC, 0600);
        if (in < 0 || log < 0)
            _exit(127);
        /* fds 3 and 4 may be taken by the pipes themselves: lift them first. */
        int r = fcntl(to_browser[0], F_DUPFD, 10), w = fcntl(from_browser[1], F_DUPFD, 10);
        if (r < 0 || w < 0 || dup2(in, 0) < 0 || dup2(log, 1) < 0 || dup2(log, 2) < 0 ||
            dup2(r, 3) < 0 || dup2(w, 4) < 0)
            _exit(127);
        for (int fd = 5; fd < 1024; fd++)
            close(fd);
        signal(SIGPIPE, SIG_DFL);
        char *args[] = {(char *)browser,
                        "--headless",
                        "--no-sandbox",
                        "--disable-gpu",
                        "--remote-debugging-pipe",
                        profile,
                        "--no-first-run",
                        "--no-default-browser-check",
                        "--disable-extensions",
                        "--disable-sync",
                        "--disable-background-networking",
                        "--disable-component-update",
                        "--disable-default-apps",
                        "--disable-breakpad",
                        "--disable-crash-reporter",
                        "--metrics-recording-only",
                        "--mute-audio",
                        "--hide-scrollbars",
                        "--no-proxy-server",
                        "--host-resolver-rules=MAP * ~NOTFOUND",
                        "about:blank",
                        NULL};
        execv(browser, args);
        _exit(127);
    }
    setpgid(pid, pid);
    close(to_browser[0]);
    close(from_browser[1]);

    cdp c = {.wfd = to_browser[1], .rfd = from_browser[0], .pid = pid, .deadline = now() + timeout};
    int status = ST_BROWSER;
    cJSON *m = NULL;
    const cJSON *res;

    /* A page target of its own, attached in flat mode (one pipe, session ids). */
    cJSON *p = cJSON_CreateObject();
    cJSON_AddStringToObject(p, "url", "about:blank");
    res = call(&c, "Target.createTarget", p, 0, &m);
    const char *target = res ? str_at(res, "targetId") : NULL;
    if (!target)
        goto done;
    p = cJSON_CreateObject();
    cJSON_AddStringToObject(p, "targetId", target);
    cJSON_AddBoolToObject(p, "flatten", 1);
    cJSON_Delete(m);
    res = call(&c, "Target.attachToTarget", p, 0, &m);
    if (!res || !str_at(res, "sessionId"))
        goto done;
    c.session = strdup(str_at(res, "sessionId"));
    cJSON_Delete(m);
    m = NULL;

    if (!call_ok(&c, "Page.enable", NULL) || !call_ok(&c, "Runtime.enable", NULL) ||
        !call_ok(&c, "Log.enable", NULL) || !call_ok(&c, "Network.enable", NULL))
        goto done;
    p = cJSON_CreateObject();
    cJSON_AddBoolToObject(p, "offline", 1);
    cJSON_AddNumberToObject(p, "latency", 0);
    cJSON_AddNumberToObject(p, "downloadThroughput", -1);
    cJSON_AddNumberToObject(p, "uploadThroughput", -1);
    if (!call_ok(&c, "Network.emulateNetworkConditions", p))
        goto done;
    p = cJSON_CreateObject();
    cJSON_AddNumberToObject(p, "width", width);
    cJSON_AddNumberToObject(p, "height", height);
    cJSON_AddNumberToObject(p, "deviceScaleFactor", 1);
    cJSON_AddBoolToObject(p, "mobile", 0);
    if (!call_ok(&c, "Emulation.setDeviceMetricsOverride", p))
        goto done;

    c.loaded = 0;
    p = cJSON_CreateObject();
    cJSON_AddStringToObject(p, "url", url);
    res = call(&c, "Page.navigate", p, 1, &m);
    if (!res)
        goto done;
    if (str_at(res, "errorText")) {
        problem(&c, "%s did not load: %s", page, str_at(res, "errorText"));
        status = ST_PROBLEMS;
        goto done;
    }
    cJSON_Delete(m);
    m = NULL;
    while (!c.loaded && now() < c.deadline && !c.crashed)
        if (!pump(&c, 0, now() + 0.05) && !c.loaded && (c.crashed || now() >= c.deadline))
            break;
    if (!c.loaded) {
        fprintf(stderr, "check-page: %s: no load event (%s)\n", page,
                c.crashed ? "the page crashed" : "timed out");
        goto done;
    }

    p = cJSON_CreateObject();
    cJSON_AddStringToObject(p, "expression", IMAGE_CHECK);
    cJSON_AddBoolToObject(p, "awaitPromise", 1);
    cJSON_AddBoolToObject(p, "returnByValue", 1);
    res = call(&c, "Runtime.evaluate", p, 1, &m);
    const cJSON *val = res ? cJSON_GetObjectItemCaseSensitive(res, "result") : NULL;
    const char *json = val ? str_at(val, "value") : NULL;
    cJSON *verdict = json ? cJSON_Parse(json) : NULL;
    if (!verdict) {
        fprintf(stderr, "check-page: the image check did not run in %s\n", page);
        goto done;
    }
    const cJSON *bad, *b;
    bad = cJSON_GetObjectItemCaseSensitive(verdict, "bad");
    cJSON_ArrayForEach(b, bad)
        problem(&c, "image not shown: %s (missing, or not a decodable image)",
                cJSON_IsString(b) ? b->valuestring : "?");
    cJSON_Delete(verdict);
    cJSON_Delete(m);
    m = NULL;

    /* Late messages (a timer's console.error, a decode error) get a moment. */
    pump(&c, 0, now() + 0.3);
    if (c.crashed)
        goto done;

    if (shot) {
        p = cJSON_CreateObject();
        cJSON_AddStringToObject(p, "format", "png");
        res = call(&c, "Page.captureScreenshot", p, 1, &m);
        const char *data = res ? str_at(res, "data") : NULL;
        if (!data)
            goto done;
        size_t n;
        unsigned char *png = b64decode(data, &n);
        if (!png || n < 8 || memcmp(png, "\x89PNG", 4) || write_file(shot, png, n)) {
            fprintf(stderr, "check-page: %s: cannot write the screenshot\n", shot);
            free(png);
            goto done;
        }
        free(png);
    }
    status = c.problems ? ST_PROBLEMS : ST_OK;

done:
    cJSON_Delete(m);
    if (status == ST_BROWSER && c.problems == 0) {
        /* Show the browser's own last words: why it did not start. */
        FILE *f = fopen(logpath, "r");
        char line[1024];
        int k = 0;
        while (f && fgets(line, sizeof line, f) && k < 40)
            if (!strstr(line, "dbus") && !strstr(line, "unexpected operator"))
                fprintf(stderr, "chromium: %s", line), k++;
        if (f)
            fclose(f);
    }
    if (status == ST_BROWSER && c.problems)
        status = ST_PROBLEMS; /* problems found before the failure are the verdict */
    /* Close the browser, then make sure its whole process group is gone. */
    send_cmd(&c, "Browser.close", NULL, 0);
    close(c.wfd);
    int ws;
    double end = now() + 3;
    pid_t w;
    while ((w = waitpid(pid, &ws, WNOHANG)) == 0 && now() < end)
        usleep(20000);
    if (w == 0) {
        kill(-pid, SIGKILL);
        waitpid(pid, &ws, 0);
    } else {
        kill(-pid, SIGKILL); /* helpers left in the group, if any */
    }
    close(c.rfd);
    nftw(dir, rm_entry, 16, FTW_DEPTH | FTW_PHYS);
    for (int i = 0; i < c.nreqs; i++)
        free(c.reqs[i].id), free(c.reqs[i].url);
    free(c.reqs);
    free(c.session);
    free(c.buf);
    free(url);
    return status;
}
