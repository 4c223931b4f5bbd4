/* XDMF 2 sidecars describing lahar's HDF5 output for ParaView (Xdmf3ReaderT / XDMF Reader).
 * One temporal collection; each time step is a spatial collection holding the grids of the
 * writers present (moving bodies, fixed bodies, body centres, particles), so body and particle
 * output join the same file (lahar_output_xdmf_combine in output.h). */
#ifndef LAHAR_XDMF_H
#define LAHAR_XDMF_H
#include <stddef.h>
#include <stdint.h>
#include <sys/types.h>

/* A growing XDMF file: the header and footer are written at open; each time step overwrites the
 * footer with the step's XML followed by the footer again in one pwrite, so between steps the
 * file is always well-formed and a viewer can open it while the job runs. */
typedef struct {
    int fd;
    off_t tail; /* offset of the footer */
} lahar_xdmf_file;

int lahar_xdmf_open(lahar_xdmf_file *f, const char *path, char *err, size_t n);
/* buf must have room for len + LAHAR_XDMF_FOOTER_MAX bytes (the footer is appended in place). */
int lahar_xdmf_append(lahar_xdmf_file *f, char *buf, size_t len, size_t cap);
void lahar_xdmf_close(lahar_xdmf_file *f);
#define LAHAR_XDMF_FOOTER_MAX 64

/* What the body grids of a time step refer to (in file `h5name`, relative to the XDMF file). */
typedef struct {
    const char *h5name;
    int nbody;
    int nodes_per_cell;           /* 3 triangles (3D), 2 line segments (2D) */
    int64_t moving_vertices, moving_cells;
    int64_t fixed_vertices, fixed_cells;
} lahar_xdmf_bodies;

typedef struct {
    const char *h5name;
    unsigned fields;              /* LAHAR_PFIELD_* mask */
} lahar_xdmf_particles;

/* Text builders; they return the number of characters written (as snprintf, excluding NUL) or
 * a value >= cap when the buffer is too small. `snap` is the snapshot group index. */
size_t lahar_xdmf_step_begin(char *buf, size_t cap, int64_t step, double t);
size_t lahar_xdmf_bodies_grids(char *buf, size_t cap, const lahar_xdmf_bodies *b, int64_t snap);
size_t lahar_xdmf_particles_grid(char *buf, size_t cap, const lahar_xdmf_particles *p, int64_t snap, int64_t n);
size_t lahar_xdmf_step_end(char *buf, size_t cap);

#endif
