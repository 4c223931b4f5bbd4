/* The output writers' private interface: only common/io/output*.c include it (users include
 * output.h). What one writer shares with the others, each defined once:
 *
 *   output_h5.c       room on the disk, the last error, HDF5 files, groups, attributes, datasets,
 *                     the /header group, SWMR row appends
 *   output_snapfile.c a snapshot file and its twin: appends that a killed writer cannot corrupt
 *   output_resume.c   the snapshot list of a file, a resumed writer's XDMF sidecar */
#ifndef LAHAR_OUTPUT_H5_H
#define LAHAR_OUTPUT_H5_H
#include <hdf5.h>
#include <stddef.h>
#include <stdint.h>
#include "output.h"
#include "xdmf.h"

#define OUT_PATH_MAX 1200
#define OUT_XML_CAP 16384
#define FORCES_FLUSH_SECONDS 0.5 /* the force and gauge streams flush at least this often (wall s) */

/* output_h5.c: room on the disk and failed writes (the message in lahar_output_error()) */
int out_room(const char *path, double need, const char *what, int64_t step, double t);
void out_write_failed(const char *path, const char *what, int64_t step, double t);
int out_close(hid_t f);

/* output_h5.c: HDF5 objects without time stamps, files without locks */
hid_t out_dcpl(void);
hid_t out_group(hid_t loc, const char *name);
int out_snapshots_group(hid_t f);
hid_t out_file_open(const char *path, unsigned flags, int create);
hid_t out_str_type(void);
int out_attr(hid_t loc, const char *name, hid_t type, int n, const void *data);
int out_attr_double(hid_t loc, const char *name, double v);
int out_attr_int64(hid_t loc, const char *name, int64_t v);
int out_attr_string(hid_t loc, const char *name, const char *s);
hid_t out_header_group(hid_t f, const lahar_case *c);
int out_dataset(hid_t loc, const char *name, hid_t memtype, hid_t filetype, int rank, hsize_t d0, hsize_t d1,
                const void *data);
int out_strings(hid_t loc, const char *name, int n, const char *const *s);
int out_append_rows(hid_t id, hid_t mtype, int rank, hsize_t start, hsize_t rows, hsize_t nb, const void *buf);
double out_wall_seconds(void);
void out_stream_cache(hid_t fapl, double chunk_bytes);

/* output_snapfile.c: a snapshot file (bodies.h5, particles.h5, contacts.h5) and its twin
 * OUT/.<name>.twin, which holds the same snapshots. append writes /snapshots/NNNNNN (time,
 * step, then what fill(group, ctx) writes) into the twin, swaps the two names, and writes the
 * snapshot again into the former file: the file's name always refers to a completely written
 * file. fill is called twice with the same ctx and must write the same both times. append
 * checks room on the disk first; 0, or -1 with the message in lahar_output_error(). close
 * removes the twin. init with in_place set (the case's output.twins: false) writes into the
 * file itself, with no twin. */
typedef int (*out_snapshot_fill)(hid_t group, void *ctx);
typedef struct {
    char path[OUT_PATH_MAX + 16];
    char twin[OUT_PATH_MAX + 32];
    int twin_ok;  /* the twin holds what the file holds (else it is copied before the next append) */
    int in_place; /* snapshots go into the file itself (output.twins: false, or a file system that
                   * cannot swap two names) */
} out_snapfile;
void out_snapfile_init(out_snapfile *sf, const char *path, int in_place);
int out_snapfile_append(out_snapfile *sf, double need, const char *what, int64_t nsnap, int64_t step, double t,
                        out_snapshot_fill fill, void *ctx);
void out_snapfile_close(out_snapfile *sf);
int out_snapfile_twin_path(const char *path, char *twin, size_t n);

/* output_resume.c: one snapshot group of a file as found on disk */
typedef struct {
    int64_t step, snap, n;
    double t;
} out_snap_entry;
int64_t out_read_snapshot_list(const char *path, out_snap_entry **list);
/* A resumed run (lahar_case.resume): the snapshot count of an existing file and its XDMF sidecar
 * rebuilt from the snapshots on disk (bodies: the body grids, NULL for particles with *fields). */
int out_resume_sidecar(const char *h5path, const char *xmfpath, lahar_xdmf_file *xmf,
                       const lahar_xdmf_bodies *bodies, const unsigned *fields, int64_t *nsnap, char *err,
                       size_t n);

#endif
