/*
 * rf_quilt.c — the coordinate map of a sampled reflectance-field model
 * (Meseth, Müller & Klein 2003, section 6: the synthesis "does not copy
 * texton values from the example to the new texture but instead stores
 * texture coordinates referencing the example texture") by image quilting
 * (Efros & Freeman 2001, the paper's reference 6) on the representative
 * image (rf_feature.c). The paper used Tong et al.'s texton synthesis and
 * notes that "the underlying algorithm used to generate the synthesis
 * result does not directly influence our rendering method"; quilting is
 * chosen here because it copies whole blocks, so the map is piecewise a
 * shift (it deflates to little, docs/rf.md) and every block keeps the
 * sample's structures intact.
 *
 * Blocks of block x block texels, overlapping by `overlap`, are placed in
 * raster order. For each, every position of the sample is a candidate;
 * its error is the sum of squared feature differences over the texels of
 * the block that are already placed (the left and top overlaps, and the
 * sample's own place); one is drawn (seeded) among those within
 * (1 + tolerance) of the best, and joined along the minimum-error boundary
 * cut (rf_cut.c). The surface is a torus, as every renderer tiles it: the
 * last block of a row (of a column) overlaps the first on its right
 * (below), so the surface tiles without a seam.
 *
 * The sample keeps its place: the block grid starts at the sample's own
 * place in the surface, the blocks that lie on it (spaced evenly so that
 * they cover it exactly) come first and copy it unchanged (the identity
 * candidate, no draw), and the other blocks, spaced evenly round the rest
 * of the torus, join it along cuts like any other neighbour. Where the rest
 * of a side is shorter than a block less two overlaps (a surface a little
 * larger than the place: a 64 x 43 capture on a 64 x 64 texture), its one
 * block is shortened to the rest and one overlap at each end; a whole
 * block would wrap round deep into the place (15 of the 43 rows there).
 * So the data's pixel correspondence holds on the sample's place except
 * where such a cut runs into its border, within one overlap of its edges;
 * a sample of the whole image on a surface of its size is exactly the
 * identity.
 * Candidates of a block are
 * scored in parallel (one job per candidate row, each score depending only
 * on its position), so the map does not depend on the thread count.
 */
#include "rf/rf_sample.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Where the blocks go along one side of n texels, relative to the start
 * of the sample's place (origin): first `inside` blocks evenly spaced over
 * the fe texels of the place, then the others evenly spaced over the rest
 * of the side and overlapping the place's first and last blocks by at least
 * `overlap` (the torus). A side shorter than a block has one block, the
 * whole side, and does not wrap; a place shorter than a block has no
 * blocks of its own. */
typedef struct axis {
    int n, len, count, inside, origin, wraps;
    /* > 0: the length of the one block after the place's own, where the
     * rest of the side is shorter than a block less two overlaps (a whole
     * block there would reach deeper than one overlap into the place) */
    int rest_len;
    int *pos;
} axis;

/* The length of block i along the axis. */
static int block_len(const axis *a, int i)
{
    return i >= a->inside && a->rest_len > 0 ? a->rest_len : a->len;
}

/* count positions from a to b (the last block starting at b), evenly. */
static void spread(int *pos, int count, int a, int b)
{
    for (int i = 0; i < count; i++)
        pos[i] = count > 1 ? a + (int)((int64_t)i * (b - a) / (count - 1)) : a;
}

static btf_status axis_init(axis *a, int n, int start, int fe, int block, int overlap,
                            btf_error *err)
{
    memset(a, 0, sizeof *a);
    a->n = n;
    a->pos = btf__alloc((size_t)n + 2, sizeof(int), err);
    if (!a->pos)
        return BTF_E_NOMEM;
    if (n <= block) { /* one block, the whole side */
        a->len = n, a->count = 1, a->pos[0] = 0;
        a->inside = fe == n && start == 0;
        return BTF_OK;
    }
    a->wraps = 1, a->len = block;
    int step = block - overlap;
    if (fe >= block) {
        a->origin = start;
        a->inside = 1 + (fe - block + step - 1) / step;
        spread(a->pos, a->inside, 0, fe - block);
        if (fe < n) { /* the rest: from fe - overlap to n + overlap */
            int span = n - fe + 2 * overlap - block;
            int others = span > 0 ? 1 + (span + step - 1) / step : 1;
            spread(a->pos + a->inside, others, fe - overlap, fe - overlap + (span > 0 ? span : 0));
            a->count = a->inside + others;
            if (span < 0) /* one shorter block: exactly one overlap at each end */
                a->rest_len = n - fe + 2 * overlap;
        } else {
            a->count = a->inside;
            a->wraps = 0; /* the place covers the side: it ends where it starts */
        }
    } else {
        a->count = (n + step - 1) / step;
        for (int i = 0; i < a->count; i++)
            a->pos[i] = (int)((int64_t)i * n / a->count);
    }
    return BTF_OK;
}

/* The overlaps of block i along an axis: before it and (the wrap) after it. */
static void axis_overlaps(const axis *a, int i, int *before, int *after)
{
    *before = i > 0 ? a->pos[i - 1] + block_len(a, i - 1) - a->pos[i] : 0;
    *after = a->wraps && i == a->count - 1 ? a->pos[i] + block_len(a, i) - a->n : 0;
    *after = *after > 0 ? *after : 0;
}

typedef struct quilt {
    const rf_quilt_args *q;
    float *sf;             /* [sh * sw * 3] the sample's features */
    uint16_t *map;
    unsigned char *known;  /* [surface] */
    axis ax, ay;
    /* the current block: its corner, its overlaps (left, top, right, bottom) */
    int bx, by, bw, bh, nu, nv, nk;
    int ov[4];
    int *kx, *ky;          /* [block^2] the placed texels in it, block coordinates */
    float *kf;             /* [block^2 * 3] and their features */
    double *score;         /* [sample texels] */
} quilt;

/* The surface texel of block texel (c, r), wrapped round the torus. */
static size_t at(const quilt *Q, int c, int r)
{
    int x = (Q->bx + c) % Q->q->surface_w, y = (Q->by + r) % Q->q->surface_h;
    return (size_t)y * Q->q->surface_w + x;
}

static const float *sample_feat(const quilt *Q, int u, int v)
{
    return Q->sf + ((size_t)v * Q->q->sw + u) * RF_FEATURES;
}

static const float *placed_feat(const quilt *Q, size_t s)
{
    return sample_feat(Q, Q->map[2 * s], Q->map[2 * s + 1]);
}

static double dist2(const float *a, const float *b)
{
    double s = 0.0;
    for (int k = 0; k < RF_FEATURES; k++) {
        double d = (double)a[k] - b[k];
        s += d * d;
    }
    return s;
}

/* The overlap error of candidate (u, v). */
static double score_one(const quilt *Q, int u, int v)
{
    double s = 0.0;
    for (int k = 0; k < Q->nk; k++)
        s += dist2(sample_feat(Q, u + Q->kx[k], v + Q->ky[k]), Q->kf + RF_FEATURES * k);
    return s;
}

/* The overlap error of every candidate in row v of the sample. */
static btf_status score_job(void *user, int v, int worker, btf_error *err)
{
    (void)worker, (void)err;
    quilt *Q = user;
    for (int u = 0; u < Q->nu; u++)
        Q->score[(size_t)v * Q->nu + u] = score_one(Q, u, v);
    return BTF_OK;
}

/* The already placed texels of the current block (and their features). */
static void gather_known(quilt *Q)
{
    Q->nk = 0;
    for (int r = 0; r < Q->bh; r++)
        for (int c = 0; c < Q->bw; c++) {
            size_t s = at(Q, c, r);
            if (!Q->known[s])
                continue;
            Q->kx[Q->nk] = c, Q->ky[Q->nk] = r;
            memcpy(Q->kf + RF_FEATURES * Q->nk, placed_feat(Q, s), RF_FEATURES * sizeof(float));
            Q->nk++;
        }
}

static int has_lattice(const quilt *Q)
{
    const int *L = Q->q->lattice;
    return (long)L[0] * L[3] - (long)L[1] * L[2] != 0;
}

/* Moves candidate i (v * nu + u) to the nearest position in the sample
 * whose offset from the current block's own place (its position relative
 * to the sample's place) is a lattice vector; 0 when none is near. */
static int snap(const quilt *Q, int *i)
{
    const int *L = Q->q->lattice;
    int u = *i % Q->nu, v = *i / Q->nu;
    long px = Q->bx - Q->ax.origin, py = Q->by - Q->ay.origin;
    double det = (double)L[0] * L[3] - (double)L[1] * L[2];
    double ox = (double)(u - px), oy = (double)(v - py);
    long s = lround((ox * L[3] - oy * L[2]) / det), t = lround((L[0] * oy - L[1] * ox) / det);
    long best = -1, best_d = 0;
    for (int ds = -2; ds <= 2; ds++)
        for (int dt = -2; dt <= 2; dt++) {
            long cu = px + (s + ds) * L[0] + (t + dt) * L[2];
            long cv = py + (s + ds) * L[1] + (t + dt) * L[3];
            if (cu < 0 || cv < 0 || cu >= Q->nu || cv >= Q->nv)
                continue;
            long d = (cu - u) * (cu - u) + (cv - v) * (cv - v);
            if (best < 0 || d < best_d)
                best = cv * Q->nu + cu, best_d = d;
        }
    if (best < 0)
        return 0;
    *i = (int)best;
    return 1;
}

/* q->candidates positions drawn (each moved onto the lattice, when there
 * is one), the best of them taken (ties: the first drawn), so the choice
 * depends on the seed alone. */
static btf_status choose_drawn(quilt *Q, btf_rng *rng, int *pick)
{
    size_t n = (size_t)Q->nu * Q->nv;
    double best = DBL_MAX;
    int lattice = has_lattice(Q), any = 0;
    *pick = 0;
    for (int c = 0; c < Q->q->candidates; c++) {
        int i = (int)(btf__rng_next(rng) % n);
        if (lattice && !snap(Q, &i))
            continue;
        double s = score_one(Q, i % Q->nu, i / Q->nu);
        if (s < best || !any) {
            best = s;
            *pick = i;
            any = 1;
        }
    }
    return BTF_OK;
}

/* The candidate drawn for the current block, as v * nu + u. */
static btf_status choose(quilt *Q, btf_rng *rng, int *pick, btf_error *err)
{
    size_t n = (size_t)Q->nu * Q->nv;
    if (Q->nk == 0) { /* nothing to match: any position (on the lattice) */
        *pick = (int)(btf__rng_next(rng) % n);
        if (Q->q->candidates > 0 && has_lattice(Q))
            snap(Q, pick);
        return BTF_OK;
    }
    if (Q->q->candidates > 0 && (size_t)Q->q->candidates < n)
        return choose_drawn(Q, rng, pick);
    /* thread start-up costs more than a small block's scores */
    int threads = (double)n * Q->nk < 65536.0 ? 1 : Q->q->threads;
    btf_status rc = btf__pool_run(Q->nv, threads, score_job, Q, NULL, err);
    if (rc)
        return rc;
    double best = DBL_MAX;
    for (size_t i = 0; i < n; i++)
        best = Q->score[i] < best ? Q->score[i] : best;
    double limit = best * (1.0 + Q->q->tolerance);
    uint64_t within = 0;
    for (size_t i = 0; i < n; i++)
        within += Q->score[i] <= limit;
    uint64_t k = within ? btf__rng_next(rng) % within : 0;
    for (size_t i = 0; i < n; i++)
        if (Q->score[i] <= limit && k-- == 0) {
            *pick = (int)i;
            return BTF_OK;
        }
    *pick = 0; /* scores that are all NaN: cannot happen with finite features */
    return BTF_OK;
}

/* Places the candidate (u, v) in the current block along the cuts. */
static void place(quilt *Q, int u, int v, double *e, unsigned char *take, double *scratch,
                  int *path)
{
    for (int r = 0; r < Q->bh; r++)
        for (int c = 0; c < Q->bw; c++) {
            size_t s = at(Q, c, r);
            e[(size_t)r * Q->bw + c] =
                Q->known[s] ? dist2(placed_feat(Q, s), sample_feat(Q, u + c, v + r)) : 0.0;
        }
    rf_cut(e, Q->bw, Q->bh, Q->ov, take, scratch, path);
    for (int r = 0; r < Q->bh; r++)
        for (int c = 0; c < Q->bw; c++) {
            size_t s = at(Q, c, r);
            if (Q->known[s] && !take[(size_t)r * Q->bw + c])
                continue;
            Q->map[2 * s] = (uint16_t)(u + c), Q->map[2 * s + 1] = (uint16_t)(v + r);
            Q->known[s] = 1;
        }
}

static btf_status run(quilt *Q, btf_error *err)
{
    const rf_quilt_args *q = Q->q;
    int B = q->block;
    double *e = btf__alloc((size_t)B * B, 2 * sizeof(double), err);
    unsigned char *take = btf__alloc((size_t)B * B, 1, err);
    int *path = btf__alloc((size_t)4 * B, sizeof(int), err);
    btf_status rc = e && take && path ? BTF_OK : BTF_E_NOMEM;
    btf_rng rng;
    btf__rng_seed(&rng, q->seed);
    for (int j = 0; rc == BTF_OK && j < Q->ay.count; j++)
        for (int i = 0; rc == BTF_OK && i < Q->ax.count; i++) {
            Q->bx = Q->ax.origin + Q->ax.pos[i], Q->by = Q->ay.origin + Q->ay.pos[j];
            Q->bw = block_len(&Q->ax, i), Q->bh = block_len(&Q->ay, j);
            Q->nu = q->sw - Q->bw + 1, Q->nv = q->sh - Q->bh + 1;
            axis_overlaps(&Q->ax, i, &Q->ov[0], &Q->ov[2]);
            axis_overlaps(&Q->ay, j, &Q->ov[1], &Q->ov[3]);
            int pick = 0;
            if (i < Q->ax.inside && j < Q->ay.inside) { /* on the sample's place: itself */
                pick = Q->ay.pos[j] * Q->nu + Q->ax.pos[i];
            } else {
                gather_known(Q);
                rc = choose(Q, &rng, &pick, err);
            }
            if (rc == BTF_OK)
                place(Q, pick % Q->nu, pick / Q->nu, e, take, e + (size_t)B * B, path);
        }
    BTF_FREE_ALL(e, take, path);
    return rc;
}

/* How much of the sample's place [start, start + side) lies on a surface
 * side of n texels. */
static int place_extent(int start, int side, int n)
{
    return start >= n ? 0 : start + side <= n ? side : n - start;
}

btf_status rf_quilt(const rf_quilt_args *q, uint16_t *map, btf_error *err)
{
    if (q->sw < 1 || q->sh < 1 || q->sw > 65536 || q->sh > 65536 || q->surface_w < 1 ||
        q->surface_h < 1 || q->block < 1 || q->block > q->sw || q->block > q->sh ||
        q->overlap < 0 || 2 * q->overlap > q->block || !(q->tolerance >= 0.0))
        return btf__fail(err, BTF_E_ARG, "quilting: sample %dx%d, surface %dx%d, block %d, "
                         "overlap %d, tolerance %g (expected a block within the sample, an "
                         "overlap of at most half the block)", q->sw, q->sh, q->surface_w,
                         q->surface_h, q->block, q->overlap, q->tolerance);
    quilt Q;
    memset(&Q, 0, sizeof Q);
    Q.q = q, Q.map = map;
    size_t B2 = (size_t)q->block * q->block;
    Q.sf = btf__alloc((size_t)q->sw * q->sh, RF_FEATURES * sizeof(float), err);
    Q.known = btf__calloc((size_t)q->surface_w * q->surface_h, 1, err);
    Q.kx = btf__alloc(B2, sizeof(int), err);
    Q.ky = btf__alloc(B2, sizeof(int), err);
    Q.kf = btf__alloc(B2, RF_FEATURES * sizeof(float), err);
    Q.score = btf__alloc((size_t)q->sw * q->sh, sizeof(double), err);
    btf_status rc = BTF_E_NOMEM;
    if (Q.sf && Q.known && Q.kx && Q.ky && Q.kf && Q.score &&
        axis_init(&Q.ax, q->surface_w, q->sx, place_extent(q->sx, q->sw, q->surface_w),
                  q->block, q->overlap, err) == BTF_OK &&
        axis_init(&Q.ay, q->surface_h, q->sy, place_extent(q->sy, q->sh, q->surface_h),
                  q->block, q->overlap, err) == BTF_OK) {
        for (int v = 0; v < q->sh; v++)
            memcpy(Q.sf + (size_t)v * q->sw * RF_FEATURES,
                   q->feat + ((size_t)(q->sy + v) * q->feat_w + q->sx) * RF_FEATURES,
                   (size_t)q->sw * RF_FEATURES * sizeof(float));
        rc = run(&Q, err);
    }
    free(Q.sf), free(Q.known), free(Q.kx), free(Q.ky), free(Q.kf), free(Q.score);
    free(Q.ax.pos), free(Q.ay.pos);
    return rc;
}
