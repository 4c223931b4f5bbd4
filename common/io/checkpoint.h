/* Checkpoint files (coordinator/README.md "Checkpoints and resume"): one HDF5 file per process
 * in OUT/checkpoints/NNNNNN/ (NNNNNN = the step index of the state), written into
 * NNNNNN.tmp/ first and renamed by the coordinator once every file is on disk.
 *
 * A process describes its state once, with one function that calls lahar_ckpt_f64/_i64/... for
 * every array and scalar: opened for writing the calls store the values, opened for reading
 * they load them into the same places (and check each size). Writing and reading can therefore
 * not drift apart. Every file carries the checkpoint format and the lahar version that wrote
 * it; a file of another format is refused with a message. */
#ifndef LAHAR_CHECKPOINT_H
#define LAHAR_CHECKPOINT_H
#include <stddef.h>
#include <stdint.h>

#define LAHAR_CKPT_FORMAT 1
#define LAHAR_CKPT_DIR "checkpoints"

typedef struct {
    int64_t file;   /* hid_t */
    int writing;    /* 1: store, 0: load */
    int failed;     /* a call failed; the first message is in err */
    char err[1024];
    char path[1024]; /* the file (writing: its directory's room is checked before each array) */
} lahar_ckpt_file;

/* Create path (writing) or open it (reading, format and version checked). 0, or -1 with f->err. */
int lahar_ckpt_create(lahar_ckpt_file *f, const char *path, const char *role);
int lahar_ckpt_open(lahar_ckpt_file *f, const char *path, const char *role);
/* Writing: flush, close and fsync the file. Reading: close. 0, or -1 with f->err (also when a
 * call before failed). */
int lahar_ckpt_close(lahar_ckpt_file *f);

/* One named array of n values: stored, or loaded into data (which must hold n; a dataset of
 * another length fails the file). n = 0 stores an empty dataset. */
void lahar_ckpt_f64(lahar_ckpt_file *f, const char *name, double *data, int64_t n);
void lahar_ckpt_i64(lahar_ckpt_file *f, const char *name, int64_t *data, int64_t n);
void lahar_ckpt_i32(lahar_ckpt_file *f, const char *name, int32_t *data, int64_t n);
void lahar_ckpt_u8(lahar_ckpt_file *f, const char *name, uint8_t *data, int64_t n);
/* An int as a one-element int64 dataset. */
void lahar_ckpt_int(lahar_ckpt_file *f, const char *name, int *v);
/* A byte blob of any length: stored from (*data, *n), or loaded into a new malloc'd *data with
 * its length in *n (free it). */
void lahar_ckpt_blob(lahar_ckpt_file *f, const char *name, void **data, size_t *n);
/* Length of a stored array (reading), or -1 when it does not exist. */
int64_t lahar_ckpt_length(lahar_ckpt_file *f, const char *name);

/* OUT/checkpoints/NNNNNN or NNNNNN.tmp into buf. */
void lahar_ckpt_dir(char *buf, size_t n, const char *outdir, int64_t step, int tmp);
/* mkdir -p (also for OUT itself). 0 or -1 (errno). */
int lahar_mkdir_p(const char *path);
/* fsync a file or directory by path. 0 or -1 (errno). */
int lahar_ckpt_fsync_path(const char *path);

#endif
