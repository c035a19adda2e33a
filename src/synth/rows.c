/*
 * rows.c — CAR fields generated row by row (Haindl & Filip 2007, section
 * II.C: each sub-band level is a field of the causal recursion
 * Y_r = sum_s gamma_s Y_{r+s} + sigma e_r): the generator for bands and
 * machines the wavefront (wave.c) does not take, giving the same bits.
 *
 * A row's sum splits in two: the earlier-row terms and the noise read
 * finished rows only and run as independent per-pixel sums the compiler
 * vectorises (earlier_rows); the same-row terms are a sequential chain
 * (chains.c). To give the core independent chains to overlap, the bands of
 * one subspace step together and each produces two rows at once where it
 * is wide enough (btf__rows_pair): row r + 1 runs a chunk behind row r.
 */
#include "synth/synth.h"

#include "btf_shared.h"

#include <limits.h>
#include <string.h>

typedef float v8f __attribute__((vector_size(32)));

/* A vector from 8 floats at p, unaligned (a macro: a function returning a
 * 32-byte vector would change the ABI of the portable build). */
#define LOAD8(p) __extension__({ v8f v_; memcpy(&v_, (p), sizeof v_); v_; })

/* acc[i] = (((0 + g0 src0[i]) + g1 src1[i]) + ...) + sigma e[i]: the
 * earlier-row terms in stored order, then the noise (btf_car_accumulate,
 * btf_car_output). One pass over the row with 32 pixels in registers, not
 * one pass per term: the terms' adds form four independent chains and acc
 * is written once. Same operations, same order as term by term. */
SYNTH_AVX2_CLONES
static void earlier_rows(const float *const *src, const float *gamma, int n, float sigma,
                         const float *e, float *acc, int fw)
{
    int i = 0;
    for (; i + 32 <= fw; i += 32) {
        v8f a0 = {0}, a1 = {0}, a2 = {0}, a3 = {0};
        for (int s = 0; s < n; s++) {
            const float *p = src[s] + i;
            v8f gs = {0};
            gs += gamma[s]; /* broadcast: 0 + g is g exactly */
            a0 = a0 + gs * LOAD8(p);
            a1 = a1 + gs * LOAD8(p + 8);
            a2 = a2 + gs * LOAD8(p + 16);
            a3 = a3 + gs * LOAD8(p + 24);
        }
        v8f sg = {0};
        sg += sigma;
        a0 = a0 + sg * LOAD8(e + i);
        a1 = a1 + sg * LOAD8(e + i + 8);
        a2 = a2 + sg * LOAD8(e + i + 16);
        a3 = a3 + sg * LOAD8(e + i + 24);
        memcpy(acc + i, &a0, sizeof a0);
        memcpy(acc + i + 8, &a1, sizeof a1);
        memcpy(acc + i + 16, &a2, sizeof a2);
        memcpy(acc + i + 24, &a3, sizeof a3);
    }
    for (; i + 8 <= fw; i += 8) { /* what is left, 8 pixels at a time */
        v8f a0 = {0};
        for (int s = 0; s < n; s++) {
            v8f gs = {0};
            gs += gamma[s];
            a0 = a0 + gs * LOAD8(src[s] + i);
        }
        v8f sg = {0};
        sg += sigma;
        a0 = a0 + sg * LOAD8(e + i);
        memcpy(acc + i, &a0, sizeof a0);
    }
    for (; i < fw; i++) {
        float a = 0.0f;
        for (int s = 0; s < n; s++)
            a = btf_car_accumulate(a, gamma[s], src[s][i]);
        acc[i] = btf_car_output(a, sigma, e[i]);
    }
}

/* One field row being generated: the earlier-row terms of its recursion
 * Y_r = sum_s gamma_s Y_{r+s} + sigma e_r, summed in the order of
 * btf_shared.h (the GPU sums the same way): the offsets of earlier rows in
 * stored order, then the noise, then the same-row offsets farthest first.
 * Everything up to the noise reads finished rows only, so it runs as
 * independent per-pixel chains the compiler vectorises (row_job_acc, into
 * acc); the same-row terms are sequential (jobs_same_row). */
typedef struct row_job {
    synth_field *f;
    const float *earlier[BTF_CAR_MAX_NEIGHBOURS]; /* earlier rows, at field column 0 */
    float earlier_gamma[BTF_CAR_MAX_NEIGHBOURS];
    int n_earlier;
    const float *noise; /* the row's Gaussians */
    float *acc;         /* the earlier-row part and the noise of each pixel */
    float *out;         /* the row in the ring, field column 0 */
} row_job;

/* The Gaussians of field row r (noise_row.c): column c uses component
 * c & 3 of block c >> 2 of row r, with c and r offset by BTF_NOISE_ORIGIN.
 * A tileable field takes those of (r mod period_h, c mod period_w): one
 * period of the row drawn once, read periodically (the noise the GPU
 * shader draws pixel by pixel). */
static void noise_row(const synth_field *f, uint32_t seed_lo, uint32_t seed_hi, int r, float *e)
{
    if (f->period_w > 0) {
        uint32_t row = (uint32_t)(btf_period_coord(r, f->period_h) + BTF_NOISE_ORIGIN);
        uint32_t b0 = (uint32_t)BTF_NOISE_ORIGIN >> 2, n = ((uint32_t)f->period_w + 3u) >> 2;
        btf__noise_blocks(seed_lo, seed_hi, f->stream, row, b0, n, f->vector_noise,
                          f->period_noise);
        int c = btf_period_coord(f->fx0, f->period_w);
        for (int i = 0; i < f->fw; i++) {
            e[i] = f->period_noise[c];
            c = c + 1 == f->period_w ? 0 : c + 1;
        }
        return;
    }
    uint32_t urow = (uint32_t)(r + BTF_NOISE_ORIGIN);
    uint32_t c0 = (uint32_t)(f->fx0 + BTF_NOISE_ORIGIN), c1 = c0 + (uint32_t)f->fw;
    uint32_t b0 = c0 >> 2, b1 = (c1 + 3u) >> 2;
    /* out[4 * (b - b0) + lane] is column b * 4 + lane */
    btf__noise_blocks(seed_lo, seed_hi, f->stream, urow, b0, b1 - b0, f->vector_noise,
                      e - (c0 & 3u));
}

/* Starts field row r: its noise into noise + 3 (3 floats of slack before,
 * for the block alignment), its terms, its ring row. Rows above the
 * field's first row are zero: their ring slots were cleared at start and
 * are only overwritten by rows of the field. */
static void row_job_init(row_job *j, synth_field *f, int r, float *noise, float *acc,
                         uint32_t seed_lo, uint32_t seed_hi)
{
    const btf_car_band *b = f->band;
    j->f = f;
    j->noise = noise + 3;
    noise_row(f, seed_lo, seed_hi, r, noise + 3);
    j->n_earlier = 0;
    for (int s = 0; s < b->n; s++)
        if (b->offsets[s].row != 0) {
            j->earlier[j->n_earlier] = synth_field_ring_row(f, r + b->offsets[s].row) +
                                       b->offsets[s].col;
            j->earlier_gamma[j->n_earlier++] = b->gamma[s];
        }
    j->acc = acc;
    j->out = synth_field_ring_row(f, r);
}

/* The earlier-row part of columns [from, from + len): reads the rows above
 * up to column from + len - 1 + their reach to the right. */
static void row_job_acc(const row_job *j, int from, int len)
{
    const float *src[BTF_CAR_MAX_NEIGHBOURS];
    for (int s = 0; s < j->n_earlier; s++)
        src[s] = j->earlier[s] + from;
    earlier_rows(src, j->earlier_gamma, j->n_earlier, j->f->band->sigma, j->noise + from,
                 j->acc + from, len);
}

/* The same-row part of a row whose same-row set is not one of the family's
 * shapes, columns [from, from + len): the general loop, same operations. */
static void same_row_general(const row_job *j, int from, int len)
{
    const synth_field *f = j->f;
    float *out = j->out;
    for (int i = from; i < from + len; i++) {
        float a = j->acc[i];
        for (int t = 0; t < f->n_same_row; t++)
            a = btf_car_accumulate(a, f->same_row_gamma[t], out[i + f->same_row_col[t]]);
        out[i] = a;
    }
}

/* The same-row part of n rows, row t over columns [from[t], from[t] + len)
 * (its columns before are done): rows of one shape step together, up to
 * SYNTH_MAX_CHAINS in one loop. */
static void jobs_same_row(row_job *const *jobs, const int *from, int n, int len)
{
    if (len <= 0)
        return;
    for (int k = 0; k <= 3; k++) {
        synth_chain grp[SYNTH_MAX_CHAINS];
        int m = 0;
        for (int t = 0; t < n; t++)
            if (jobs[t]->f->same_row_shape == k) {
                grp[m++] = (synth_chain){jobs[t]->acc + from[t], jobs[t]->out + from[t],
                                         jobs[t]->f->same_row_gamma3};
                if (m == SYNTH_MAX_CHAINS) {
                    btf__chains(grp, m, k, len);
                    m = 0;
                }
            }
        if (m)
            btf__chains(grp, m, k, len);
    }
    for (int t = 0; t < n; t++)
        if (jobs[t]->f->same_row_shape < 0)
            same_row_general(jobs[t], from[t], len);
}

void btf__rows_step(synth_field *const *f, int n, uint32_t seed_lo, uint32_t seed_hi)
{
    row_job job[3], *jp[3] = {NULL, NULL, NULL};
    int zero[3] = {0, 0, 0}, common = INT_MAX;
    for (int b = 0; b < n; b++) {
        row_job_init(&job[b], f[b], f[b]->next++, f[b]->noise, f[b]->acc, seed_lo, seed_hi);
        row_job_acc(&job[b], 0, f[b]->fw);
        jp[b] = &job[b];
        common = f[b]->fw < common ? f[b]->fw : common;
    }
    jobs_same_row(jp, zero, n, common);
    for (int b = 0; b < n; b++) /* bands of larger margins are wider */
        jobs_same_row(&jp[b], &common, 1, f[b]->fw - common);
}

/* The columns of a chunk in btf__rows_pair. */
#define PAIR_CHUNK 64

/* How far row r + 1 trails row r: a chunk plus row r + 1's reach into row
 * r to the right, so that a chunk of row r + 1 reads only finished columns
 * of row r. */
int btf__rows_pair_lead(synth_field *const *f, int n)
{
    int reach = 0;
    for (int b = 0; b < n; b++)
        for (int s = 0; s < f[b]->band->n; s++) {
            btf_offset o = f[b]->band->offsets[s];
            if (o.row == -1 && o.col > reach)
                reach = o.col;
        }
    return PAIR_CHUNK + reach;
}

/* Two rows, r and r + 1, of n bands generated together. */
typedef struct row_pair {
    int n, lead;
    row_job first[3], second[3]; /* rows r and r + 1 of each band */
    int widest, narrowest;       /* field widths */
    int shape;                   /* the bands' common same-row shape, or -1 */
} row_pair;

/* Starts rows r and r + 1 of each band: both rows' noise and terms, row
 * r's earlier-row part over the whole row (the rows above are finished). */
static void row_pair_init(row_pair *p, synth_field *const *f, int n, int lead, uint32_t seed_lo,
                          uint32_t seed_hi)
{
    p->n = n, p->lead = lead;
    p->widest = 0, p->narrowest = INT_MAX, p->shape = f[0]->same_row_shape;
    for (int b = 0; b < n; b++) {
        int r = f[b]->next;
        f[b]->next += 2;
        row_job_init(&p->first[b], f[b], r, f[b]->noise, f[b]->acc, seed_lo, seed_hi);
        row_job_init(&p->second[b], f[b], r + 1, f[b]->noise_next, f[b]->acc_next, seed_lo,
                     seed_hi);
        row_job_acc(&p->first[b], 0, f[b]->fw);
        p->widest = f[b]->fw > p->widest ? f[b]->fw : p->widest;
        p->narrowest = f[b]->fw < p->narrowest ? f[b]->fw : p->narrowest;
        p->shape = f[b]->same_row_shape == p->shape ? p->shape : -1;
    }
}

/* The chunk of row r at column x and of row r + 1 at x - lead, all bands
 * a whole chunk wide and of one shape: straight to one loop of 2 n chains
 * (the usual case). */
static void row_pair_chunk_uniform(row_pair *p, int x)
{
    synth_chain c[SYNTH_MAX_CHAINS];
    for (int b = 0; b < p->n; b++) {
        const row_job *first = &p->first[b], *second = &p->second[b];
        row_job_acc(second, x - p->lead, PAIR_CHUNK); /* row r is done up to x - 1 */
        c[2 * b] = (synth_chain){first->acc + x, first->out + x, first->f->same_row_gamma3};
        c[2 * b + 1] = (synth_chain){second->acc + x - p->lead, second->out + x - p->lead,
                                     second->f->same_row_gamma3};
    }
    btf__chains(c, 2 * p->n, p->shape, PAIR_CHUNK);
}

/* The same for any bands: those past their width sit out, those in their
 * last (partial) chunk run on their own, the others share a loop. */
static void row_pair_chunk(row_pair *p, int x)
{
    row_job *full[6], *part[2];
    int at[6], nfull = 0;
    for (int b = 0; b < p->n; b++) {
        int fw = p->first[b].f->fw, len = fw - x < PAIR_CHUNK ? fw - x : PAIR_CHUNK;
        if (len <= 0)
            continue;
        row_job_acc(&p->second[b], x - p->lead, len); /* row r is done up to x - 1 */
        int from[2] = {x, x - p->lead};
        if (len < PAIR_CHUNK) {
            part[0] = &p->first[b], part[1] = &p->second[b];
            jobs_same_row(part, from, 2, len);
            continue;
        }
        at[nfull] = from[0], full[nfull++] = &p->first[b];
        at[nfull] = from[1], full[nfull++] = &p->second[b];
    }
    jobs_same_row(full, at, nfull, PAIR_CHUNK);
}

/* Row r + 1 runs `lead` columns behind row r, chunk by chunk, its
 * earlier-row part computed just before each chunk from the part of row r
 * already finished. Every value is the same sum in the same order as
 * btf__rows_step gives. Each band runs over its own width (the margins
 * differ). */
void btf__rows_pair(synth_field *const *f, int n, int lead, uint32_t seed_lo, uint32_t seed_hi)
{
    row_pair p;
    row_pair_init(&p, f, n, lead, seed_lo, seed_hi);
    row_job *first[3] = {&p.first[0], &p.first[1], &p.first[2]};
    row_job *second[3] = {&p.second[0], &p.second[1], &p.second[2]};
    int at[3] = {0, 0, 0};
    jobs_same_row(first, at, n, lead); /* row r alone */
    int x = lead;
    if (p.shape >= 0)
        for (; x + PAIR_CHUNK <= p.narrowest; x += PAIR_CHUNK)
            row_pair_chunk_uniform(&p, x);
    for (; x < p.widest; x += PAIR_CHUNK)
        row_pair_chunk(&p, x);
    for (int b = 0; b < n; b++) { /* row r + 1 alone: its last lead columns */
        at[b] = f[b]->fw - lead;
        row_job_acc(second[b], at[b], lead);
    }
    jobs_same_row(second, at, n, lead);
}
