/*
 * text.c — the report's text plumbing: a growable buffer that SVG and HTML
 * writers append to freely (an allocation failure is sticky and checked
 * once), and escaping of text for HTML and XML (src/report/report.h).
 */
#include "report/report.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int grow(btf_buf *b, size_t extra)
{
    if (b->failed)
        return -1;
    if (extra > ((size_t)-1) / 2 - b->len) {
        b->failed = 1;
        return -1;
    }
    size_t need = b->len + extra + 1;
    if (need <= b->cap)
        return 0;
    size_t cap = b->cap ? b->cap : 256;
    while (cap < need)
        cap *= 2;
    char *d = realloc(b->data, cap);
    if (!d) {
        b->failed = 1;
        return -1;
    }
    b->data = d;
    b->cap = cap;
    return 0;
}

int btf__buf_put(btf_buf *b, const char *s, size_t n)
{
    if (grow(b, n))
        return -1;
    if (n)
        memcpy(b->data + b->len, s, n);
    b->len += n;
    b->data[b->len] = '\0';
    return 0;
}

int btf__buf_puts(btf_buf *b, const char *s)
{
    return s ? btf__buf_put(b, s, strlen(s)) : 0;
}

int btf__buf_printf(btf_buf *b, const char *fmt, ...)
{
    if (b->failed)
        return -1;
    char small[256];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(small, sizeof small, fmt, ap);
    va_end(ap);
    if (n < 0) {
        b->failed = 1;
        return -1;
    }
    if ((size_t)n < sizeof small)
        return btf__buf_put(b, small, (size_t)n);
    if (grow(b, (size_t)n))
        return -1;
    va_start(ap, fmt);
    vsnprintf(b->data + b->len, (size_t)n + 1, fmt, ap);
    va_end(ap);
    b->len += (size_t)n;
    return 0;
}

/* The length of the valid UTF-8 sequence at s (1..4), or 0 when the bytes
 * there are not one (overlong forms, surrogates and values past U+10FFFF
 * included). */
static int utf8_len(const unsigned char *s)
{
    unsigned c = s[0];
    if (c < 0x80)
        return 1;
    int n;
    unsigned cp;
    if ((c & 0xE0) == 0xC0)
        n = 2, cp = c & 0x1F;
    else if ((c & 0xF0) == 0xE0)
        n = 3, cp = c & 0x0F;
    else if ((c & 0xF8) == 0xF0)
        n = 4, cp = c & 0x07;
    else
        return 0;
    for (int i = 1; i < n; i++) {
        if ((s[i] & 0xC0) != 0x80)
            return 0;
        cp = (cp << 6) | (s[i] & 0x3F);
    }
    static const unsigned min[5] = {0, 0, 0x80, 0x800, 0x10000};
    if (cp < min[n] || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF) ||
        cp == 0xFFFE || cp == 0xFFFF)
        return 0;
    return n;
}

/* Calls put(user, bytes, n) for the escaped form of text, a run at a time. */
typedef int (*put_fn)(void *user, const char *s, size_t n);

static int escape(const char *text, put_fn put, void *user)
{
    static const char bad[] = "\xEF\xBF\xBD"; /* U+FFFD */
    const unsigned char *s = (const unsigned char *)text;
    const unsigned char *run = s;
    while (*s) {
        const char *rep = NULL;
        int n = 1;
        switch (*s) {
        case '&': rep = "&amp;"; break;
        case '<': rep = "&lt;"; break;
        case '>': rep = "&gt;"; break;
        case '"': rep = "&quot;"; break;
        case '\'': rep = "&#39;"; break;
        default:
            if (*s < 0x20 && *s != '\t' && *s != '\n' && *s != '\r')
                rep = bad;
            else if (*s == 0x7F)
                rep = bad;
            else if (*s >= 0x80 && (n = utf8_len(s)) == 0)
                rep = bad, n = 1;
        }
        if (!rep) {
            s += n;
            continue;
        }
        if ((s > run && put(user, (const char *)run, (size_t)(s - run))) ||
            put(user, rep, strlen(rep)))
            return -1;
        s += n;
        run = s;
    }
    return s > run ? put(user, (const char *)run, (size_t)(s - run)) : 0;
}

static int put_buf(void *user, const char *s, size_t n)
{
    return btf__buf_put(user, s, n);
}

static int put_file(void *user, const char *s, size_t n)
{
    return fwrite(s, 1, n, user) == n ? 0 : -1;
}

int btf__buf_html(btf_buf *b, const char *text)
{
    if (b->failed)
        return -1;
    return text ? escape(text, put_buf, b) : 0;
}

int btf__html_fputs(FILE *f, const char *text)
{
    return text ? escape(text, put_file, f) : 0;
}

btf_status btf__buf_check(const btf_buf *b, const char *name, btf_error *err)
{
    if (b->failed)
        return btf__fail(err, BTF_E_NOMEM, "%s: out of memory while composing the text",
                         name ? name : "text");
    return BTF_OK;
}

btf_status btf__buf_write(const btf_buf *b, const char *path, btf_error *err)
{
    btf_status st = btf__buf_check(b, path, err);
    if (st != BTF_OK)
        return st;
    return btf_write_file_atomic(path, b->data ? b->data : "", b->len, err);
}

void btf__buf_free(btf_buf *b)
{
    if (!b)
        return;
    free(b->data);
    b->data = NULL;
    b->len = b->cap = 0;
    b->failed = 0;
}
