/*
 * pair_file.c — the name of a measured pair's picture in a report folder,
 * shared by the orchestration (which writes it) and the page and JSON
 * writers (which name it), so that the three agree.
 */
#include "report/report_data.h"

#include <stdio.h>

void btf_report_pair_file(const btf_report_data *d, int pair, char *buf, size_t n)
{
    const btf_pair_quality *p = &d->q.pairs[pair];
    snprintf(buf, n, "pair-v%02d-l%02d.png", p->view, p->light);
}
