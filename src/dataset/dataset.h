/*
 * dataset.h — BTF datasets on disk below the public btf_dataset_* calls
 * (src/dataset/): the layouts' file lists (UBO2003, UTIA, manifests, RTI
 * light files), near-field captures, and the reusable read buffer. The
 * Bonn .btf files have their own header, dataset/ubo2014.h. The files
 * themselves are read through src/io/ (io/io.h). Private to the library.
 */
#ifndef BTF_DATASET_H
#define BTF_DATASET_H

#include "btfcar.h"

#include <stddef.h>

/* btf_dataset_read into a buffer that is reused (dataset/dataset.c): when
 * img already holds an image of the dataset's size, a .btf file's image is
 * decoded straight into it; otherwise (or for image files, which their
 * decoders allocate) img is freed and read afresh. img must be
 * zero-initialised or hold an image; on failure it is freed. Streaming
 * loops keep one such buffer per thread instead of allocating one per
 * image: on a 151 x 151 x 400^2 .btf file the fresh buffers' page faults
 * were 40 % of an analysis (docs/datasets.md, "UBO2014 .btf files"). */
btf_status btf__dataset_read_into(const btf_dataset *ds, int view, int light, btf_image *img,
                                  btf_error *err);

/* The measured pairs of a dataset as *present: [view * n_lights + light]
 * 1 when the set holds the pair (dataset/dataset.c); freed by the caller. */
btf_status btf__dataset_present(const btf_dataset *ds, unsigned char **present, btf_error *err);

/* Dataset layouts (dataset/dataset_scan.c): the image files of a dataset
 * folder (UBO2003 or UTIA names) or manifest as entries, from the names
 * alone; dataset/dataset.c makes the (view, light) table of them. */
#define BTF_DATASET_PATH_MAX 4096
/* The most a near-field image's view or light direction may change across
 * it (degrees; docs/datasets.md, "Near-field captures"). */
#define BTF_NEAR_FIELD_MAX_SPREAD 15.0
/* A near-field capture (docs/datasets.md, "Near-field captures"): the
 * camera and the point light at known positions above the sample, the
 * image covering size_x x size_y around the origin of their frame (x to
 * the image's right, y to its top, z the surface normal; one unit, e.g.
 * cm). The entry's directions are those from the image's centre. */
typedef struct btf_near_field {
    int on;
    double camera[3], light[3];
    double size_x, size_y;
} btf_near_field;
typedef struct btf_dataset_entry {
    char *path;
    btf_dir light, view;
    btf_near_field near; /* on 0: directions hold for every pixel */
} btf_dataset_entry;
typedef struct btf_dataset_entries {
    btf_dataset_entry *items;
    int count, cap;
    btf_layout layout;
    int flat;        /* UBO2003 files in one folder (no tvCCC_pvDDD/) */
    char ext[8];     /* the first file's extension, for messages */
} btf_dataset_entries;
/* The entry list (dataset/dataset_entries.c), shared by every layout's
 * reader: btf__dataset_entries_add appends a copy of path with its
 * directions (BTF_E_NOMEM when out of memory); btf__dataset_entries_free
 * frees the entries and zeroes l. */
btf_status btf__dataset_entries_add(btf_dataset_entries *l, const char *path, btf_dir light,
                                    btf_dir view, btf_error *err);
void btf__dataset_entries_free(btf_dataset_entries *l);
/* The first entry whose path an earlier one has (*again) and that earlier
 * one (*first); both -1 when every path is listed once. */
btf_status btf__dataset_entries_repeat(const btf_dataset_entries *l, int *first, int *again,
                                       btf_error *err);

/* A near-field image's per-pixel correction (dataset/near_field.c): every
 * pixel multiplied by the light's irradiance at the image centre over its own,
 * (|L - P| / |L|)^3 for a point light L over the surface point P (inverse
 * square and cosine), so that the image is lit as its centre is. */
void btf__near_field_correct(const btf_near_field *nf, btf_image *img);
/* The largest angle (degrees) between the centre's view or light direction
 * and a corner's. */
double btf__near_field_spread(const btf_near_field *nf);
/* Directions from the image centre to a position (x, y, z > 0). */
btf_dir btf__near_field_dir(const double *pos);

/* Every entry of the dataset at path: a folder is scanned, a file is read as
 * a manifest. A folder without any image of a known layout is BTF_E_FORMAT.
 * Free l (also on failure) with btf__dataset_entries_free. */
btf_status btf__dataset_list_entries(const char *path, btf_dataset_entries *l, btf_error *err);
/* RTI light files (dataset/rti_lp.c, layout BTF_LAYOUT_RTI): "N", then N
 * lines "PATH X Y Z" (the unit vector towards the light; PATH relative to base,
 * or absolute) as entries of view (0, 0). btf__rti_lp_name: 1 when path ends
 * in ".lp". btf__rti_lp_parse reads n bytes of text named name (messages
 * "NAME:LINE: ..."), checking that every image is a regular file when
 * check_files; btf__rti_lp_read reads the file at path, images beside it.
 * Free l (also on failure) with btf__dataset_entries_free. */
int btf__rti_lp_name(const char *path);
btf_status btf__rti_lp_parse(const char *text, size_t n, const char *name, const char *base,
                             int check_files, btf_dataset_entries *l, btf_error *err);
btf_status btf__rti_lp_read(const char *path, btf_dataset_entries *l, btf_error *err);

#endif
