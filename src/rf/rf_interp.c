/*
 * rf_interp.c — the four closest measured views of a view direction and
 * their weights (Meseth, Müller & Klein 2003, section 5.4): "we choose the
 * closest theta values from the existing measurement data. Next, for each
 * such theta, we determine the closest phi values. These four samples
 * determine the four closest measured view directions [...] The according
 * weights are computed via bilinear interpolation (please note that the
 * measured samples are non-uniformly spread)". The weights sum to 1 (to
 * float rounding) and change continuously with the direction; at a
 * measured view the weight is exactly 1 on that view.
 *
 * The arithmetic is btf_rf_four_views of src/rf/btf_rf_shared.h, in
 * float: the very function the renderers (CPU and GPU) blend with, so that
 * what this call reports is what a render uses. The direction set is ring
 * by ring (theta ascending, phi ascending within a ring), as every
 * btf_dirset is. Above the last ring (theta past 75 in ubo81) and below
 * the first the nearest ring alone is used; a ring of one direction (the
 * pole) gives it both azimuth weights.
 */
#include "rf/rf.h"

void btf__rf_view_weights(const btf_dirset *views, btf_dir view, int idx[4], double w[4])
{
    for (int i = 0; i < 4; i++)
        idx[i] = 0, w[i] = 0.0;
    if (!views || views->count < 1 || !views->dirs)
        return;
    btf_rf_views v = btf_rf_four_views(views, (float)view.theta, (float)view.phi);
    idx[0] = v.i0, idx[1] = v.i1, idx[2] = v.i2, idx[3] = v.i3;
    w[0] = v.w0, w[1] = v.w1, w[2] = v.w2, w[3] = v.w3;
}
