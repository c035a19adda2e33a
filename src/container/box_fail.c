/*
 * box_fail.c — the one-line messages of the model files (docs/design.md,
 * "Conventions"): every failure of MODEL.btfcar and of the
 * reflectance-field file names the file or buffer first, "NAME: what is
 * wrong (expected ...)" (docs/model-format.md, "Validation").
 */
#include "container/container.h"

#include <stdarg.h>
#include <stdio.h>

btf_status btf__box_fail(btf_error *err, btf_status code, const char *name, const char *fmt, ...)
{
    char msg[sizeof err->msg];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return btf__fail(err, code, "%s: %s", name, msg);
}
