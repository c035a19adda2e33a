/*
 * wave.c — a CAR field (Haindl & Filip 2007, section II.C: each sub-band
 * level is synthesised by its causal recursion) generated as a wavefront:
 * eight rows at once, one per AVX2 lane (docs/synthesis.md, "Speed on the
 * CPU").
 *
 * Why. Each pixel of the causal recursion Y_r = sum_s gamma_s Y_{r+s} +
 * sigma e_r waits on its left neighbour (a multiply and an add), so a row
 * is a sequential chain, and row by row the vector units sit idle while
 * the chain runs. Row r + 1 only needs row r up to a few columns to the
 * right, though: when lane k works on row r + k, WAVE_LAG columns behind
 * lane k - 1, every neighbour a lane needs is already computed, and one
 * vector step advances eight rows by one column. The noise is counter
 * based, so each lane draws its own (row, block) directly (no row of noise
 * is stored and reread), and the earlier-row terms are one lane rotation
 * of vectors computed a few steps before.
 *
 * Lanes never stop: lane k runs rows row0 + k, row0 + k + 8, ... back to
 * back, each a lap of `lap` positions: `left_pad` zero columns, the field's
 * fw columns, lap - left_pad - fw zero columns (the zero boundary of
 * synthesis; pad positions are masked to +0 exactly as the rows' zero
 * columns are). Step t holds lane k at sequence index s = t - k WAVE_LAG,
 * lap number s / lap, position s % lap (lanes with s < 0 are above the
 * field: zero). `history` keeps the last `lap` step vectors (slot t % lap,
 * `history_slot`; its first WAVE_MIRROR slots repeated past lap, so a run
 * of slots never wraps). A neighbour d rows up and dc columns over is lane
 * k - d at step t - d WAVE_LAG + dc, or, for lanes k < d, lane k - d + 8 on
 * its previous lap, at step t - lap + (8 - d) WAVE_LAG + dc: a blend of two
 * slots, rotated by d lanes (wave_rotated). Every 8 steps the eight vectors
 * are transposed into 8 consecutive columns of each lane's row and stored
 * in the level's ring of rows, which the pyramid reads as before.
 *
 * Bits. Every pixel is the same sum in the same order as the row-by-row
 * code (src/synth/rows.c) and the GPU shader (btf_shared.h): earlier-row terms
 * in stored order starting from 0, then sigma e, then the same-row terms
 * farthest first. Noise is btf_noise4 of the same (row, block) through the
 * same AVX2 code as noise rows (src/synth/noise_avx2.h). tests/unit/test_car.c checks
 * every value against the recursion written out pixel by pixel.
 *
 * Scope: GCC on x86-64 with AVX2 (else, or when the caller asks for the
 * portable noise or for rows, the row-by-row code runs), bands whose earlier-row offsets lie within
 * WAVE_REACH_ROW rows up and WAVE_REACH_COL columns either way and whose
 * same-row offsets are columns -k .. -1 (k <= 3): every member of the
 * candidate family; fields at least WAVE_MIN_LAP wide.
 */
#include "core/core.h"
#include "synth/synth.h"

#include "btf_noise.h"
#include "btf_shared.h"

#include <stdlib.h>
#include <string.h>

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define WAVE_AVAILABLE 1
#pragma GCC push_options
#pragma GCC target("avx2")
#include "noise_avx2.h" /* up here: struct btf_wave holds a philox8_plan */
#pragma GCC pop_options
#endif

#define WAVE_LAG 16     /* columns lane k trails lane k - 1: > WAVE_REACH_COL + 7, so
                         * a group's 8 steps read only earlier groups' values */
#define WAVE_REACH_ROW 3 /* largest row offset handled (the family's) */
#define WAVE_REACH_COL 4 /* largest |column offset| handled */
#define WAVE_SPAN (2 * WAVE_REACH_COL) /* column spread of one row offset's terms */
#define WAVE_MIRROR 16  /* slots past lap that repeat the first ones (>= WAVE_SPAN + 8) */
#define WAVE_MIN_LAP 136 /* > 8 WAVE_LAG + WAVE_REACH_COL: the two slots a lane
                          * blend reads stay apart */

struct btf_wave {
    int fw;                     /* field width */
    int left_pad;               /* zero columns before the field in each lap */
    int lap;                    /* positions of one lap: pads + field, a multiple of 8 */
    int row0;                   /* first field row */
    uint32_t block0;            /* noise block of lap position 0 */
    uint32_t stream;
    float sigma;
    /* Earlier-row terms, stored order, grouped by their row offset: a row
     * group's terms read one run of consecutive step vectors, rotated once. */
    int n_earlier;
    int term_group[BTF_CAR_MAX_NEIGHBOURS]; /* its row group */
    int term_at[BTF_CAR_MAX_NEIGHBOURS];    /* its first vector in the group's run */
    float term_gamma[BTF_CAR_MAX_NEIGHBOURS];
    int n_row_groups;                       /* distinct row offsets */
    int group_rows_up[WAVE_REACH_ROW];      /* d: the group's rows up */
    int group_steps_back[WAVE_REACH_ROW];   /* d WAVE_LAG - (smallest dc): start of the run */
    int group_n_steps[WAVE_REACH_ROW];      /* length of the run: 8 + the spread of its columns */
    int same_row_shape;         /* same-row offsets: columns -k .. -1, k this */
    float same_row_gamma3[3];   /* their gammas (columns -3, -2, -1) */
    int64_t steps;              /* steps done, a multiple of 8 */
    int history_slot;           /* steps % lap: the slot the next step goes to */
    int32_t pos[8];             /* each lane's position (s while s < 0) */
    uint32_t noise_row[8];      /* each lane's row + BTF_NOISE_ORIGIN */
    float last_steps[3][8];     /* the last three step vectors, latest first */
    float *dst[8];              /* where each lane's next 8 positions go, or NULL */
    float *history;             /* lap + WAVE_MIRROR step vectors */
    float *ring;                /* the level's ring of rows */
    int depth, pad;
    size_t stride;
#ifdef WAVE_AVAILABLE
    int planned;                /* plan holds the rounds of plan_seed */
    uint32_t plan_seed[2];
    philox8_plan plan;
#endif
};

int btf__wave_available(void)
{
#ifdef WAVE_AVAILABLE
    return btf__noise_avx2_available();
#else
    return 0;
#endif
}

int btf__wave_supported(const btf_car_band *b, int fw)
{
#ifdef WAVE_AVAILABLE
    float gamma3[3];
    if (!btf__noise_avx2_available() || btf__car_same_row_shape(b, gamma3) < 0)
        return 0;
    for (int s = 0; s < b->n; s++) {
        int d = -b->offsets[s].row, dc = b->offsets[s].col;
        if (d > WAVE_REACH_ROW || dc > WAVE_REACH_COL || dc < -WAVE_REACH_COL)
            return 0;
    }
    return fw >= WAVE_MIN_LAP;
#else
    (void)b, (void)fw;
    return 0;
#endif
}

/* The ring padding a wave needs on each side of a row: the zero columns of
 * its laps are stored too. */
int btf__wave_pad(void)
{
    return 2 * WAVE_REACH_COL + 8;
}

void btf__wave_free(btf_wave *w)
{
    if (!w)
        return;
    free(w->history);
    free(w);
}

/* Where lane k's row and position start in the ring (its row above the
 * field: NULL). */
static float *wave_dst(const btf_wave *w, int k)
{
    if (w->pos[k] < 0)
        return NULL;
    /* the ring row of r, as synth_field_ring_row finds it (only when a lane
     * starts a row: the division is rare) */
    int r = (int)(w->noise_row[k] - (uint32_t)BTF_NOISE_ORIGIN);
    int slot = ((r % w->depth) + w->depth) % w->depth;
    return w->ring + (size_t)slot * w->stride + w->pad + (w->pos[k] - w->left_pad);
}

btf_wave *btf__wave_new(const btf_car_band *b, int fw, int fx0, int row0, uint32_t stream,
                        float *ring, int depth, int pad, btf_error *err)
{
    if (depth < BTF_WAVE_DEPTH || pad < btf__wave_pad()) {
        btf__fail(err, BTF_E_ARG, "wavefront ring of %d rows padded by %d: expected >= %d and %d",
                  depth, pad, BTF_WAVE_DEPTH, btf__wave_pad());
        return NULL;
    }
    btf_wave *w = btf__calloc(1, sizeof *w, err);
    if (!w)
        return NULL;
    int left = 0, right = 0;
    for (int s = 0; s < b->n; s++) {
        int dc = b->offsets[s].col;
        left = -dc > left ? -dc : left;
        right = dc > right ? dc : right;
    }
    /* Lap position 0 starts a noise block: left_pad >= left, fx0 - left_pad on a block
     * boundary (BTF_NOISE_ORIGIN is a multiple of 4). */
    uint32_t c0 = (uint32_t)(fx0 + BTF_NOISE_ORIGIN);
    w->left_pad = left + (int)((c0 - (uint32_t)left) & 3u);
    w->block0 = (c0 - (uint32_t)w->left_pad) >> 2;
    w->lap = (w->left_pad + fw + right + 7) / 8 * 8; /* right pad: lap - left_pad - fw >= right */
    w->fw = fw;
    w->row0 = row0;
    w->stream = stream;
    w->sigma = b->sigma;
    w->same_row_shape = btf__car_same_row_shape(b, w->same_row_gamma3);
    for (int s = 0; s < b->n; s++) {
        int d = -b->offsets[s].row, dc = b->offsets[s].col;
        if (d == 0)
            continue;
        int r = 0;
        while (r < w->n_row_groups && w->group_rows_up[r] != d)
            r++;
        if (r == w->n_row_groups) {
            w->group_rows_up[r] = d;
            w->n_row_groups++;
        }
        w->term_group[w->n_earlier] = r;
        w->term_at[w->n_earlier] = d * WAVE_LAG - dc; /* steps back, made relative below */
        w->term_gamma[w->n_earlier++] = b->gamma[s];
    }
    for (int r = 0; r < w->n_row_groups; r++) {
        int lo = INT32_MAX, hi = 0;
        for (int s = 0; s < w->n_earlier; s++)
            if (w->term_group[s] == r) {
                lo = w->term_at[s] < lo ? w->term_at[s] : lo;
                hi = w->term_at[s] > hi ? w->term_at[s] : hi;
            }
        w->group_steps_back[r] = hi;
        w->group_n_steps[r] = 8 + hi - lo;
    }
    for (int s = 0; s < w->n_earlier; s++)
        w->term_at[s] = w->group_steps_back[w->term_group[s]] - w->term_at[s];
    for (int k = 0; k < 8; k++) {
        w->pos[k] = -k * WAVE_LAG;
        w->noise_row[k] = (uint32_t)(row0 + k + BTF_NOISE_ORIGIN);
    }
    size_t history_size = ((size_t)w->lap + WAVE_MIRROR) * 8 * sizeof(float);
    w->history = aligned_alloc(32, history_size);
    if (!w->history) {
        btf__wave_free(w);
        btf__fail(err, BTF_E_NOMEM, "out of memory");
        return NULL;
    }
    memset(w->history, 0, history_size);
    w->ring = ring, w->depth = depth, w->pad = pad;
    w->stride = (size_t)fw + 2 * (size_t)pad;
    for (int k = 0; k < 8; k++)
        w->dst[k] = wave_dst(w, k);
    return w;
}

#ifdef WAVE_AVAILABLE
#pragma GCC push_options
#pragma GCC target("avx2")

#define WAVE_FN static inline __attribute__((always_inline))

/* 8 x 8 transpose: r[k] lane j = v[j] lane k. */
WAVE_FN void transpose8(const __m256 *v, __m256 *r)
{
    __m256 t0 = _mm256_unpacklo_ps(v[0], v[1]), t1 = _mm256_unpackhi_ps(v[0], v[1]);
    __m256 t2 = _mm256_unpacklo_ps(v[2], v[3]), t3 = _mm256_unpackhi_ps(v[2], v[3]);
    __m256 t4 = _mm256_unpacklo_ps(v[4], v[5]), t5 = _mm256_unpackhi_ps(v[4], v[5]);
    __m256 t6 = _mm256_unpacklo_ps(v[6], v[7]), t7 = _mm256_unpackhi_ps(v[6], v[7]);
    __m256 u0 = _mm256_shuffle_ps(t0, t2, 0x44), u1 = _mm256_shuffle_ps(t0, t2, 0xEE);
    __m256 u2 = _mm256_shuffle_ps(t1, t3, 0x44), u3 = _mm256_shuffle_ps(t1, t3, 0xEE);
    __m256 u4 = _mm256_shuffle_ps(t4, t6, 0x44), u5 = _mm256_shuffle_ps(t4, t6, 0xEE);
    __m256 u6 = _mm256_shuffle_ps(t5, t7, 0x44), u7 = _mm256_shuffle_ps(t5, t7, 0xEE);
    r[0] = _mm256_permute2f128_ps(u0, u4, 0x20);
    r[1] = _mm256_permute2f128_ps(u1, u5, 0x20);
    r[2] = _mm256_permute2f128_ps(u2, u6, 0x20);
    r[3] = _mm256_permute2f128_ps(u3, u7, 0x20);
    r[4] = _mm256_permute2f128_ps(u0, u4, 0x31);
    r[5] = _mm256_permute2f128_ps(u1, u5, 0x31);
    r[6] = _mm256_permute2f128_ps(u2, u6, 0x31);
    r[7] = _mm256_permute2f128_ps(u3, u7, 0x31);
}

/* The 32 Gaussians of the next 8 steps, e[j] for step j: each lane's two
 * blocks (its positions p .. p + 7) of its own row, btf_noise4's bits. */
WAVE_FN void wave_noise(const btf_wave *w, __m256i pos, __m256i noise_row, __m256 *e)
{
    v8u blk = (v8u)_mm256_add_epi32(_mm256_set1_epi32((int)w->block0),
                                    _mm256_srai_epi32(pos, 2));
    v8u block[2] = {blk, blk + 1u}, cx[2], cy[2], cz[2], cw[2];
    philox8_noise(2, block, (v8u)noise_row, &w->plan, cx, cy, cz, cw);
    /* btf_noise4: (x, y) give components 0 and 1, (z, w) components 2 and 3 */
    v8u a[4] = {cx[0], cx[1], cz[0], cz[1]}, b[4] = {cy[0], cy[1], cw[0], cw[1]};
    v8f z0[4], z1[4];
    gauss2_lockstep(4, a, b, z0, z1);
    e[0] = (__m256)z0[0], e[1] = (__m256)z1[0], e[2] = (__m256)z0[2], e[3] = (__m256)z1[2];
    e[4] = (__m256)z0[1], e[5] = (__m256)z1[1], e[6] = (__m256)z0[3], e[7] = (__m256)z1[3];
}

/* The values d rows up of each lane for n consecutive steps from slot x
 * (the slots of history, mirror included): lane k takes lane k - d of the step,
 * lanes below d lane k - d + 8 of the step 8 WAVE_LAG later, which holds the
 * row d up on its previous lap. */
WAVE_FN void wave_rotated(const btf_wave *w, int x, int d, int n, __m256 *out)
{
    int x2 = x + 8 * WAVE_LAG;
    x2 = x2 >= w->lap ? x2 - w->lap : x2;
    const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    __m256 high = _mm256_castsi256_ps(_mm256_cmpgt_epi32(lane, _mm256_set1_epi32(7 - d)));
    __m256i idx = _mm256_and_si256(_mm256_sub_epi32(lane, _mm256_set1_epi32(d)),
                                   _mm256_set1_epi32(7));
    const float *cur = w->history + (size_t)x * 8, *prev = w->history + (size_t)x2 * 8;
    for (int i = 0; i < n; i++) {
        __m256 mixed = _mm256_blendv_ps(_mm256_load_ps(cur + 8 * i),
                                        _mm256_load_ps(prev + 8 * i), high);
        out[i] = _mm256_permutevar8x32_ps(mixed, idx);
    }
}

/* Stores lane k's 8 positions from row[k] into its ring row, then moves
 * each lane on by 8 positions (`past`: the lanes that start a row). */
WAVE_FN void wave_store(btf_wave *w, const __m256 *row, int past)
{
    for (int k = 0; k < 8; k++)
        if (w->dst[k]) {
            _mm256_storeu_ps(w->dst[k], row[k]);
            w->dst[k] += 8;
        }
    if (past)
        for (int k = 0; k < 8; k++)
            if (past & (1 << k) || !w->dst[k])
                w->dst[k] = wave_dst(w, k);
}

/* The earlier-row part and the noise of the next 8 steps: acc[j] =
 * (((0 + g_1 Y_1) + g_2 Y_2) + ...) + sigma e[j] per lane, terms in stored
 * order (btf_car_accumulate, btf_car_output). Reads only steps before w->steps. */
WAVE_FN void wave_terms(const btf_wave *w, const __m256 *e, __m256 *acc)
{
    __m256 rot[WAVE_REACH_ROW][8 + WAVE_SPAN];
    for (int r = 0; r < w->n_row_groups; r++) {
        int x = w->history_slot - w->group_steps_back[r];
        wave_rotated(w, x < 0 ? x + w->lap : x, w->group_rows_up[r], w->group_n_steps[r], rot[r]);
    }
    __m256 a0 = _mm256_setzero_ps(), a1 = a0, a2 = a0, a3 = a0, a4 = a0, a5 = a0, a6 = a0;
    __m256 a7 = a0; /* in registers: an array here became memory cleared by rep stos */
    for (int s = 0; s < w->n_earlier; s++) {
        const __m256 g = _mm256_set1_ps(w->term_gamma[s]);
        const __m256 *src = rot[w->term_group[s]] + w->term_at[s];
        a0 = _mm256_add_ps(a0, _mm256_mul_ps(g, src[0]));
        a1 = _mm256_add_ps(a1, _mm256_mul_ps(g, src[1]));
        a2 = _mm256_add_ps(a2, _mm256_mul_ps(g, src[2]));
        a3 = _mm256_add_ps(a3, _mm256_mul_ps(g, src[3]));
        a4 = _mm256_add_ps(a4, _mm256_mul_ps(g, src[4]));
        a5 = _mm256_add_ps(a5, _mm256_mul_ps(g, src[5]));
        a6 = _mm256_add_ps(a6, _mm256_mul_ps(g, src[6]));
        a7 = _mm256_add_ps(a7, _mm256_mul_ps(g, src[7]));
    }
    const __m256 sigma = _mm256_set1_ps(w->sigma);
    acc[0] = _mm256_add_ps(a0, _mm256_mul_ps(sigma, e[0]));
    acc[1] = _mm256_add_ps(a1, _mm256_mul_ps(sigma, e[1]));
    acc[2] = _mm256_add_ps(a2, _mm256_mul_ps(sigma, e[2]));
    acc[3] = _mm256_add_ps(a3, _mm256_mul_ps(sigma, e[3]));
    acc[4] = _mm256_add_ps(a4, _mm256_mul_ps(sigma, e[4]));
    acc[5] = _mm256_add_ps(a5, _mm256_mul_ps(sigma, e[5]));
    acc[6] = _mm256_add_ps(a6, _mm256_mul_ps(sigma, e[6]));
    acc[7] = _mm256_add_ps(a7, _mm256_mul_ps(sigma, e[7]));
}

/* Steps w->steps .. + 7: noise, earlier-row part, then the same-row chain
 * (`shape` terms, a constant where inlined) lane by lane in vector steps, +0
 * outside the field; the step vectors into history, the rows into the ring. */
WAVE_FN void wave_group_shape(btf_wave *w, const int shape)
{
    __m256i pos = _mm256_loadu_si256((const __m256i *)w->pos);
    __m256i noise_row = _mm256_loadu_si256((const __m256i *)w->noise_row);
    __m256 e[8], acc[8], out[8];
    wave_noise(w, pos, noise_row, e);
    wave_terms(w, e, acc);
    __m256 y1 = _mm256_loadu_ps(w->last_steps[0]), y2 = _mm256_loadu_ps(w->last_steps[1]);
    __m256 y3 = _mm256_loadu_ps(w->last_steps[2]);
    const __m256 g0 = _mm256_set1_ps(w->same_row_gamma3[0]), g1 = _mm256_set1_ps(w->same_row_gamma3[1]);
    const __m256 g2 = _mm256_set1_ps(w->same_row_gamma3[2]);
    /* lane k is a field column when 0 <= pos + j - left_pad < fw: one signed
     * compare after moving both sides by 2^31 */
    const __m256i flip = _mm256_set1_epi32(INT32_MIN);
    const __m256i left_pad = _mm256_set1_epi32(w->left_pad);
    const __m256i q0 = _mm256_add_epi32(_mm256_sub_epi32(pos, left_pad), flip);
    const __m256i end = _mm256_add_epi32(_mm256_set1_epi32(w->fw), flip);
    float *slot = w->history + (size_t)w->history_slot * 8;
    /* every lane inside the field for all 8 steps (the usual case): no mask */
    __m256i last = _mm256_add_epi32(q0, _mm256_set1_epi32(7));
    __m256i inside = _mm256_and_si256(_mm256_cmpgt_epi32(end, q0), _mm256_cmpgt_epi32(end, last));
    int masked = _mm256_movemask_ps(_mm256_castsi256_ps(inside)) != 0xFF;
    for (int j = 0; j < 8; j++) {
        __m256 v = acc[j];
        if (shape >= 3)
            v = _mm256_add_ps(v, _mm256_mul_ps(g0, y3));
        if (shape >= 2)
            v = _mm256_add_ps(v, _mm256_mul_ps(g1, y2));
        if (shape >= 1)
            v = _mm256_add_ps(v, _mm256_mul_ps(g2, y1));
        if (masked) {
            __m256i in = _mm256_cmpgt_epi32(end, _mm256_add_epi32(q0, _mm256_set1_epi32(j)));
            v = _mm256_and_ps(v, _mm256_castsi256_ps(in)); /* +0 outside the field */
        }
        y3 = y2, y2 = y1, y1 = v;
        _mm256_store_ps(slot + 8 * j, v);
        out[j] = v;
    }
    if (w->history_slot < WAVE_MIRROR) /* the mirror past lap */
        memcpy(w->history + ((size_t)w->lap + w->history_slot) * 8, slot, 8 * 8 * sizeof(float));
    _mm256_storeu_ps(w->last_steps[0], y1);
    _mm256_storeu_ps(w->last_steps[1], y2);
    _mm256_storeu_ps(w->last_steps[2], y3);
    /* next positions; a lane past its lap starts its next row */
    pos = _mm256_add_epi32(pos, _mm256_set1_epi32(8));
    __m256i past = _mm256_cmpgt_epi32(pos, _mm256_set1_epi32(w->lap - 1));
    pos = _mm256_sub_epi32(pos, _mm256_and_si256(past, _mm256_set1_epi32(w->lap)));
    noise_row = _mm256_add_epi32(noise_row, _mm256_and_si256(past, _mm256_set1_epi32(8)));
    _mm256_storeu_si256((__m256i *)w->pos, pos);
    _mm256_storeu_si256((__m256i *)w->noise_row, noise_row);
    __m256 rows[8];
    transpose8(out, rows);
    /* lanes still above the field (pos < 0 before: dst NULL) are checked too */
    wave_store(w, rows, _mm256_movemask_ps(_mm256_castsi256_ps(past)) |
                            (w->steps < 8 * WAVE_LAG ? 0x100 : 0));
    w->steps += 8;
    w->history_slot += 8;
    if (w->history_slot == w->lap)
        w->history_slot = 0;
}

static void wave_group_any(btf_wave *w)
{
    switch (w->same_row_shape) {
    case 0: wave_group_shape(w, 0); break;
    case 1: wave_group_shape(w, 1); break;
    case 2: wave_group_shape(w, 2); break;
    default: wave_group_shape(w, 3); break;
    }
}

void btf__wave_run(btf_wave *w, int row, uint32_t seed_lo, uint32_t seed_hi)
{
    int64_t i = (int64_t)row - w->row0;
    int64_t lap_index = i / 8, lane = i % 8;
    int64_t done = (lap_index + 1) * w->lap + lane * WAVE_LAG; /* its last position stored */
    if (!w->planned || w->plan_seed[0] != seed_lo || w->plan_seed[1] != seed_hi) {
        philox8_plan_make(&w->plan, w->stream, seed_lo, seed_hi);
        w->plan_seed[0] = seed_lo, w->plan_seed[1] = seed_hi;
        w->planned = 1;
    }
    while (w->steps < done)
        wave_group_any(w);
}
#pragma GCC pop_options
#else
void btf__wave_run(btf_wave *w, int row, uint32_t seed_lo, uint32_t seed_hi)
{
    (void)w, (void)row, (void)seed_lo, (void)seed_hi; /* never created */
}
#endif
