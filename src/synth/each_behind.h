/*
 * each_behind.h — btf_synthesise_each with each finished image written
 * behind the synthesis (each_behind.c), as btfcar synthesise writes whole
 * images. Private to the library (and its command line).
 */
#ifndef BTF_SYNTH_EACH_BEHIND_H
#define BTF_SYNTH_EACH_BEHIND_H

#include "btfcar.h"

/* The writer and what the run reports back. */
typedef struct btf_each_behind {
    btf_image_fn write;        /* image i, on the writer thread; freed after */
    void *user;                /* write's */
    btf_progress_fn progress;  /* NULL, or (i + 1) / n "synthesising" once
                                  image i is handed over (the calling thread) */
    void *progress_user;
    double hand_s;             /* out: seconds handing images over (waiting
                                  for the previous write included) */
    double wait_s;             /* out: seconds waiting for the writes after
                                  the synthesis */
    int write_failed;          /* out: the failure returned is a write's
                                  (its message names its file, not the model) */
} btf_each_behind;

/* btf_synthesise_each, the images handed to b->write on a thread of its own
 * while the next one is synthesised (and the previous matched beside it):
 * one image waits at most, so three are in memory (one written, one
 * matched, one synthesised). The first failed write stops the batch and
 * is returned (nothing is written after it); without a thread to be had,
 * the writes run on the calling thread. The same files as writing each
 * image in the btf_image_fn of btf_synthesise_each. */
btf_status btf__synthesise_each_behind(const btf_model *m, const int *subspaces, int n,
                                       const btf_synth_opts *opts, btf_each_behind *b,
                                       btf_error *err);

#endif
