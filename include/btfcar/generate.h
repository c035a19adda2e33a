/*
 * btfcar/generate.h — procedural materials: built-in height fields with a
 * reflectance, rendered into the images a BTF measurement takes (btfcar
 * generate).
 * Part of the public C API of btfcar; include/btfcar.h includes every
 * topical header, and its conventions (docs/api.md) hold here too.
 */
#ifndef BTFCAR_GENERATE_H
#define BTFCAR_GENERATE_H

#include "base.h"
#include "image.h"

#include <stdint.h>

/* What this header declares is part of the ABI of libbtfcar.so: the library
 * is compiled with -fvisibility=hidden, and the declarations of the public
 * headers alone are exported (docs/install.md, "Shared library and soname"). */
#pragma GCC visibility push(default)

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------ procedural materials */

/* A material: a periodic height field (in texel units) with an albedo and the
 * parameters of its reflectance (Lambertian + one specular lobe). */
typedef struct btf_procedural {
    char name[32];
    int size;               /* width = height = size texels */
    float *height;          /* size*size, texel units, periodic */
    float *normal;          /* size*size*3, unit vectors, z up */
    float *albedo;          /* size*size*3, linear RGB */
    float specular;         /* specular albedo */
    float shininess;        /* Blinn-Phong exponent of the lobe */
    float fresnel0;         /* reflectance of the coat at normal incidence (0: none) */
    float ambient;          /* fraction of light reaching shadowed points */
} btf_procedural;

/* Names of the built-in materials, NULL-terminated: leather, fabric, wood. */
const char *const *btf_procedural_names(void);
btf_status btf_procedural_make(const char *name, int size, uint64_t seed, btf_procedural *m,
                             btf_error *err);
void btf_procedural_free(btf_procedural *m);

/* Renders the rectified image the BTF measures for one (view, light) pair:
 * for every texel of the reference plane, the view ray finds the visible
 * surface point (masking, parallax), which is lit by the light unless the
 * height field casts a shadow on it. Output: linear RGB, size x size. */
btf_status btf_procedural_render(const btf_procedural *m, btf_dir view, btf_dir light,
                               btf_image *out, btf_error *err);

typedef struct btf_generate_opts {
    size_t struct_size; /* sizeof the struct (set by the defaults); 0: this header's */
    int size;               /* 0: 128 */
    uint64_t seed;          /* 0 is a valid seed */
    int jpeg_quality;       /* 0: 95 */
    int threads;            /* 0: the number of online CPUs */
    btf_progress_fn progress;
    void *progress_user;
} btf_generate_opts;
/* The defaults: size 128, seed 0, JPEG quality 95, threads 0 (all CPUs). */
btf_generate_opts btf_generate_defaults(void);

/* Writes the 81 x 81 images of a material in the UBO2003 layout under outdir
 * (per-view folders), and outdir/truth/{height,normals,albedo}.exr. */
btf_status btf_generate(const char *material, const char *outdir,
                        const btf_generate_opts *opts, btf_error *err);

#ifdef __cplusplus
}
#endif

#pragma GCC visibility pop
#endif /* BTFCAR_GENERATE_H */
