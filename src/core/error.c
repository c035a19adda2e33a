/*
 * error.c — status names and the one-line error messages every fallible call
 * returns (docs/design.md, "Conventions").
 */
#include "core/core.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

const char *btf_status_name(btf_status status)
{
    switch (status) {
    case BTF_OK: return "ok";
    case BTF_E_ARG: return "invalid argument";
    case BTF_E_IO: return "I/O error";
    case BTF_E_FORMAT: return "bad file format";
    case BTF_E_DATA: return "inconsistent data";
    case BTF_E_NOMEM: return "out of memory";
    case BTF_E_UNSUPPORTED: return "unsupported";
    case BTF_E_NUMERIC: return "numerical failure";
    default: return "unknown error";
    }
}

int btf__fail(btf_error *err, int code, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err->msg, sizeof err->msg, fmt, ap);
        va_end(ap);
        /* Messages are one line: a newline from a file name would break that. */
        for (char *p = err->msg; *p; p++)
            if (*p == '\n' || *p == '\r')
                *p = ' ';
        err->code = code;
    }
    return code;
}

int btf__error_name(btf_error *err, const char *name)
{
    if (!err)
        return BTF_E_NOMEM;
    if (name && strncmp(err->msg, name, strlen(name)) != 0) {
        char m[sizeof err->msg];
        memcpy(m, err->msg, sizeof m);
        btf__fail(err, err->code, "%s: %s", name, m[0] ? m : btf_status_name(err->code));
    }
    return err->code;
}
