/*
 * btfcar.h — the public C API of btfcar, a toolkit for probabilistic modelling
 * of Bidirectional Texture Functions (Haindl & Filip, TPAMI 2007).
 *
 * This header includes every topical header of the API; a program may
 * include this one or only the topical headers it needs (each stands alone):
 *
 *   btfcar/base.h      version, errors, callbacks, atomic files, directions
 *   btfcar/image.h     float images; PNG, JPEG and OpenEXR files
 *   btfcar/dataset.h   BTF datasets: layouts, reading, UBO2014 .btf writing
 *   btfcar/generate.h  procedural materials (btfcar generate)
 *   btfcar/model.h     the CAR model and the reflectance-field model, files
 *   btfcar/analyse.h   segmentation, photometric stereo, the CAR and RF fits
 *   btfcar/synth.h     synthesis on the CPU
 *   btfcar/render.h    hemisphere interpolation, range maps, scenes, renders
 *   btfcar/report.h    texture distances, the report, the sweep, the library
 *   btfcar/gpu.h       the Vulkan compute path
 *
 * Conventions (docs/api.md):
 *  - a fallible call returns a btf_status (BTF_OK = 0, errors negative) and,
 *    when given a non-NULL btf_error, fills it with one line naming the file,
 *    the value and what was expected. The library never prints and never exits.
 *  - options structs are valid when zero-initialised: a zero field means its
 *    default, and btf_X_defaults() returns the struct btf_X_opts with every
 *    default written out (the same results as the zeroed struct). A NULL
 *    options pointer means the defaults.
 *  - what a call allocates into a caller's struct is released by the matching
 *    *_free (or *_close) function, which accepts a zeroed struct and NULL.
 *  - parsers work on memory (btf_image_decode, btf_model_decode); the file
 *    readers (btf_image_read, btf_model_read) are thin wrappers over them.
 *  - images are linear float, channels interleaved, row 0 at the top.
 *  - directions are in degrees: theta from the surface normal (z), phi the
 *    azimuth measured from +x towards +y.
 *
 * What the headers declare is the ABI of libbtfcar.so: the library is
 * compiled with -fvisibility=hidden, and each topical header's
 * declarations, under #pragma GCC visibility push(default), alone are
 * exported (docs/install.md, "Shared library and soname").
 */
#ifndef BTFCAR_H
#define BTFCAR_H

#include "btfcar/base.h"
#include "btfcar/image.h"
#include "btfcar/dataset.h"
#include "btfcar/generate.h"
#include "btfcar/model.h"
#include "btfcar/analyse.h"
#include "btfcar/synth.h"
#include "btfcar/render.h"
#include "btfcar/report.h"
#include "btfcar/gpu.h"
#include "btfcar/material.h"

#endif /* BTFCAR_H */
