/*
 * analyse.h — the analysis's parts (src/analyse/) that other stages and the
 * tests call: one subspace's marginal transfer, and the range stage alone
 * (the sweep shares one range map between analyses). The public entries
 * are btf_analyse and btf_texture_fit (btfcar/analyse.h). Private to the
 * library.
 */
#ifndef BTF_ANALYSE_H
#define BTF_ANALYSE_H

#include "btfcar.h"

/* The marginal transfer of subspace `subspace` of m from its exemplar img
 * (linear RGB, the image the subspace was fitted to): the exemplar's
 * decorrelated quantiles and RGB range, and the mean and standard deviation
 * of each band of a synthesis of the subspace (512 x 512, a fixed seed, no
 * transfer). btf_texture_fit and btf_analyse call it for every subspace. */
btf_status btf__fit_marginals(const btf_image *img, btf_model *m, int subspace, btf_error *err);

/* Stage 2 alone: the range tile of the dataset (photometric stereo, as
 * btf_analyse makes it) into out's range fields; nothing else of out is
 * touched. For work shared between analyses (btf_analyse_opts.range_from). */
btf_status btf__analyse_range(const btf_dataset *ds, const btf_analyse_opts *opts, btf_model *out,
                              btf_error *err);

#endif
