/*
 * presets.c — named points of the speed/accuracy trade for
 * `btfcar analyse --preset` (docs/report.md, "Presets"), chosen
 * from the Pareto fronts that the sweep (src/report/sweep.c) measured on
 * the three generated materials; the measurements behind each choice are
 * in docs/report.md.
 */
#include "core/core.h"
#include "car/car.h"

#include <string.h>

/* {subspaces, levels, neighbours}, 0: auto; the measured choice (format
 * 1.5 with the structure layer, 2026-12-04): docs/report.md. */
#define PRESET_FAST 2, 1, 4     /* on the bytes-vs-distance front of all three materials */
#define PRESET_BALANCED 4, 1, 4 /* on the bytes-vs-distance front of all three materials */
#define PRESET_ACCURATE 8, 0, 0 /* within 1.3 % of each material's closest of the 64 */

typedef struct preset {
    const char *name;
    int subspaces, levels, neighbours; /* 0: the automatic choice */
} preset;

static const preset PRESETS[] = {
    {"fast", PRESET_FAST},
    {"balanced", PRESET_BALANCED},
    {"accurate", PRESET_ACCURATE},
};

const char *const *btf_analyse_preset_names(void)
{
    static const char *const names[] = {"fast", "balanced", "accurate", NULL};
    return names;
}

btf_status btf_analyse_preset(const char *name, btf_analyse_opts *o, btf_error *err)
{
    if (!o)
        return btf__fail(err, BTF_E_ARG, "preset: no options given");
    for (size_t i = 0; name && i < sizeof PRESETS / sizeof PRESETS[0]; i++) {
        if (strcmp(name, PRESETS[i].name))
            continue;
        const preset *p = &PRESETS[i];
        o->segment.subspaces = p->subspaces;
        o->fit.levels = p->levels;
        o->fit.car.n_fixed = 0;
        if (p->neighbours > 0) {
            btf_offset fam[BTF_CAR_MAX_NEIGHBOURS];
            btf__car_candidate_offsets(fam);
            memcpy(o->fit.car.fixed, fam, (size_t)p->neighbours * sizeof fam[0]);
            o->fit.car.n_fixed = p->neighbours;
        }
        return BTF_OK;
    }
    return btf__fail(err, BTF_E_ARG, "preset '%s': expected fast, balanced or accurate",
                     name ? name : "(null)");
}
